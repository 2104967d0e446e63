//! The OSQP step solver (B. Stellato, G. Banjac, P. Goulart, A. Bemporad, S. Boyd, "OSQP: an
//! operator splitting solver for quadratic programs", Math. Prog. Comp. 12, 2020), through the
//! `osqp` crate 0.6.3 (OSQP 0.6 with its bundled QDLDL), for either body.
//!
//! QP form: `minimise ½ zᵀPz + qᵀz  s.t.  l <= Az <= u` with `P = C` (its upper triangle, from
//! the body's [`SpdSystem`]), `q = −b`, `A` the rows `s_k e_{i_k}ᵀ`, `l = lo`, `u = `
//! [`OSQP_INFTY`]; OSQP's dual at an active lower bound is negative, so `r = −y`. Set up once
//! per run; each step updates `q` and `l` and warm-starts from the previous answer. Without
//! constraints `A` is `0 × n` and OSQP solves the unconstrained problem by its ADMM iteration.
//! Every answer reported solved is audited ([`crate::step::audit`]); another status (but
//! "solved inaccurate" with `accept_inaccurate`) or a failed audit is an error. Determinism:
//! single-threaded, and the rho adaptation interval fixed (OSQP's default adapts after a
//! fraction of the set-up *time*), so a run gives the same bits every time on a machine.

use crate::linalg::system::{Csc, SpdSystem, TridiagSystem};
use crate::linalg::tridiag::SymTridiag;
use crate::step::audit::{AUDIT_MARGIN, INACCURATE_FACTOR, KktAudit, Slack};
use crate::step::law::{Law, LawFamily};
use crate::step::solver::Constraints;
use crate::step::{
    OsqpStatus, SettingsError, SetupError, SolveInfo, SolverReport, StepFailure, StepSolver,
};
use osqp::{CscMatrix, Problem, Settings, Solution, Status};
use std::borrow::Cow;

/// OSQP's `eps_abs` and `eps_rel` unless set: tight enough that, polished, the answer agrees
/// with the exact solver to round-off on the talk's scenes (VERIFICATION.md, section "Step solvers").
pub const OSQP_DEFAULT_EPS: f64 = 1e-10;
/// OSQP's iteration limit unless set: far above what the talk's scenes need per step.
pub const OSQP_DEFAULT_MAX_ITER: u32 = 100_000;
/// Rho adaptation every 25 iterations unless set: OSQP 0.6's default (0 = tied to the setup
/// time) makes the iteration, hence the bits of the answer, depend on the machine's load.
pub const OSQP_DEFAULT_ADAPTIVE_RHO_INTERVAL: u32 = 25;

/// OSQP's infinity (`OSQP_INFTY` in constants.h): bounds at or beyond it count as absent.
/// `f64::INFINITY` must not be used: it breaks OSQP's infeasibility tests.
pub const OSQP_INFTY: f64 = 1e30;

/// The OSQP settings a scene can choose (defaults: the `OSQP_DEFAULT_*` constants).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct OsqpSettings {
    pub eps_abs: f64,
    pub eps_rel: f64,
    pub polish: bool,
    pub max_iter: u32,
    pub adaptive_rho_interval: u32,
    pub accept_inaccurate: bool,
}

impl Default for OsqpSettings {
    fn default() -> Self {
        Self {
            eps_abs: OSQP_DEFAULT_EPS,
            eps_rel: OSQP_DEFAULT_EPS,
            polish: true,
            max_iter: OSQP_DEFAULT_MAX_ITER,
            adaptive_rho_interval: OSQP_DEFAULT_ADAPTIVE_RHO_INTERVAL,
            accept_inaccurate: false,
        }
    }
}

impl OsqpSettings {
    /// Checks every field against its range; the error names the field.
    pub fn validate(&self) -> Result<(), SettingsError> {
        for (field, v) in [("eps_abs", self.eps_abs), ("eps_rel", self.eps_rel)] {
            if !(v.is_finite() && v >= 0.0) {
                return Err(SettingsError::new(field, v, "must be a finite number >= 0"));
            }
        }
        if self.eps_abs == 0.0 && self.eps_rel == 0.0 {
            return Err(SettingsError::new(
                "eps_abs",
                self.eps_abs,
                "eps_abs and eps_rel cannot both be 0 (OSQP would never stop)",
            ));
        }
        if self.max_iter == 0 {
            return Err(SettingsError::new("max_iter", 0, "must be >= 1"));
        }
        if self.adaptive_rho_interval == 0 {
            return Err(SettingsError::new(
                "adaptive_rho_interval",
                0,
                "must be >= 1 (0 selects OSQP's time-based interval, which makes runs differ)",
            ));
        }
        Ok(())
    }

