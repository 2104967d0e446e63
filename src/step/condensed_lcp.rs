//! The exact step solver by condensation onto the constraints, for any body whose `C` is
//! factorised ([`SpdSystem`]); with a compliance `ε > 0`, the penalty law on the same LCP.
//!
//! With `z⁰ = C⁻¹ b`, `z = z⁰ + C⁻¹ Eᵀ r` (`E` the `m × n` rows `s_k e_{i_k}ᵀ`) and the gap
//! `w = E z − lo = S r + q`, `S = E C⁻¹ Eᵀ` (SPD: `E` has full row rank), `q = E z⁰ − lo`: the
//! LCP `w >= 0 ⊥ r >= 0` of [`crate::step::lcp`], exact. Normal compliance `ε r = (lo − Ez)⁺`
//! is the LCP on `S + εI`. `S` is formed once per run by solves on blocks of unit columns.
//! Each step: `z⁰` (one solve), the LCP, and, when some `r_k > 0`, `z` again from
//! `C z = b + Eᵀ r` (a second solve: backward stable, where `z⁰ + C⁻¹Eᵀr` would cancel digits
//! when contact stops a fast body). Memory: `2m²` doubles besides the factor.

use crate::linalg::system::SpdSystem;
use crate::step::lcp::{DenseLcp, LcpError};
use crate::step::solver::Constraints;
use crate::step::{SetupError, SolveInfo, StepFailure, StepSolver};

/// Largest block of unit columns solved at once when forming `S`, in doubles (`n · block`):
/// 32 MiB of right-hand sides, so that the set-up stays within the run's memory budget.
const S_BLOCK_DOUBLES: usize = 1 << 22;

/// `S = E C⁻¹ Eᵀ` (row-major, symmetrised bitwise), from blocks of unit columns solved with
/// the factor of `C`.
pub fn condensed_matrix(constraints: &Constraints, system: &mut impl SpdSystem) -> Vec<f64> {
    let (m, n) = (constraints.len(), system.dim());
    let (unknowns, signs) = (&constraints.unknowns, &constraints.directions);
    let mut s = vec![0.0; m * m];
    let block = (S_BLOCK_DOUBLES / n.max(1)).clamp(1, m.max(1));
    let mut x = vec![0.0; n * block];
    for start in (0..m).step_by(block) {
        let cols = block.min(m - start);
        let x = &mut x[..n * cols];
        x.fill(0.0);
        for c in 0..cols {
            x[c * n + unknowns[start + c]] = signs[start + c];
        }
        system.solve_columns_in_place(x, cols);
        for c in 0..cols {
            for j in 0..m {
                s[j * m + start + c] = signs[j] * x[c * n + unknowns[j]];
            }
        }
    }
    for j in 0..m {
        for k in 0..j {
            let v = 0.5 * (s[j * m + k] + s[k * m + j]);
            s[j * m + k] = v;
            s[k * m + j] = v;
        }
    }
    s
}

/// Condensation and the exact LCP solver (or the penalty law with `ε > 0`).
pub struct CondensedLcp<S: SpdSystem> {
    system: S,
    constraints: Constraints,
    /// `None` without constraints: then a step is one solve.
    lcp: Option<DenseLcp>,
    /// `ε` of the penalty law, 0 for Signorini.
    epsilon: f64,
    q: Vec<f64>,
    w: Vec<f64>,
}

impl<S: SpdSystem> CondensedLcp<S> {
    /// Forms `S` (plus `εI` for the penalty law, `epsilon > 0`) and its LCP solver.
    pub fn new(mut system: S, constraints: Constraints, epsilon: f64) -> Result<Self, SetupError> {
        if !(epsilon.is_finite() && epsilon >= 0.0) {
            return Err(crate::step::SettingsError::new(
                "epsilon",
                epsilon,
                "must be a finite number > 0",
            )
            .into());
        }
        let m = constraints.len();
        let lcp = if m == 0 {
            None
        } else {
            let mut s = condensed_matrix(&constraints, &mut system);
            for k in 0..m {
                s[k * m + k] += epsilon;
            }
            Some(DenseLcp::new(s, m).map_err(|e| SetupError::Contact(e.to_string()))?)
        };
        Ok(Self {
            system,
            constraints,
            lcp,
            epsilon,
            q: vec![0.0; m],
            w: vec![0.0; m],
        })
    }

    /// `S_jk` (`S + εI` for the penalty law; `None` without constraints).
    pub fn s(&self, j: usize, k: usize) -> Option<f64> {
        self.lcp.as_ref().map(|l| l.entry(j, k))
    }

    /// Stored values of the factor of `C`, and the matrix with its factorisation.
    pub fn system(&self) -> &S {
        &self.system
    }
}

impl<S: SpdSystem> StepSolver for CondensedLcp<S> {
    fn name(&self) -> &'static str {
        if self.epsilon > 0.0 {
            "penalty"
        } else {
            "exact"
        }
    }

    /// `z⁰ = C⁻¹ b`, the LCP for the reactions, and, when one is positive, `z` from
    /// `C z = b + Eᵀ r`. Allocates nothing.
    fn solve(
        &mut self,
        rhs: &[f64],
        lower: &[f64],
        z: &mut [f64],
        reactions: &mut [f64],
    ) -> Result<SolveInfo, StepFailure> {
        z.copy_from_slice(rhs);
        self.system.solve_in_place(z);
        let Some(lcp) = &mut self.lcp else {
            return Ok(SolveInfo { iterations: 1 });
        };
        let (unknowns, signs) = (&self.constraints.unknowns, &self.constraints.directions);
        for (k, q) in self.q.iter_mut().enumerate() {
            *q = signs[k] * z[unknowns[k]] - lower[k];
        }
        let iterations = lcp
            .solve(&self.q, reactions, &mut self.w)
            .map_err(|e| match e {
                LcpError::IterationLimit { iterations } => {
                    StepFailure::IterationLimit { iterations }
                }
                LcpError::NonFinite | LcpError::NotPositiveDefinite { .. } => {
                    StepFailure::NonFinite
                }
            })?;
        if reactions.iter().any(|&r| r > 0.0) {
            // z from C z = b + Eᵀ r directly (backward stable).
            z.copy_from_slice(rhs);
            for (k, r) in reactions.iter().enumerate() {
                z[unknowns[k]] += signs[k] * r;
            }
            self.system.solve_in_place(z);
        }
        Ok(SolveInfo { iterations })
    }
}
