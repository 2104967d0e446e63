//! The bar: P1 elements on `[0, L]`, the consistent mass and stiffness matrices and their
//! variants ([`matrices`]), the discretisation of a scene (`discretisation`), the bar's
//! constraints and kernels as a body of the scheme (`body`; the right-hand side and the
//! energy sums, each with its optimised twin on the uniform mesh, in `kernels`), and the
//! closed-form solutions that serve as references ([`closed_form`]).
//!
//! Imports `crate::linalg`, [`crate::step`], [`crate::scene`] and [`crate::scheme`].

pub(crate) mod body;
pub mod closed_form;
pub(crate) mod discretisation;
pub(crate) mod kernels;
pub mod matrices;

pub use body::{BarBody, Kernels, Simulation};
pub use closed_form::ClosedForm;
pub use discretisation::{Constraint, Discretisation};
