//! An independent check of every step answer against the optimality conditions of the step
//! problem (see [`crate::step::solver`]):
//!
//! ```text
//!   C z = b + Σ_k r_k s_k e_{i_k},   s_k z_{i_k} >= lo_k,   r_k >= 0,   r_k (s_k z_{i_k} − lo_k) = 0   (Signorini)
//!   C z = b + Σ_k r_k s_k e_{i_k},   ε r_k = max(0, lo_k − s_k z_{i_k})                          (penalty (PP))
//! ```
//!
//! recomputed from the solver's `z` and `r` with this crate's own kernels, never from a
//! solver's own residuals. A solver that reports success with an answer failing the audit
//! returns [`StepFailure::AuditFailed`] instead of a result.
//!
//! The checks, their scales and their round-off floors follow OSQP's own termination test and
//! add one it does not make (stationarity mapped to displacement):
//! `docs/step-solvers.md#kkt-audit`.

use crate::linalg::kernels::ldlt::NotPositiveDefinite;
use crate::linalg::norms::max_abs;
use crate::linalg::system::{SpdSystem, TridiagSystem, inverse_norm_estimate};
use crate::linalg::tridiag::SymTridiag;
use crate::step::report::{AuditReport, StepFailure, Worst};
use crate::step::solver::Constraints;

/// Margin over OSQP's own stopping test: OSQP evaluates its residuals on its scaled copy of the
/// data and may accept a polished answer that trades a little of one residual for the other
/// (polish.c), so the same formula recomputed here can come out a few times larger; ten times
/// still refuses anything that misses OSQP's own criterion by more than a decade.
pub const AUDIT_MARGIN: f64 = 10.0;

/// OSQP's "solved inaccurate" means its criterion held with both `eps` multiplied by 10
/// (auxil.c, `check_termination(.., approximate)`); accepted steps are audited accordingly.
pub const INACCURATE_FACTOR: f64 = 10.0;

/// Round-off floor of the bar's audit, in units of `ε·(magnitude of the terms)`
/// ([`TridiagSystem`]'s `roundoff_ulps`, where the reason is given).
pub const ROUNDOFF_ULPS: f64 = 32.0;

/// OSQP's dual-residual tolerance (auxil.c; the module doc): `eps_abs + eps_rel · max(‖Cz‖∞,
/// ‖b‖∞, ‖r‖∞)`, from the three norms; the audit applies it with its margin, the studies and
/// tests with OSQP's own `eps` to read OSQP's verdict.
pub fn dual_tolerance(eps_abs: f64, eps_rel: f64, cz_norm: f64, b_norm: f64, r_norm: f64) -> f64 {
    eps_abs + eps_rel * cz_norm.max(b_norm).max(r_norm)
}

/// The contact law an answer must satisfy.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Law {
    /// Signorini complementarity, to OSQP-style tolerances `eps_abs`, `eps_rel` as given to
    /// the solver (the audit multiplies them by [`AUDIT_MARGIN`]).
    Signorini { eps_abs: f64, eps_rel: f64 },
    /// Normal compliance `ε r_j = max(0, lo_j − z_j)`, solved directly: round-off floors only.
    Penalty { epsilon: f64 },
}

/// The audit of one run: the matrix with its factorisation, the constraints, scratch space and
/// the worst residuals. [`KktAudit::check`] allocates nothing.
#[derive(Clone, Debug)]
pub struct KktAudit<S: SpdSystem = TridiagSystem> {
    system: S,
    constraints: Constraints,
    /// `‖C‖_∞` and an estimate of `‖C⁻¹‖_∞`, for the round-off floors.
    c_norm: f64,
    inv_norm: f64,
    /// `|(C⁻¹)_{jk}|` on the constrained unknowns, row-major: solvers that form
    /// `z_j = z⁰_j + Σ_k (C⁻¹)_{jk} r_k` round `z_j` to ulps of `|z⁰_j|`, which is at most
    /// `|z_j| + Σ_k |(C⁻¹)_{jk} r_k|`.
    schur_abs: Vec<f64>,
    residual: Vec<f64>,
    report: AuditReport,
}

impl KktAudit<TridiagSystem> {
    /// Set-up for the tridiagonal matrix `c` and lower bounds at the unknowns `nodes`;
    /// `penalty` selects which checks the report lists.
    pub fn new(
        c: &SymTridiag,
        nodes: &[usize],
        penalty: bool,
    ) -> Result<Self, NotPositiveDefinite> {
        Ok(Self::with_system(
            TridiagSystem::new(c)?,
            Constraints::lower_bounds(nodes),
            penalty,
        ))
    }
}

