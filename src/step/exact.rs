//! The exact step solver: active-set enumeration over at most two constrained nodes.
//!
//! With the unconstrained solution `z⁰ = C⁻¹ b` and the columns `c_j = C⁻¹ e_j` (computed once per
//! run), the solution for an active set `A` is `z = z⁰ + Σ_{j∈A} r_j c_j` with the reactions from
//! the Schur system `S_AA r_A = lo_A − z⁰_A`, `S_jk = (C⁻¹)_jk`. The QP is strictly convex, so
//! exactly one active set satisfies the KKT conditions (up to ties, where a bound is active with
//! a zero reaction and two sets give the same point). In floating point the candidates are
//! ranked by their KKT violation, measured in units of displacement, and the first set with the
//! smallest violation in the order ∅, {first}, {second}, {both} wins: deterministic, and equal to
//! the exact answer whenever that one satisfies KKT to round-off.
//!
//! Warm start on the previous active set and the direct re-solve that guards against
//! cancellation: [docs/step-solvers.md](../docs/step-solvers.md#exact-solver).

use crate::linalg::ldlt::{Ldlt, NotPositiveDefinite, RowChange};
use crate::linalg::tridiag::SymTridiag;
use crate::linalg::update::{add_columns_in_place, add_in_place};
use crate::step::schur::{
    Column, constraint_rows, factor_each_subset, inverse_columns, least_violating, masked_solve,
    row_product, schur_complement,
};
use crate::step::{SolveInfo, StepFailure, StepSolver};

/// Largest cancellation `max|z⁰| / max(|z|, |u^n|)` over the columns' support accepted from
/// the superposition `z⁰ + Σ r_j c_j`: its rounding error is about `ε max|z⁰|`, i.e. this many
/// ulps of `|z|` or of the state `u^n` it is added to, against the few ulps of a direct solve;
/// beyond it the step is solved directly (the audit's round-off floor,
/// `audit::ROUNDOFF_ULPS = 32`, leaves room for 8 and the solve's own ulps). Measured against
/// `|u^n|` too because an error below a few ulps of `u^n` is lost in `u^n + z` anyway, while
/// a bar settling on an obstacle (`z ≈ 0` at the contact, `z⁰` one step of free fall) would
/// otherwise pay for a second solve on every step.
pub const RESOLVE_CANCELLATION: f64 = 8.0;

/// Exact enumeration for zero, one or two constrained nodes.
#[derive(Clone, Debug)]
pub struct ExactSolver {
    factor: Ldlt,
    columns: Vec<Column>,
    /// `S = (C⁻¹)_{jk}` on the constrained nodes.
    schur: [[f64; 2]; 2],
    /// Row `i` of `C` at each constrained node `i`: `C_i,i−1`, `C_i,i+1` (0 where absent) and
    /// the row sum (all the direct solve reads of `C`).
    rows: [[f64; 3]; 2],
    /// The factorisation of `C` with the rows and columns of active set `mask` replaced by
    /// identity ones, at index `mask − 1` (halves shared with `factor` where equal).
    reduced: Vec<Ldlt>,
    /// Steps recomputed by the direct solve (cancellation beyond [`RESOLVE_CANCELLATION`]).
    resolved: u64,
    /// Steps whose superposition and `u += z` were one pass ([`ExactSolver::superpose_and_add`]).
    merged: u64,
    /// `max|u^n|` of the state `z` is added to ([`StepSolver::set_state_scale`]; 0 if not given).
    state_scale: f64,
    /// The active set of the last answer (the mask of [`ExactSolver::enumerate`]), tried first.
    previous: u8,
    /// Steps answered by the direct solve on the previous active set ([`ExactSolver::warm`]).
    warm_kept: u64,
}

impl ExactSolver {
    /// Factorises `C` and precomputes `C⁻¹ e_j` for each constrained node (at most two).
    pub fn new(c: &SymTridiag, nodes: &[usize]) -> Result<Self, NotPositiveDefinite> {
        assert!(
            nodes.len() <= 2,
            "the end-node enumeration handles at most two bounds"
        );
        let factor = Ldlt::factor(c)?;
        let columns = inverse_columns(&factor, nodes);
        let schur = schur_complement(&columns);
        let reduced = factor_each_subset(c, nodes, RowChange::Identity, &factor)?;
        let rows = constraint_rows(c, nodes);
        Ok(Self {
            factor,
            columns,
            schur,
            rows,
            reduced,
            resolved: 0,
            merged: 0,
            state_scale: 0.0,
            previous: 0,
            warm_kept: 0,
        })
    }

