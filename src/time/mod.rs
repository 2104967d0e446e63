//! The time loop: the discretisation of a scene, the scheme stepped with a step solver, the
//! discrete energy balance of every step, and the run's outputs (summary, history, displacement).
//!
//! Imports every layer below it: [`crate::linalg`], [`crate::step`], [`crate::scene`], [`crate::bar`].

pub mod clock;
pub mod energy;
pub mod error;
#[cfg(feature = "npy")]
pub mod npy;
pub mod rhs;
pub mod run;
pub mod simulation;
pub mod summary;

pub use error::RunError;
pub use run::{run_in_memory, run_to_dir};
pub use simulation::{Simulation, StepRecord};
pub use summary::{ContactEpisode, Summary, Tracker};
