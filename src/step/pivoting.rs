//! Block principal pivoting (Júdice & Pires, Comput. Oper. Res. 21, 1994) safeguarded by
//! Murty's single pivoting rule (Murty 1974), for an LCP with a P-matrix, written once for
//! every solver that runs it ([`crate::step::block_pivot`] on the bar's tridiagonal `C`,
//! [`crate::step::lcp`] on the dense condensed `S`). Each solver supplies its own solve on an
//! active set and its list of infeasible indices ([`ActiveSetProblem`]); [`pivot`] decides
//! which indices flip: every infeasible one while their number reaches new minima (with
//! [`BLOCK_PATIENCE`] tries of grace), then one at a time by Murty's rule in the solver's fixed
//! order. It stops at the first active set with no infeasible index, or with the solver's
//! iteration-limit error: never at an unverified point. Termination and the tie threshold:
//! `docs/step-solvers.md#block-principal-pivoting`.

/// Block iterations allowed without a decrease of the number of infeasible indices before the
/// single-pivot safeguard takes over (Júdice & Pires use a small constant; 10 keeps the fast
/// block steps through transient increases).
pub const BLOCK_PATIENCE: u32 = 10;
/// An index counts as infeasible only beyond this many ulps of the scale of the quantity
/// compared (each solver states its scales; `round_off_threshold`): below it, the sign is
/// round-off and either choice satisfies KKT. Half the audit's floor
/// ([`crate::step::audit::ROUNDOFF_ULPS`] = 32, on the same scales), so that an accepted answer
/// also passes the audit with room for the rounding of its recomputed residuals (64 on
/// `max|z| + max|lo|` let the talk's distributed scene end a step 1.4 times over the audit's
/// primal floor).
pub const TIE_ULPS: f64 = 16.0;

/// The round-off threshold [`TIE_ULPS`] ulps of `scale`: a margin below `−threshold` is
/// infeasible, one above it is feasible or a tie.
#[inline(always)]
pub fn round_off_threshold(scale: f64) -> f64 {
    TIE_ULPS * f64::EPSILON * scale
}

/// The iteration limit for `constraints` indices: Murty's rule is finite but may in theory
/// need exponentially many pivots; beyond this the solve fails with an error instead of
/// returning an unverified point.
pub fn iteration_limit(constraints: usize) -> u32 {
    50 * (constraints as u32).max(1) + 100
}

/// The fixed order in which Murty's rule picks the single index to flip.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum MurtyOrder {
    /// The least infeasible index.
    LeastIndex,
    /// The greatest infeasible index (the least one with the indices numbered backwards).
    GreatestIndex,
}

/// One LCP as a solver sees it: its active set, a solve on it, and the verdict per index.
pub trait ActiveSetProblem {
    /// What a failed solve, or the iteration limit, returns.
    type Error;
    /// The order of Murty's single pivots.
    const MURTY_ORDER: MurtyOrder;
    /// Solves on the current active set and lists the infeasible indices (in increasing
    /// order) for [`ActiveSetProblem::infeasible`].
    fn solve_active_set(&mut self) -> Result<(), Self::Error>;
    /// The infeasible indices of the last solve, increasing; empty at the solution.
    fn infeasible(&self) -> &[usize];
    /// Flips every infeasible index (active to free, free to active).
    fn flip_all_infeasible(&mut self);
    /// Flips the one index `index`.
    fn flip_one(&mut self, index: usize);
    /// The error for a run stopped after `iterations` active sets.
    fn iteration_limit_error(iterations: u32) -> Self::Error;
}

/// Runs block principal pivoting with Murty's safeguard from the problem's current active set
/// (the warm start) to the solution; returns the number of active sets solved, or the
/// problem's error (a failed solve, or `max_iterations` reached).
#[inline]
pub fn pivot<P: ActiveSetProblem>(problem: &mut P, max_iterations: u32) -> Result<u32, P::Error> {
    pivot_with_patience(problem, max_iterations, BLOCK_PATIENCE)
}

