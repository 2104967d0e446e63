//! The exact step solver: active-set enumeration over at most two constrained nodes.
//!
//! With the unconstrained solution `z⁰ = C⁻¹ b` and `S_jk = (C⁻¹)_jk` on the constrained nodes
//! (computed once per run), the reactions of an active set `A` solve `S_AA r_A = lo_A − z⁰_A`.
//! The QP is strictly convex, so exactly one active set satisfies the KKT conditions (up to
//! ties, where a bound is active with a zero reaction and two sets give the same point). In
//! floating point the candidates are ranked by their KKT violation, measured in units of
//! displacement, and the first set with the smallest violation in the order ∅, {first},
//! {second}, {both} wins. The answer on the chosen set is computed by a direct solve,
//! `z_A = lo_A`, `C_FF z_F = b_F − C_FA lo_A`, `r_A = (Cz − b)_A`: backward stable.
//!
//! Warm start: the previous step's active set is tried first by the same direct solve and kept
//! when it meets the KKT conditions (`docs/step-solvers.md#end-enumeration`).
//! The step matrix enters through [`EndSystem`]: the bar's tridiagonal `C` ([`BarEnds`]), or
//! any body's matrix whose constrained unknowns are at most two.

use crate::linalg::kernels::ldlt::{NotPositiveDefinite, RowChange};
use crate::linalg::tridiag::SymTridiag;
use crate::step::schur::{
    StepFactor, constraint_rows, factor_each_subset, least_violating, masked_solve, row_product,
    schur_complement,
};
use crate::step::solver::add_in_place;
use crate::step::{SolveInfo, StepFailure, StepSolver};

/// What the enumeration needs of the step matrix `A` (symmetric, nonsingular, `E A⁻¹ Eᵀ` on the
/// constrained unknowns `i_j` positive definite): solves with `A` and with `A_M`, `A` with the
/// rows and columns of active set `M` (bit `j`: constraint `j`) replaced by identity ones, both
/// factorised once, and `A`'s entries in the constrained columns. Solves allocate nothing.
pub trait EndSystem {
    /// `x = A⁻¹ b`.
    fn solve_into(&mut self, b: &[f64], x: &mut [f64]);
    /// `x = A⁻¹ b`, then `u += x`: a system may do both in one pass (the same bits).
    fn solve_into_and_add(&mut self, b: &[f64], x: &mut [f64], u: &mut [f64]) {
        self.solve_into(b, x);
        add_in_place(u, x);
    }
    /// `x ← A_M⁻¹ x` for active set `mask` (not empty).
    fn solve_reduced_in_place(&mut self, mask: u8, x: &mut [f64]);
    /// `x_k −= A_{k,i_j} v` at the other rows `k` of column `i_j` off active set `mask`: a
    /// known `z_{i_j} = v` moved to the right-hand side.
    fn move_to_rhs(&self, j: usize, v: f64, mask: u8, x: &mut [f64]);
    /// `(A z)_{i_j}`.
    fn row_product(&self, j: usize, z: &[f64]) -> f64;
    /// `S_jk = (A⁻¹)_{i_j i_k}`, bitwise symmetric (set-up only).
    fn schur_complement(&mut self) -> [[f64; 2]; 2];
}

/// The bar's `C` (tridiagonal) as an [`EndSystem`]: its factorisation and, for each non-empty
/// subset of the constrained nodes, that of `C` with those rows and columns replaced by
/// identity ones.
#[derive(Clone, Debug)]
pub struct BarEnds {
    factor: StepFactor,
    /// The constrained nodes (at most two).
    nodes: Vec<usize>,
    /// Row `i` of `C` at each constrained node `i`: `C_i,i−1`, `C_i,i+1` (0 where absent) and
    /// the row sum (all the direct solve reads of `C`).
    rows: [[f64; 3]; 2],
    /// The factorisation of `C` with the rows and columns of active set `mask` replaced by
    /// identity ones, at index `mask − 1`.
    reduced: Vec<StepFactor>,
}

