//! The penalty step solver: the talk's penalised problem (PP) (Petrov & Schatzman 2009), normal
//! compliance. The unilateral constraint at each Signorini node is replaced by the force
//! `(u + a)⁻/ε`, taken implicitly at `t^{n+1}`; in the increment `z` the step reads
//!
//! ```text
//!   C z = b + Σ_j r_j e_j,   ε r_j = max(0, lo_j − z_j),
//! ```
//!
//! the optimality condition of the strictly convex problem
//! `min ½ zᵀCz − bᵀz + Σ_j ((lo_j − z_j)⁺)²/(2ε)`, so it has exactly one solution. The gap
//! `z_j − lo_j = −ε r_j` is negative in contact: penetration ≈ ε × reaction, and
//! complementarity holds only in the limit ε → 0.
//!
//! Solution, exact to round-off. As in [`crate::exact`], with `z⁰ = C⁻¹ b`, `c_j = C⁻¹ e_j`
//! and `S_jk = (C⁻¹)_jk` on the constrained nodes, `z = z⁰ + Σ_j r_j c_j`, and the conditions
//! become the linear complementarity problem in `r ∈ ℝᵏ` (k <= 2):
//!
//! ```text
//!   w = (S + εI) r − (lo − z⁰_c) >= 0,   r >= 0,   wᵀ r = 0,     (w_j = z_j − lo_j + ε r_j)
//! ```
//!
//! `S + εI` is symmetric positive definite (S is a principal block of `C⁻¹`), hence a
//! P-matrix, so the LCP has exactly one solution for every right-hand side (Cottle, Pang &
//! Stone, *The Linear Complementarity Problem*, Thm 3.3.7). Its support is one of the `2^k <= 4`
//! subsets `A`, on which `(S + εI)_AA r_A = (lo − z⁰)_A` is linear. Trying the subsets in
//! the order ∅, {first}, {second}, {both} and accepting the first whose `r_A >= 0` and
//! `w >= 0` therefore terminates after at most four 1×1 or 2×2 solves; this is semismooth
//! Newton on the piecewise-linear equation `ε r = (lo − z⁰ − S r)⁺` with every piece visited at
//! most once. In floating point the candidates are ranked by their violation, as in the exact
//! solver, so the choice is deterministic. `iterations` is the number of subsets tried.

use crate::audit::{KktAudit, Law};
use crate::error::{RunError, SceneError};
use crate::exact::{Column, inverse_columns, least_violating, masked_solve, schur_complement};
use crate::solver::{SolveInfo, SolverReport, StepFailure, StepSolver};
use crate::tridiag::{Ldlt, NotPositiveDefinite, SymTridiag};

/// Why the penalty solver could not be set up.
#[derive(Debug, thiserror::Error)]
pub enum PenaltySetupError {
    #[error(transparent)]
    Matrix(#[from] NotPositiveDefinite),
    #[error("epsilon = {0} must be a finite number > 0")]
    Epsilon(f64),
    #[error("the penalty solver handles the two Signorini ends only, not {0} constrained nodes")]
    TooManyBounds(usize),
}

impl From<PenaltySetupError> for RunError {
    fn from(e: PenaltySetupError) -> Self {
        match e {
            PenaltySetupError::Matrix(m) => RunError::Matrix(m),
            PenaltySetupError::Epsilon(v) => RunError::Scene(SceneError::Invalid {
                field: "solver.epsilon".into(),
                value: v.to_string(),
                allowed: "must be a finite number > 0".into(),
            }),
            PenaltySetupError::TooManyBounds(k) => RunError::Scene(SceneError::Invalid {
                field: "solver.method".into(),
                value: "\"penalty\"".into(),
                allowed: format!(
                    "the penalty solver handles the two Signorini ends only; this scene constrains \
                     {k} nodes (use exact or osqp for an obstacle)"
                ),
            }),
        }
    }
}

/// Normal compliance with parameter `ε`, solved exactly per step, audited every step.
#[derive(Clone, Debug)]
pub struct PenaltySolver {
    epsilon: f64,
    factor: Ldlt,
    columns: Vec<Column>,
    /// `S + εI` on the constrained nodes.
    matrix: [[f64; 2]; 2],
    audit: KktAudit,
}

impl PenaltySolver {
    /// Factorises `C`, precomputes `C⁻¹ e_j` for each constrained node (at most two).
    pub fn new(c: &SymTridiag, nodes: &[usize], epsilon: f64) -> Result<Self, PenaltySetupError> {
        if nodes.len() > 2 {
            return Err(PenaltySetupError::TooManyBounds(nodes.len()));
        }
        if !(epsilon.is_finite() && epsilon > 0.0) {
            return Err(PenaltySetupError::Epsilon(epsilon));
        }
        let factor = Ldlt::factor(c)?;
        let columns = inverse_columns(&factor, nodes);
        let mut matrix = schur_complement(&columns);
        for (a, row) in matrix.iter_mut().enumerate().take(columns.len()) {
            row[a] += epsilon;
        }
        let audit = KktAudit::new(c, nodes, true)?;
        Ok(Self {
            epsilon,
            factor,
            columns,
            matrix,
            audit,
        })
    }

    pub fn epsilon(&self) -> f64 {
        self.epsilon
    }

    /// Reactions and LCP violation (in displacement) of support `mask`, given `d = lo − z⁰`.
    fn candidate(&self, mask: u8, d: &[f64; 2]) -> ([f64; 2], f64) {
        let k = self.columns.len();
        let m = &self.matrix;
        let r = masked_solve(m, d, mask);
        let mut violation: f64 = 0.0;
        for j in 0..k {
            if mask & (1 << j) != 0 {
                violation = violation.max(-r[j] * m[j][j]);
            } else {
                // w_j = ((S + εI) r)_j − d_j with r_j = 0 must be >= 0.
                let wj = (0..k).map(|i| m[j][i] * r[i]).sum::<f64>() - d[j];
                violation = violation.max(-wj);
            }
        }
        (r, violation)
    }
}

impl StepSolver for PenaltySolver {
    fn name(&self) -> &'static str {
        "penalty"
    }

    fn solve(
        &mut self,
        rhs: &[f64],
        lower: &[f64],
        z: &mut [f64],
        reactions: &mut [f64],
    ) -> Result<SolveInfo, StepFailure> {
        self.factor.solve_into(rhs, z);
        let k = self.columns.len();
        let mut d = [0.0; 2];
        for (j, col) in self.columns.iter().enumerate() {
            d[j] = lower[j] - z[col.node];
        }
        if !d[..k].iter().all(|v| v.is_finite()) {
            return Err(StepFailure::NonFinite);
        }
        let (tried, mask, r) = least_violating(k, |mask| self.candidate(mask, &d));
        for (j, col) in self.columns.iter().enumerate() {
            let active = mask & (1 << j) != 0;
            reactions[j] = if active { r[j] } else { 0.0 };
            if active && r[j] != 0.0 {
                col.add_scaled(r[j], z);
            }
        }
        let law = Law::Penalty {
            epsilon: self.epsilon,
        };
        self.audit
            .check(law, rhs, &lower[..k], z, &reactions[..k])?;
        Ok(SolveInfo { iterations: tried })
    }

    fn report(&self) -> Option<SolverReport> {
        Some(SolverReport {
            audit: self.audit.report().clone(),
            inaccurate_steps: None,
        })
    }
}
