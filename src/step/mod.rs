//! One time step's constrained quadratic programme and the solvers behind the [`StepSolver`]
//! seam, for every body: condensation onto the constraints with an exact LCP solve (any body),
//! enumeration over the bar's two ends and block pivoting for its obstacle (tridiagonal
//! kernels), penalty and OSQP; with Coulomb friction, Lemke's method on the condensed LCP and
//! OSQP's Tresca fixed point; the contact laws, and the independent audit of every answer
//! against its law. Which one serves a scene's `[solver] method` on each body is the table of
//! [`algorithm`].
//!
//! Imports only `crate::linalg`.

pub mod algorithm;
pub mod audit;
pub(crate) mod block_pivot;
pub(crate) mod condensed_lcp;
pub(crate) mod condensed_lemke;
pub(crate) mod end_enumeration;
pub(crate) mod end_penalty;
pub mod law;
pub(crate) mod lcp;
pub(crate) mod lemke;
pub(crate) mod osqp;
pub(crate) mod osqp_tresca;
mod pivot_sweeps;
pub(crate) mod pivoting;
pub mod report;
pub(crate) mod schur;
pub(crate) mod semismooth_penalty;
pub mod solver;

pub use algorithm::{Algorithm, Shape, SolverMethod, algorithm_for};
pub use end_penalty::PenaltySettings;
pub use law::{Law, LawFamily, Slip};
pub use osqp::OsqpSettings;
pub use report::{
    AuditReport, OsqpStatus, SettingsError, SetupError, SolveInfo, SolverReport, StepFailure,
};
pub use solver::{Constraints, Friction, StepSolver};

pub(crate) use block_pivot::BlockPivoting;
pub(crate) use condensed_lcp::CondensedLcp;
pub(crate) use condensed_lemke::CondensedLemke;
pub(crate) use end_enumeration::EndEnumeration;
pub(crate) use end_penalty::EndPenalty;
pub(crate) use osqp::Osqp;
pub(crate) use osqp_tresca::OsqpTresca;
pub(crate) use semismooth_penalty::SemismoothPenalty;
