//! Linear algebra of the bodies: symmetric tridiagonal matrices ([`tridiag`]) and their
//! factorisation ([`ldlt`], with its optimised twin for the per-step solve, [`ldlt_fast`]),
//! sparse matrices on a CSR pattern ([`sparse`]) and their sparse Cholesky factorisation
//! ([`cholesky`], faer); the step matrix with its factorisation as the solvers see it
//! ([`system`]); the CPU dispatch that runs kernels compiled for AVX ([`dispatch`]); ∞-norms
//! ([`norms`]) and the spectrum of `C` ([`spectrum`]); quasi-definite coupled systems of two
//! fields: block-tridiagonal with their block `LDLᵀ` ([`block_tridiag`], with its twisted twin
//! for the thermal step, [`block_tridiag_fast`]), checked in the tests against a banded `LDLᵀ`
//! of the same matrix (`banded`, test-only).
//!
//! Bottom layer: imports nothing from the crate.

#[cfg(test)]
pub(crate) mod banded;
pub mod block_tridiag;
pub mod block_tridiag_fast;
pub mod cholesky;
pub mod dispatch;
pub mod ldlt;
pub mod ldlt_fast;
pub mod norms;
pub mod sparse;
pub mod spectrum;
pub mod system;
pub mod tridiag;

pub use ldlt::{Ldlt, NotPositiveDefinite};
pub use norms::{max_abs, max_distance};
pub use tridiag::SymTridiag;
