//! A run's outputs, through the same code for both bodies: `summary.json` (`summary`),
//! `history.csv` (`history`) and the profile file (`profiles`, `displacement.csv` or
//! `displacement.npy`) or the ParaView files (`vtk`), the text of their numbers (`text`),
//! written whole or not at all (`files`) by the run loop (`run`), or kept in memory
//! ([`memory`]).
//!
//! Imports every layer below it.

pub(crate) mod files;
pub(crate) mod history;
pub mod memory;
#[cfg(feature = "npy")]
pub(crate) mod npy;
pub(crate) mod profiles;
pub(crate) mod run;
pub(crate) mod summary;
pub(crate) mod text;
pub(crate) mod vtk;

pub use run::{
    BarSimulation, Certify, RunOptions, run_in_memory, run_plane_in_memory, run_plane_to_dir,
    run_plane_to_dir_with, run_thermal_in_memory, run_to_dir, run_to_dir_with,
};
pub use summary::{ContactEpisode, Iterations, Summary, TimeShares, Tracker};
pub use text::output_time;
