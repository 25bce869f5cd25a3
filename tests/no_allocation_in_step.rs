//! `Integrator::step` does not allocate: a counting global allocator watches every
//! scheme through impact, contact, release and free flight, for linear and nonlinear
//! contacts, on both Delassus paths (dense, and per-active-column whose columns are
//! computed inside the step when a contact first activates).

mod common;

use std::alloc::{GlobalAlloc, Layout, System};
use std::cell::Cell;

use signorini::contact::sphere::InsideSphere;
use signorini::delassus::DelassusKind;
use signorini::integrators::{self, Metric, SchemeKind, SchemeParams};
use signorini::model::point_mass::point_mass;
use signorini::scene::bar::BarScene;

struct Counting;

thread_local! {
    // Per thread: the test harness runs other tests (which do allocate) in parallel.
    static ALLOCS: Cell<usize> = const { Cell::new(0) };
}

fn bump() {
    ALLOCS.with(|c| c.set(c.get() + 1));
}

unsafe impl GlobalAlloc for Counting {
    unsafe fn alloc(&self, l: Layout) -> *mut u8 {
        bump();
        unsafe { System.alloc(l) }
    }
    unsafe fn dealloc(&self, p: *mut u8, l: Layout) {
        unsafe { System.dealloc(p, l) }
    }
    unsafe fn realloc(&self, p: *mut u8, l: Layout, n: usize) -> *mut u8 {
        bump();
        unsafe { System.realloc(p, l, n) }
    }
}

#[global_allocator]
static GLOBAL: Counting = Counting;

fn count_steps(integ: &mut dyn integrators::Integrator, steps: usize) -> usize {
    let before = ALLOCS.with(|c| c.get());
    for _ in 0..steps {
        integ.step().unwrap();
    }
    ALLOCS.with(|c| c.get()) - before
}

#[test]
fn bar_steps_do_not_allocate() {
    for kind in SchemeKind::ALL {
        for metric in [Metric::Mass, Metric::Euclidean] {
            for delassus in [DelassusKind::Dense, DelassusKind::Columns] {
                let mut s = BarScene {
                    elements: 100,
                    dt: 2e-6,
                    ..BarScene::default()
                };
                s.scheme.kind = kind;
                s.scheme.metric = metric;
                s.scheme.delassus = delassus;
                let m = s.build().unwrap();
                let mut integ = m.into_integrator(&s.scheme, s.dt).unwrap();
                // 500 steps: contact (≈ 200 steps at this mesh and step), release, flight.
                let n = count_steps(integ.as_mut(), 500);
                assert_eq!(
                    n,
                    0,
                    "{} {:?} {:?} allocated {n} times",
                    kind.name(),
                    metric,
                    delassus
                );
            }
        }
    }
}

#[test]
fn nonlinear_contact_steps_do_not_allocate() {
    for (kind, delassus) in SchemeKind::ALL
        .into_iter()
        .flat_map(|k| [(k, DelassusKind::Dense), (k, DelassusKind::Columns)])
    {
        let sys = point_mass(2, 1.0, &[0.0, 0.0]).unwrap();
        let c = InsideSphere::new(
            vec![vec![0, 1]],
            vec![vec![0.0, 0.0]],
            vec![0.0, 0.0],
            1.0,
            0.5,
        )
        .unwrap();
        let p = SchemeParams {
            kind,
            delassus,
            ..SchemeParams::default()
        };
        let mut integ =
            integrators::build(&p, sys, Box::new(c), &[0.0, 0.5], &[1.0, 0.37], 1e-2).unwrap();
        let n = count_steps(integ.as_mut(), 1000);
        assert_eq!(n, 0, "{} {delassus:?} allocated {n} times", kind.name());
    }
}