    /// Steps so far whose superposition cancelled beyond [`RESOLVE_CANCELLATION`] and were
    /// recomputed by the direct solve.
    pub fn resolved_steps(&self) -> u64 {
        self.resolved
    }

    /// Steps so far answered by the direct solve on the previous step's active set (the warm
    /// start met the KKT conditions, no enumeration).
    pub fn warm_steps(&self) -> u64 {
        self.warm_kept
    }

    /// Steps so far whose superposition and `u += z` were one pass (through
    /// [`StepSolver::solve_and_advance`]).
    pub fn merged_steps(&self) -> u64 {
        self.merged
    }

    /// The direct solve on active set `mask`: `z_A = lo_A`, `C_FF z_F = b_F − C_FA lo_A`,
    /// `r_A = (Cz − b)_A` (round-off below zero clamped, as in `active_set`). Returns whether
    /// the answer met the KKT conditions before the clamp: `r_A >= 0` and `z_j >= lo_j` off
    /// `A` (false on a NaN).
    fn solve_on_active_set(
        &self,
        mask: u8,
        rhs: &[f64],
        lower: &[f64],
        z: &mut [f64],
        reactions: &mut [f64],
    ) -> bool {
        let mut kkt = true;
        let n = z.len();
        z.copy_from_slice(rhs);
        let active = |i: usize| {
            self.columns
                .iter()
                .enumerate()
                .any(|(j, col)| col.node == i && mask & (1 << j) != 0)
        };
        for (j, col) in self.columns.iter().enumerate() {
            if mask & (1 << j) == 0 {
                continue;
            }
            let (i, [left, right, _]) = (col.node, self.rows[j]);
            z[i] = lower[j];
            if i > 0 && !active(i - 1) {
                z[i - 1] -= left * lower[j];
            }
            if i + 1 < n && !active(i + 1) {
                z[i + 1] -= right * lower[j];
            }
        }
        self.reduced[mask as usize - 1].solve_in_place(z);
        for (j, col) in self.columns.iter().enumerate() {
            reactions[j] = 0.0;
            if mask & (1 << j) == 0 {
                continue;
            }
            let i = col.node;
            // Round-off below zero clamped; a NaN kept, for the caller's finiteness check.
            let rj = row_product(self.rows[j], i, z) - rhs[i];
            kkt &= rj >= 0.0;
            reactions[j] = if rj < 0.0 { 0.0 } else { rj };
        }
        for (j, col) in self.columns.iter().enumerate() {
            if mask & (1 << j) == 0 {
                kkt &= z[col.node] >= lower[j];
            }
        }
        kkt
    }

    /// Warm start: the direct solve on the previous answer's active set, kept when it meets the
    /// KKT conditions exactly in floating point (unclamped reactions `>= 0` on the set,
    /// `z_j >= lo_j` off it). `None` when there is nothing to try (the previous set was empty:
    /// the enumeration tries ∅ first anyway), else whether the answer was kept; a miss leaves
    /// `z` and `reactions` to be overwritten.
    fn warm(
        &mut self,
        rhs: &[f64],
        lower: &[f64],
        z: &mut [f64],
        reactions: &mut [f64],
    ) -> Option<bool> {
        if self.previous == 0 {
            return None;
        }
        let kept = self.solve_on_active_set(self.previous, rhs, lower, z, reactions);
        self.warm_kept += u64::from(kept);
        Some(kept)
    }

