//! The bar: P1 elements on `[0, L]`, the consistent mass and stiffness matrices and their
//! variants ([`matrices`]), the discretisation of a scene ([`discretisation`]), the bar's
//! kernels and constraints as a body of the scheme ([`body`]; the right-hand side in [`rhs`],
//! the energy sums in [`energy`], their optimised twins on a uniform mesh in [`rhs_fast`] and
//! [`energy_fast`]), and the closed-form solutions that serve as references ([`closed_form`]).
//!
//! Imports [`crate::linalg`], [`crate::step`], [`crate::scene`] and [`crate::scheme`].

pub mod body;
pub mod closed_form;
pub mod discretisation;
pub mod energy;
pub mod energy_fast;
pub mod matrices;
pub mod rhs;
pub mod rhs_fast;

pub use body::{BarBody, Kernels, Simulation};
pub use closed_form::ClosedForm;
pub use discretisation::{Constraint, Discretisation};
