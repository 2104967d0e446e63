//! The penalty step solver: the talk's penalised problem (PP) (Petrov & Schatzman 2009), normal
//! compliance. The unilateral constraint at each Signorini node is replaced by the force
//! `(u + a)⁻/ε`, taken implicitly at `t^{n+1}`; in the increment `z` the step reads
//!
//! ```text
//!   C z = b + Σ_j r_j e_j,   ε r_j = max(0, lo_j − z_j),
//! ```
//!
//! the optimality condition of `min ½ zᵀCz − bᵀz + Σ_j ((lo_j − z_j)⁺)²/(2ε)`, strictly convex
//! (one solution). The gap `z_j − lo_j = −ε r_j` is negative in contact: penetration ≈ ε ×
//! reaction, and complementarity holds only in the limit ε → 0.
//!
//! Each step solves the LCP in the reactions by enumerating the at most four supports, then
//! computes the answer by a direct solve on the chosen one; why this is exact and backward
//! stable: `docs/step-solvers.md#end-penalty`.

use crate::linalg::kernels::ldlt::RowChange;
use crate::linalg::system::TridiagSystem;
use crate::linalg::tridiag::SymTridiag;
use crate::step::audit::{KktAudit, Slack};
use crate::step::law::{Law, LawFamily, reaction_from_gap};
use crate::step::schur::{
    StepFactor, constraint_rows, factor_each_subset, least_violating, masked_solve, row_product,
    schur_complement,
};
use crate::step::solver::Constraints;
use crate::step::{SettingsError, SetupError, SolveInfo, SolverReport, StepFailure, StepSolver};

/// ε of the penalised problem unless set: penetration ≈ ε × reaction, so about 1e-6 for the
/// talk's reactions of order 1.
pub const PENALTY_DEFAULT_EPSILON: f64 = 1e-6;

/// The penalty solver's settings.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct PenaltySettings {
    /// ε of (PP) (default [`PENALTY_DEFAULT_EPSILON`]): the compliance, penetration = ε × reaction.
    pub epsilon: f64,
}

impl Default for PenaltySettings {
    fn default() -> Self {
        Self {
            epsilon: PENALTY_DEFAULT_EPSILON,
        }
    }
}

impl PenaltySettings {
    /// Checks every field against its range; the error names the field.
    pub fn validate(&self) -> Result<(), SettingsError> {
        if !(self.epsilon.is_finite() && self.epsilon > 0.0) {
            return Err(SettingsError::new(
                "epsilon",
                self.epsilon,
                "must be a finite number > 0",
            ));
        }
        Ok(())
    }
}

/// Normal compliance with parameter `ε`, solved exactly per step, audited every step.
#[derive(Clone, Debug)]
pub struct EndPenalty {
    epsilon: f64,
    factor: StepFactor,
    /// The constrained nodes (at most two).
    nodes: Vec<usize>,
    /// `S + εI` on the constrained nodes.
    matrix: [[f64; 2]; 2],
    /// `1/ε`, the contact spring.
    stiffness: f64,
    /// Row `i` of `C` at each constrained node ([`constraint_rows`]).
    rows: [[f64; 3]; 2],
    /// Per constrained node: whether its reaction is taken from the gap, `(lo_j − z_j)/ε`
    /// (when `C_jj >= 1/ε`), else from stationarity, `(C z − b)_j` (see
    /// [`EndPenalty::solve_on_support`]).
    from_gap: [bool; 2],
    /// The factorisation of `C + Σ_{j∈A} e_j e_jᵀ/ε` for support `A = mask`, at `mask − 1`.
    springs: Vec<StepFactor>,
    /// The support of the last answer, tried first.
    previous: u8,
    /// `C` with its factorisation, for the audit.
    system: TridiagSystem,
    audit: KktAudit,
}

