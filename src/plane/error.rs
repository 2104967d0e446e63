//! [`PlaneError`]: a plane run that could not be set up or finished.

use crate::plane::factor::FactorError;
use crate::scene::SceneError;
use std::path::PathBuf;

/// A plane run that could not be set up or finished.
#[derive(Debug, thiserror::Error)]
pub enum PlaneError {
    #[error(transparent)]
    Scene(#[from] SceneError),
    #[error("cannot factorise: {0}")]
    Factor(#[from] FactorError),
    #[error("step {step}: the contact problem failed: {reason}")]
    Contact { step: usize, reason: String },
    #[error("step {step} (t = {time}): the state is not finite")]
    NonFinite { step: usize, time: f64 },
    #[error("cannot write {path}: {source}")]
    Write {
        path: PathBuf,
        source: std::io::Error,
    },
}

impl PlaneError {
    /// Process exit code: 2 for bad input, 1 for a failure during the run.
    pub fn exit_code(&self) -> i32 {
        match self {
            PlaneError::Scene(_) => 2,
            _ => 1,
        }
    }
}
