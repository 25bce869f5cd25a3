//! 3-D solids: assembly time serial vs parallel (rayon, 1 thread vs all cores), and the
//! per-step cost of Algorithm 2 (LCP `auto`) on a hex8 box pressed on a plane with its
//! whole bottom face, for about 10⁴ and 10⁵ dofs, with the Delassus data dense (`n × m`
//! blocks formed once) or per active column (DESIGN.md §4). The step samples are the
//! steady pressed state: every column is computed before the first sample. And the
//! neo-Hookean internal force with its tangent (what each full-Newton iterate of a
//! nonlinear structure assembles) and alone (a residual check), batched, on 1 and 2
//! threads. Run: `cargo bench --bench solid`.

use criterion::{BenchmarkId, Criterion, criterion_group, criterion_main};
use signorini::contact::plane::NodesOnPlane;
use signorini::delassus::DelassusKind;
use signorini::integrators::{self, SchemeParams};
use signorini::model::MassKind;
use signorini::model::generate::box_mesh;
use signorini::model::solid::{CellKind, Formulation, Material, assemble};
use signorini::solvers::LcpKind;

const MAT: Material = Material {
    young: 210e9,
    poisson: 0.3,
    density: 7800.0,
    model: signorini::model::solid::MaterialModel::LINEAR,
};

/// Box sizes: (n, n, n) hex8 cells → 3 (n+1)³ dofs: n = 14 → 10 125, n = 31 → 98 304.
const SIZES: [usize; 2] = [14, 31];

fn assembly(c: &mut Criterion) {
    let mut g = c.benchmark_group("solid_assembly");
    g.sample_size(10);
    for n in SIZES {
        let mesh = box_mesh(CellKind::Hex8, [n, n, n], [1.0, 1.0, 1.0]);
        let dofs = 3 * (n + 1).pow(3);
        for threads in [1usize, 0] {
            let pool = rayon::ThreadPoolBuilder::new()
                .num_threads(threads)
                .build()
                .unwrap();
            let label = if threads == 1 { "serial" } else { "parallel" };
            g.bench_function(BenchmarkId::new(label, dofs), |b| {
                b.iter(|| {
                    pool.install(|| {
                        assemble(&mesh, &MAT, Formulation::Solid, MassKind::Consistent).unwrap()
                    })
                })
            });
        }
    }
    g.finish();
}

fn hyperelastic(c: &mut Criterion) {
    use signorini::model::hyperelastic::{HyperBody, Hyperelastic};
    let mut g = c.benchmark_group("hyperelastic_assembly");
    g.sample_size(10);
    let n = SIZES[0];
    let mesh = box_mesh(CellKind::Hex8, [n, n, n], [1.0, 1.0, 1.0]);
    let dofs = 3 * (n + 1).pow(3);
    let u: Vec<f64> = (0..dofs).map(|i| 1e-3 * (i as f64).sin()).collect();
    for threads in [1usize, 2] {
        let pool = rayon::ThreadPoolBuilder::new()
            .num_threads(threads)
            .build()
            .unwrap();
        // the plan cuts the nodes for the pool it is built in
        let body = pool.install(|| HyperBody::new(&mesh, Hyperelastic::neo_hookean(&MAT)).unwrap());
        let mut batch = body.batch();
        let mut k = vec![0.0; body.plan().nnz()];
        let mut f = vec![0.0; dofs];
        g.bench_function(
            BenchmarkId::new(format!("tangent_{threads}_threads"), dofs),
            |b| {
                b.iter(|| {
                    pool.install(|| {
                        body.evaluate_batched((None, &u), Some(&mut k), &mut f, &mut batch)
                    })
                    .unwrap()
                })
            },
        );
        g.bench_function(
            BenchmarkId::new(format!("force_{threads}_threads"), dofs),
            |b| {
                b.iter(|| {
                    pool.install(|| body.evaluate_batched((None, &u), None, &mut f, &mut batch))
                        .unwrap()
                })
            },
        );
    }
    g.finish();
}

fn steps(c: &mut Criterion) {
    let mut g = c.benchmark_group("solid_step");
    g.sample_size(10);
    for n in SIZES {
        let mesh = box_mesh(CellKind::Hex8, [n, n, n], [1.0, 1.0, 1.0]);
        let sys = assemble(&mesh, &MAT, Formulation::Solid, MassKind::Consistent).unwrap();
        let dofs = sys.ndof();
        // the z0 face rests on the plane z = 0; the box moves down at 0.1 m/s
        let face = &mesh.node_sets["z0"];
        let contacts = NodesOnPlane::new(
            face.iter()
                .map(|&v| vec![3 * v, 3 * v + 1, 3 * v + 2])
                .collect(),
            face.iter().map(|&v| mesh.points[v].to_vec()).collect(),
            vec![0.0, 0.0, 1.0],
            0.0,
            0.0,
        )
        .unwrap();
        let mut v0 = vec![0.0; dofs];
        for v in v0.iter_mut().skip(2).step_by(3) {
            *v = -0.1;
        }
        for (label, delassus) in [
            ("dense", DelassusKind::Dense),
            ("columns", DelassusKind::Columns),
        ] {
            let params = SchemeParams {
                lcp: LcpKind::Auto,
                delassus,
                ..SchemeParams::default()
            };
            let mut integ = integrators::build(
                &params,
                sys.clone(),
                Box::new(contacts.clone()),
                &vec![0.0; dofs],
                &v0,
                1e-6,
            )
            .unwrap();
            g.bench_function(BenchmarkId::new(label, dofs), |b| {
                b.iter(|| integ.step().unwrap())
            });
        }
    }
    g.finish();
}

criterion_group!(benches, assembly, hyperelastic, steps);
criterion_main!(benches);
