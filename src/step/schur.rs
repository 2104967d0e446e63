//! What the exact and penalty solvers share: the columns `c_j = C⁻¹ e_j` of the constrained
//! nodes, their Schur complement `S_jk = (C⁻¹)_jk`, the 2 × 2 masked solve of an active set,
//! the ranking of candidate sets by KKT violation, and the factorisations of `C` with the rows
//! of each subset of constrained nodes changed (for the direct solves).

use crate::linalg::ldlt::{Ldlt, NotPositiveDefinite, RowChange};
use crate::linalg::norms::max_abs;
use crate::linalg::tridiag::SymTridiag;
use crate::linalg::update::max4;

/// Column `C⁻¹ e_j`, truncated to where it is a normal floating-point number. Shared with the
/// penalty solver, which uses the same Schur complement.
#[derive(Clone, Debug)]
pub(crate) struct Column {
    pub(crate) node: usize,
    /// The entries in `support` only (the column decays geometrically away from `node`).
    pub(crate) values: Vec<f64>,
    /// Entries outside `support` are below `f64::MIN_POSITIVE` in magnitude and are dropped:
    /// adding `r · c` with such `c` cannot change a displacement that is not itself subnormal.
    pub(crate) support: std::ops::Range<usize>,
    /// `max_i |c_i|`.
    pub(crate) max_abs: f64,
}

/// The factorisations of `C` with the rows of each non-empty subset `mask` of `nodes` changed
/// by `change`, at index `mask − 1`; shared with the penalty solver. End nodes change one half
/// only: the other is taken from `factor` (of `C`) or a factorisation made before, neither
/// computed nor stored twice.
pub(crate) fn factor_each_subset(
    c: &SymTridiag,
    nodes: &[usize],
    change: RowChange,
    factor: &Ldlt,
) -> Result<Vec<Ldlt>, NotPositiveDefinite> {
    let subsets: Vec<Vec<usize>> = (1u8..(1 << nodes.len()))
        .map(|mask| {
            (nodes.iter().enumerate())
                .filter(|&(j, _)| mask & (1 << j) != 0)
                .map(|(_, &node)| node)
                .collect()
        })
        .collect();
    let mut made: Vec<Ldlt> = Vec::new();
    for subset in &subsets {
        let known: Vec<(&[usize], &Ldlt)> = std::iter::once((&[][..], factor))
            .chain(subsets.iter().map(Vec::as_slice).zip(&made))
            .collect();
        made.push(Ldlt::factor_with_rows_changed(c, subset, change, &known)?);
    }
    Ok(made)
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

/// `C⁻¹ e_j` for each node, computed with `factor` (set-up only).
pub(crate) fn inverse_columns(factor: &Ldlt, nodes: &[usize]) -> Vec<Column> {
    nodes
        .iter()
        .map(|&node| {
            let mut values = factor.column_of_inverse(node);
            for v in values.iter_mut() {
                if v.abs() < f64::MIN_POSITIVE {
                    *v = 0.0;
                }
            }
            let start = values.iter().position(|v| *v != 0.0).unwrap_or(0);
            let end = values.iter().rposition(|v| *v != 0.0).map_or(0, |e| e + 1);
            let max_abs = max_abs(&values);
            // The support kept in the column's own storage (no second J-sized copy).
            values.truncate(end);
            values.drain(..start.min(end));
            Column {
                node,
                max_abs,
                values,
                support: start..end,
            }
        })
        .collect()
}

/// `S_jk = (C⁻¹)_{jk}` on the (at most two) nodes, made bitwise symmetric so that no choice
/// made from it depends on the order of the nodes.
pub(crate) fn schur_complement(columns: &[Column]) -> [[f64; 2]; 2] {
    let mut schur = [[0.0; 2]; 2];
    for (a, ca) in columns.iter().enumerate() {
        for (b, cb) in columns.iter().enumerate() {
            schur[a][b] = ca.value(cb.node);
        }
    }
    if columns.len() == 2 {
        let s = 0.5 * (schur[0][1] + schur[1][0]);
        schur[0][1] = s;
        schur[1][0] = s;
    }
    schur
}

impl Column {
    /// `(C⁻¹)_{i, node}` (0 outside the support).
    fn value(&self, i: usize) -> f64 {
        if self.support.contains(&i) {
            self.values[i - self.support.start]
        } else {
            0.0
        }
    }

    /// `z += r · c + r2 · c2` (evaluated as `(z + r·c) + r2·c2`, the bits of two
    /// [`Column::add_scaled`] passes) for two columns with the same support, in one pass;
    /// returns `max|z|` over the support before and after.
    pub(crate) fn add_scaled_pair(
        &self,
        r: f64,
        other: &Column,
        r2: f64,
        z: &mut [f64],
    ) -> (f64, f64) {
        debug_assert_eq!(self.support, other.support);
        let (mut before, mut after) = ([0.0f64; 4], [0.0f64; 4]);
        let zs = &mut z[self.support.clone()];
        let mut zc = zs.chunks_exact_mut(4);
        let (mut ac, mut bc) = (self.values.chunks_exact(4), other.values.chunks_exact(4));
        for ((z4, a4), b4) in (&mut zc).zip(&mut ac).zip(&mut bc) {
            for k in 0..4 {
                before[k] = before[k].max(z4[k].abs());
                z4[k] = (z4[k] + r * a4[k]) + r2 * b4[k];
                after[k] = after[k].max(z4[k].abs());
            }
        }
        let rest = zc.into_remainder();
        for ((zi, ai), bi) in rest.iter_mut().zip(ac.remainder()).zip(bc.remainder()) {
            before[0] = before[0].max(zi.abs());
            *zi = (*zi + r * ai) + r2 * bi;
            after[0] = after[0].max(zi.abs());
        }
        (max4(before), max4(after))
    }

    /// `z += r · C⁻¹ e_j` over the column's numerical support; returns `max|z|` over the
    /// support before and after.
    pub(crate) fn add_scaled(&self, r: f64, z: &mut [f64]) -> (f64, f64) {
        // Four running maxima each: one chain of dependent `max`es would be latency-bound
        // (the column spans the whole bar when C is stiff); the maxima are exact, so the
        // order does not change the result.
        let (mut before, mut after) = ([0.0f64; 4], [0.0f64; 4]);
        let (mut zc, mut cc) = (
            z[self.support.clone()].chunks_exact_mut(4),
            self.values.chunks_exact(4),
        );
        for (z4, c4) in (&mut zc).zip(&mut cc) {
            for k in 0..4 {
                before[k] = before[k].max(z4[k].abs());
                z4[k] += r * c4[k];
                after[k] = after[k].max(z4[k].abs());
            }
        }
        for (zi, ci) in zc.into_remainder().iter_mut().zip(cc.remainder()) {
            before[0] = before[0].max(zi.abs());
            *zi += r * ci;
            after[0] = after[0].max(zi.abs());
        }
        (max4(before), max4(after))
    }
}