    /// Reactions and KKT violation of active set `mask` (bit k = constrained node k active),
    /// given `z⁰` at the constrained nodes.
    fn candidate(&self, mask: u8, z0: &[f64; 2], lower: &[f64]) -> ([f64; 2], f64) {
        let k = self.columns.len();
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

impl StepSolver for ExactSolver {
    fn name(&self) -> &'static str {
        "exact"
    }

    fn set_state_scale(&mut self, max_abs_u: f64) {
        self.state_scale = max_abs_u;
    }

    fn solve(
        &mut self,
        rhs: &[f64],
        lower: &[f64],
        z: &mut [f64],
        reactions: &mut [f64],
    ) -> Result<SolveInfo, StepFailure> {
        let missed = match self.warm(rhs, lower, z, reactions) {
            Some(true) => return Ok(SolveInfo { iterations: 1 }),
            Some(false) => 1,
            None => 0,
        };
        let Some((tried, mask)) = self.active_set(rhs, lower, z, reactions)? else {
            // Non-finite values anywhere are caught by the stepper's energy check.
            return Ok(SolveInfo { iterations: 1 });
        };
        self.superpose_or_resolve(mask, rhs, lower, z, reactions)?;
        Ok(SolveInfo {
            iterations: missed + tried,
        })
    }

    /// As [`StepSolver::solve`] then `u += z`, with the same bits, but when the cancellation
    /// test cannot fire (see `ExactSolver::superpose_and_add`) the superposition and the
    /// addition are one pass over the bar instead of two.
    fn solve_and_advance(
        &mut self,
        rhs: &[f64],
        lower: &[f64],
        u: &mut [f64],
        z: &mut [f64],
        reactions: &mut [f64],
    ) -> Result<(SolveInfo, f64), StepFailure> {
        if self.columns.is_empty() {
            // Nothing to enumerate: the update is made inside the solve, and the state scale
            // (read only by the cancellation test of constrained steps) is not needed.
            self.factor.solve_into_and_add(rhs, z, u);
            return Ok((SolveInfo { iterations: 1 }, 0.0));
        }
        let missed = match self.warm(rhs, lower, z, reactions) {
            Some(true) => return Ok((SolveInfo { iterations: 1 }, add_in_place(u, z))),
            Some(false) => 1,
            None => 0,
        };
        let Some((tried, mask)) = self.active_set(rhs, lower, z, reactions)? else {
            return Ok((SolveInfo { iterations: 1 }, add_in_place(u, z)));
        };
        let info = SolveInfo {
            iterations: missed + tried,
        };
        if let Some(max_abs) = self.superpose_and_add(mask, lower, u, z, reactions) {
            self.merged += 1;
            return Ok((info, max_abs));
        }
        self.superpose_or_resolve(mask, rhs, lower, z, reactions)?;
        Ok((info, add_in_place(u, z)))
    }
}

impl ExactSolver {
    /// `z = z⁰ = C⁻¹ b`, then the active set by enumeration ([`ExactSolver::enumerate`]):
    /// `(sets tried, mask)`, or `None` when no node is constrained.
    fn active_set(
        &mut self,
        rhs: &[f64],
        lower: &[f64],
        z: &mut [f64],
        reactions: &mut [f64],
    ) -> Result<Option<(u32, u8)>, StepFailure> {
        self.factor.solve_into(rhs, z);
        if self.columns.is_empty() {
            return Ok(None);
        }
        let (tried, mask) = self.enumerate(lower, z, reactions)?;
        self.previous = mask;
        Ok(Some((tried, mask)))
    }

    /// [`ExactSolver::superpose`], and the direct solve when it cancelled.
    fn superpose_or_resolve(
        &mut self,
        mask: u8,
        rhs: &[f64],
        lower: &[f64],
        z: &mut [f64],
        reactions: &mut [f64],
    ) -> Result<(), StepFailure> {
        if self.superpose(mask, lower, z, reactions)? {
            self.resolve(mask, rhs, lower, z, reactions)?;
        }
        Ok(())
    }

    /// The direct solve of a step whose superposition cancelled (counted).
    fn resolve(
        &mut self,
        mask: u8,
        rhs: &[f64],
        lower: &[f64],
        z: &mut [f64],
        reactions: &mut [f64],
    ) -> Result<(), StepFailure> {
        self.resolved += 1;
        self.solve_on_active_set(mask, rhs, lower, z, reactions);
        if !z.iter().all(|v| v.is_finite()) {
            return Err(StepFailure::NonFinite);
        }
        if !reactions[..self.columns.len()]
            .iter()
            .all(|v| v.is_finite())
        {
            return Err(StepFailure::NonFinite);
        }
        Ok(())
    }

