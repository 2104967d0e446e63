//! Linear algebra of the bodies: symmetric tridiagonal matrices ([`tridiag`]) and the
//! per-step kernels with their optimised twins ([`kernels`]: the tridiagonal and the
//! block-tridiagonal `LDLᵀ`, each beside its twisted twin, and the CPU dispatch that runs
//! kernels compiled for AVX); sparse matrices on a CSR pattern ([`sparse`]) and their sparse
//! Cholesky factorisation ([`cholesky`], faer); the step matrix with its factorisation as the
//! solvers see it ([`system`]); ∞-norms ([`norms`]) and the spectrum of `C` ([`spectrum`]).
//!
//! Bottom layer: imports nothing from the crate.

pub mod cholesky;
pub mod kernels;
pub mod norms;
pub mod sparse;
pub mod spectrum;
pub mod system;
pub mod tridiag;

pub use kernels::ldlt::{Ldlt, NotPositiveDefinite};
pub use norms::{max_abs, max_distance};
pub use tridiag::SymTridiag;
