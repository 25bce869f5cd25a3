//! The dense and the per-active-column Delassus paths (DESIGN.md §4) compute the same
//! iterates: every scheme, both projection metrics, a linear contact set (a hex8 box
//! pressed on a plane: 25 contacts activating at once, then releasing) and a
//! nonlinear one (the same box against a sphere, where `G(q)` is re-linearized every
//! Newton iteration). Tolerance 1e-9 relative to the largest value: the two paths
//! differ only in the order of the floating-point sums (axpys over dense columns
//! against one sparse solve of the gathered right-hand side); a wrong column, a
//! stale column after eviction or a missing feedback term changes results at the
//! 1e-3 level or more.

mod common;

use signorini::contact::ContactSet;
use signorini::contact::plane::NodesOnPlane;
use signorini::contact::sphere::{RoundObstacle, Side};
use signorini::delassus::DelassusKind;
use signorini::integrators::{self, Metric, SchemeKind, SchemeParams};
use signorini::model::generate::box_mesh;
use signorini::model::solid::{CellKind, Formulation, Material, assemble};
use signorini::model::{LinearSystem, MassKind};

const MAT: Material = Material {
    young: 1e7,
    poisson: 0.3,
    density: 1000.0,
    model: signorini::model::solid::MaterialModel::LINEAR,
};

fn box_system() -> (LinearSystem, Vec<[f64; 3]>, Vec<usize>) {
    let mesh = box_mesh(CellKind::Hex8, [4, 4, 4], [0.1, 0.1, 0.1]);
    let sys = assemble(&mesh, &MAT, Formulation::Solid, MassKind::Consistent).unwrap();
    let face = mesh.node_sets["z0"].clone();
    (sys, mesh.points.clone(), face)
}

fn run(
    params: &SchemeParams,
    sys: &LinearSystem,
    contacts: Box<dyn ContactSet>,
    steps: usize,
    h: f64,
) -> (Vec<f64>, Vec<f64>, Vec<f64>) {
    let n = sys.ndof();
    let mut v0 = vec![0.0; n];
    for v in v0.iter_mut().skip(2).step_by(3) {
        *v = -1.0;
    }
    let mut integ =
        integrators::build(params, sys.clone(), contacts, &vec![0.0; n], &v0, h).unwrap();
    let mut impulses = Vec::new();
    for _ in 0..steps {
        let st = integ.step().unwrap();
        assert_eq!(st.caps_hit, 0, "{:?}: cap hit", params.kind);
        impulses.extend_from_slice(&integ.state().impulse);
    }
    let s = integ.state();
    (s.q.clone(), s.v.clone(), impulses)
}

fn compare(make: &dyn Fn() -> Box<dyn ContactSet>, steps: usize, h: f64, what: &str) {
    let (sys, _, _) = box_system();
    for kind in SchemeKind::ALL {
        for metric in [Metric::Mass, Metric::Euclidean] {
            let base = SchemeParams {
                kind,
                metric,
                ..SchemeParams::default()
            };
            let dense = run(
                &SchemeParams {
                    delassus: DelassusKind::Dense,
                    ..base
                },
                &sys,
                make(),
                steps,
                h,
            );
            let cols = run(
                &SchemeParams {
                    delassus: DelassusKind::Columns,
                    ..base
                },
                &sys,
                make(),
                steps,
                h,
            );
            assert!(
                dense.2.iter().any(|&p| p > 0.0),
                "{what}: no contact happened"
            );
            for (name, a, b) in [
                ("q", &dense.0, &cols.0),
                ("v", &dense.1, &cols.1),
                ("P", &dense.2, &cols.2),
            ] {
                let d = common::max_rel_diff(a, b);
                assert!(
                    d < 1e-9,
                    "{what} {} {metric:?}: {name} differs by {d:e} between the paths",
                    kind.name()
                );
            }
        }
    }
}

