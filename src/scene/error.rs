//! [`SceneError`]: a scene that cannot be run as written, kept apart from failures during a run
//! ([`crate::scheme::RunError`]) and from a step solver's own outcome ([`crate::step::StepFailure`]).

use crate::step::SettingsError;
use std::path::PathBuf;

/// A scene that cannot be run as written. Every variant names the offending field or item.
#[derive(Debug, thiserror::Error)]
pub enum SceneError {
    #[error("cannot read scene file {path}: {source}")]
    Read {
        path: PathBuf,
        source: std::io::Error,
    },
    #[error("unknown scene `{name}`: neither a built-in scene ({builtins}) nor an existing file")]
    UnknownScene { name: String, builtins: String },
    #[error("scene is not valid: {0}")]
    Syntax(String),
    #[error("`{field}` = {value}: {allowed}")]
    Invalid {
        field: String,
        value: String,
        allowed: String,
    },
    #[error("`{field}` = \"{text}\": {reason}")]
    Expression {
        field: String,
        text: String,
        reason: String,
    },
    #[error("`{field}` = \"{text}\" evaluates to {value} at x = {x}, t = {t}")]
    NonFinite {
        field: String,
        text: String,
        x: f64,
        t: f64,
        value: f64,
    },
    #[error("`{field}` = \"{text}\" evaluates to {value} at s = {s}, t = {t}")]
    NonFiniteEdge {
        field: String,
        text: String,
        s: f64,
        t: f64,
        value: f64,
    },
    #[error("`{field}` = \"{text}\" evaluates to {value} at x = {x}, y = {y}, t = {t}")]
    NonFinitePlane {
        field: String,
        text: String,
        x: f64,
        y: f64,
        t: f64,
        value: f64,
    },
    #[error(
        "inadmissible initial state: `{field}` gives u = {value} at node {node} (x = {x}), \
         below the obstacle -{gap} (`{gap_field}`)"
    )]
    Inadmissible {
        field: String,
        gap_field: String,
        node: usize,
        x: f64,
        value: f64,
        gap: f64,
    },
    #[error("--set {assignment}: {reason}")]
    Override { assignment: String, reason: String },
}

impl From<SettingsError> for SceneError {
    fn from(e: SettingsError) -> Self {
        SceneError::Invalid {
            field: format!("solver.{}", e.field),
            value: e.value,
            allowed: e.allowed.into(),
        }
    }
}

/// A field outside its range.
pub(crate) fn invalid(field: &str, value: f64, allowed: &str) -> SceneError {
    SceneError::Invalid {
        field: field.to_string(),
        value: value.to_string(),
        allowed: allowed.to_string(),
    }
}