/// Frictional steps (NSGS and PROX on the velocity problem, eq. 15): the elastic hex8
/// block of `meshes/sliding_block.toml` sliding, sticking and rocking, under the three
/// schemes that take friction, on both Delassus paths; and a particle in a circle with
/// friction (curved obstacle: the frame turns with the normal).
#[test]
fn frictional_steps_do_not_allocate() {
    use signorini::scene::file::Scene;
    use signorini::solvers::friction::FrictionSolverKind;
    let path = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("meshes/sliding_block.toml");
    for kind in [
        SchemeKind::MoreauJean,
        SchemeKind::DirectProjection,
        SchemeKind::CombinedProjection,
    ] {
        for delassus in [DelassusKind::Dense, DelassusKind::Columns] {
            for solver in [FrictionSolverKind::Nsgs, FrictionSolverKind::Prox] {
                let mut scene = Scene::from_file(&path).unwrap();
                scene.scheme.kind = kind;
                scene.scheme.delassus = delassus;
                scene.scheme.friction.solver = solver;
                let (model, _) = scene.build().unwrap();
                let mut integ = model.into_integrator(&scene.scheme, 1e-3).unwrap();
                let n = count_steps(integ.as_mut(), 400);
                assert_eq!(
                    n,
                    0,
                    "{} {delassus:?} {solver:?} allocated {n} times",
                    kind.name()
                );
            }
        }
        let sys = point_mass(2, 1.0, &[0.0, 0.0]).unwrap();
        let c = InsideSphere::new(
            vec![vec![0, 1]],
            vec![vec![0.0, 0.0]],
            vec![0.0, 0.0],
            1.0,
            0.5,
        )
        .unwrap()
        .with_friction(0.3)
        .unwrap();
        let p = SchemeParams {
            kind,
            ..SchemeParams::default()
        };
        let mut integ =
            integrators::build(&p, sys, Box::new(c), &[0.0, 0.5], &[1.0, 0.37], 1e-2).unwrap();
        let n = count_steps(integ.as_mut(), 1000);
        assert_eq!(
            n,
            0,
            "{} in a circle with friction allocated {n} times",
            kind.name()
        );
    }
}

/// The coupled position solve of Algorithms 1 and 2 (issue 16 §1) on the undamped block
/// of `tests/regression_alg2_friction_undamped.rs` at h = 1e-4, on both Delassus paths:
/// the counted steps must run coupled solves (asserted) without allocating.
#[test]
fn coupled_position_solves_do_not_allocate() {
    use signorini::scene::file::Scene;
    let text = common::blocks::undamped_block(1e-4, 0.3, "combined-projection", 0.5, 0.3);
    for kind in [SchemeKind::DirectProjection, SchemeKind::CombinedProjection] {
        for delassus in [DelassusKind::Dense, DelassusKind::Columns] {
            let mut scene = Scene::from_toml(&text).unwrap();
            scene.scheme.kind = kind;
            scene.scheme.delassus = delassus;
            let (model, _) = scene.build().unwrap();
            let mut integ = model.into_integrator(&scene.scheme, 1e-4).unwrap();
            for _ in 0..100 {
                integ.step().unwrap();
            }
            let mut coupled = 0;
            let before = ALLOCS.with(|c| c.get());
            for _ in 0..2400 {
                coupled += integ.step().unwrap().coupled_solves;
            }
            let n = ALLOCS.with(|c| c.get()) - before;
            assert!(
                coupled > 0,
                "{} {delassus:?}: no coupled solve",
                kind.name()
            );
            assert_eq!(n, 0, "{} {delassus:?} allocated {n} times", kind.name());
        }
    }
}

/// The matrix-free path (`solvers::global`): the hex8 block pressed on the plane with
/// its 25 contacts past a workspace cap of 16 rows, every scheme, frictionless (MPRGP)
/// and with friction (the accelerated projected gradient; the schemes that have it),
/// on both Delassus paths: the counted steps run matrix-free solves (asserted) without
/// allocating.
#[test]
fn matrix_free_solves_do_not_allocate() {
    use signorini::scene::file::Scene;
    for mu in [0.0, 0.3] {
        let text = common::blocks::undamped_block(1e-4, 0.3, "moreau-jean", 0.5, mu)
            .replace("theta = 0.5", "theta = 0.5\nmax_active_rows = 16");
        for kind in SchemeKind::ALL {
            if mu > 0.0
                && matches!(
                    kind,
                    SchemeKind::SchatzmanPaoli | SchemeKind::TrapezoidPosition
                )
            {
                continue;
            }
            for delassus in [DelassusKind::Dense, DelassusKind::Columns] {
                let mut scene = Scene::from_toml(&text).unwrap();
                scene.scheme.kind = kind;
                scene.scheme.delassus = delassus;
                let (model, _) = scene.build().unwrap();
                let mut integ = model.into_integrator(&scene.scheme, 1e-4).unwrap();
                integ.step().unwrap();
                let mut global = 0;
                let before = ALLOCS.with(|c| c.get());
                for _ in 0..50 {
                    global += integ.step().unwrap().global_solves;
                }
                let n = ALLOCS.with(|c| c.get()) - before;
                assert!(global > 0, "{} μ = {mu}: no matrix-free solve", kind.name());
                assert_eq!(
                    n,
                    0,
                    "{} {delassus:?} μ = {mu} allocated {n} times",
                    kind.name()
                );
            }
        }
    }
}

