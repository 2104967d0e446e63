//! Error types. Bad input ([`SceneError`]) is kept apart from failures during a run
//! ([`RunError`]) and from a step solver's own outcome ([`crate::solver::StepFailure`]).

use crate::solver::StepFailure;
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
    #[error("`{field}` = \"{text}\" cannot be used: {reason}")]
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

/// A run that started but could not finish.
#[derive(Debug, thiserror::Error)]
pub enum RunError {
    #[error(transparent)]
    Scene(#[from] SceneError),
    #[error("step {step} (t = {time}): solver `{solver}` failed: {failure}")]
    Step {
        step: usize,
        time: f64,
        solver: String,
        failure: StepFailure,
    },
    #[error("the step matrix C is not positive definite ({0}); check dt, viscosity and matrices")]
    Matrix(#[from] crate::tridiag::NotPositiveDefinite),
    #[error("solver `{solver}` cannot be set up: {reason}")]
    SolverSetup { solver: String, reason: String },
    #[error("cannot write {path}: {source}")]
    Write {
        path: PathBuf,
        source: std::io::Error,
    },
}

impl RunError {
    /// Process exit code: 2 for bad input, 1 for a failure during the run.
    pub fn exit_code(&self) -> i32 {
        match self {
            RunError::Scene(_) => 2,
            _ => 1,
        }
    }
}