    /// Given `z = z⁰`: the active set by enumeration (bit `j` of the mask: node `j` active)
    /// and its reactions; returns the number of sets tried and the mask.
    fn enumerate(
        &self,
        lower: &[f64],
        z: &[f64],
        reactions: &mut [f64],
    ) -> Result<(u32, u8), StepFailure> {
        let k = self.columns.len();
        let mut z0 = [0.0; 2];
        for (j, col) in self.columns.iter().enumerate() {
            z0[j] = z[col.node];
        }
        if z0[..k].iter().any(|v| !v.is_finite()) {
            return Err(StepFailure::NonFinite);
        }
        let (tried, mask, r) = least_violating(k, |mask| self.candidate(mask, &z0, lower));
        for (j, rj) in reactions[..k].iter_mut().enumerate() {
            *rj = if mask & (1 << j) != 0 { r[j] } else { 0.0 };
        }
        if !reactions[..k].iter().all(|v| v.is_finite()) {
            return Err(StepFailure::NonFinite);
        }
        Ok((tried, mask))
    }

    /// `z = z⁰ + Σ r_j c_j`, `z_j = lo_j` on the active set; returns whether the superposition
    /// cancelled beyond [`RESOLVE_CANCELLATION`] (then the step must be solved directly).
    fn superpose(
        &self,
        mask: u8,
        lower: &[f64],
        z: &mut [f64],
        reactions: &[f64],
    ) -> Result<bool, StepFailure> {
        let k = self.columns.len();
        // max|z⁰| before and max|z| after the superposition, over the columns' support.
        let (mut before, mut after) = (0.0f64, 0.0f64);
        let both = k == 2 && reactions[0] != 0.0 && reactions[1] != 0.0;
        let (s0, s1) = (
            &self.columns[0].support,
            self.columns.get(1).map_or(0..0, |c| c.support.clone()),
        );
        let max_abs = |v: &[f64]| v.iter().fold(0.0f64, |m, x| m.max(x.abs()));
        if both && *s0 == s1 {
            // Both columns over the same support (a stiff C): one pass, same bits as two.
            (before, after) =
                self.columns[0].add_scaled_pair(reactions[0], &self.columns[1], reactions[1], z);
        } else if both && s0.start.max(s1.start) < s0.end.min(s1.end) {
            // Partly overlapping supports: measure z⁰ and z over the union (rare: not the
            // stiff case, whose supports are the whole bar, nor the short-column case).
            let union = s0.start.min(s1.start)..s0.end.max(s1.end);
            before = max_abs(&z[union.clone()]);
            self.columns[0].add_scaled(reactions[0], z);
            self.columns[1].add_scaled(reactions[1], z);
            after = max_abs(&z[union]);
        } else {
            // Disjoint supports (or one active column): each pass sees z⁰ and final values.
            for (j, col) in self.columns.iter().enumerate() {
                if reactions[j] != 0.0 {
                    let (b, a) = col.add_scaled(reactions[j], z);
                    before = before.max(b);
                    after = after.max(a);
                }
            }
        }
        for (j, col) in self.columns.iter().enumerate() {
            if mask & (1 << j) != 0 {
                z[col.node] = lower[j];
            }
        }
        Ok(before > RESOLVE_CANCELLATION * after.max(self.state_scale))
    }

