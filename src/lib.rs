//! # viscobar
//!
//! A reference implementation of the time-stepping scheme of A. Petrov and M. Schatzman
//! ("On the numerical approximation of a viscoelastic problem with unilateral constraints",
//! talk, Lisboa 2009) for the Kelvin–Voigt bar on `[0, L]`:
//!
//! ```text
//!   u_tt − u_xx − α u_xxt = l,   s = u_x + α u_xt,
//!   0 <= u(0) + a_0 ⊥ −s(0) >= 0,   0 <= u(L) + a_L ⊥ s(L) >= 0   (or free, or clamped ends),
//! ```
//!
//! discretised with P1 elements in space and the implicit three-level scheme (VI)_h in time,
//! each step a bound-constrained quadratic programme solved exactly.
//!
//! Modules, one concept each: [`tridiag`] (banded kernels), [`matrices`] (M and R),
//! [`scene`] (input), [`expr`] (expressions), [`solver`] (the step-solver seam), [`exact`] (the
//! exact enumeration), [`osqp_solver`] (OSQP, Stellato et al. 2020) and [`penalty`] (the talk's
//! penalised problem (PP)), [`audit`] (the independent optimality check of their answers),
//! [`oracle`] (a dense brute-force reference for tests), [`simulation`] (the time stepper and
//! energy balance), [`closed_form`] (exact solutions), [`run`] (outputs).

pub mod active_set;
pub mod agreement;
pub mod audit;
pub mod closed_form;
pub mod compare;
pub mod converge;
pub mod dispatch;
pub mod error;
pub mod exact;
pub mod expr;
pub mod figures;
pub mod matrices;
pub mod oracle;
pub mod osqp_solver;
pub mod penalty;
pub mod run;
pub mod scene;
pub mod simulation;
pub mod solver;
pub mod spectrum;
pub mod stiff;
pub mod study;
pub mod tridiag;
pub mod verify;

pub use error::{RunError, SceneError};
pub use scene::Scene;
pub use simulation::Simulation;