impl BarEnds {
    /// `twisted`: the optimised twin `TwistedLdlt` (else the plain `Ldlt`).
    pub fn new(
        c: &SymTridiag,
        nodes: &[usize],
        twisted: bool,
    ) -> Result<Self, NotPositiveDefinite> {
        Ok(Self {
            factor: StepFactor::new(c, &[], RowChange::Identity, twisted)?,
            rows: constraint_rows(c, nodes),
            reduced: factor_each_subset(c, nodes, RowChange::Identity, twisted)?,
            nodes: nodes.to_vec(),
        })
    }
}

impl EndSystem for BarEnds {
    fn solve_into(&mut self, b: &[f64], x: &mut [f64]) {
        self.factor.solve_into(b, x);
    }

    fn solve_into_and_add(&mut self, b: &[f64], x: &mut [f64], u: &mut [f64]) {
        self.factor.solve_into_and_add(b, x, u);
    }

    fn solve_reduced_in_place(&mut self, mask: u8, x: &mut [f64]) {
        self.reduced[mask as usize - 1].solve_in_place(x);
    }

    /// The neighbours `i ± 1` of node `i = i_j`, where they are not active nodes themselves.
    fn move_to_rhs(&self, j: usize, v: f64, mask: u8, x: &mut [f64]) {
        let n = x.len();
        let i = self.nodes[j];
        let is_active_node =
            |i: usize| (0..self.nodes.len()).any(|k| mask & (1 << k) != 0 && self.nodes[k] == i);
        let [left, right, _] = self.rows[j];
        if i > 0 && !is_active_node(i - 1) {
            x[i - 1] -= left * v;
        }
        if i + 1 < n && !is_active_node(i + 1) {
            x[i + 1] -= right * v;
        }
    }

    fn row_product(&self, j: usize, z: &[f64]) -> f64 {
        row_product(self.rows[j], self.nodes[j], z)
    }

    fn schur_complement(&mut self) -> [[f64; 2]; 2] {
        schur_complement(&self.factor, &self.nodes)
    }
}

/// Exact enumeration for zero, one or two constrained unknowns of the step matrix `E` (the
/// bar's `C` unless said otherwise).
#[derive(Clone, Debug)]
pub struct EndEnumeration<E: EndSystem = BarEnds> {
    system: E,
    /// The constrained unknowns (at most two).
    nodes: Vec<usize>,
    /// `S = (C⁻¹)_{jk}` on the constrained nodes.
    schur: [[f64; 2]; 2],
    /// Try the previous step's active set first (the default; off to measure what it buys).
    warm_start: bool,
    /// The active set of the last answer (a mask: bit `j` for node `j`), tried first.
    previous: u8,
    /// Steps answered by the direct solve on the previous active set.
    warm_kept: u64,
}

impl EndEnumeration {
    /// Factorises `C` and, for each non-empty subset of the constrained nodes (at most two), `C`
    /// with those rows and columns replaced by identity ones (`TwistedLdlt`); warm start on.
    pub fn new(c: &SymTridiag, nodes: &[usize]) -> Result<Self, NotPositiveDefinite> {
        Self::with_options(c, nodes, true, true)
    }

    /// [`EndEnumeration::new`] with the plain factorisation `Ldlt` instead of its twin
    /// (`twisted = false`) or without the warm start: the same answers to round-off (with
    /// the warm start or without, the bits of the direct solve on the same set), for
    /// measuring what each buys.
    pub fn with_options(
        c: &SymTridiag,
        nodes: &[usize],
        twisted: bool,
        warm_start: bool,
    ) -> Result<Self, NotPositiveDefinite> {
        assert!(
            nodes.len() <= 2,
            "the end-node enumeration handles at most two bounds"
        );
        Ok(Self::on(
            BarEnds::new(c, nodes, twisted)?,
            nodes,
            warm_start,
        ))
    }
}

impl<E: EndSystem> EndEnumeration<E> {
    /// The solver on `system`, whose constrained unknowns are `nodes` (at most two).
    pub fn on(mut system: E, nodes: &[usize], warm_start: bool) -> Self {
        assert!(
            nodes.len() <= 2,
            "the end-node enumeration handles at most two bounds"
        );
        Self {
            schur: system.schur_complement(),
            system,
            nodes: nodes.to_vec(),
            warm_start,
            previous: 0,
            warm_kept: 0,
        }
    }

