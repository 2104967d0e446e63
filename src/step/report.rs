//! What a step solver reports: the outcome of one solve ([`SolveInfo`]) or why it produced
//! no trustworthy answer ([`StepFailure`]), and its run-level statistics ([`SolverReport`],
//! with the worst residuals of the independent audit, [`AuditReport`]).

use crate::linalg::NotPositiveDefinite;
use serde::Serialize;

/// OSQP's status when it is not "solved" (OSQP 0.6, `constants.h`); "solved inaccurate" is
/// one only when the scene does not accept it.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum OsqpStatus {
    /// Both residuals met only with the tolerances multiplied by 10.
    SolvedInaccurate,
    /// `max_iter` iterations without meeting the tolerances.
    MaxIterationsReached,
    /// The time limit was reached (never set by this crate).
    TimeLimitReached,
    /// A certificate of primal infeasibility (impossible for the step QP: a sign of bad data).
    PrimalInfeasible,
    /// Primal infeasibility to the relaxed tolerances.
    PrimalInfeasibleInaccurate,
    /// A certificate of dual infeasibility (impossible with `C` positive definite).
    DualInfeasible,
    /// Dual infeasibility to the relaxed tolerances.
    DualInfeasibleInaccurate,
    /// OSQP found `P` not positive semidefinite.
    NonConvex,
    /// A status this crate does not know.
    Unknown,
}

impl OsqpStatus {
    /// What the user can do about it, where the scene has a key for that.
    fn hint(self) -> &'static str {
        match self {
            OsqpStatus::SolvedInaccurate => " (solver.accept_inaccurate = true accepts it)",
            _ => "",
        }
    }
}

impl std::fmt::Display for OsqpStatus {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(match self {
            OsqpStatus::SolvedInaccurate => "solved inaccurate",
            OsqpStatus::MaxIterationsReached => "maximum iterations reached",
            OsqpStatus::TimeLimitReached => "run time limit reached",
            OsqpStatus::PrimalInfeasible => "primal infeasible",
            OsqpStatus::PrimalInfeasibleInaccurate => "primal infeasible inaccurate",
            OsqpStatus::DualInfeasible => "dual infeasible",
            OsqpStatus::DualInfeasibleInaccurate => "dual infeasible inaccurate",
            OsqpStatus::NonConvex => "problem non convex",
            OsqpStatus::Unknown => "unknown status",
        })
    }
}

/// Outcome statistics of one successful solve.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct SolveInfo {
    /// Iterations (active sets tried, Newton steps, ADMM iterations...), solver-specific.
    pub iterations: u32,
}

/// Run-level statistics a solver keeps about its own answers, for `summary.json`. Solvers that
/// audit their answers (see [`crate::step::audit`]) report the worst residuals seen.
#[derive(Clone, Debug, Default, PartialEq, serde::Serialize)]
pub struct SolverReport {
    /// Worst optimality residuals over all steps, each with its ratio to its tolerance.
    pub audit: AuditReport,
    /// Steps accepted although OSQP reported "solved inaccurate" (`accept_inaccurate = true`);
    /// `None` for solvers without that notion.
    pub inaccurate_steps: Option<u64>,
}

/// Why a step solver produced no trustworthy answer.
#[derive(Clone, Debug, PartialEq, thiserror::Error)]
pub enum StepFailure {
    #[error("non-finite value in the solution (right-hand side or data overflowed)")]
    NonFinite,
    /// OSQP stopped without an answer it may return.
    #[error("solver status: OSQP returned `{status}` after {iterations} iterations{}", status.hint())]
    Osqp { status: OsqpStatus, iterations: u32 },
    /// An iterative exact method did not terminate within its iteration limit (which its
    /// finite termination proof makes unreachable; kept as a guard).
    #[error("solver status: active-set iteration did not terminate in {iterations} iterations")]
    IterationLimit { iterations: u32 },
    /// The step's matrix, made when the run first met its state, could not be set up.
    #[error("setting up the step's matrix failed: {0}")]
    Setup(String),
    /// The solver reported success but its answer fails an optimality condition checked
    /// independently by [`crate::step::audit::KktAudit`].
    #[error("audit failed: {what} = {value:e} exceeds its tolerance {tolerance:e}")]
    AuditFailed {
        what: &'static str,
        value: f64,
        tolerance: f64,
    },
    /// The frictional step's complementarity problem was not solved (Lemke's method).
    #[error("solver status: {0}")]
    Lemke(#[from] crate::step::lemke::LemkeError),
    /// The fixed point of Tresca problems (OSQP with friction) did not settle.
    #[error(
        "solver status: the fixed point of Tresca problems did not converge in {iterations} \
         iterations (last relative change of the normal reactions {change:e})"
    )]
    FixedPoint { iterations: u32, change: f64 },
}