    pub(crate) fn to_osqp(self) -> Settings {
        Settings::default()
            .verbose(false)
            .eps_abs(self.eps_abs)
            .eps_rel(self.eps_rel)
            .max_iter(self.max_iter)
            .polish(self.polish)
            .warm_start(true)
            .adaptive_rho_interval(Some(self.adaptive_rho_interval))
    }
}

/// OSQP on the step problem, set up once per run, audited every step.
pub struct Osqp<S: SpdSystem = TridiagSystem> {
    problem: Problem,
    settings: OsqpSettings,
    k: usize,
    /// `q = −b`, and the previous answer for the warm start.
    q: Vec<f64>,
    x_prev: Vec<f64>,
    y_prev: Vec<f64>,
    /// `C` with its factorisation, for the audit.
    system: S,
    audit: KktAudit,
    inaccurate_steps: u64,
}

impl<S: SpdSystem> std::fmt::Debug for Osqp<S> {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("Osqp")
            .field("settings", &self.settings)
            .field("constraints", &self.k)
            .finish_non_exhaustive()
    }
}

pub(crate) fn osqp_csc(m: Csc) -> CscMatrix<'static> {
    CscMatrix {
        nrows: m.nrows,
        ncols: m.ncols,
        indptr: Cow::Owned(m.indptr),
        indices: Cow::Owned(m.indices),
        data: Cow::Owned(m.data),
    }
}

/// The `m × n` matrix `A` with row `k` equal to `s_k e_{i_k}ᵀ`, in CSC (rows ascending within
/// a column).
fn constraint_csc(n: usize, constraints: &Constraints) -> CscMatrix<'static> {
    let mut by_column: Vec<(usize, usize)> = (constraints.unknowns.iter().copied())
        .enumerate()
        .map(|(k, i)| (i, k))
        .collect();
    by_column.sort_unstable();
    let mut indptr = Vec::with_capacity(n + 1);
    let (mut indices, mut data) = (Vec::new(), Vec::new());
    let mut next = by_column.iter().peekable();
    indptr.push(0);
    for col in 0..n {
        while let Some(&(_, k)) = next.next_if(|(i, _)| *i == col) {
            indices.push(k);
            data.push(constraints.directions[k]);
        }
        indptr.push(indices.len());
    }
    osqp_csc(Csc {
        nrows: constraints.len(),
        ncols: n,
        indptr,
        indices,
        data,
    })
}

/// The OSQP problem of one step exactly as [`Osqp`] builds it (same matrices and
/// settings), with `q = −b` and lower bounds `lower`, but without the audit: for the tests and
/// studies that examine OSQP's own answer.
pub fn raw_problem(
    c: &SymTridiag,
    nodes: &[usize],
    b: &[f64],
    lower: &[f64],
    settings: OsqpSettings,
) -> Result<Problem, SetupError> {
    let q: Vec<f64> = b.iter().map(|v| -v).collect();
    let u = vec![OSQP_INFTY; nodes.len()];
    let system = TridiagSystem::new(c)?;
    Problem::new(
        osqp_csc(system.upper_triangle()),
        &q,
        constraint_csc(c.dim(), &Constraints::lower_bounds(nodes)),
        lower,
        &u,
        &settings.to_osqp(),
    )
    .map_err(|e| SetupError::Osqp(e.to_string()))
}

/// An OSQP solver's identity allowance: `½ ρ·δ` with the audited stationarity `ρ` at its worst
/// `ratio` to the audit's tolerance `AUDIT_MARGIN · eps_rel` (`INACCURATE_FACTOR` more once an
/// inaccurate answer was taken, `inaccurate_steps > 0`).
pub(crate) fn identity_allowance(ratio: f64, inaccurate_steps: u64, eps_rel: f64) -> f64 {
    let factor = if inaccurate_steps > 0 {
        INACCURATE_FACTOR
    } else {
        1.0
    };
    ratio * AUDIT_MARGIN * factor * eps_rel
}

/// OSQP's answer and whether it was only `SolvedInaccurate` (accepted when
/// `accept_inaccurate`); any other status is a failure naming it, as OSQP's C library spells
/// it, and the iterations run.
pub(crate) fn accepted(
    status: Status<'_>,
    accept_inaccurate: bool,
) -> Result<(Solution<'_>, bool), StepFailure> {
    let iterations = status.iter();
    let status = match status {
        Status::Solved(s) => return Ok((s, false)),
        Status::SolvedInaccurate(s) if accept_inaccurate => return Ok((s, true)),
        Status::SolvedInaccurate(_) => OsqpStatus::SolvedInaccurate,
        Status::MaxIterationsReached(_) => OsqpStatus::MaxIterationsReached,
        Status::TimeLimitReached(_) => OsqpStatus::TimeLimitReached,
        Status::PrimalInfeasible(_) => OsqpStatus::PrimalInfeasible,
        Status::PrimalInfeasibleInaccurate(_) => OsqpStatus::PrimalInfeasibleInaccurate,
        Status::DualInfeasible(_) => OsqpStatus::DualInfeasible,
        Status::DualInfeasibleInaccurate(_) => OsqpStatus::DualInfeasibleInaccurate,
        Status::NonConvex(_) => OsqpStatus::NonConvex,
        _ => OsqpStatus::Unknown,
    };
    Err(StepFailure::Osqp { status, iterations })
}

