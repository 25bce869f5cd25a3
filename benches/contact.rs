//! The search of contacts between bodies (`contact::bodies`), timed alone on a flat
//! interface: a block's face of n × n quads (the master surface) under the (n + 1)² nodes
//! of another face (the slaves, offset by half a cell so that every node projects inside
//! a facet), with the default search distance. `rebuild`: the R*-tree bulk load of the
//! facets' boxes, every node's candidate list and its pairing (what
//! `Integrator::prepare` does when a node has moved half the search distance);
//! `pair`: the pairing alone (every step start where a node moved); `evaluate`: every gap and Jacobian
//! column on the pairs (every Newton iteration).
//! Run: `cargo bench --bench contact`.

use criterion::{BenchmarkId, Criterion, Throughput, criterion_group, criterion_main};
use signorini::contact::ContactJacobian;
use signorini::contact::bodies::{Interface, build};

fn search(c: &mut Criterion) {
    let mut g = c.benchmark_group("contact_search");
    g.sample_size(10);
    for n in [100usize, 300] {
        let h = 1.0 / n as f64;
        let k = n + 1;
        // master: the z = 0 face, nodes k × k, quads counter-clockwise seen from +z
        let master: Vec<[f64; 3]> = (0..k * k)
            .map(|i| [(i % k) as f64 * h, (i / k) as f64 * h, 0.0])
            .collect();
        let facets: Vec<Vec<usize>> = (0..n * n)
            .map(|f| {
                let (i, j) = (f % n, f / n);
                let a = j * k + i;
                vec![a, a + 1, a + k + 1, a + k]
            })
            .collect();
        // slaves: the nodes of a face shifted by half a cell, 1e-4 above
        let slave: Vec<[f64; 3]> = (0..k * k)
            .map(|i| [((i % k) as f64 + 0.5) * h, ((i / k) as f64 + 0.5) * h, 1e-4])
            .collect();
        let nodes: Vec<usize> = (0..k * k).collect();
        let slave_dofs = |v: usize| [Some(3 * v), Some(3 * v + 1), Some(3 * v + 2)];
        let off = 3 * k * k;
        let master_dofs = |v: usize| {
            [
                Some(off + 3 * v),
                Some(off + 3 * v + 1),
                Some(off + 3 * v + 2),
            ]
        };
        let (mut set, line) = build(
            Interface {
                dim: 3,
                slave: &nodes,
                slave_points: &slave,
                slave_dofs: &slave_dofs,
                facets: &facets,
                master_points: &master,
                master_dofs: &master_dofs,
                names: None,
            },
            false,
            (0.0, 0.3),
            None,
            64,
        )
        .unwrap();
        eprintln!("n = {n}: {} nodes against {line}", set.len());
        let q = vec![0.0; 2 * off];
        let mut gap = vec![0.0; set.len()];
        let mut jac = ContactJacobian::for_set(set.as_ref());
        g.throughput(Throughput::Elements(set.len() as u64));
        g.bench_function(BenchmarkId::new("rebuild", n * n), |b| {
            b.iter(|| {
                set.restart(&q);
                set.update(std::hint::black_box(&q)).unwrap()
            })
        });
        // two configurations 1 µm apart (below half the search distance): each update
        // re-pairs without a rebuild
        let q1: Vec<f64> = (0..2 * off)
            .map(|i| if i % 3 == 0 { 1e-6 } else { 0.0 })
            .collect();
        let mut flip = false;
        g.bench_function(BenchmarkId::new("pair", n * n), |b| {
            b.iter(|| {
                flip = !flip;
                let x = if flip { &q1 } else { &q };
                set.update(std::hint::black_box(x)).unwrap()
            })
        });
        g.bench_function(BenchmarkId::new("evaluate", n * n), |b| {
            b.iter(|| set.evaluate(std::hint::black_box(&q), &mut gap, &mut jac))
        });
    }
    g.finish();
}

criterion_group!(benches, search);
criterion_main!(benches);
