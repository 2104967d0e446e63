//! The one-dimensional model: the P1 mass and stiffness matrices of the bar and the closed-form
//! solutions that serve as references.
//!
//! Imports [`crate::linalg`], [`crate::step`] and [`crate::scene`].

pub mod closed_form;
pub mod discretisation;
pub mod matrices;

pub use closed_form::ClosedForm;
pub use discretisation::{Constraint, Discretisation};