impl Osqp<TridiagSystem> {
    /// Sets OSQP up for the tridiagonal `C` and lower bounds at the unknowns `nodes`.
    pub fn new(
        c: &SymTridiag,
        nodes: &[usize],
        settings: OsqpSettings,
    ) -> Result<Self, SetupError> {
        settings.validate()?;
        Self::with_system(
            TridiagSystem::new(c)?,
            Constraints::lower_bounds(nodes),
            settings,
        )
    }
}

impl<S: SpdSystem> Osqp<S> {
    /// Sets OSQP up for `C` (with its factorisation, for the audit) and the constraints.
    pub fn with_system(
        mut system: S,
        constraints: Constraints,
        settings: OsqpSettings,
    ) -> Result<Self, SetupError> {
        settings.validate()?;
        let n = system.dim();
        let k = constraints.len();
        if let Some(&bad) = constraints.unknowns.iter().find(|&&j| j >= n) {
            return Err(SetupError::Osqp(format!(
                "constrained unknown {bad} outside 0..{n}"
            )));
        }
        let q = vec![0.0; n];
        let l = vec![-OSQP_INFTY; k];
        let u = vec![OSQP_INFTY; k];
        let problem = Problem::new(
            osqp_csc(system.upper_triangle()),
            &q,
            constraint_csc(n, &constraints),
            &l,
            &u,
            &settings.to_osqp(),
        )
        .map_err(|e| SetupError::Osqp(e.to_string()))?;
        Ok(Self {
            problem,
            settings,
            k,
            q,
            x_prev: vec![0.0; n],
            y_prev: vec![0.0; k],
            audit: KktAudit::new(&mut system, &constraints, LawFamily::Signorini),
            system,
            inaccurate_steps: 0,
        })
    }

    pub fn settings(&self) -> OsqpSettings {
        self.settings
    }
}

impl<S: SpdSystem> StepSolver for Osqp<S> {
    fn name(&self) -> &'static str {
        "osqp"
    }

    fn solve(
        &mut self,
        rhs: &[f64],
        lower: &[f64],
        z: &mut [f64],
        reactions: &mut [f64],
    ) -> Result<SolveInfo, StepFailure> {
        let k = self.k;
        let lower = &lower[..k];
        // OSQP takes non-finite data silently (and panics in the crate on l > u).
        if !(rhs.iter().all(|v| v.is_finite())
            && lower.iter().all(|v| v.is_finite() && v.abs() < OSQP_INFTY))
        {
            return Err(StepFailure::NonFinite);
        }
        for (qi, bi) in self.q.iter_mut().zip(rhs) {
            *qi = -bi;
        }
        self.problem.update_lin_cost(&self.q);
        if k > 0 {
            self.problem.update_lower_bound(lower);
        }
        self.problem.warm_start(&self.x_prev, &self.y_prev);
        let status = self.problem.solve();
        let iterations = status.iter();
        let (solution, inaccurate) = accepted(status, self.settings.accept_inaccurate)?;
        z.copy_from_slice(solution.x());
        let y = solution.y();
        for j in 0..k {
            // 0.0 − y rather than −y: no −0.0 reactions in the outputs.
            reactions[j] = 0.0 - y[j];
        }
        let factor = if inaccurate { INACCURATE_FACTOR } else { 1.0 };
        let slack = Slack::Osqp {
            eps_abs: factor * self.settings.eps_abs,
            eps_rel: factor * self.settings.eps_rel,
        };
        let law = Law::Signorini;
        (self.audit).check(&mut self.system, law, slack, rhs, lower, z, reactions)?;
        self.x_prev.copy_from_slice(z);
        self.y_prev.copy_from_slice(y);
        if inaccurate {
            self.inaccurate_steps += 1;
        }
        Ok(SolveInfo { iterations })
    }

    fn report(&self) -> Option<SolverReport> {
        Some(SolverReport {
            audit: self.audit.report().clone(),
            inaccurate_steps: Some(self.inaccurate_steps),
        })
    }

    fn identity_allowance(&self) -> f64 {
        let ratio = self.audit.report().stationarity.max_over_tolerance;
        identity_allowance(ratio, self.inaccurate_steps, self.settings.eps_rel)
    }
}