#[test]
fn plane_contacts_same_on_both_paths() {
    let (_, points, face) = box_system();
    let make = || common::blocks::floor_contacts(&face, &points, -1e-4);
    // 1e-4 m gap closed at 1 m/s after 1e-4 s = 5 steps; contact lasts about
    // 2 × 0.1 m / c0 ≈ 2e-3 s, so 60 steps cover impact and compression.
    compare(&make, 60, 2e-5, "plane");
}

#[test]
fn sphere_contacts_same_on_both_paths() {
    let (_, points, face) = box_system();
    let make = || -> Box<dyn ContactSet> {
        Box::new(
            RoundObstacle::general(
                face.iter()
                    .map(|&v| vec![3 * v, 3 * v + 1, 3 * v + 2])
                    .collect(),
                face.iter().map(|&v| points[v].to_vec()).collect(),
                vec![0.05, 0.05, -0.2],
                None,
                0.2 - 1e-4,
                Side::Outside,
                0.0,
            )
            .unwrap(),
        )
    };
    compare(&make, 40, 2e-5, "sphere");
}

/// A particle bouncing between two walls (e = 1) with a one-column pool: every
/// bounce evicts the other wall's column and recomputes its own; the trajectory must
/// equal the dense path's. Too many simultaneous contacts for the pool is a clear
/// error, not a wrong answer.
#[test]
fn evicted_columns_are_recomputed() {
    use signorini::contact::Composite;
    use signorini::model::point_mass::point_mass;
    let walls = || -> Box<dyn ContactSet> {
        let wall = |normal: f64| -> Box<dyn ContactSet> {
            Box::new(
                NodesOnPlane::new(vec![vec![0]], vec![vec![0.0]], vec![normal], -1.0, 1.0).unwrap(),
            )
        };
        Box::new(Composite::new(vec![wall(1.0), wall(-1.0)]))
    };
    let sys = point_mass(1, 2.0, &[0.0]).unwrap();
    let trajectory = |delassus, pool| {
        let p = SchemeParams {
            delassus,
            delassus_pool: pool,
            ..SchemeParams::default()
        };
        let mut integ = integrators::build(&p, sys.clone(), walls(), &[0.0], &[3.0], 1e-3).unwrap();
        let mut out = Vec::new();
        let mut bounces = 0;
        for _ in 0..5000 {
            integ.step().unwrap();
            let s = integ.state();
            bounces += s.impulse.iter().filter(|&&p| p > 0.0).count();
            out.push(s.q[0]);
        }
        (out, bounces)
    };
    let (dense, bounces) = trajectory(DelassusKind::Dense, 0);
    let (cols, _) = trajectory(DelassusKind::Columns, 1);
    // 5 s at 3 m/s between walls 2 m apart: 7 bounces.
    assert!(bounces >= 7, "{bounces} bounces");
    let d = common::max_rel_diff(&dense, &cols);
    assert!(d < 1e-12, "trajectories differ by {d:e}");
    // a particle driven into a corner activates two walls at once: a one-column pool
    // cannot hold them
    let corner = || -> Box<dyn ContactSet> {
        let wall = |normal: Vec<f64>| -> Box<dyn ContactSet> {
            Box::new(
                NodesOnPlane::new(vec![vec![0, 1]], vec![vec![0.0, 0.0]], normal, 0.0, 0.0)
                    .unwrap(),
            )
        };
        Box::new(Composite::new(vec![
            wall(vec![-1.0, 0.0]),
            wall(vec![0.0, -1.0]),
        ]))
    };
    let p = SchemeParams {
        delassus: DelassusKind::Columns,
        delassus_pool: 1,
        ..SchemeParams::default()
    };
    let sys = point_mass(2, 2.0, &[1.0, 1.0]).unwrap();
    let mut integ = integrators::build(&p, sys, corner(), &[0.0, 0.0], &[3.0, 3.0], 1e-3).unwrap();
    let err = integ.step().unwrap_err().to_string();
    assert!(
        err.contains("Delassus pool") && err.contains("delassus_pool"),
        "{err}"
    );
}