impl<S: SpdSystem> KktAudit<S> {
    /// Set-up for `C` (with its factorisation) and the constraints; `penalty` selects which
    /// checks the report lists.
    pub fn with_system(mut system: S, constraints: Constraints, penalty: bool) -> Self {
        let n = system.dim();
        let c_norm = system.inf_norm();
        let inv_norm = inverse_norm_estimate(&mut system);
        // Only the penalty law reads `schur_abs` (and the penalty solver has at most two
        // nodes): for an obstacle under every node it would be a dense k×k block, O(k n) work.
        let nodes = &constraints.unknowns;
        let k = if penalty { nodes.len() } else { 0 };
        let mut schur_abs = vec![0.0; k * k];
        for (a, &na) in nodes[..k].iter().enumerate() {
            let col = system.column_of_inverse(na);
            for (b, &nb) in nodes[..k].iter().enumerate() {
                schur_abs[b * k + a] = col[nb].abs();
            }
        }
        let report = AuditReport {
            primal_violation: (!penalty).then(Worst::default),
            complementarity: (!penalty).then(Worst::default),
            penalty_law: penalty.then(Worst::default),
            ..Default::default()
        };
        Self {
            system,
            constraints,
            c_norm,
            inv_norm,
            schur_abs,
            residual: vec![0.0; n],
            report,
        }
    }

    /// The worst residuals so far.
    pub fn report(&self) -> &AuditReport {
        &self.report
    }

    /// The matrix and its factorisation.
    pub fn system(&mut self) -> &mut S {
        &mut self.system
    }

    /// Checks one answer `(z, r)` of the step problem with data `(b, lo)` against `law`,
    /// records its residuals, and returns the first failed check.
    pub fn check(
        &mut self,
        law: Law,
        b: &[f64],
        lower: &[f64],
        z: &[f64],
        r: &[f64],
    ) -> Result<(), StepFailure> {
        let (nodes, directions) = (&self.constraints.unknowns, &self.constraints.directions);
        let k = nodes.len();
        if !(z.iter().all(|v| v.is_finite()) && r[..k].iter().all(|v| v.is_finite())) {
            return Err(StepFailure::NonFinite);
        }
        let (eps_abs, eps_rel) = match law {
            Law::Signorini { eps_abs, eps_rel } => (AUDIT_MARGIN * eps_abs, AUDIT_MARGIN * eps_rel),
            Law::Penalty { .. } => (0.0, 0.0),
        };
        let ulp = self.system.roundoff_ulps() * f64::EPSILON;
        // Stationarity residual, with the norms of its terms.
        self.system.mul_into(z, &mut self.residual);
        let (mut cz_norm, mut b_norm, mut z_norm) = (0.0f64, 0.0f64, 0.0f64);
        for i in 0..z.len() {
            cz_norm = cz_norm.max(self.residual[i].abs());
            b_norm = b_norm.max(b[i].abs());
            z_norm = z_norm.max(z[i].abs());
            self.residual[i] -= b[i];
        }
        let mut r_norm = 0.0f64;
        for (j, (&node, &s)) in nodes.iter().zip(directions).enumerate() {
            self.residual[node] -= s * r[j];
            r_norm = r_norm.max(r[j].abs());
        }
        let res_norm = max_abs(&self.residual);
        let floor_f = ulp * (self.c_norm * z_norm + b_norm + r_norm);
        let tol_f = dual_tolerance(eps_abs, eps_rel, cz_norm, b_norm, r_norm) + floor_f;
        self.system.solve_in_place(&mut self.residual);
        let dz_norm = max_abs(&self.residual);
        let tol_dz = eps_abs + eps_rel * z_norm + self.inv_norm * floor_f;
        let mut p_scale = 0.0f64;
        for (j, &node) in nodes.iter().enumerate() {
            p_scale = p_scale.max(z[node].abs()).max(lower[j].abs());
        }
        let tol_z = eps_abs + eps_rel * p_scale + ulp * p_scale;
        let (mut primal, mut negative, mut comp, mut comp_tol, mut law_res, mut law_tol) =
            (0.0f64, 0.0f64, 0.0f64, 0.0f64, 0.0f64, 0.0f64);
        for (j, (&node, &s)) in nodes.iter().zip(directions).enumerate() {
            let gap = s * z[node] - lower[j];
            negative = negative.max(-r[j]);
            match law {
                Law::Signorini { .. } => {
                    primal = primal.max(-gap);
                    let c = (r[j] * gap).abs();
                    let t = tol_z * r[j].abs() + tol_f * gap.abs();
                    // Keep the pair with the worst ratio, so that value and tolerance match.
                    if ratio(c, t) >= ratio(comp, comp_tol) {
                        comp = c;
                        comp_tol = t;
                    }
                }
                Law::Penalty { epsilon } => {
                    let v = (epsilon * r[j] - (-gap).max(0.0)).abs();
                    // `gap` is rounded to ulps of |z⁰_j| + |lo_j|, `ε r_j` to ulps of itself.
                    let coupled: f64 = (0..k).map(|i| self.schur_abs[j * k + i] * r[i].abs()).sum();
                    // A reaction taken from stationarity, `(Cz − b)_j`, brings that row's
                    // rounding, `u (|C||z| + |b|)_j`, times ε ([`reaction_from_gap`]).
                    let row = if reaction_from_gap(self.system.diagonal(node), 1.0 / epsilon) {
                        0.0
                    } else {
                        epsilon * (self.system.abs_row_product(node, z) + b[node].abs())
                    };
                    let t = ulp
                        * (z[node].abs() + coupled + lower[j].abs() + (epsilon * r[j]).abs() + row);
                    if ratio(v, t) >= ratio(law_res, law_tol) {
                        law_res = v;
                        law_tol = t;
                    }
                }
            }
        }
        record_and_check(
            &mut self.report,
            [
                ("primal violation (lo_k - s_k z_k)+", primal, tol_z),
                ("negative reaction (-r_k)+", negative, tol_f),
                ("complementarity |r_k (s_k z_k - lo_k)|", comp, comp_tol),
                ("stationarity |Cz - b - r|", res_norm, tol_f),
                (
                    "stationarity in displacement |C^-1 (Cz - b - r)|",
                    dz_norm,
                    tol_dz,
                ),
            ],
            Some((
                "penalty law |eps r_k - (lo_k - s_k z_k)+|",
                law_res,
                law_tol,
            )),
        )
    }
}