    /// The superposition and `u += z` in one pass over the bar, when the cancellation test
    /// cannot fire and the active nodes are end nodes (left out of the pass and set to
    /// `lo_j` after). The test measures `max|z⁰| > 8 max(max|z|, s)` with `s = max|u^n|`;
    /// since `|z⁰_i| <= |z_i| + Σ|r_j| max|c_j|` (up to a few ulps), a bound
    /// `Σ|r_j| max|c_j| <= 6 s` rules it out, and the maxima it would track are skipped.
    /// The bar is cut where the columns' supports start and end, and each piece adds the
    /// columns it meets: the same arithmetic, so the same bits, as
    /// [`ExactSolver::superpose`] followed by [`add_in_place`]. Returns `max|u^{n+1}|`, or
    /// `None` (nothing done) when the conditions do not hold.
    fn superpose_and_add(
        &self,
        mask: u8,
        lower: &[f64],
        u: &mut [f64],
        z: &mut [f64],
        reactions: &[f64],
    ) -> Option<f64> {
        let n = z.len();
        let bound: f64 = (self.columns.iter().zip(reactions))
            .map(|(col, r)| r.abs() * col.max_abs)
            .sum();
        // Negated so that a NaN bound takes the checked path.
        #[allow(clippy::neg_cmp_op_on_partial_ord)]
        if !(bound <= (RESOLVE_CANCELLATION - 2.0) * self.state_scale) {
            return None;
        }
        let active = |j: usize| mask & (1 << j) != 0;
        let (mut first, mut end) = (0, n);
        for (j, col) in self.columns.iter().enumerate() {
            match col.node {
                _ if !active(j) => {}
                0 => first = 1,
                node if node + 1 == n => end = n - 1,
                _ => return None,
            }
        }
        let first = first.min(end);
        let live = |(_, r): (&Column, &f64)| *r != 0.0;
        let covers =
            |(col, _): (&Column, &f64)| col.support.start <= first && col.support.end >= end;
        let mut max_abs = if (self.columns.iter().zip(reactions))
            .filter(|&t| live(t))
            .all(covers)
        {
            // Every column in play covers the whole range (the usual case: one piece).
            let mut terms = (self.columns.iter().zip(reactions))
                .filter(|&t| live(t))
                .map(|(col, &r)| {
                    (
                        r,
                        &col.values[first - col.support.start..end - col.support.start],
                    )
                });
            let (u, z) = (&mut u[first..end], &mut z[first..end]);
            match (terms.next(), terms.next()) {
                (None, _) => add_in_place(u, z),
                (Some(t), None) => add_columns_in_place(u, z, [t]),
                (Some(t), Some(t2)) => add_columns_in_place(u, z, [t, t2]),
            }
        } else {
            self.add_in_pieces(first, end, u, z, reactions)
        };
        for (j, col) in self.columns.iter().enumerate() {
            if active(j) {
                z[col.node] = lower[j];
                u[col.node] += lower[j];
                max_abs = max_abs.max(u[col.node].abs());
            }
        }
        Some(max_abs)
    }

