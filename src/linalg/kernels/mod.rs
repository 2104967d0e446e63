//! The per-step factorisations, each plain kernel beside its optimised twin: the tridiagonal
//! `LDLᵀ` ([`ldlt`]) and its twisted twin for the bar's solve ([`ldlt_fast`]); the
//! block-tridiagonal `LDLᵀ` of quasi-definite coupled systems of two fields ([`block_tridiag`])
//! and its twisted twin for the thermal step ([`block_tridiag_fast`]), checked in the tests
//! against a banded `LDLᵀ` of the same matrix (`banded`, test-only); the CPU dispatch that runs
//! the twins' streaming loops compiled for AVX ([`dispatch`]). A twin stays where a step a user
//! runs is at least 1.2x faster with it (benches/README.md, the twins table), and is tested
//! against its plain kernel.

#[cfg(test)]
pub(crate) mod banded;
pub mod block_tridiag;
pub mod block_tridiag_fast;
pub mod dispatch;
pub mod ldlt;
pub mod ldlt_fast;
