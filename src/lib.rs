//! # viscobar
//!
//! A reference implementation of the time-stepping scheme of A. Petrov and M. Schatzman
//! ("On the numerical approximation of a viscoelastic problem with unilateral constraints",
//! talk, Lisboa 2009): the Kelvin–Voigt bar `u_tt − u_xx − α u_xxt = l` on `[0, L]` (P1) and the
//! plane-strain body (Q1), Signorini conditions at the bar's ends, under it, or on the body's
//! edges; the implicit three-level scheme (VI)_h, each step a constrained quadratic programme.
//!
//! Layers, imports pointing down this list only (`tests/layers.rs`): [`linalg`] (tridiagonal
//! and sparse matrices, their factorisations) → [`step`] (the step problem's solvers and their
//! audit) → [`scene`] (input) → [`scheme`] (the talk's scheme, for any body) → [`bar`] (P1, its
//! kernels, closed forms) → [`plane`] (Q1, sparse Cholesky) → [`output`] (runs and their files,
//! both bodies) → [`study`] (refinement, comparison, mass variants, figures). The certificate
//! (VERIFICATION.md's tables, the tolerance registry) is the member crate `viscobar-certificate`.

//! # Use as a library
//!
//! Build a scene in code (or parse one with [`Scene::from_toml`], or take a built-in with
//! [`scene::load`]), run it, and read the contact intervals and the energy history. The bar
//! below moves at `v0 = 1` towards an obstacle `a0 = 0.1` under its left end (the `impact`
//! scene): contact starts at `t1 = a0 / v0` and lasts `2L`.
//!
//! ```
//! use viscobar::scene::{Bar, Condition, EndSpec, Initial, Mesh, Time};
//! use viscobar::{Scene, run_in_memory};
//!
//! let scene = Scene {
//!     description: None,
//!     bar: Bar { length: 1.0, viscosity: 0.0, matrices: Default::default(), mass: Default::default() },
//!     left: EndSpec::new(Condition::Signorini, Some(0.1)),
//!     right: EndSpec::new(Condition::Free, None),
//!     initial: Initial { displacement: "0".into(), velocity: "-1".into() },
//!     load: Default::default(),
//!     obstacle: None,
//!     heat: None,
//!     mesh: Mesh { elements: 100 },
//!     time: Time { step: 0.01, end: 3.0 },
//!     solver: Default::default(),
//!     output: Default::default(),
//! };
//! let (records, summary, _simulation) = run_in_memory("impact", &scene)?;
//!
//! // One contact episode at the left end: [t1, t1 + 2L] = [0.1, 2.1] up to a few steps (the
//! // contact-time error of P1 elements, VERIFICATION.md).
//! let left = &summary.contact_intervals["left"];
//! let within = |t: f64, exact: f64| (t - exact).abs() <= 3.0 * scene.time.step;
//! assert_eq!(left.len(), 1);
//! assert!(within(left[0][0], 0.1) && within(left[0][1], 2.1), "{left:?}");
//!
//! // The energy history: without viscosity or load, only contact can change the energy.
//! let energy: Vec<f64> = records.iter().map(|r| r.energy).collect();
//! assert_eq!(energy.len(), summary.steps);
//! assert!(energy.last().unwrap() <= &energy[0]);
//! # Ok::<(), viscobar::RunError>(())
//! ```
//!
//! A scene built in code is validated like a scene file: [`Simulation::new`] returns the same
//! [`SceneError`] (inside [`RunError::Scene`]) that the command line prints.

pub mod bar;
pub mod linalg;
pub mod output;
pub mod plane;
pub mod scene;
pub mod scheme;
pub mod step;
pub mod study;
pub mod thermal;

pub use bar::Simulation;
pub use output::{ContactEpisode, Summary, run_in_memory, run_to_dir};
pub use plane::PlaneSimulation;
pub use scene::{AnyScene, PlaneScene, Scene, SceneError, SolverMethod};
pub use scheme::{RunError, StepRecord};
pub use step::{StepFailure, StepSolver};