    /// The superposition and `u += z` over `first..end` for columns whose supports cut it
    /// into pieces: each piece adds the columns it meets (see
    /// [`ExactSolver::superpose_and_add`]); returns `max|u|` over the range.
    fn add_in_pieces(
        &self,
        first: usize,
        end: usize,
        u: &mut [f64],
        z: &mut [f64],
        reactions: &[f64],
    ) -> f64 {
        // Pieces of constant column set between consecutive cuts.
        let mut cuts = [first, end, first, end, first, end];
        for (k, col) in self.columns.iter().enumerate() {
            let clamp = |i: usize| i.clamp(first, end);
            cuts[2 + 2 * k] = clamp(col.support.start);
            cuts[3 + 2 * k] = clamp(col.support.end);
        }
        cuts.sort_unstable();
        let mut max_abs = 0.0f64;
        for (a, b) in cuts.iter().zip(&cuts[1..]).map(|(&a, &b)| (a, b)) {
            if a == b {
                continue;
            }
            let mut terms = (self.columns.iter().zip(reactions))
                .filter(|(col, r)| **r != 0.0 && col.support.contains(&a))
                .map(|(col, &r)| {
                    let s = col.support.start;
                    (r, &col.values[a - s..b - s])
                });
            let (u, z) = (&mut u[a..b], &mut z[a..b]);
            let m = match (terms.next(), terms.next()) {
                (None, _) => add_in_place(u, z),
                (Some((r, c)), None) => add_columns_in_place(u, z, [(r, c)]),
                (Some((r, c)), Some(t)) => add_columns_in_place(u, z, [(r, c), t]),
            };
            max_abs = max_abs.max(m);
        }
        max_abs
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
    use crate::step::audit::{KktAudit, Law};

    /// Two direct solves of the same reduced system, each a few ulps of `max|z|` off, agree to
    /// this many.
    const DIRECT_SOLVES_AGREE_ULPS: f64 = 64.0;

    /// Regression (found by the stiff case matrix): a free-free bar of 20 elements at
    /// `α = 1e6`, `Δt = 1e4 Δx`, flying rigidly at `Δt v = −500` per step onto obstacles at gap 0
    /// under both ends. The superposition `z⁰ + Σ r_j c_j` cancelled 500 down to about 1e-7
    /// and returned an answer off by about itself. The answer must now pass the KKT audit at its round-off
    /// floors in displacement and equal the block-pivoting solver's direct solve.
    #[test]
    fn stiff_impact_stopping_a_rigid_flight_is_solved_to_round_off() {
        let (c, b) = rigid_flight();
        let nodes = c.dim();
        let ends = [0, nodes - 1];
        let lower = [0.0, 0.0];
        let (mut z, mut reactions) = (vec![0.0; nodes], [0.0; 2]);
        let mut solver = ExactSolver::new(&c, &ends).unwrap();
        solver.solve(&b, &lower, &mut z, &mut reactions).unwrap();
        assert_eq!(solver.resolved_steps(), 1);
        let mut audit = KktAudit::new(&c, &ends, false).unwrap();
        let law = Law::Signorini {
            eps_abs: 0.0,
            eps_rel: 0.0,
        };
        audit.check(law, &b, &lower, &z, &reactions).unwrap();

        let mut pivot = crate::step::block_pivot::BlockPivotSolver::new(&c, &ends).unwrap();
        let (mut z_pivot, mut r_pivot) = (vec![0.0; nodes], [0.0; 2]);
        pivot.solve(&b, &lower, &mut z_pivot, &mut r_pivot).unwrap();
        let z_max = z_pivot.iter().fold(0.0f64, |a, v| a.max(v.abs()));
        // Both are direct solves of the same reduced system: equal to a few ulps of |z|.
        let tol = DIRECT_SOLVES_AGREE_ULPS * f64::EPSILON * z_max;
        for (a, p) in z.iter().zip(&z_pivot) {
            assert!((a - p).abs() <= tol, "{a:e} vs {p:e}");
        }
    }

    /// `solve_and_advance` against `solve` then `u += z` (the two-pass path it replaces),
    /// bit for bit, with one and with two bounds active, in a state large enough that the
    /// cancellation test cannot fire (one merged pass): on the stiff bar (both columns span
    /// the bar), a mild bar of 600 elements (the supports, about 450 nodes each, overlap in
    /// part) and of 2000 elements (disjoint supports); and once with a small state, where
    /// the two passes must remain.
    #[test]
    fn merged_superposition_and_update_has_the_bits_of_the_two_passes() {
        let (stiff, b_stiff) = rigid_flight();
        // Columns decay by about 5 a node here: below f64::MIN_POSITIVE after ~450 nodes.
        let mild = |elements: usize| {
            let dx = 1.0 / elements as f64;
            let c = SymTridiag::combine(
                1.0 / (dx * dx),
                &mass(MatrixVariant::Consistent, elements + 1, dx),
                0.5,
                &stiffness(MatrixVariant::Consistent, elements + 1, dx),
            );
            let b = c.mul(&vec![-0.01; elements + 1]);
            (c, b)
        };
        let ((overlap, b_overlap), (disjoint, b_disjoint)) = (mild(600), mild(2000));
        let (large, small) = (1e6, 1e-3);
        let cases = [
            (&stiff, &b_stiff, [0.0, 0.0], large, 1),
            (&stiff, &b_stiff, [0.0, -1e9], large, 1),
            (&stiff, &b_stiff, [0.0, 0.0], small, 0),
            (&overlap, &b_overlap, [0.0, 0.0], large, 1),
            (&overlap, &b_overlap, [-1e9, 0.0], large, 1),
            (&disjoint, &b_disjoint, [0.0, 0.0], large, 1),
        ];
        for (c, b, lower, state, merged) in cases {
            let nodes = c.dim();
            let ends = [0, nodes - 1];
            let u0: Vec<f64> = (0..nodes).map(|i| state * (1.0 + i as f64)).collect();
            let scale = max_abs(&u0);
            let mut two_pass = ExactSolver::new(c, &ends).unwrap();
            two_pass.set_state_scale(scale);
            let (s0, s1) = (&two_pass.columns[0].support, &two_pass.columns[1].support);
            let shape = if s0 == s1 {
                "same"
            } else if s0.end > s1.start {
                "overlap"
            } else {
                "disjoint"
            };
            let expected = match nodes {
                601 => "overlap",
                2001 => "disjoint",
                _ => "same",
            };
            assert_eq!(shape, expected, "supports {s0:?}, {s1:?}");
            let (mut z1, mut r1, mut u1) = (vec![0.0; nodes], [0.0; 2], u0.clone());
            two_pass.solve(b, &lower, &mut z1, &mut r1).unwrap();
            let m1 = add_in_place(&mut u1, &z1);
            let mut one_pass = ExactSolver::new(c, &ends).unwrap();
            one_pass.set_state_scale(scale);
            let (mut z2, mut r2, mut u2) = (vec![0.0; nodes], [0.0; 2], u0.clone());
            let (_, m2) = one_pass
                .solve_and_advance(b, &lower, &mut u2, &mut z2, &mut r2)
                .unwrap();
            assert_eq!(one_pass.merged_steps(), merged, "lower {lower:?}");
            assert!(r2.iter().any(|r| *r > 0.0), "a bound is active");
            let bits = |v: &[f64]| v.iter().map(|x| x.to_bits()).collect::<Vec<_>>();
            assert_eq!(bits(&z1), bits(&z2));
            assert_eq!(bits(&u1), bits(&u2));
            assert_eq!(bits(&r1), bits(&r2));
            assert_eq!(m1.to_bits(), m2.to_bits());
        }
    }

    /// The same step added to a state of size 1e3 (> 500 / 8): the superposition's error,
    /// about `ε · 500`, is below 8 ulps of that state, so no second solve; with the state at
    /// 10 it is not, and the step is solved again.
    #[test]
    fn cancellation_is_weighed_against_the_state_it_is_added_to() {
        let (c, b) = rigid_flight();
        let nodes = c.dim();
        let ends = [0, nodes - 1];
        let (mut z, mut reactions) = (vec![0.0; nodes], [0.0; 2]);
        for (state, resolved) in [(1e3, 0), (10.0, 1)] {
            // A fresh solver: a second call on the same one would keep the first's active set
            // by the warm start and never superpose.
            let mut solver = ExactSolver::new(&c, &ends).unwrap();
            solver.set_state_scale(state);
            solver
                .solve(&b, &[0.0, 0.0], &mut z, &mut reactions)
                .unwrap();
            assert_eq!(solver.resolved_steps(), resolved, "state {state}");
        }
    }

    /// The warm start on the stiff rigid flight (both ends stopped) and on a mild bar: the
    /// second call keeps the first call's active set by the direct solve, passes the KKT audit
    /// at its round-off floors and agrees with the enumeration of a fresh solver; `solve` and
    /// `solve_and_advance` give the same bits on it. When the contact set changes (one
    /// bound dropped far below), the warm answer fails KKT and the step is enumerated: the
    /// bits of a fresh solver's answer, with the wasted attempt counted as a set tried.
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
                let mut s = ExactSolver::new(c, &ends).unwrap();
                let (mut z, mut r) = (vec![0.0; nodes], [0.0; 2]);
                let info = s.solve(b, lower, &mut z, &mut r).unwrap();
                (z, r, info.iterations)
            };
            let both = [0.0, 0.0];
            let (z_enum, r_enum, _) = fresh(&both);
            assert!(r_enum.iter().all(|r| *r > 0.0), "both ends in contact");

