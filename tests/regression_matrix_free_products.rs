//! Issue 35: a constant `G` whose one-step problems are solved matrix-free
//! (`crate::solvers::global`) takes its products `W x` through the flexibilities `F` of
//! the dofs `G` touches (`Delassus::condense_products`: `F` formed once from the
//! factor's `L⁻¹S` on their elimination-tree paths) instead of one sparse solve each.
//! A 12 × 12 × 4-cell hex8 block (2 535 dofs: a supernodal factor) dropped at 1 m/s on
//! the rigid floor, its 169 base nodes in contact, with the dense one-step workspaces
//! capped at 16 rows so that every problem goes matrix-free: every scheme of the
//! θ-method core, both metrics, at h = 2e-5 s and 8× coarser, `flexibility` (products through `F`; `auto` takes them
//! only where the dense blocks do not fit) against `columns` (products through the
//! factor).
//!
//! Tolerance: the two runs differ only in the order of the products' sums (round-off,
//! 1e-16 relative per product), which MPRGP's iterates carry to its stopping test and
//! the Newton loop over 35 steps: measured at most 3.4e-13 of the largest impulse and
//! 1.4e-13 of the largest coordinate (every scheme, metric and step). 1e-9 leaves three
//! orders of margin and is far below what a wrong entry of `F` (a missing tree path: a
//! column of `W` off by its coupling to the other contacts, tens of percent) would give.

mod common;

use signorini::contact::ContactSet;
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

fn block() -> (LinearSystem, Box<dyn Fn() -> Box<dyn ContactSet>>) {
    let mesh = box_mesh(CellKind::Hex8, [12, 12, 4], [0.12, 0.12, 0.04]);
    let sys = assemble(&mesh, &MAT, Formulation::Solid, MassKind::Consistent).unwrap();
    let face = mesh.node_sets["z0"].clone();
    let points = mesh.points.clone();
    let make = move || common::blocks::floor_contacts(&face, &points, -1e-4);
    (sys, Box::new(make))
}

/// `q` and every step's impulses, and the path phrase.
fn run(
    params: &SchemeParams,
    sys: &LinearSystem,
    contacts: Box<dyn ContactSet>,
    h: f64,
) -> (Vec<f64>, Vec<f64>, String) {
    let n = sys.ndof();
    let mut v0 = vec![0.0; n];
    for v in v0.iter_mut().skip(2).step_by(3) {
        *v = -1.0;
    }
    let mut integ =
        integrators::build(params, sys.clone(), contacts, &vec![0.0; n], &v0, h).unwrap();
    let mut impulses = Vec::new();
    let mut products = 0;
    // the 1e-4 m gap closes after 5 steps; 30 steps of compression
    for _ in 0..35 {
        let st = integ.step().unwrap();
        assert_eq!(st.caps_hit, 0, "{:?}: cap hit", params.kind);
        products += st.global_products;
        impulses.extend_from_slice(&integ.state().impulse);
    }
    assert!(
        products > 0,
        "{:?}: no problem went matrix-free",
        params.kind
    );
    (integ.state().q.clone(), impulses, integ.path())
}

#[test]
fn products_through_the_flexibilities_match_products_through_the_factor() {
    let (sys, make) = block();
    // the scene's step and 8× coarser (the gap then closes within the first step)
    for (kind, h) in [
        SchemeKind::MoreauJean,
        SchemeKind::DirectProjection,
        SchemeKind::CombinedProjection,
    ]
    .into_iter()
    .flat_map(|k| [(k, 2e-5), (k, 1.6e-4)])
    {
        for metric in [Metric::Mass, Metric::Euclidean] {
            let base = SchemeParams {
                kind,
                metric,
                max_active_rows: 16,
                delassus: DelassusKind::Flexibility,
                ..SchemeParams::default()
            };
            let (qa, pa, path) = run(&base, &sys, make(), h);
            assert!(
                path.contains("W x = Bᵀ F (B x)") && path.contains("of the 169 dofs"),
                "{kind:?}: {path}"
            );
            let cols = SchemeParams {
                delassus: DelassusKind::Columns,
                ..base
            };
            let (qc, pc, path_c) = run(&cols, &sys, make(), h);
            assert!(!path_c.contains("Bᵀ F"), "{path_c}");
            assert!(
                pa.iter().filter(|&&p| p > 0.0).count() > 16 * 10,
                "{kind:?}: too few impulses"
            );
            for (what, a, b) in [("q", &qa, &qc), ("impulses", &pa, &pc)] {
                let d = common::max_rel_diff(a, b);
                assert!(
                    d < 1e-9,
                    "{kind:?} {metric:?} h = {h}: {what} differ by {d:e}"
                );
            }
        }
    }
}
