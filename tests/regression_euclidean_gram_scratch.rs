//! Regression: the Euclidean metric's `W_N = GᵀG` was computed with a scratch vector
//! that still held `G`, doubling it, so each projection removed only half the
//! violation (the bar's tip gap halved step after step: −1.25e-7, −6.25e-8, …).

use signorini::app::run_bar;
use signorini::integrators::{Metric, SchemeKind};
use signorini::run::Quiet;
use signorini::scene::bar::BarScene;

#[test]
fn euclidean_projection_removes_the_whole_violation_in_one_step() {
    for kind in [SchemeKind::DirectProjection, SchemeKind::CombinedProjection] {
        let mut s = BarScene {
            dt: 5e-6,
            t_end: 5e-5,
            ..BarScene::default()
        };
        s.scheme.kind = kind;
        s.scheme.metric = Metric::Euclidean;
        let r = run_bar(&s, None, &mut Quiet).unwrap();
        assert!(
            r.summary.max_violation <= 1e-14,
            "{:e}",
            r.summary.max_violation
        );
    }
}
