//! The input: a scene's TOML schema (the bar's, [`schema`], or the plane body's, [`plane`]),
//! its validation and the expressions it holds (initial data, loads, gaps), with
//! [`SceneError`] naming the field at fault.
//!
//! Imports [`crate::linalg`] and [`crate::step`] (solver settings).

pub mod error;
pub mod expr;
pub mod friction;
pub mod heat;
pub mod nodal;
pub mod output;
pub mod parser;
pub mod plane;
pub mod schema;
pub mod separation;
pub mod solver;
pub mod vecmath;

pub use error::SceneError;
pub use expr::Expression;
pub use output::*;
pub use plane::{AnyScene, PlaneScene, load_any};
pub use schema::*;
pub use solver::*;