/// The matrix-free path for a nonlinear `G` (contacts between bodies on the
/// per-active-column path past 64 active rows): two 8³-cell cubes meeting over a face of
/// 81 contacts; the counted steps run matrix-free solves (asserted) without allocating.
#[test]
fn matrix_free_solves_between_bodies_do_not_allocate() {
    use signorini::scene::file::Scene;
    let text = common::blocks::two_cubes(1e-4, "columns");
    let scene = Scene::from_toml(&text).unwrap();
    let (model, _) = scene.build().unwrap();
    let mut integ = model.into_integrator(&scene.scheme, 1e-5).unwrap();
    integ.prepare().unwrap();
    integ.step().unwrap();
    let mut global = 0;
    let before = ALLOCS.with(|c| c.get());
    for _ in 0..8 {
        global += integ.step().unwrap().global_solves;
    }
    let n = ALLOCS.with(|c| c.get()) - before;
    assert!(global > 0, "no matrix-free solve");
    assert_eq!(n, 0, "allocated {n} times");
}

/// `auto`'s Newton fallback in the step loop and Algorithm 2's complementarity rounds
/// (issue 16 §2, large μ): the shipped sliding block launched at 1 m/s with μ = 1e6,
/// where NSGS and PROX cycle on the first step and the dense Newton methods finish, and
/// with μ = 1e3, where the combined rule's Newton loop cycles on the first step and the
/// round is redone with complementarity. Both must run (asserted) without allocating.
#[test]
fn large_friction_fallbacks_do_not_allocate() {
    use signorini::scene::file::Scene;
    let path = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("meshes/sliding_block.toml");
    let text = std::fs::read_to_string(path).unwrap();
    for mu in [1e6, 1e3] {
        let scene =
            Scene::from_toml(&text.replace("friction = 0.3", &format!("friction = {mu:?}")))
                .unwrap();
        // the rounds redone with complementarity are the paper's rule's (eq. 68 without
        // a solution for the set); the default rule holds fewer rows and needs none here
        let mut scene = scene;
        scene.scheme = scene.scheme.paper_rules();
        let (model, _) = scene.build().unwrap();
        let mut integ = model.into_integrator(&scene.scheme, scene.time.dt).unwrap();
        let (mut friction_fallbacks, mut rounds_redone) = (0, 0);
        let before = ALLOCS.with(|c| c.get());
        for _ in 0..50 {
            let st = integ.step().unwrap();
            assert_eq!(st.caps_hit, 0, "μ = {mu}");
            friction_fallbacks += st.friction_fallbacks;
            rounds_redone += st.complementarity_fallbacks;
        }
        let n = ALLOCS.with(|c| c.get()) - before;
        assert_eq!(n, 0, "μ = {mu}: allocated {n} times");
        if mu == 1e6 {
            assert!(friction_fallbacks > 0, "μ = {mu}: no Newton fallback ran");
        } else {
            assert!(rounds_redone > 0, "μ = {mu}: no complementarity round ran");
        }
    }
}

