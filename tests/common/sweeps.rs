//! What the sweep tests share: a progress that counts the runs, and the small bar they
//! sweep.

use signorini::study::sweep::{RunRecord, SweepProgress};

/// Counts the runs a sweep makes.
pub struct Count(pub usize);

impl SweepProgress for Count {
    fn run(&mut self, _: usize, _: usize, _: &RunRecord, _: f64) {
        self.0 += 1;
    }
}

/// A bar of 40 elements to 4.5e-4 s (the contact lasts 3.85e-4 s): a few milliseconds
/// a run.
pub fn small_bar() -> Vec<String> {
    vec![
        "bodies[0].mesh.elements=40".into(),
        "time.t_end=4.5e-4".into(),
    ]
}