/// The worst value of one audited quantity over a run, and its worst ratio to its tolerance
/// (the audit fails when the ratio exceeds 1).
#[derive(Clone, Copy, Debug, Default, PartialEq, Serialize)]
pub struct Worst {
    pub max: f64,
    pub max_over_tolerance: f64,
}

impl Worst {
    pub(crate) fn observe(&mut self, value: f64, tolerance: f64) {
        self.max = self.max.max(value);
        let ratio = if tolerance > 0.0 {
            value / tolerance
        } else if value > 0.0 {
            f64::INFINITY
        } else {
            0.0
        };
        self.max_over_tolerance = self.max_over_tolerance.max(ratio);
    }
}

/// The worst audit residuals of a run (`summary.json`, field `audit`). Checks that do not apply
/// to the law are absent: primal feasibility and complementarity for the penalty law, the
/// penalty law for Signorini.
#[derive(Clone, Debug, Default, PartialEq, Serialize)]
pub struct AuditReport {
    /// Steps audited.
    pub steps: u64,
    /// `max_j (lo_j − z_j)⁺`, displacement.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub primal_violation: Option<Worst>,
    /// `max_j (−r_j)⁺`, force.
    pub negative_reaction: Worst,
    /// `max_j |r_j (z_j − lo_j)|`, force × displacement.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub complementarity: Option<Worst>,
    /// `max_j |ε r_j − max(0, lo_j − z_j)|`, displacement.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub penalty_law: Option<Worst>,
    /// `‖Cz − b − Σ r_j e_j‖_∞`, force.
    pub stationarity: Worst,
    /// `‖C⁻¹(Cz − b − Σ r_j e_j)‖_∞`, displacement.
    pub stationarity_displacement: Worst,
    /// Friction: `max_j (|r_T,j| − μ_j r_N,j)⁺`, force (the Coulomb cone).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub friction_cone: Option<Worst>,
    /// Friction: `max_j |μ_j r_N,j |δ_j| + r_T,j δ_j|` (`δ` the central slip), force ×
    /// displacement: 0 when `r_T = −μ r_N sign δ` wherever `δ ≠ 0`.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub slip_law: Option<Worst>,
}

/// Why a step solver could not be set up: bad input, as opposed to a [`StepFailure`] during a
/// run.
#[derive(Debug, thiserror::Error)]
pub enum SetupError {
    /// The step matrix is not numerically positive definite.
    #[error(transparent)]
    Matrix(#[from] NotPositiveDefinite),
    /// A setting outside its range.
    #[error(transparent)]
    Settings(#[from] SettingsError),
    /// More constrained nodes than the solver handles (the penalty solver: the two ends).
    #[error(
        "the {solver} solver handles the two Signorini ends only, not {nodes} constrained nodes"
    )]
    TooManyBounds { solver: &'static str, nodes: usize },
    /// OSQP refused the problem; its own message.
    #[error("{0}")]
    Osqp(String),
    /// The condensed contact matrix `S = E C⁻¹ Eᵀ` could not be factorised.
    #[error("the contact problem cannot be set up: {0}")]
    Contact(String),
}

/// A solver setting outside its range, named by its key in the scene's `[solver]` table
/// (Clarabel's `SettingsError::BadFieldValue`).
#[derive(Clone, Debug, PartialEq, thiserror::Error)]
#[error("`solver.{field}` = {value}: {allowed}")]
pub struct SettingsError {
    /// The key in `[solver]`.
    pub field: &'static str,
    /// The value given, as text.
    pub value: String,
    /// What is allowed.
    pub allowed: &'static str,
}

impl SettingsError {
    pub(crate) fn new(field: &'static str, value: impl ToString, allowed: &'static str) -> Self {
        Self {
            field,
            value: value.to_string(),
            allowed,
        }
    }
}