/// The linear-solver backends refactor and solve without allocating after their set-up
/// (the Newton loop of nonlinear scenes will refactor `M̂ⁿ` inside the step): Cholesky
/// (simplicial and tridiagonal), LDLᵀ and dense LU. The sparse LU is left out on
/// purpose: its fill depends on the pivots (`linalg::solver` module doc).
#[test]
fn linear_solver_refactors_and_solves_do_not_allocate() {
    use signorini::linalg::SparseMatrix;
    use signorini::linalg::solver::{SolverKind, factor};
    let n = 60;
    // a Laplacian with a far coupling (not tridiagonal), and a tridiagonal one
    let matrix = |shift: f64, far: bool| {
        let mut t = Vec::new();
        for i in 0..n {
            t.push(faer::sparse::Triplet::new(i, i, 2.0 + shift));
            if i + 1 < n {
                t.push(faer::sparse::Triplet::new(i, i + 1, -1.0));
                t.push(faer::sparse::Triplet::new(i + 1, i, -1.0));
            }
            if far && i + 7 < n {
                t.push(faer::sparse::Triplet::new(i, i + 7, 0.1));
                t.push(faer::sparse::Triplet::new(i + 7, i, 0.1));
            }
        }
        SparseMatrix::try_new_from_triplets(n, n, &t).unwrap()
    };
    for (kind, far, s1, s2) in [
        (SolverKind::Cholesky, true, 0.5, 0.7),
        (SolverKind::Cholesky, false, 0.5, 0.7),
        (SolverKind::Ldlt, true, -2.5, -2.3),
        (SolverKind::Dense, true, -2.5, 0.3),
    ] {
        let (a1, a2) = (matrix(s1, far), matrix(s2, far));
        let mut f = factor(a1.as_ref(), "M̂", kind, None).unwrap();
        let mut x = vec![1.0; n];
        let mut block = vec![1.0; 4 * n];
        let before = ALLOCS.with(|c| c.get());
        for a in [&a2, &a1, &a2] {
            f.refactor(a.as_ref(), "M̂").unwrap();
            f.solve_in_place(&mut x);
            f.solve_block_in_place(&mut block, 4);
            f.solve_columns_independently(&mut block, 4);
        }
        let n_alloc = ALLOCS.with(|c| c.get()) - before;
        assert_eq!(
            n_alloc,
            0,
            "{kind:?} ({}) allocated {n_alloc} times",
            f.backend_name()
        );
    }
}

/// The hyperelastic body's internal force and tangent (what the Newton loop of a
/// nonlinear structure evaluates at every iterate) are assembled without reserving
/// anything after the plan: counted on the worker thread of a one-thread rayon pool,
/// where the assembly runs.
#[test]
fn hyperelastic_assembly_does_not_allocate() {
    use signorini::model::generate::box_mesh;
    use signorini::model::hyperelastic::{HyperBody, Hyperelastic};
    use signorini::model::solid::{CellKind, Material};
    let mat = Material {
        young: 1e7,
        poisson: 0.3,
        density: 1000.0,
        model: signorini::model::solid::MaterialModel::LINEAR,
    };
    let pool = rayon::ThreadPoolBuilder::new()
        .num_threads(1)
        .build()
        .unwrap();
    for kind in [CellKind::Hex8, CellKind::Tet4] {
        let mesh = box_mesh(kind, [4, 3, 2], [0.4, 0.3, 0.2]);
        let body = HyperBody::new(&mesh, Hyperelastic::neo_hookean(&mat)).unwrap();
        let n = body.plan().order();
        let u: Vec<f64> = (0..n).map(|i| 1e-3 * (i as f64).sin()).collect();
        let mut k = vec![0.0; body.plan().nnz()];
        let mut f = vec![0.0; n];
        let allocated = pool.install(|| {
            body.evaluate(&u, &mut k, &mut f).unwrap();
            let before = ALLOCS.with(|c| c.get());
            for _ in 0..3 {
                body.evaluate(&u, &mut k, &mut f).unwrap();
            }
            ALLOCS.with(|c| c.get()) - before
        });
        assert_eq!(allocated, 0, "{kind:?}: {allocated} allocations");
    }
}

/// A neo-Hookean cube dropped at 1 m/s onto a plane (impact after 10 steps, then
/// compression and rebound): the steps of a nonlinear structure (each Newton iterate
/// assembles, refactors `M̂ⁿ` and condenses `W` again) do not allocate, in Moreau–Jean and
/// Algorithms 1 and 2, with full and modified Newton and with the energy–momentum
/// option (discrete-gradient forces). Counted on the worker thread of a
/// one-thread rayon pool, where the parallel assembly runs.
#[test]
fn nonlinear_structure_steps_do_not_allocate() {
    let pool = rayon::ThreadPoolBuilder::new()
        .num_threads(1)
        .build()
        .unwrap();
    for kind in [
        SchemeKind::MoreauJean,
        SchemeKind::DirectProjection,
        SchemeKind::CombinedProjection,
    ] {
        for (modified, em) in [(false, false), (true, false), (false, true)] {
            let text = format!(
                r#"
[time]
dt = 1e-4
t_end = 0.02
[scheme]
kind = "{}"
energy_momentum = {em}
newton = {{ modified = {modified} }}
[[bodies]]
name = "cube"
mesh = {{ generator = "box", cell = "hex8", cells = [3, 3, 3], size = [0.1, 0.1, 0.1] }}
material = {{ young = 1e5, poisson = 0.3, density = 1000.0, model = "neo-hookean" }}
velocity = [0.0, 0.0, -1.0]
[[obstacles]]
name = "floor"
type = "plane"
point = [0.0, 0.0, -0.001]
normal = [0.0, 0.0, 1.0]
[[contacts]]
body = "cube"
nodes = "z0"
obstacle = "floor"
"#,
                kind.name()
            );
            let scene = signorini::scene::file::Scene::from_toml(&text).unwrap();
            let allocated = pool.install(|| {
                let (model, _) = scene.build().unwrap();
                let mut integ = model.into_integrator(&scene.scheme, scene.time.dt).unwrap();
                integ.step().unwrap();
                let n = count_steps(integ.as_mut(), 150);
                // in contact at step 151 (impact at step 10; 2L/c ≈ 200 steps)
                assert!(
                    integ.state().impulse.iter().any(|&p| p > 0.0),
                    "the cube presses on the floor"
                );
                n
            });
            assert_eq!(
                allocated,
                0,
                "{} (modified Newton: {modified}, energy–momentum: {em}) allocated {allocated} times",
                kind.name()
            );
        }
    }
}

