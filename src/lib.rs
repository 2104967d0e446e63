//! # viscobar
//!
//! A reference implementation of the time-stepping scheme of A. Petrov and M. Schatzman
//! ("On the numerical approximation of a viscoelastic problem with unilateral constraints",
//! talk, Lisboa 2009): the Kelvin–Voigt bar `u_tt − u_xx − α u_xxt = l` on `[0, L]` (P1) and the
//! plane-strain body (Q1), Signorini conditions at the bar's ends, under it, or on the body's
//! edges; the implicit three-level scheme (VI)_h, each step a constrained quadratic programme.
//!
//! Layers, imports pointing down this list only (`tests/layers.rs`): `linalg` (matrices,
//! factorisations, per-step kernels and their twins) → [`step`] (the step's solvers, their
//! audit) → [`scene`] (input) → [`scheme`] (the talk's scheme, for any body) → [`bar`] (P1,
//! closed forms) → [`thermal`] (the bar with a temperature) → [`plane`] (Q1, sparse Cholesky)
//! → [`output`] (runs and their files) → [`study`] (refinement, comparison, figures). The
//! certificate is the member crate `viscobar-certificate`. Use as a library: [`run_in_memory`]
//! runs a scene built in code (its doc, a tested example).
//!
//! Public: what a user calls (scenes, runs, each body's simulation, records and summaries, the
//! closed forms, the studies) and the seams a researcher extends ([`Body`], [`StepSolver`]).
//! The hidden module `internals` opens the rest to the certificate, tests and benches: not API.

pub mod bar;
#[doc(hidden)]
pub mod internals;
pub(crate) mod linalg;
pub mod output;
pub mod plane;
pub mod scene;
pub mod scheme;
pub mod step;
pub mod study;
pub mod thermal;

pub use bar::Simulation;
pub use output::{
    BarSimulation, ContactEpisode, Summary, run_in_memory, run_plane_in_memory, run_plane_to_dir,
    run_to_dir,
};
pub use plane::PlaneSimulation;
pub use scene::{AnyScene, PlaneScene, Scene, SceneError, SolverMethod};
pub use scheme::{Body, RunError, StepRecord};
pub use step::{StepFailure, StepSolver};
pub use thermal::ThermalSimulation;
