//! Per-step cost of Moreau–Jean and Algorithm 2 on the impacting bar, N = 10²…10⁶, in
//! contact and in flight (issue 35 §2).
//!
//! `h = L/(N c0)` (Courant number 1, so the contact lasts about 2N steps). `contact`:
//! the reference bar (gap 0), rebuilt outside the timing every 2N steps, so every timed
//! step has the tip on the wall; `flight`: the same bar 1 m from the wall (reached after
//! 10 s: never). Reported: time per step; criterion's throughput divides by the N + 1
//! dofs. The process flushes subnormals to zero as a run does (`FlushGuard`).
//!
//! Run: `cargo bench --bench step` (add `-- --quick` for a fast look, or a filter such
//! as `-- 1000000`).

use std::time::{Duration, Instant};

use criterion::{BenchmarkId, Criterion, Throughput, criterion_group, criterion_main};
use signorini::integrators::{Integrator, SchemeKind};
use signorini::linalg::FlushGuard;
use signorini::scene::bar::BarScene;

fn build(kind: SchemeKind, n: usize, gap: f64) -> Box<dyn Integrator> {
    let mut s = BarScene {
        elements: n,
        gap,
        ..BarScene::default()
    };
    s.dt = s.length / (n as f64 * (s.young / s.density).sqrt());
    s.scheme.kind = kind;
    let m = s.build().unwrap();
    m.into_integrator(&s.scheme, s.dt).unwrap()
}

fn bench_steps(c: &mut Criterion) {
    let _flush = FlushGuard::for_run();
    let mut g = c.benchmark_group("bar_step");
    for n in [100usize, 1_000, 10_000, 100_000, 1_000_000] {
        g.throughput(Throughput::Elements(n as u64 + 1));
        match n {
            1_000_000 => g.sample_size(10).measurement_time(Duration::from_secs(10)),
            10_000.. => g.sample_size(20).measurement_time(Duration::from_secs(8)),
            _ => g.sample_size(100).measurement_time(Duration::from_secs(5)),
        };
        for kind in [SchemeKind::MoreauJean, SchemeKind::CombinedProjection] {
            for (phase, gap) in [("contact", 0.0), ("flight", 1.0)] {
                let id = BenchmarkId::new(format!("{}/{phase}", kind.name()), n);
                g.bench_function(id, |b| {
                    b.iter_custom(|iters| {
                        let cycle = 2 * n as u64;
                        let mut total = Duration::ZERO;
                        let mut done = 0;
                        while done < iters {
                            let mut integ = build(kind, n, gap);
                            let k = cycle.min(iters - done);
                            let mut impulse = 0.0;
                            let t = Instant::now();
                            for _ in 0..k {
                                integ.step().unwrap();
                                impulse += integ.state().impulse[0];
                            }
                            total += t.elapsed();
                            // the phase is the one named: an impulse in contact, none
                            // in flight
                            assert_eq!(impulse > 0.0, phase == "contact", "{phase}");
                            done += k;
                        }
                        total
                    })
                });
            }
        }
    }
    g.finish();
}

criterion_group!(benches, bench_steps);
criterion_main!(benches);