/// The slider–crank of sec. 6.3.1 (configuration-dependent mass, gyroscopic terms, a
/// nonsymmetric `M̂ⁿ` on the dense LU, four frictional corners with gaps nonlinear in `q`):
/// its steps do not allocate in Moreau–Jean and Algorithms 1 and 2, over the first
/// 500 steps at h = 1e-4 (the slider meets both guides: impacts, sliding and the
/// friction solver's fallbacks included).
#[test]
fn slider_crank_steps_do_not_allocate() {
    for kind in [
        SchemeKind::MoreauJean,
        SchemeKind::DirectProjection,
        SchemeKind::CombinedProjection,
    ] {
        let text = format!(
            "[example]\nkind = \"slider-crank\"\n[time]\ndt = 1e-4\nt_end = 0.06\n\
             [scheme]\nkind = \"{}\"\n",
            kind.name()
        );
        let scene = signorini::scene::file::Scene::from_toml(&text).unwrap();
        let (model, _) = scene.build().unwrap();
        let mut integ = model.into_integrator(&scene.scheme, scene.time.dt).unwrap();
        integ.step().unwrap();
        let mut closed = 0;
        let before = ALLOCS.with(|c| c.get());
        for _ in 0..500 {
            integ.step().unwrap();
            closed += usize::from(integ.state().impulse.iter().any(|&p| p > 0.0));
        }
        let allocated = ALLOCS.with(|c| c.get()) - before;
        assert!(
            closed > 10,
            "the slider touches its guides ({closed} steps)"
        );
        assert_eq!(allocated, 0, "{} allocated {allocated} times", kind.name());
    }
}

/// Contacts between bodies (issue 18): the coarse hex8 bars of `meshes/hex_bars.toml`
/// (node-to-surface, the zone-condensed path with its flexibilities (`auto`) and with
/// the `n × z` blocks (`dense`), and the per-column path) and the
/// two rods (a constant `G`), under every scheme. The candidate lists are brought up to
/// date by `prepare()` before each step (it may rebuild the tree and allocate); the step
/// itself does not allocate.
#[test]
fn steps_of_contacts_between_bodies_do_not_allocate() {
    use signorini::scene::file::Scene;
    let root = std::path::Path::new(env!("CARGO_MANIFEST_DIR"));
    for kind in SchemeKind::ALL {
        for (file, delassus) in [
            ("hex_bars.toml", "auto"),
            ("hex_bars.toml", "columns"),
            ("hex_bars.toml", "dense"),
            ("two_bars.toml", "auto"),
        ] {
            let set: Vec<String> = [
                format!("scheme.kind=\"{}\"", kind.name()),
                format!("scheme.delassus=\"{delassus}\""),
            ]
            .into_iter()
            .chain(
                (file == "hex_bars.toml")
                    .then(|| {
                        [
                            "bodies[0].mesh.cells=[20,1,1]".to_string(),
                            "bodies[1].mesh.cells=[15,2,2]".to_string(),
                            "time.dt=5e-6".to_string(),
                        ]
                    })
                    .into_iter()
                    .flatten(),
            )
            .chain(
                (file == "two_bars.toml")
                    .then(|| {
                        [
                            "bodies[0].mesh.elements=50".to_string(),
                            "bodies[1].mesh.elements=50".to_string(),
                            "time.dt=4e-6".to_string(),
                        ]
                    })
                    .into_iter()
                    .flatten(),
            )
            .collect();
            let scene = Scene::from_file_with(&root.join("meshes").join(file), &set).unwrap();
            let (model, _) = scene.build().unwrap();
            let mut integ = model.into_integrator(&scene.scheme, scene.time.dt).unwrap();
            // 150 steps: contact (2L/c ≈ 77 and 96 steps), release, flight
            let mut n = 0;
            for _ in 0..150 {
                integ.prepare().unwrap();
                n += count_steps(integ.as_mut(), 1);
            }
            assert_eq!(
                n,
                0,
                "{file} {} {delassus}: allocated {n} times",
                kind.name()
            );
        }
    }
}

