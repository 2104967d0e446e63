//! What the exact and penalty solvers share: their factorisations of `C` (the plain `Ldlt` or
//! its twin `TwistedLdlt`), with the rows of each subset of constrained nodes changed for the
//! direct solves; the Schur complement `S_jk = (C⁻¹)_jk` on the constrained nodes, the 2 × 2
//! masked solve of an active set and the ranking of candidate sets by KKT violation.

use crate::linalg::kernels::ldlt::{Ldlt, NotPositiveDefinite, RowChange};
use crate::linalg::kernels::ldlt_fast::TwistedLdlt;
use crate::linalg::tridiag::SymTridiag;
use crate::step::solver::add_in_place;

/// A factorisation the end solvers solve with every step: the optimised twin (their default)
/// or the plain one (to measure what the twin buys, `benches/twins.rs`).
#[derive(Clone, Debug)]
pub(crate) enum StepFactor {
    Plain(Ldlt),
    Twisted(TwistedLdlt),
}

impl StepFactor {
    /// `C` with the rows of `nodes` changed by `change` (none: `C` itself).
    pub(crate) fn new(
        c: &SymTridiag,
        nodes: &[usize],
        change: RowChange,
        twisted: bool,
    ) -> Result<Self, NotPositiveDefinite> {
        Ok(if twisted {
            Self::Twisted(TwistedLdlt::factor_with_rows_changed(c, nodes, change)?)
        } else {
            Self::Plain(Ldlt::factor_with_rows_changed(c, nodes, change)?)
        })
    }

    pub(crate) fn solve_in_place(&self, x: &mut [f64]) {
        match self {
            Self::Plain(f) => f.solve_in_place(x),
            Self::Twisted(f) => f.solve_in_place(x),
        }
    }

    /// `x = A⁻¹ b`, then `u += x` (one pass with the twin).
    pub(crate) fn solve_into_and_add(&self, b: &[f64], x: &mut [f64], u: &mut [f64]) {
        match self {
            Self::Plain(f) => {
                f.solve_into(b, x);
                add_in_place(u, x);
            }
            Self::Twisted(f) => f.solve_into_and_add(b, x, u),
        }
    }

    pub(crate) fn solve_into(&self, b: &[f64], x: &mut [f64]) {
        match self {
            Self::Plain(f) => f.solve_into(b, x),
            Self::Twisted(f) => f.solve_into(b, x),
        }
    }
}

/// The factorisations of `C` with the rows of each non-empty subset `mask` of `nodes` changed
/// by `change`, at index `mask − 1`, each from scratch.
pub(crate) fn factor_each_subset(
    c: &SymTridiag,
    nodes: &[usize],
    change: RowChange,
    twisted: bool,
) -> Result<Vec<StepFactor>, NotPositiveDefinite> {
    (1u8..(1 << nodes.len()))
        .map(|mask| {
            let subset: Vec<usize> = (nodes.iter().enumerate())
                .filter(|&(j, _)| mask & (1 << j) != 0)
                .map(|(_, &node)| node)
                .collect();
            StepFactor::new(c, &subset, change, twisted)
        })
        .collect()
}

/// Row `i` of `C` at each constrained node `i`: `C_i,i−1`, `C_i,i+1` (0 where absent) and the
/// row sum, for [`row_product`]; shared with the penalty solver.
pub(crate) fn constraint_rows(c: &SymTridiag, nodes: &[usize]) -> [[f64; 3]; 2] {
    let mut rows = [[0.0; 3]; 2];
    for (row, &i) in rows.iter_mut().zip(nodes) {
        let left = if i > 0 { c.off[i - 1] } else { 0.0 };
        let right = if i + 1 < c.dim() { c.off[i] } else { 0.0 };
        *row = [left, right, c.row_sums()[i]];
    }
    rows
}

/// `(C z)_i` from row `i` of [`constraint_rows`], in difference form: exact for a rigid `z`
/// where the row sum is 0.
pub(crate) fn row_product([left, right, sum]: [f64; 3], i: usize, z: &[f64]) -> f64 {
    let mut cz = sum * z[i];
    if i > 0 {
        cz += left * (z[i - 1] - z[i]);
    }
    if i + 1 < z.len() {
        cz += right * (z[i + 1] - z[i]);
    }
    cz
}

/// The reactions of active set `mask` (bit `j`: node `j`) from `m r = d` restricted to it
/// (zero off it), by Cramer's rule; shared with the penalty solver, whose `m` is `S + εI`.
pub(crate) fn masked_solve(m: &[[f64; 2]; 2], d: &[f64; 2], mask: u8) -> [f64; 2] {
    match mask {
        0 => [0.0, 0.0],
        1 => [d[0] / m[0][0], 0.0],
        2 => [0.0, d[1] / m[1][1]],
        _ => {
            let det = m[0][0] * m[1][1] - m[0][1] * m[1][0];
            [
                (m[1][1] * d[0] - m[0][1] * d[1]) / det,
                (m[0][0] * d[1] - m[1][0] * d[0]) / det,
            ]
        }
    }
}

/// The active sets of `k <= 2` nodes tried in the order ∅, {first}, {second}, {both}:
/// `candidate(mask)` gives a set's reactions and violation; the first set with the least
/// violation wins, and a set with none ends the search (the problem's solution is unique).
/// Returns the number of sets tried, the winning mask and its reactions.
pub(crate) fn least_violating(
    k: usize,
    candidate: impl Fn(u8) -> ([f64; 2], f64),
) -> (u32, u8, [f64; 2]) {
    let mut best = (0u8, [0.0; 2], f64::INFINITY);
    let mut tried = 0;
    for mask in 0..(1u8 << k) {
        tried += 1;
        let (r, violation) = candidate(mask);
        if violation < best.2 {
            best = (mask, r, violation);
        }
        if violation <= 0.0 {
            break;
        }
    }
    (tried, best.0, best.1)
}

/// `S_jk = (C⁻¹)_{jk}` on the (at most two) nodes, from the columns `C⁻¹ e_j` (set-up only),
/// made bitwise symmetric so that no choice made from it depends on the order of the nodes.
pub(crate) fn schur_complement(factor: &StepFactor, nodes: &[usize]) -> [[f64; 2]; 2] {
    let mut schur = [[0.0; 2]; 2];
    let n = match factor {
        StepFactor::Plain(f) => f.dim(),
        StepFactor::Twisted(f) => f.dim(),
    };
    let mut column = vec![0.0; n];
    for (a, &i) in nodes.iter().enumerate() {
        column.fill(0.0);
        column[i] = 1.0;
        factor.solve_in_place(&mut column);
        for (b, &k) in nodes.iter().enumerate() {
            schur[a][b] = column[k];
        }
    }
    if nodes.len() == 2 {
        let s = 0.5 * (schur[0][1] + schur[1][0]);
        schur[0][1] = s;
        schur[1][0] = s;
    }
    schur
}
