//! The input: a scene's TOML schema, its validation and the expressions it holds (initial data,
//! loads, gaps), with [`SceneError`] naming the field at fault.
//!
//! Imports [`crate::linalg`] and [`crate::step`] (solver settings).

pub mod error;
pub mod expr;
pub mod nodal;
pub mod schema;
pub mod separation;

pub use error::SceneError;
pub use expr::Expression;
pub use schema::*;