    /// Steps so far answered by the direct solve on the previous step's active set (the warm
    /// start met the KKT conditions, no enumeration).
    pub fn warm_steps(&self) -> u64 {
        self.warm_kept
    }

    /// The direct solve on active set `mask`: `z_A = lo_A`, `C_FF z_F = b_F − C_FA lo_A`,
    /// `r_A = (Cz − b)_A` (round-off below zero clamped). Returns whether the answer met the
    /// KKT conditions before the clamp: `r_A >= 0` and `z_j >= lo_j` off `A` (false on a NaN).
    fn solve_on_active_set(
        &mut self,
        mask: u8,
        rhs: &[f64],
        lower: &[f64],
        z: &mut [f64],
        reactions: &mut [f64],
    ) -> bool {
        let active = |j: usize| mask & (1 << j) != 0;
        z.copy_from_slice(rhs);
        for (j, &i) in self.nodes.iter().enumerate().filter(|&(j, _)| active(j)) {
            z[i] = lower[j];
            self.system.move_to_rhs(j, lower[j], mask, z);
        }
        self.system.solve_reduced_in_place(mask, z);
        let mut kkt = true;
        for (j, &i) in self.nodes.iter().enumerate() {
            if active(j) {
                // Round-off below zero clamped; a NaN kept, for the caller's finiteness check.
                let rj = self.system.row_product(j, z) - rhs[i];
                kkt &= rj >= 0.0;
                reactions[j] = if rj < 0.0 { 0.0 } else { rj };
            } else {
                kkt &= z[i] >= lower[j];
                reactions[j] = 0.0;
            }
        }
        kkt
    }

    /// Reactions and KKT violation of active set `mask` (bit k = constrained node k active),
    /// given `z⁰` at the constrained nodes.
    fn candidate(&self, mask: u8, z0: &[f64; 2], lower: &[f64]) -> ([f64; 2], f64) {
        let k = self.nodes.len();
        let s = &self.schur;
        let d = [lower[0] - z0[0], if k > 1 { lower[1] - z0[1] } else { 0.0 }];
        let r = masked_solve(s, &d, mask);
        let mut violation: f64 = 0.0;
        for j in 0..k {
            if mask & (1 << j) != 0 {
                // A negative reaction, in units of displacement.
                violation = violation.max(-r[j] * s[j][j]);
            } else {
                let zj = z0[j] + (0..k).map(|i| r[i] * s[j][i]).sum::<f64>();
                violation = violation.max(lower[j] - zj);
            }
        }
        (r, violation)
    }
}

impl<E: EndSystem> StepSolver for EndEnumeration<E> {
    fn name(&self) -> &'static str {
        "exact"
    }

    /// Without a constrained node, the solve and the update in one pass
    /// ([`EndSystem::solve_into_and_add`]).
    fn solve_and_advance(
        &mut self,
        rhs: &[f64],
        lower: &[f64],
        z: &mut [f64],
        reactions: &mut [f64],
        u: &mut [f64],
    ) -> Result<SolveInfo, StepFailure> {
        if self.nodes.is_empty() {
            self.system.solve_into_and_add(rhs, z, u);
            return Ok(SolveInfo { iterations: 1 });
        }
        let info = self.solve(rhs, lower, z, reactions)?;
        add_in_place(u, z);
        Ok(info)
    }

    /// The warm start on the previous active set; on a miss, `z⁰`, the enumeration and the
    /// direct solve on the set it chooses.
    fn solve(
        &mut self,
        rhs: &[f64],
        lower: &[f64],
        z: &mut [f64],
        reactions: &mut [f64],
    ) -> Result<SolveInfo, StepFailure> {
        let k = self.nodes.len();
        let mut missed = 0;
        if self.previous != 0 && self.warm_start {
            if self.solve_on_active_set(self.previous, rhs, lower, z, reactions) {
                self.warm_kept += 1;
                return Ok(SolveInfo { iterations: 1 });
            }
            missed = 1;
        }
        self.system.solve_into(rhs, z);
        if k == 0 {
            // Non-finite values anywhere are caught by the stepper's energy check.
            return Ok(SolveInfo { iterations: 1 });
        }
        let mut z0 = [0.0; 2];
        for (j, &i) in self.nodes.iter().enumerate() {
            z0[j] = z[i];
        }
        if z0[..k].iter().any(|v| !v.is_finite()) {
            return Err(StepFailure::NonFinite);
        }
        let (tried, mask, r) = least_violating(k, |mask| self.candidate(mask, &z0, lower));
        if !r[..k].iter().all(|v| v.is_finite()) {
            return Err(StepFailure::NonFinite);
        }
        self.previous = mask;
        reactions[..k].fill(0.0);
        if mask != 0 {
            self.solve_on_active_set(mask, rhs, lower, z, reactions);
            if !(z.iter().all(|v| v.is_finite()) && reactions[..k].iter().all(|v| v.is_finite())) {
                return Err(StepFailure::NonFinite);
            }
        }
        Ok(SolveInfo {
            iterations: missed + tried,
        })
    }
}