/// Whether the penalty solver takes a constrained node's reaction from its gap,
/// `(lo_j − z_j)/ε`: when the spring `1/ε` (`stiffness`) is no stiffer than `C_jj`; otherwise
/// from stationarity, `(C z − b)_j` (`EndPenalty::solve_on_support`). The solver and the
/// audit, which weighs each form's round-off, share this rule.
pub fn reaction_from_gap(c_jj: f64, stiffness: f64) -> bool {
    c_jj >= stiffness
}

/// One audited residual: what it measures, its value and its tolerance.
pub type Residual = (&'static str, f64, f64);

/// Records one step's residuals in `report` (worst ratios) and fails on the first one above
/// its tolerance. `checks` are, in order:
/// primal violation, negative reaction, complementarity, stationarity, stationarity in
/// displacement; `penalty_law` is the penalty solver's law, when it has one.
pub fn record_and_check(
    report: &mut AuditReport,
    checks: [Residual; 5],
    penalty_law: Option<Residual>,
) -> Result<(), StepFailure> {
    let [primal, negative, comp, stationarity, displacement] = checks;
    report.steps += 1;
    report.stationarity.observe(stationarity.1, stationarity.2);
    report
        .stationarity_displacement
        .observe(displacement.1, displacement.2);
    report.negative_reaction.observe(negative.1, negative.2);
    if let Some(w) = report.primal_violation.as_mut() {
        w.observe(primal.1, primal.2);
    }
    if let Some(w) = report.complementarity.as_mut() {
        w.observe(comp.1, comp.2);
    }
    if let (Some(w), Some(law)) = (report.penalty_law.as_mut(), penalty_law) {
        w.observe(law.1, law.2);
    }
    let in_order = [primal, negative, comp].into_iter().chain(penalty_law);
    first_failure(in_order.chain([stationarity, displacement]))
}

/// The audit's verdict on its checks `(what, value, tolerance)` in order: the first whose
/// value exceeds its tolerance (or is NaN) fails the step.
pub(crate) fn first_failure(
    checks: impl IntoIterator<Item = (&'static str, f64, f64)>,
) -> Result<(), StepFailure> {
    for (what, value, tolerance) in checks {
        // Negated so that a NaN residual fails.
        #[allow(clippy::neg_cmp_op_on_partial_ord)]
        if !(value <= tolerance) {
            return Err(StepFailure::AuditFailed {
                what,
                value,
                tolerance,
            });
        }
    }
    Ok(())
}

/// `value / tolerance`, infinite for a positive value against a zero tolerance.
pub(crate) fn ratio(value: f64, tolerance: f64) -> f64 {
    if tolerance > 0.0 {
        value / tolerance
    } else if value > 0.0 {
        f64::INFINITY
    } else {
        0.0
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Regression: the Signorini audit of an obstacle under every node used to build the dense
    /// `k×k` block of `C⁻¹` (8 TB at 1e6 nodes), aborting OSQP runs on large distributed
    /// scenes and the stiff matrix. Set-up is now O(n) in time and memory.
    #[test]
    fn signorini_audit_of_an_obstacle_under_every_node_sets_up_in_linear_memory() {
        let n = 200_000;
        let c = SymTridiag::new(vec![4.0; n], vec![-1.0; n - 1]);
        let nodes: Vec<usize> = (0..n).collect();
        let mut audit = KktAudit::new(&c, &nodes, false).unwrap();
        assert!(audit.schur_abs.is_empty());
        // An exact answer (z = C⁻¹ b, every bound inactive) passes the round-off audit.
        let z = vec![1.0; n];
        let b = c.mul(&z);
        let lower = vec![0.0; n];
        let r = vec![0.0; n];
        let law = Law::Signorini {
            eps_abs: 0.0,
            eps_rel: 0.0,
        };
        audit.check(law, &b, &lower, &z, &r).unwrap();
    }
}