            let mut solver = ExactSolver::new(c, &ends).unwrap();
            let mut advancing = ExactSolver::new(c, &ends).unwrap();
            let (mut z, mut r) = (vec![0.0; nodes], [0.0; 2]);
            let (mut z2, mut r2, mut u2) = (vec![0.0; nodes], [0.0; 2], vec![0.0; nodes]);
            for call in 0..2 {
                let info = solver.solve(b, &both, &mut z, &mut r).unwrap();
                u2.fill(1.0);
                advancing
                    .solve_and_advance(b, &both, &mut u2, &mut z2, &mut r2)
                    .unwrap();
                assert_eq!(solver.warm_steps(), call, "warm on the second call only");
                assert_eq!(info.iterations, if call == 0 { 4 } else { 1 });
            }
            assert_eq!((bits(&z), bits(&r)), (bits(&z2), bits(&r2)));
            let mut audit = KktAudit::new(c, &ends, false).unwrap();
            let law = Law::Signorini {
                eps_abs: 0.0,
                eps_rel: 0.0,
            };
            audit.check(law, b, &both, &z, &r).unwrap();
            let z_max = max_abs(&z_enum);
            // The direct solve against the enumeration's answer (direct too on the stiff bar,
            // superposed on the mild one): both to a few ulps of |z|.
            let tol = DIRECT_SOLVES_AGREE_ULPS * f64::EPSILON * z_max;
            for (a, e) in z.iter().zip(&z_enum) {
                assert!((a - e).abs() <= tol, "{a:e} vs {e:e}");
            }

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
