//! Linear algebra of the bar: symmetric tridiagonal matrices ([`tridiag`]), their factorisations
//! ([`ldlt`]), the O(n) update kernel ([`update`]) and the CPU dispatch that runs kernels
//! compiled for AVX ([`dispatch`]); ∞-norms ([`norms`]) and the spectrum of `C` ([`spectrum`]).
//!
//! Bottom layer: imports nothing from the crate.

pub mod dispatch;
pub mod ldlt;
pub mod norms;
pub mod spectrum;
pub mod tridiag;
pub mod update;

pub use ldlt::{Ldlt, NotPositiveDefinite};
pub use norms::{max_abs, max_distance};
pub use tridiag::SymTridiag;