/// `C` of a free-free bar of 20 elements at `α = 1e6`, `Δt = 1e4 Δx`, and the `b` of a rigid
/// flight at `Δt v = −500` per step: the stiff case matrix's worst cancellation (tests of the
/// exact and penalty solvers).
#[cfg(test)]
pub(crate) fn rigid_flight() -> (SymTridiag, Vec<f64>) {
    use crate::bar::matrices::{MatrixVariant, mass, stiffness};
    let (elements, alpha) = (20usize, 1e6);
    let dx = 1.0 / elements as f64;
    let dt = 1e4 * dx;
    let nodes = elements + 1;
    let m = mass(MatrixVariant::Consistent, nodes, dx);
    let r = stiffness(MatrixVariant::Consistent, nodes, dx);
    let c = SymTridiag::combine(1.0 / (dt * dt), &m, 0.5 + alpha / (2.0 * dt), &r);
    let b = c.mul(&vec![-500.0; nodes]);
    (c, b)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::bar::matrices::{MatrixVariant, mass, stiffness};
    use crate::linalg::norms::max_abs;
    use crate::linalg::system::TridiagSystem;
    use crate::step::Constraints;
    use crate::step::audit::{KktAudit, Slack};
    use crate::step::law::{Law, LawFamily};

    /// The Signorini audit at its round-off floors of the answer `(z, r)` with data `(b, lo)`.
    fn audit_at_round_off(
        c: &SymTridiag,
        ends: &[usize],
        b: &[f64],
        lo: &[f64],
        z: &[f64],
        r: &[f64],
    ) {
        let mut system = TridiagSystem::new(c).unwrap();
        let constraints = Constraints::lower_bounds(ends);
        let mut audit = KktAudit::new(&mut system, &constraints, LawFamily::Signorini);
        (audit.check(&mut system, Law::Signorini, Slack::NONE, b, lo, z, r)).unwrap();
    }

    /// Two direct solves of the same reduced system (different elimination orders), each a
    /// few ulps of `max|z|` off, agree to this many.
    const DIRECT_SOLVES_AGREE_ULPS: f64 = 64.0;

    /// Regression (found by the stiff case matrix): a free-free bar of 20 elements at
    /// `α = 1e6`, `Δt = 1e4 Δx`, flying rigidly at `Δt v = −500` per step onto obstacles at gap 0
    /// under both ends. A superposition `z⁰ + Σ r_j c_j` cancels 500 down to about 1e-7 there
    /// and returns an answer off by about itself; the direct solve on the chosen set must pass
    /// the KKT audit at its round-off floors and equal the block-pivoting solver's direct solve.
    #[test]
    fn stiff_impact_stopping_a_rigid_flight_is_solved_to_round_off() {
        let (c, b) = rigid_flight();
        let nodes = c.dim();
        let ends = [0, nodes - 1];
        let lower = [0.0, 0.0];
        let (mut z, mut reactions) = (vec![0.0; nodes], [0.0; 2]);
        let mut solver = EndEnumeration::new(&c, &ends).unwrap();
        solver.solve(&b, &lower, &mut z, &mut reactions).unwrap();
        assert!(reactions.iter().all(|r| *r > 0.0), "both ends stop the bar");
        audit_at_round_off(&c, &ends, &b, &lower, &z, &reactions);

        let mut pivot = crate::step::block_pivot::BlockPivoting::new(&c, &ends).unwrap();
        let (mut z_pivot, mut r_pivot) = (vec![0.0; nodes], [0.0; 2]);
        pivot.solve(&b, &lower, &mut z_pivot, &mut r_pivot).unwrap();
        let tol = DIRECT_SOLVES_AGREE_ULPS * f64::EPSILON * max_abs(&z_pivot);
        for (a, p) in z.iter().zip(&z_pivot) {
            assert!((a - p).abs() <= tol, "{a:e} vs {p:e}");
        }
    }

    /// The warm start on the stiff rigid flight (both ends stopped) and on a mild bar: the
    /// second call keeps the first call's active set (one set tried) and gives the bits of a
    /// fresh solver's enumerated answer (the same direct solve on the same set), which passes
    /// the KKT audit at its round-off floors. When the contact set changes (one bound dropped
    /// far below), the warm answer fails KKT and the step is enumerated: the bits of a fresh
    /// solver's answer, with the wasted attempt counted as a set tried.
    #[test]
    fn warm_start_keeps_a_lasting_contact_and_enumerates_when_it_changes() {
        let (stiff, b_stiff) = rigid_flight();
        let mild = {
            let elements = 50;
            let dx = 1.0 / elements as f64;
            let c = SymTridiag::combine(
                1.0 / (dx * dx),
                &mass(MatrixVariant::Consistent, elements + 1, dx),
                0.5 + 0.1 / (2.0 * dx),
                &stiffness(MatrixVariant::Consistent, elements + 1, dx),
            );
            let b = c.mul(&vec![-0.01; elements + 1]);
            (c, b)
        };
        let bits = |v: &[f64]| v.iter().map(|x| x.to_bits()).collect::<Vec<_>>();
        for (c, b) in [(&stiff, &b_stiff), (&mild.0, &mild.1)] {
            let nodes = c.dim();
            let ends = [0, nodes - 1];
            let fresh = |lower: &[f64; 2]| {
                let mut s = EndEnumeration::new(c, &ends).unwrap();
                let (mut z, mut r) = (vec![0.0; nodes], [0.0; 2]);
                let info = s.solve(b, lower, &mut z, &mut r).unwrap();
                (z, r, info.iterations)
            };
            let both = [0.0, 0.0];
            let (z_enum, r_enum, _) = fresh(&both);
            assert!(r_enum.iter().all(|r| *r > 0.0), "both ends in contact");

            let mut solver = EndEnumeration::new(c, &ends).unwrap();
            let (mut z, mut r) = (vec![0.0; nodes], [0.0; 2]);
            for call in 0..2 {
                let info = solver.solve(b, &both, &mut z, &mut r).unwrap();
                assert_eq!(solver.warm_steps(), call, "warm on the second call only");
                assert_eq!(info.iterations, if call == 0 { 4 } else { 1 });
            }
            assert_eq!((bits(&z), bits(&r)), (bits(&z_enum), bits(&r_enum)));
            audit_at_round_off(c, &ends, b, &both, &z, &r);

            // The right end released: its warm reaction would be negative.
            let released = [0.0, -1e9];
            let info = solver.solve(b, &released, &mut z, &mut r).unwrap();
            assert_eq!(solver.warm_steps(), 1, "a miss is not counted as warm");
            let (z_fresh, r_fresh, tried) = fresh(&released);
            assert_eq!((bits(&z), bits(&r)), (bits(&z_fresh), bits(&r_fresh)));
            assert_eq!(info.iterations, tried + 1);
            assert!(r[0] > 0.0 && r[1] == 0.0, "r = {r:?}");

            // Back to both bounds: the warm set {left} now leaves the right end below its bound.
            let info = solver.solve(b, &both, &mut z, &mut r).unwrap();
            assert_eq!(solver.warm_steps(), 1, "a miss is not counted as warm");
            let (z_fresh, r_fresh, tried) = fresh(&both);
            assert_eq!((bits(&z), bits(&r)), (bits(&z_fresh), bits(&r_fresh)));
            assert_eq!(info.iterations, tried + 1);
        }
    }
}
