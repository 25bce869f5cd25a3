//! The kernels of one bar step, timed alone: the sparse Cholesky solve with `M̂`, the
//! stiffness product `K x`, and the free-velocity computation that combines them.
//! Run: `cargo bench --bench kernels`.

use criterion::{BenchmarkId, Criterion, Throughput, criterion_group, criterion_main};
use signorini::assembly::linear_combination;
use signorini::linalg::{SpdFactor, sym_spmv_add};
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
        let mut f = SpdFactor::new(mhat.as_ref(), "M̂").unwrap();
        let mut x: Vec<f64> = (0..=n).map(|i| (i as f64 * 0.1).sin()).collect();
        let mut y = vec![0.0; n + 1];
        g.throughput(Throughput::Elements(n as u64 + 1));
        g.bench_function(BenchmarkId::new("cholesky_solve", n), |b| {
            b.iter(|| f.solve_in_place(std::hint::black_box(&mut x)))
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

criterion_group!(benches, kernels);
criterion_main!(benches);