/// [`pivot`] with `grace` block iterations of patience.
#[inline(always)]
fn pivot_with_patience<P: ActiveSetProblem>(
    problem: &mut P,
    max_iterations: u32,
    grace: u32,
) -> Result<u32, P::Error> {
    let mut best_count = usize::MAX;
    let mut patience = grace;
    for iteration in 1..=max_iterations {
        problem.solve_active_set()?;
        let infeasible = problem.infeasible();
        let count = infeasible.len();
        if count == 0 {
            return Ok(iteration);
        }
        // A new minimum restores the patience; at most one reset per value of the minimum.
        if count < best_count {
            best_count = count;
            patience = grace;
        } else {
            patience = patience.saturating_sub(1);
        }
        if patience > 0 {
            problem.flip_all_infeasible();
        } else {
            let index = match P::MURTY_ORDER {
                MurtyOrder::LeastIndex => infeasible[0],
                MurtyOrder::GreatestIndex => infeasible[count - 1],
            };
            problem.flip_one(index);
        }
    }
    Err(P::iteration_limit_error(max_iterations))
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The scale of a margin of the small LCP below, for its tie threshold: `‖M‖∞ max|z| +
    /// max|q|` stays below 10 on every active set it visits (`|z_k| <= 3`).
    const MARGIN_SCALE: f64 = 10.0;
    /// Distance of the answer from `1/3`: Gaussian elimination on small integers rounds to a
    /// few ulps of 1.
    const ANSWER_TOL: f64 = 16.0 * f64::EPSILON;

    /// A dense LCP `w = M z + q >= 0 ⊥ z >= 0` on a non-symmetric P-matrix, solved on each
    /// active set by Gaussian elimination, counting the single pivots.
    struct SmallLcp {
        m: [[f64; 3]; 3],
        q: [f64; 3],
        active: [bool; 3],
        z: [f64; 3],
        infeasible: Vec<usize>,
        single_pivots: u32,
    }

    #[derive(Debug, PartialEq)]
    struct Limit(u32);

    impl ActiveSetProblem for SmallLcp {
        type Error = Limit;
        const MURTY_ORDER: MurtyOrder = MurtyOrder::LeastIndex;
        fn solve_active_set(&mut self) -> Result<(), Limit> {
            // z_A = −M_AA⁻¹ q_A (no pivoting needed: the principal minors of a P-matrix are
            // positive), z_F = 0.
            let idx: Vec<usize> = (0..3).filter(|&k| self.active[k]).collect();
            let a = idx.len();
            let mut g: Vec<Vec<f64>> = idx
                .iter()
                .map(|&i| {
                    let mut row: Vec<f64> = idx.iter().map(|&j| self.m[i][j]).collect();
                    row.push(-self.q[i]);
                    row
                })
                .collect();
            for p in 0..a {
                let (upper, lower) = g.split_at_mut(p + 1);
                let pivot_row = &upper[p];
                for row in lower {
                    let f = row[p] / pivot_row[p];
                    for (x, &y) in row[p..].iter_mut().zip(&pivot_row[p..]) {
                        *x -= f * y;
                    }
                }
            }
            self.z = [0.0; 3];
            for p in (0..a).rev() {
                let tail: f64 = (p + 1..a).map(|c| g[p][c] * self.z[idx[c]]).sum();
                self.z[idx[p]] = (g[p][a] - tail) / g[p][p];
            }
            self.infeasible.clear();
            for k in 0..3 {
                let w: f64 = self.q[k] + (0..3).map(|j| self.m[k][j] * self.z[j]).sum::<f64>();
                let margin = if self.active[k] { self.z[k] } else { w };
                if margin < -round_off_threshold(MARGIN_SCALE) {
                    self.infeasible.push(k);
                }
            }
            Ok(())
        }
        fn infeasible(&self) -> &[usize] {
            &self.infeasible
        }
        fn flip_all_infeasible(&mut self) {
            for &k in &self.infeasible {
                self.active[k] = !self.active[k];
            }
        }
        fn flip_one(&mut self, index: usize) {
            assert_eq!(
                index, self.infeasible[0],
                "Murty's rule flips the least index"
            );
            self.active[index] = !self.active[index];
            self.single_pivots += 1;
        }
        fn iteration_limit_error(iterations: u32) -> Limit {
            Limit(iterations)
        }
    }

    /// `M = [[1,2,0],[0,1,2],[2,0,1]]` (principal minors 1, 1 and 9: a P-matrix), `q = −1`,
    /// from the active set {1, 2}: flipping every infeasible index returns to the start after
    /// three active sets, so block pivoting alone never ends; Murty's rule must act, and the
    /// driver ends at the unique solution `z = (1/3, 1/3, 1/3)`, `w = 0`.
    fn cycling_lcp() -> SmallLcp {
        SmallLcp {
            m: [[1.0, 2.0, 0.0], [0.0, 1.0, 2.0], [2.0, 0.0, 1.0]],
            q: [-1.0; 3],
            active: [false, true, true],
            z: [0.0; 3],
            infeasible: Vec::new(),
            single_pivots: 0,
        }
    }

    #[test]
    fn block_flips_alone_cycle_on_the_small_p_matrix_lcp() {
        let mut lcp = cycling_lcp();
        let never_impatient = u32::MAX;
        assert_eq!(
            pivot_with_patience(&mut lcp, 60, never_impatient),
            Err(Limit(60))
        );
        assert_eq!(lcp.single_pivots, 0);
    }

    #[test]
    fn murtys_rule_breaks_the_cycle_and_reaches_the_solution() {
        let mut lcp = cycling_lcp();
        let iterations = pivot(&mut lcp, iteration_limit(3)).unwrap();
        assert!(lcp.single_pivots > 0, "the fallback acted");
        assert!(iterations > BLOCK_PATIENCE, "{iterations}");
        assert_eq!(lcp.active, [true; 3]);
        for z in lcp.z {
            assert!((z - 1.0 / 3.0).abs() <= ANSWER_TOL, "{z}");
        }
    }
}
