//! The bar's certificate beyond the tables that [`crate::verify`] computes itself (the matrices,
//! the solve, the built-in scenes, the closed forms, the α-sweep):
//!
//! - [`stiff`], [`stiff_runs`]: the stiff and extreme case matrix (`verify --stiff`), every step
//!   solver at the corners of the bar's parameters; [`stiff`] says what is checked, [`stiff_runs`]
//!   runs the cases;
//! - [`roundoff`]: the rigid mode's round-off ("Round-off");
//! - [`mass_study`]: the mass variants side by side ("Mass variants");
//! - [`viscous_contact`]: the manufactured viscous contact's refinement study.
//!
//! The bar's moving obstacle is checked beside the plane's ([`crate::plane::moving`]), its
//! temperature in [`crate::thermal`], its step solvers against each other in [`crate::solvers`].

pub mod mass_study;
pub mod roundoff;
pub mod stiff;
pub mod stiff_runs;
pub mod viscous_contact;
