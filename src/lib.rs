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
//! Layers, each a folder whose module doc says what it owns; imports point down this list only
//! (`tests/layers.rs` checks it):
//! [`linalg`] (tridiagonal kernels) → [`step`] (the step solvers and their audit) →
//! [`scene`] (input) → [`bar`] (matrices, closed forms) → [`time`] (the time loop, energy
//! balance and outputs) → [`study`] (the verification studies).

pub mod bar;
pub mod linalg;
pub mod scene;
pub mod step;
pub mod study;
pub mod time;

pub use scene::{Scene, SceneError};
pub use time::{RunError, Simulation};
