//! The input: a scene's TOML schema (the bar's, `schema`, or the plane body's, [`plane`]),
//! its validation and the expressions it holds (initial data, loads, gaps), with
//! [`SceneError`] naming the field at fault.
//!
//! Imports `crate::linalg` and [`crate::step`] (solver settings).

pub(crate) mod error;
pub(crate) mod expr;
pub(crate) mod friction;
pub mod heat;
pub(crate) mod nodal;
pub(crate) mod output;
pub(crate) mod parser;
pub mod plane;
pub mod plane_heat;
pub(crate) mod schema;
pub(crate) mod separation;
pub(crate) mod solver;
pub(crate) mod vecmath;

pub use error::SceneError;
pub use expr::Expression;
pub use output::*;
pub use plane::{AnyScene, PlaneScene, load_any};
pub use schema::*;
pub use solver::*;
