//! One time step's constrained quadratic programme and the solvers behind the [`StepSolver`]
//! seam, for every body: condensation onto the constraints with an exact LCP solve (any body),
//! enumeration over the bar's two ends and block pivoting for its obstacle (tridiagonal
//! kernels), penalty and OSQP; with Coulomb friction, Lemke's method on the condensed LCP and
//! OSQP's Tresca fixed point; with the independent audits of their answers. Which one serves a
//! scene's `[solver] method` on each body is the table of [`algorithm`].
//!
//! Imports only `crate::linalg`.

pub mod algorithm;
pub mod audit;
pub mod block_pivot;
pub mod condensed_lcp;
pub mod condensed_lemke;
pub mod end_enumeration;
pub mod end_penalty;
pub mod friction_audit;
pub mod lcp;
pub mod lemke;
pub mod osqp;
pub mod osqp_tresca;
mod pivot_sweeps;
pub mod pivoting;
pub mod report;
pub mod schur;
pub mod semismooth_penalty;
pub mod solver;

pub use algorithm::{Algorithm, Shape, SolverMethod, algorithm_for};
pub use block_pivot::BlockPivoting;
pub use condensed_lcp::CondensedLcp;
pub use condensed_lemke::CondensedLemke;
pub use end_enumeration::EndEnumeration;
pub use end_penalty::{EndPenalty, PenaltySettings};
pub use osqp::{Osqp, OsqpSettings};
pub use osqp_tresca::OsqpTresca;
pub use report::{
    AuditReport, OsqpStatus, SettingsError, SetupError, SolveInfo, SolverReport, StepFailure,
};
pub use semismooth_penalty::SemismoothPenalty;
pub use solver::{Constraints, Friction, StepSolver};
