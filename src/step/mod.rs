//! One time step's constrained quadratic programme and the solvers behind the [`StepSolver`]
//! seam, for every body: condensation onto the constraints with an exact LCP solve (any body),
//! enumeration over the bar's two ends and block pivoting for its obstacle (tridiagonal
//! kernels), penalty and OSQP; with Coulomb friction, Lemke's method on the condensed LCP and
//! OSQP's Tresca fixed point; the contact laws, and the independent audit of every answer
//! against its law.
//!
//! Imports only [`crate::linalg`].

pub mod audit;
pub mod block_pivot;
pub mod condensed;
pub mod exact;
pub mod friction;
pub mod law;
pub mod lcp;
pub mod lemke;
pub mod osqp;
pub mod penalty;
mod pivot_sweeps;
pub mod report;
pub mod schur;
pub mod solver;
pub mod sparse_penalty;
pub mod tresca;

pub use block_pivot::BlockPivotSolver;
pub use condensed::CondensedSolver;
pub use exact::ExactSolver;
pub use friction::FrictionalSolver;
pub use osqp::{OsqpSettings, OsqpSolver};
pub use penalty::{PenaltySettings, PenaltySolver};
pub use report::{
    AuditReport, OsqpStatus, SettingsError, SetupError, SolveInfo, SolverReport, StepFailure,
};
pub use solver::{Constraints, Friction, StepSolver};
pub use sparse_penalty::SparsePenaltySolver;
pub use tresca::TrescaSolver;