/// Issue 49: a step after a change of `h` allocates nothing, and a change back to a
/// step whose factor and Delassus data are cached (the accuracy mode's ladder) allocates
/// nothing either (the state is saved into a kept snapshot, the cache's list never
/// grows). The first change to a new `h` factors and condenses, and may allocate.
#[test]
fn steps_after_a_change_of_step_do_not_allocate() {
    for kind in [
        SchemeKind::MoreauJean,
        SchemeKind::DirectProjection,
        SchemeKind::CombinedProjection,
    ] {
        for delassus in [DelassusKind::Dense, DelassusKind::Columns] {
            let mut s = BarScene {
                elements: 100,
                dt: 2e-6,
                ..BarScene::default()
            };
            s.scheme.kind = kind;
            s.scheme.delassus = delassus;
            let m = s.build().unwrap();
            let mut integ = m.into_integrator(&s.scheme, s.dt).unwrap();
            let label = format!("{} {delassus:?}", kind.name());
            assert_eq!(count_steps(integ.as_mut(), 20), 0, "{label}");
            integ.set_dt(1e-6).unwrap();
            assert_eq!(count_steps(integ.as_mut(), 50), 0, "{label} at h/2");
            integ.set_dt(2e-6).unwrap();
            assert_eq!(count_steps(integ.as_mut(), 50), 0, "{label} back at h");
            let before = ALLOCS.with(|c| c.get());
            integ.set_dt(1e-6).unwrap();
            integ.set_dt(2e-6).unwrap();
            let n = ALLOCS.with(|c| c.get()) - before;
            assert_eq!(
                n, 0,
                "{label}: changes between cached steps allocated {n} times"
            );
            assert_eq!(count_steps(integ.as_mut(), 300), 0, "{label} to flight");
        }
    }
}

/// Issue 50: the accuracy mode's windows (a step of 2h and two of h from one snapshot,
/// the snapshots restored for the observers) allocate nothing once the snapshots hold a
/// state and the ladder's steps are factored: the bar on a one-rung ladder (steps h and
/// 2h), three schemes, dense and column Delassus data.
#[test]
fn accuracy_windows_do_not_allocate() {
    use signorini::run::accuracy::{AccuracySpec, Controller};
    for kind in [
        SchemeKind::MoreauJean,
        SchemeKind::DirectProjection,
        SchemeKind::CombinedProjection,
    ] {
        for delassus in [DelassusKind::Dense, DelassusKind::Columns] {
            let mut s = BarScene {
                elements: 100,
                dt: 2e-6,
                ..BarScene::default()
            };
            s.scheme.kind = kind;
            s.scheme.delassus = delassus;
            let m = s.build().unwrap();
            let checks = signorini::run::RunChecks::new(&s.scheme, 1.0);
            let mut integ = m.into_integrator(&s.scheme, s.dt).unwrap();
            let spec = AccuracySpec {
                tol: 1e-2,
                dt_max: 2e-6,
                dt_min: 2e-6,
                t_end: 1e-3,
            };
            let mut ctrl = Controller::new(spec, integ.as_ref(), &checks, 0.5, None);
            let label = format!("{} {delassus:?}", kind.name());
            for _ in 0..3 {
                ctrl.window_step(integ.as_mut(), &checks, &mut []).unwrap();
            }
            let before = ALLOCS.with(|c| c.get());
            for _ in 0..100 {
                ctrl.window_step(integ.as_mut(), &checks, &mut []).unwrap();
            }
            let n = ALLOCS.with(|c| c.get()) - before;
            assert_eq!(n, 0, "{label}: 100 windows allocated {n} times");
        }
    }
}
