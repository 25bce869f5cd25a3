//! The contact zone's set-up runs on rayon's threads (the blocked column solves and the
//! tiled `K` products of `F_E`, `delassus::condense_zone`): issue 18 asks that its
//! results do not change between 1 and 2 threads. Two 8³-cell hex8 cubes meeting over a
//! face (81 node-to-surface contacts, 486 zone dofs: four chunks of columns, sixteen
//! tiles of `K` products), both zone storages, Algorithm 2, 40 steps through the first
//! closing: every impulse and every coordinate of `q` bitwise equal. Any dependence of a
//! column on its thread or on its neighbours in a batch shows in the last bits.

mod common;

use signorini::integrators::Integrator;
use signorini::scene::file::Scene;

/// The impulses of every step and the final `q`, built and stepped on `threads` threads.
fn history(delassus: &str, threads: usize) -> (Vec<f64>, Vec<f64>, String) {
    let pool = rayon::ThreadPoolBuilder::new()
        .num_threads(threads)
        .build()
        .unwrap();
    pool.install(|| {
        let scene = Scene::from_toml(&common::blocks::two_cubes(4e-4, delassus)).unwrap();
        let (model, _) = scene.build().unwrap();
        let h = scene.time.dt;
        let mut integ: Box<dyn Integrator> = model.into_integrator(&scene.scheme, h).unwrap();
        let steps = (scene.time.t_end / h).round() as usize;
        let mut impulses = Vec::new();
        for _ in 0..steps {
            integ.prepare().unwrap();
            let st = integ.step().unwrap();
            assert_eq!(st.caps_hit, 0);
            impulses.extend_from_slice(&integ.state().impulse);
        }
        (impulses, integ.state().q.clone(), integ.path())
    })
}

#[test]
fn zone_set_up_is_independent_of_the_thread_count() {
    for (delassus, kept) in [("auto", "not kept"), ("dense", "Â⁻¹S 4131×486 condensed")] {
        let (p1, q1, path) = history(delassus, 1);
        assert!(path.contains(kept), "{delassus}: {path}");
        assert!(
            p1.iter().any(|&p| p > 0.0),
            "{delassus}: the cubes never touched"
        );
        let (p2, q2, _) = history(delassus, 2);
        assert!(
            p1 == p2,
            "{delassus}: impulses differ between 1 and 2 threads"
        );
        assert!(q1 == q2, "{delassus}: q differs between 1 and 2 threads");
    }
}
