//! The bar's per-step kernels, each plain kernel beside its optimised twin on a uniform mesh
//! (every bar mesh is uniform, so the twins run): the right-hand side ([`rhs`], [`rhs_fast`])
//! and the sums of the energy balance ([`energy`], [`energy_fast`]). A twin stays where a step
//! a user runs is at least 1.2x faster with it (benches/README.md, the twins table), and is
//! tested against its plain kernel.

pub mod energy;
pub mod energy_fast;
pub mod rhs;
pub mod rhs_fast;
