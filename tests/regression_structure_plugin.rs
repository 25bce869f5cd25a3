//! Issue 49 §3: a structure model is a plug, not a branch. A [`StructureModel`] written
//! outside the crate is handed to a [`Problem`] ([`Problem::with_structure`]); the plan
//! asks it for the step matrix's analysis, the build factors through it, every step asks
//! it for the free velocity, and the driver reads its kind through the integrator (no
//! edit to the core, the plan or the driver). The toy here is the linear structure with
//! a counter on each question: the run must be the default one bit for bit, and each
//! question must have reached the toy (once for the plan, once for the factor, once per
//! step and once more per change of `h`).

use std::sync::Arc;
use std::sync::atomic::{AtomicUsize, Ordering};

use signorini::error::Error;
use signorini::integrators::step_matrix::{StepAnalysis, StepForm, StepMatrix};
use signorini::integrators::structure::{LinearStructure, StepData, StructureModel};
use signorini::integrators::{Problem, StepStats, build_problem};
use signorini::linalg::{LinearSolver, SparseMatrix};
use signorini::model::LinearSystem;
use signorini::scene::bar::BarScene;

/// Calls per question: analyse, factor, begin_step.
#[derive(Debug, Default)]
struct Calls([AtomicUsize; 3]);

/// The linear structure, counting what it is asked.
#[derive(Debug)]
struct Counting {
    inner: LinearStructure,
    calls: Arc<Calls>,
}

impl StructureModel for Counting {
    fn step_matrix_constant(&self) -> bool {
        true
    }
    fn analyse(&self, sys: &LinearSystem, form: StepForm, h: f64) -> Result<StepAnalysis, Error> {
        self.calls.0[0].fetch_add(1, Ordering::Relaxed);
        self.inner.analyse(sys, form, h)
    }
    fn factor(
        &mut self,
        sys: &LinearSystem,
        step: (StepForm, f64),
        initial: (&[f64], &[f64]),
        planned: Option<StepMatrix>,
    ) -> Result<Box<dyn LinearSolver>, Error> {
        self.calls.0[1].fetch_add(1, Ordering::Relaxed);
        self.inner.factor(sys, step, initial, planned)
    }
    fn tangent<'a>(&'a self, sys: &'a LinearSystem) -> &'a SparseMatrix {
        self.inner.tangent(sys)
    }
    fn begin_step(&mut self, cx: &mut StepData<'_>, stats: &mut StepStats) -> Result<bool, Error> {
        self.calls.0[2].fetch_add(1, Ordering::Relaxed);
        self.inner.begin_step(cx, stats)
    }
    fn describe(&self, sys: &LinearSystem, backend: &str, n: usize) -> String {
        format!("counting: {}", self.inner.describe(sys, backend, n))
    }
}

#[test]
fn a_structure_from_outside_the_crate_is_planned_built_and_stepped() {
    let bar = BarScene {
        elements: 50,
        ..BarScene::default()
    };
    let h = 4e-6;
    let steps = 40;
    let mut reference = bar
        .build()
        .unwrap()
        .into_integrator(&bar.scheme, h)
        .unwrap();
    let calls = Arc::new(Calls::default());
    let model = bar.build().unwrap();
    let toy = Counting {
        inner: LinearStructure::new(&model.problem.system),
        calls: calls.clone(),
    };
    let mut problem: Problem = model.problem.with_structure(Box::new(toy));
    let plan = problem.plan(&bar.scheme, h).unwrap();
    assert!(
        plan.describe().contains("tridiagonal"),
        "{}",
        plan.describe()
    );
    let mut integ = build_problem(&bar.scheme, problem, h).unwrap();
    assert!(integ.path().starts_with("counting: "), "{}", integ.path());
    for _ in 0..steps {
        reference.step().unwrap();
        integ.step().unwrap();
        assert_eq!(integ.state().q, reference.state().q);
        assert_eq!(integ.state().impulse, reference.state().impulse);
    }
    integ.set_dt(h / 2.0).unwrap();
    integ.step().unwrap();
    let n = |i: usize| calls.0[i].load(Ordering::Relaxed);
    // the plan's analysis, the build's factor (taking the planned matrix) and the one
    // for h/2, a free velocity per step
    assert_eq!((n(0), n(1), n(2)), (1, 2, steps + 1));
}
