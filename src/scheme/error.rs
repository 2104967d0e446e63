//! [`RunError`]: a run, of either body, that could not be set up or finished, and how each
//! layer's set-up errors map onto it.

use crate::linalg::NotPositiveDefinite;
use crate::linalg::cholesky::FactorError;
use crate::scene::SceneError;
use crate::step::SetupError;
use crate::step::StepFailure;
use std::path::PathBuf;

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
    Matrix(#[from] NotPositiveDefinite),
    #[error("cannot factorise: {0}")]
    Factor(#[from] FactorError),
    #[error("solver `{solver}` cannot be set up: {reason}")]
    SolverSetup { solver: String, reason: String },
    /// A step broke the run's certificate ([`crate::scheme::certify`]).
    #[error("the run is not certified: {0}")]
    Uncertified(crate::scheme::CertificateFailure),
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

impl From<SetupError> for RunError {
    fn from(e: SetupError) -> Self {
        match e {
            SetupError::Matrix(m) => RunError::Matrix(m),
            SetupError::Settings(e) => RunError::Scene(e.into()),
            SetupError::Osqp(reason) => RunError::SolverSetup {
                solver: "osqp".into(),
                reason,
            },
            SetupError::Contact(reason) => RunError::SolverSetup {
                solver: "exact".into(),
                reason,
            },
            SetupError::TooManyBounds { solver, nodes } => RunError::Scene(SceneError::Invalid {
                field: "solver.method".into(),
                value: format!("\"{solver}\""),
                allowed: format!(
                    "the {solver} solver handles the two Signorini ends only; this scene constrains \
                     {nodes} nodes (use exact or osqp for an obstacle)"
                ),
            }),
        }
    }
}
