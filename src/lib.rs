//! # signorini
//!
//! Finite-element time integration of elastic structures with unilateral contact and
//! impact, following V. Acary, "Projected event-capturing time-stepping schemes for
//! nonsmooth mechanical systems with unilateral contact and Coulomb's friction",
//! CMAME 2013 (equation numbers in the docs refer to it).
//!
//! The data flow (DESIGN.md §1): a scene ([`scene`]) builds a model ([`model`]:
//! sparse `M`, `K`, `C`, `f`; [`contact`]: gaps `g(q)`, Jacobians `G(q)`, restitution),
//! an integrator ([`integrators`]) steps it with one of the paper's five schemes using
//! the one-step solvers of [`solvers`], and [`run`] drives the steps, collects the
//! statistics and writes [`io`] outputs; [`analytic`] holds closed-form references.
//!
//! ```
//! use signorini::scene::bar::BarScene;
//! let scene = BarScene { elements: 50, dt: 1e-6, t_end: 5e-4, ..BarScene::default() };
//! let result = signorini::app::run_bar(&scene, None, &mut signorini::run::Quiet).unwrap();
//! let c = result.summary.contact.as_ref().unwrap();
//! // 1 % from the analytic E S |v0| / c0 even on a 50-element bar
//! assert!((c.plateau_force / c.analytic_force - 1.0).abs() < 0.01);
//! ```

// Numerical kernels index several arrays in lockstep; iterator chains would hide that.
#![allow(clippy::needless_range_loop)]
#![deny(unsafe_code)]

pub mod analytic;
pub mod app;
pub mod assembly;
pub mod contact;
pub mod delassus;
pub mod error;
pub mod integrators;
pub mod io;
pub mod limits;
pub mod linalg;
pub mod model;
pub mod plot;
pub mod run;
pub mod scene;
pub mod solvers;
pub mod study;

pub use error::Error;
