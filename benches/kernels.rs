//! The kernels of one bar step, timed alone: the tridiagonal solve with `M̂` (fused
//! multiply-add where the CPU has it, and portable), the
//! stiffness product `K x`, the energy's quadratic form `xᵀ K x`, and the free-velocity computation that combines them.
//! Run: `cargo bench --bench kernels`.

use criterion::{BenchmarkId, Criterion, Throughput, criterion_group, criterion_main};
use signorini::assembly::linear_combination;
use signorini::linalg::{SpdFactor, quadratic_form, sym_spmv_add};
use signorini::scene::bar::BarScene;

fn kernels(c: &mut Criterion) {
    let mut g = c.benchmark_group("bar_kernels");
    for n in [1_000usize, 100_000] {
        let s = BarScene {
            elements: n,
            ..BarScene::default()
        };
        let sys = s.rod().assemble().unwrap();
        let h = 1e-7;
        let mhat = linear_combination(&[(1.0, &sys.mass), (h * h / 4.0, &sys.stiffness)]);
        let mut x: Vec<f64> = (0..=n).map(|i| (i as f64 * 0.1).sin()).collect();
        let mut y = vec![0.0; n + 1];
        g.throughput(Throughput::Elements(n as u64 + 1));
        // the tridiagonal L D Lᵀ solve in the default arithmetic (fused multiply-add
        // where the CPU has it) and in the portable one
        for (name, portable) in [("cholesky_solve", false), ("cholesky_solve_portable", true)] {
            signorini::linalg::set_portable_arithmetic(portable);
            let mut f = SpdFactor::new(mhat.as_ref(), "M̂").unwrap();
            g.bench_function(BenchmarkId::new(name, n), |b| {
                b.iter(|| f.solve_in_place(std::hint::black_box(&mut x)))
            });
        }
        signorini::linalg::set_portable_arithmetic(false);
        g.bench_function(BenchmarkId::new("energy_quadratic_form", n), |b| {
            b.iter(|| quadratic_form(sys.stiffness.as_ref(), std::hint::black_box(&x)))
        });
        g.bench_function(BenchmarkId::new("stiffness_spmv", n), |b| {
            b.iter(|| {
                sym_spmv_add(
                    sys.stiffness.as_ref(),
                    -1.0,
                    &x,
                    std::hint::black_box(&mut y),
                )
            })
        });
    }
    g.finish();
}

/// One sparse solve vs a block of `SOLVE_BLOCK` right-hand sides with the factored
/// `M̂` of a 3-D hex8 box (the Delassus set-up solves one column per contact).
fn block_solves(c: &mut Criterion) {
    use signorini::linalg::SOLVE_BLOCK;
    use signorini::model::MassKind;
    use signorini::model::generate::box_mesh;
    use signorini::model::solid::{CellKind, Formulation, Material, assemble};
    let mut g = c.benchmark_group("solid_solves");
    g.sample_size(10);
    let mat = Material {
        young: 210e9,
        poisson: 0.3,
        density: 7800.0,
        model: signorini::model::solid::MaterialModel::LINEAR,
    };
    for cells in [14usize, 31] {
        let mesh = box_mesh(CellKind::Hex8, [cells; 3], [1.0; 3]);
        let sys = assemble(&mesh, &mat, Formulation::Solid, MassKind::Consistent).unwrap();
        let n = sys.ndof();
        let h = 1e-6;
        let mhat = linear_combination(&[(1.0, &sys.mass), (h * h / 4.0, &sys.stiffness)]);
        let mut f = SpdFactor::new(mhat.as_ref(), "M̂").unwrap();
        let mut x: Vec<f64> = (0..n * SOLVE_BLOCK)
            .map(|i| (i as f64 * 0.1).sin())
            .collect();
        g.throughput(Throughput::Elements(SOLVE_BLOCK as u64));
        g.bench_function(BenchmarkId::new("one_at_a_time", n), |b| {
            b.iter(|| {
                for col in x.chunks_exact_mut(n) {
                    f.solve_in_place(std::hint::black_box(col));
                }
            })
        });
        g.bench_function(BenchmarkId::new("blocked", n), |b| {
            b.iter(|| f.solve_block_in_place(std::hint::black_box(&mut x), SOLVE_BLOCK))
        });
    }
    g.finish();
}

criterion_group!(benches, kernels, block_solves);
criterion_main!(benches);
