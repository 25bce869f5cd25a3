//! Per-step cost of Moreau–Jean and Algorithm 2 on the impacting bar, N = 10²…10⁵.
//!
//! `h = L/(N c0)` (Courant number 1, so the contact lasts about 2N steps). Each timed
//! sample runs consecutive steps of one bar; every 4N steps the bar is rebuilt outside
//! the timing, so the samples mix contact (half) and free flight (half) as the
//! reference run does. Reported: time per step; divide by N + 1 dofs for ns/dof/step.
//!
//! Run: `cargo bench --bench step` (add `-- --quick` for a fast look).

use std::time::{Duration, Instant};

use criterion::{BenchmarkId, Criterion, Throughput, criterion_group, criterion_main};
use signorini::integrators::{Integrator, SchemeKind};
use signorini::scene::bar::BarScene;

fn build(kind: SchemeKind, n: usize) -> Box<dyn Integrator> {
    let mut s = BarScene {
        elements: n,
        ..BarScene::default()
    };
    s.dt = s.length / (n as f64 * (s.young / s.density).sqrt());
    s.scheme.kind = kind;
    let m = s.build().unwrap();
    m.into_integrator(&s.scheme, s.dt).unwrap()
}

fn bench_steps(c: &mut Criterion) {
    let mut g = c.benchmark_group("bar_step");
    for n in [100usize, 1_000, 10_000, 100_000] {
        g.throughput(Throughput::Elements(n as u64 + 1));
        if n >= 10_000 {
            g.sample_size(20).measurement_time(Duration::from_secs(8));
        }
        for kind in [SchemeKind::MoreauJean, SchemeKind::CombinedProjection] {
            g.bench_function(BenchmarkId::new(kind.name(), n), |b| {
                b.iter_custom(|iters| {
                    let cycle = 4 * n as u64;
                    let mut total = Duration::ZERO;
                    let mut done = 0;
                    while done < iters {
                        let mut integ = build(kind, n);
                        let k = cycle.min(iters - done);
                        let t = Instant::now();
                        for _ in 0..k {
                            integ.step().unwrap();
                        }
                        total += t.elapsed();
                        done += k;
                    }
                    total
                })
            });
        }
    }
    g.finish();
}

criterion_group!(benches, bench_steps);
criterion_main!(benches);
