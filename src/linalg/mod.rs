//! Linear algebra of the bar: symmetric tridiagonal matrices, their LDLᵀ factorisations and the
//! O(n) streaming kernels of a step, with the CPU dispatch that runs them compiled for AVX.
//!
//! Bottom layer: imports nothing from the crate.

pub mod dispatch;
pub mod norms;
pub mod spectrum;
pub mod tridiag;

pub use norms::{max_abs, max_distance};
pub use tridiag::{Ldlt, NotPositiveDefinite, SymTridiag};
