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

/// Issue 35: under the `M̂⁻¹` metric the zone flexibilities `F` and `F_E` come from the
/// factor (`F = ZᵀZ`, `Z = L⁻¹PS` on the zone's elimination-tree paths; `F_E` from the
/// factor's tangent along `K`) instead of `2z` column solves. The same scene with the
/// zone kept as `Â⁻¹S` (`dense`, the swept columns) gives the same run: the two forms of
/// `F` agree to round-off (the unit test in `linalg::zone_flex` holds them to 1e-12 of
/// the largest entry), and 40 steps of Newton-projected iterates carry that round-off
/// into the impulses and `q`; 1e-9 of the largest value leaves three orders of margin
/// over what the unit test allows and still fails on any wrong entry of `F` or `F_E`
/// (a missing path, a transposed block), which moves the impulses at the percent level.
#[test]
fn zone_flexibilities_from_the_factor_match_the_swept_columns() {
    let (pa, qa, path) = history("auto", 2);
    assert!(path.contains("tangent along K"), "auto: {path}");
    let (pd, qd, path_d) = history("dense", 2);
    assert!(!path_d.contains("tangent"), "dense: {path_d}");
    let close = |a: &[f64], b: &[f64], what: &str| {
        let scale = a.iter().fold(0.0f64, |m, x| m.max(x.abs()));
        assert!(scale > 0.0, "{what}: all zero");
        let err = a
            .iter()
            .zip(b)
            .fold(0.0f64, |m, (x, y)| m.max((x - y).abs()));
        assert!(err <= 1e-9 * scale, "{what}: {err:e} of {scale:e}");
    };
    assert_eq!(pa.len(), pd.len());
    close(&pa, &pd, "impulses");
    close(&qa, &qd, "q");
}
