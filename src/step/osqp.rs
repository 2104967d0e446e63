//! The OSQP step solver: the step problem handed to OSQP (B. Stellato, G. Banjac, P. Goulart,
//! A. Bemporad, S. Boyd, "OSQP: an operator splitting solver for quadratic programs", Math.
//! Prog. Comp. 12, 2020), through the `osqp` crate 0.6.3 (OSQP 0.6 with its bundled QDLDL).
//!
//! QP form: `minimise ½ zᵀPz + qᵀz  s.t.  l <= Az <= u` with `P = C` (upper triangle, built
//! directly in CSC from the tridiagonal), `q = −b`, `A` the rows selecting the constrained
//! nodes, `l = lo` (it moves every step: `lo = −a − u^n`) and `u = `[`OSQP_INFTY`]. OSQP is set
//! up once per run; each step updates `q` and `l` and warm-starts from the previous step's
//! answer, which is close since the increment varies smoothly in time. With no constrained node
//! `A` is `0 × n`: OSQP accepts it (checked in tests) and solves the unconstrained problem by
//! its ADMM iteration like any other, so the `osqp` method still uses OSQP there.
//!
//! OSQP's dual `y` is negative at an active lower bound, so the reaction is `r = −y`.
//!
//! Every answer OSQP reports as solved is audited ([`crate::step::audit`]); a status other than
//! "solved" (or "solved inaccurate" with `accept_inaccurate`) or a failed audit is an error.
//!
//! Determinism: OSQP runs single-threaded, and the rho adaptation interval is fixed (OSQP's
//! default adapts after a fraction of the set-up *time*), so a run gives the same bits every
//! time on a given machine and build.

use crate::linalg::tridiag::SymTridiag;
use crate::step::audit::{INACCURATE_FACTOR, KktAudit, Law};
use crate::step::{
    OsqpStatus, SettingsError, SetupError, SolveInfo, SolverReport, StepFailure, StepSolver,
};
use osqp::{CscMatrix, Problem, Settings, Status};
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

    fn to_osqp(self) -> Settings {
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
pub struct OsqpSolver {
    problem: Problem,
    settings: OsqpSettings,
    k: usize,
    /// `q = −b`, and the previous answer for the warm start.
    q: Vec<f64>,
    x_prev: Vec<f64>,
    y_prev: Vec<f64>,
    audit: KktAudit,
    inaccurate_steps: u64,
}

impl std::fmt::Debug for OsqpSolver {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("OsqpSolver")
            .field("settings", &self.settings)
            .field("constraints", &self.k)
            .finish_non_exhaustive()
    }
}

/// `C`'s upper triangle in CSC: column `j` holds `C[j−1][j]` (for `j > 0`) and `C[j][j]`.
fn upper_csc(c: &SymTridiag) -> CscMatrix<'static> {
    let n = c.dim();
    let mut indptr = Vec::with_capacity(n + 1);
    let mut indices = Vec::with_capacity(2 * n);
    let mut data = Vec::with_capacity(2 * n);
    indptr.push(0);
    for j in 0..n {
        if j > 0 {
            indices.push(j - 1);
            data.push(c.off[j - 1]);
        }
        indices.push(j);
        data.push(c.diag[j]);
        indptr.push(indices.len());
    }
    CscMatrix {
        nrows: n,
        ncols: n,
        indptr: Cow::Owned(indptr),
        indices: Cow::Owned(indices),
        data: Cow::Owned(data),
    }
}

/// The `k × n` selection `A e_{nodes[j]} = e_j`, in CSC (rows ascending within a column).
fn selection_csc(n: usize, nodes: &[usize]) -> CscMatrix<'static> {
    let mut indptr = Vec::with_capacity(n + 1);
    let mut indices = Vec::new();
    indptr.push(0);
    for col in 0..n {
        indices.extend((0..nodes.len()).filter(|&j| nodes[j] == col));
        indptr.push(indices.len());
    }
    let data = vec![1.0; indices.len()];
    CscMatrix {
        nrows: nodes.len(),
        ncols: n,
        indptr: Cow::Owned(indptr),
        indices: Cow::Owned(indices),
        data: Cow::Owned(data),
    }
}

/// The OSQP problem of one step exactly as [`OsqpSolver`] builds it (same matrices and
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
    Problem::new(
        upper_csc(c),
        &q,
        selection_csc(c.dim(), nodes),
        lower,
        &u,
        &settings.to_osqp(),
    )
    .map_err(|e| SetupError::Osqp(e.to_string()))
}

/// OSQP's status, as its C library spells it.
pub(crate) fn status_of(status: &Status<'_>) -> OsqpStatus {
    match status {
        Status::SolvedInaccurate(_) => OsqpStatus::SolvedInaccurate,
        Status::MaxIterationsReached(_) => OsqpStatus::MaxIterationsReached,
        Status::TimeLimitReached(_) => OsqpStatus::TimeLimitReached,
        Status::PrimalInfeasible(_) => OsqpStatus::PrimalInfeasible,
        Status::PrimalInfeasibleInaccurate(_) => OsqpStatus::PrimalInfeasibleInaccurate,
        Status::DualInfeasible(_) => OsqpStatus::DualInfeasible,
        Status::DualInfeasibleInaccurate(_) => OsqpStatus::DualInfeasibleInaccurate,
        Status::NonConvex(_) => OsqpStatus::NonConvex,
        _ => OsqpStatus::Unknown,
    }
}

impl OsqpSolver {
    /// Sets OSQP up for `C` and the constrained nodes (local indices).
    pub fn new(
        c: &SymTridiag,
        nodes: &[usize],
        settings: OsqpSettings,
    ) -> Result<Self, SetupError> {
        settings.validate()?;
        let n = c.dim();
        let k = nodes.len();
        if let Some(&bad) = nodes.iter().find(|&&j| j >= n) {
            return Err(SetupError::Osqp(format!(
                "constrained node {bad} outside 0..{n}"
            )));
        }
        let audit = KktAudit::new(c, nodes, false)?;
        let q = vec![0.0; n];
        let l = vec![-OSQP_INFTY; k];
        let u = vec![OSQP_INFTY; k];
        let problem = Problem::new(
            upper_csc(c),
            &q,
            selection_csc(n, nodes),
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
            audit,
            inaccurate_steps: 0,
        })
    }

    pub fn settings(&self) -> OsqpSettings {
        self.settings
    }
}

impl StepSolver for OsqpSolver {
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
        let (solution, inaccurate) = match status {
            Status::Solved(s) => (s, false),
            Status::SolvedInaccurate(s) if self.settings.accept_inaccurate => (s, true),
            other => {
                return Err(StepFailure::Osqp {
                    status: status_of(&other),
                    iterations,
                });
            }
        };
        z.copy_from_slice(solution.x());
        let y = solution.y();
        for j in 0..k {
            // 0.0 − y rather than −y: no −0.0 reactions in the outputs.
            reactions[j] = 0.0 - y[j];
        }
        let factor = if inaccurate { INACCURATE_FACTOR } else { 1.0 };
        let law = Law::Signorini {
            eps_abs: factor * self.settings.eps_abs,
            eps_rel: factor * self.settings.eps_rel,
        };
        self.audit.check(law, rhs, lower, z, reactions)?;
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
}