impl EndPenalty {
    /// Factorises `C` and `C` with a spring at each subset of the constrained nodes (at most
    /// two; `TwistedLdlt`), and computes `S + εI`.
    pub fn new(
        c: &SymTridiag,
        nodes: &[usize],
        settings: PenaltySettings,
    ) -> Result<Self, SetupError> {
        if nodes.len() > 2 {
            return Err(SetupError::TooManyBounds {
                solver: "penalty",
                nodes: nodes.len(),
            });
        }
        settings.validate()?;
        let epsilon = settings.epsilon;
        let factor = StepFactor::new(c, &[], RowChange::Identity, true)?;
        let mut matrix = schur_complement(&factor, nodes);
        for (a, row) in matrix.iter_mut().enumerate().take(nodes.len()) {
            row[a] += epsilon;
        }
        let stiffness = 1.0 / epsilon;
        let springs = factor_each_subset(c, nodes, RowChange::AddToDiagonal(stiffness), true)?;
        let mut system = TridiagSystem::new(c)?;
        let constraints = Constraints::lower_bounds(nodes);
        let audit = KktAudit::new(&mut system, &constraints, LawFamily::Penalty);
        Ok(Self {
            epsilon,
            factor,
            nodes: nodes.to_vec(),
            matrix,
            stiffness,
            rows: constraint_rows(c, nodes),
            from_gap: [0, 1].map(|j| {
                nodes
                    .get(j)
                    .is_some_and(|&i| reaction_from_gap(c.diag[i], stiffness))
            }),
            springs,
            previous: 0,
            system,
            audit,
        })
    }

    pub fn epsilon(&self) -> f64 {
        self.epsilon
    }

    /// Reactions and LCP violation (in displacement) of support `mask`, given `d = lo − z⁰`.
    fn candidate(&self, mask: u8, d: &[f64; 2]) -> ([f64; 2], f64) {
        let k = self.nodes.len();
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

    /// The direct solve on support `mask` (see the module documentation); returns whether it
    /// meets the conditions, `z_j <= lo_j` on the support and `z_j >= lo_j` off it (false on a
    /// NaN). On the support `r_j = (lo_j − z_j)/ε = (C z − b)_j` up to the solve's residual
    /// `δ ~ u (‖C‖ + 1/ε) |z|` (`u` the unit round-off). Taken from the gap (the law's own
    /// [`Law::penalty_reaction`]), the penalty law holds to round-off and stationarity is off by `δ` plus the gap's rounding times `1/ε`;
    /// taken from stationarity, stationarity holds and the law is off by `ε δ`, where `δ`
    /// includes the rounding of the row `(C z − b)_j` itself, `u (|C||z| + |b|)_j`: with a stiff
    /// `C` (a coarse mesh) its terms cancel to a much smaller reaction. Each node
    /// uses the form whose error is round-off of what the audit weighs it against: the gap
    /// when its spring `1/ε` is softer than `C_jj`, stationarity otherwise. Round-off below
    /// zero is clamped.
    fn solve_on_support(
        &self,
        mask: u8,
        rhs: &[f64],
        lower: &[f64],
        z: &mut [f64],
        reactions: &mut [f64],
    ) -> bool {
        z.copy_from_slice(rhs);
        for (j, &i) in self.nodes.iter().enumerate() {
            if mask & (1 << j) != 0 {
                z[i] += self.stiffness * lower[j];
            }
        }
        self.springs[mask as usize - 1].solve_in_place(z);
        let mut met = true;
        for (j, &i) in self.nodes.iter().enumerate() {
            let compression = lower[j] - z[i];
            if mask & (1 << j) != 0 {
                met &= compression >= 0.0;
                reactions[j] = if self.from_gap[j] {
                    Law::penalty_reaction(compression, self.epsilon)
                } else {
                    let rj = row_product(self.rows[j], i, z) - rhs[i];
                    if rj < 0.0 { 0.0 } else { rj }
                };
            } else {
                met &= compression <= 0.0;
                reactions[j] = 0.0;
            }
        }
        met
    }
}

impl StepSolver for EndPenalty {
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
        let mut tried = 1;
        let k = self.nodes.len();
        let warm = self.previous != 0;
        if !(warm && self.solve_on_support(self.previous, rhs, lower, z, reactions)) {
            self.factor.solve_into(rhs, z);
            let mut d = [0.0; 2];
            for (j, &i) in self.nodes.iter().enumerate() {
                d[j] = lower[j] - z[i];
            }
            if !d[..k].iter().all(|v| v.is_finite()) {
                return Err(StepFailure::NonFinite);
            }
            let (enumerated, mask, _) = least_violating(k, |mask| self.candidate(mask, &d));
            tried = u32::from(warm) + enumerated;
            reactions[..k].fill(0.0);
            if mask != 0 {
                // The support is the LCP's; its conditions hold to round-off, not checked.
                self.solve_on_support(mask, rhs, lower, z, reactions);
            }
            self.previous = mask;
        }
        let law = Law::Penalty {
            epsilon: self.epsilon,
        };
        let (lower, reactions) = (&lower[..k], &reactions[..k]);
        (self.audit).check(&mut self.system, law, Slack::NONE, rhs, lower, z, reactions)?;
        Ok(SolveInfo { iterations: tried })
    }

    fn report(&self) -> Option<SolverReport> {
        Some(SolverReport {
            audit: self.audit.report().clone(),
            inaccurate_steps: None,
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Regression (found by the stiff case matrix, `gap0-a1e6-r1e4-e20`): the rigid flight of
    /// `exact::rigid_flight` stopped by penalty springs under both ends. The superposition
    /// `z⁰ + Σ r_j c_j` failed the audit's round-off floors; the direct solve passes them
    /// (the audit runs inside `solve`), with springs softer than `C_jj` (reactions from the
    /// gap) and stiffer ones (from stationarity), and the second call keeps the support by the
    /// warm start (one set tried). Which form each regime needs is checked by the scenes:
    /// reactions from the gap everywhere fail `tests/solvers.rs`; from stationarity
    /// everywhere, the stiff matrix's `Δt = 1e-3 Δx` rows (VERIFICATION.md) fail the law.
    #[test]
    fn stiff_impact_on_penalty_springs_passes_the_audit() {
        let (c, b) = crate::step::end_enumeration::rigid_flight();
        let n = c.dim();
        let ends = [0, n - 1];
        let springs = [(1e4, true), (10.0, true), (0.1, false), (1e-4, false)];
        for (epsilon, from_gap) in springs.map(|(ratio, g)| (ratio / c.diag[0], g)) {
            let mut solver = EndPenalty::new(&c, &ends, PenaltySettings { epsilon }).unwrap();
            assert_eq!(solver.from_gap, [from_gap; 2]);
            let (mut z, mut r) = (vec![0.0; n], [0.0; 2]);
            let first = solver.solve(&b, &[0.0, 0.0], &mut z, &mut r).unwrap();
            assert!(r.iter().all(|v| *v > 0.0), "both springs compressed: {r:?}");
            let second = solver.solve(&b, &[0.0, 0.0], &mut z, &mut r).unwrap();
            assert_eq!(
                (first.iterations, second.iterations),
                (4, 1),
                "ε = {epsilon:e}"
            );
        }
    }

    /// Pins the reaction-form choice of [`EndPenalty::solve_on_support`]: the rigid flight
    /// of `exact::rigid_flight` (`Δt v = −500` per step) stopped by springs under both ends at
    /// `lo = −400`. With a soft spring (`1/ε = 1e-6 C_jj`) the reaction must come from the gap:
    /// from stationarity the law is off by `ε δ`, about 1e4 times its floor. With a stiff one
    /// (`1/ε = 1e6 C_jj`) it must come from stationarity: from the gap, stationarity is off by
    /// the gap's rounding times `1/ε`, about 1e3 times its floor. Each form swapped fails the
    /// audit (run inside `solve`) on the check named; the chosen form passes.
    #[test]
    fn each_spring_regime_needs_its_reaction_form() {
        let (c, b) = crate::step::end_enumeration::rigid_flight();
        let n = c.dim();
        let ends = [0, n - 1];
        let lower = [-400.0; 2];
        let cases = [(1e6, true, "penalty law"), (1e-6, false, "stationarity")];
        for (ratio, from_gap, swapped_fails) in cases {
            let epsilon = ratio / c.diag[0];
            for swap in [false, true] {
                let mut solver = EndPenalty::new(&c, &ends, PenaltySettings { epsilon }).unwrap();
                assert_eq!(solver.from_gap, [from_gap; 2], "ε = {epsilon:e}");
                if swap {
                    solver.from_gap = [!from_gap; 2];
                }
                let (mut z, mut r) = (vec![0.0; n], [0.0; 2]);
                let result = solver.solve(&b, &lower, &mut z, &mut r);
                match (swap, result) {
                    (false, Ok(_)) => {}
                    (true, Err(StepFailure::AuditFailed { what, .. })) => assert!(
                        what.starts_with(swapped_fails),
                        "ε = {epsilon:e}, swapped form: {what}"
                    ),
                    (swap, other) => panic!("ε = {epsilon:e}, swapped {swap}: {other:?}"),
                }
            }
        }
    }
}
