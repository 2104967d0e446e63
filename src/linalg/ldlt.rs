//! The factorisation of a symmetric positive definite tridiagonal matrix, computed once per run
//! and solved every step (odd–even reduction, then a twisted factorisation: see [`Ldlt`]),
//! with the refactorisations that change a few rows and share the unchanged halves.

use crate::linalg::dispatch;
use crate::linalg::tridiag::SymTridiag;
use std::cell::Cell;
use std::sync::Arc;

/// A factorisation of a symmetric positive definite tridiagonal matrix `A` built for a short
/// critical path: one step of odd–even reduction, then a twisted factorisation of the reduced
/// system. Computed once per run.
///
/// *Reduction.* The odd nodes are not neighbours of each other, so eliminating them first
/// (pivots `d_o`) leaves a tridiagonal Schur complement `A'` on the even nodes (`ν = ⌈n/2⌉`
/// rows): `D'_r = d_2r − e_2r−1²/d_2r−1 − e_2r²/d_2r+1`, `E'_r = −e_2r e_2r+1/d_2r+1`, right-hand
/// side `b'_r = b_2r − f2_2r−1 b_2r−1 − f1_2r+1 b_2r+1` with `f1_o = e_o−1/d_o`, `f2_o = e_o/d_o`.
/// Once the even unknowns are known, `x_o = b_o/d_o − f1_o x_o−1 − f2_o x_o+1`.
///
/// *Twisted factorisation of `A'`* ("burn at both ends"): `L D Lᵀ` from the top for reduced
/// rows `0..μ`, `U D Uᵀ` from the bottom for rows `μ+1..ν`, joined at the twist row `μ = ν/2`.
/// A solve runs the top and bottom chains interleaved in one loop (two dependent chains
/// overlap instead of one waiting on itself), and each link covers two nodes of the bar: a
/// quarter of the plain sweep's latency. The reduction's and the odd nodes' arithmetic is off
/// the chains, in the slots the chains leave free.
///
/// Both parts are Gaussian elimination without pivoting on the symmetrically permuted matrix
/// `P A Pᵀ`, which is positive definite, so the solve is backward stable like the plain `L D
/// Lᵀ` sweep (Higham, *Accuracy and Stability of Numerical Algorithms*, 2nd ed., Thm 10.5 and
/// §9.5); `tests/matrices.rs` measures its backward error. No fused multiply-add: results do
/// not depend on target-cpu flags.
#[derive(Clone, Debug)]
pub struct Ldlt {
    /// One entry per reduced row in the order the inward sweep visits it, with the odd node on
    /// its inner side (towards the twist): `top[r] = [l_r, 1/D_r, f1_o, f2_o, 1/d_o]` with
    /// `o = 2r + 1` for rows `r = 0..μ` (`l_r = E'_r/D_r`); `bottom[k]` the same for row
    /// `r = ν−1−k > μ` with `o = 2r − 1` and `l_r = E'_r−1/D_r`. A half that several
    /// factorisations have is stored once ([`Ldlt::factor_with_rows_changed`]), and a half
    /// whose sweep ends in a stationary stretch stores that stretch's row once ([`Half`]).
    top: Arc<Half>,
    bottom: Arc<Half>,
    /// `[f1, 1/d]` of the last node when it is odd (`n` even): it is on no reduced row's inner
    /// side.
    outer: Option<[f64; 2]>,
    /// `1/D_μ`, the twist pivot.
    inv_twist: f64,
    n: usize,
}

/// One half of an [`Ldlt`]: `len` rows, of which the first `rows.len()` are stored and the
/// rest repeat the last one stored. A sweep that becomes stationary up to the twist (a
/// uniform interior, once the pivots have converged) repeats one row bit for bit to the
/// end: storing it once saves the set-up its pages and the solve its loads.
#[derive(Clone, Debug)]
struct Half {
    rows: Vec<[f64; 5]>,
    len: usize,
}

impl Half {
    /// Every row, the repeated ones included (tests).
    #[cfg(test)]
    fn expanded(&self) -> Vec<[f64; 5]> {
        let last = self.rows.last().copied().unwrap_or_default();
        let mut rows = self.rows.clone();
        rows.resize(self.len, last);
        rows
    }
}

/// How [`Ldlt::factor_with_rows_changed`] changes the rows (and columns) of its nodes.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum RowChange {
    /// Replaced by identity ones: the exact solver's active set, `z_j = lo_j`.
    Identity,
    /// This added to the diagonal entry: the penalty solver's contact spring `1/ε`.
    AddToDiagonal(f64),
}

/// The matrix was not numerically positive definite: pivot `index` came out as `pivot`.
#[derive(Clone, Copy, Debug, PartialEq, thiserror::Error)]
#[error("matrix is not positive definite: pivot {index} is {pivot:e}")]
pub struct NotPositiveDefinite {
    /// The node whose pivot failed (an odd node's `d_o`, or an even node's reduced pivot).
    pub index: usize,
    pub pivot: f64,
}

/// A value the solve reads from its right-hand side: `f64` for a separate one, `Cell<f64>`
/// when it is the solution vector itself (in place).
trait Value {
    fn value(&self) -> f64;
}

impl Value for f64 {
    #[inline(always)]
    fn value(&self) -> f64 {
        *self
    }
}

impl Value for Cell<f64> {
    #[inline(always)]
    fn value(&self) -> f64 {
        self.get()
    }
}

/// Detects where a factorisation sweep has become stationary. Row `k` of a sweep is a
/// function of the entries it reads (`inputs`) and of the state the previous row carries (its
/// multiplier, its odd node's quotients, its reduced off-diagonal). When a row (not the first,
/// whose pivot has no previous term) leaves the same state as the row before it and the next
/// row reads the same entries, the next row repeats it bit for bit, and so on by induction: on
/// a uniform stretch of the matrix, once the pivots have converged, the sweep copies rows
/// instead of dividing (the same bits, a fraction of the set-up's work).
#[derive(Default)]
struct Steady {
    /// The inputs of the last row computed and the state it left, as bits.
    inputs: [u64; 5],
    state: [u64; 5],
    /// That state equals the one the row before it left, and the row is not the first.
    repeating: bool,
}

impl Steady {
    /// Whether row `k`, reading `inputs`, repeats row `k − 1` (the last row recorded or
    /// repeated).
    #[inline(always)]
    fn repeats(&self, k: usize, inputs: [f64; 5]) -> bool {
        k >= 2 && self.repeating && inputs.map(f64::to_bits) == self.inputs
    }

    /// Row `k` computed from `inputs`, leaving `state`.
    #[inline(always)]
    fn record(&mut self, k: usize, inputs: [f64; 5], state: [f64; 5]) {
        let state = state.map(f64::to_bits);
        self.repeating = k >= 1 && state == self.state;
        self.inputs = inputs.map(f64::to_bits);
        self.state = state;
    }
}

/// The matrix's own arrays (`d(i) = rd[i]`, `e(i) = re[i]` away from the `changed` rows), for
/// finding where a stationary sweep may copy rows: row `r` repeats the row swept before it
/// when it reads the same entries shifted by two nodes.
struct RawRows<'a> {
    rd: &'a [f64],
    re: &'a [f64],
    changed: &'a [usize],
    n: usize,
}

/// The first `j` in `from..to` with `v[j] != v[j − 2]` bitwise, or `to` (`from >= 2`): eight
/// comparisons at a time without a branch, then one by one from the block that differs.
fn first_lag2_change(v: &[f64], from: usize, to: usize) -> usize {
    if from >= to {
        return to;
    }
    let (a, b) = (&v[from - 2..to - 2], &v[from..to]);
    let mut k = 0;
    for (ca, cb) in a.chunks_exact(8).zip(b.chunks_exact(8)) {
        if !(ca.iter().zip(cb)).fold(true, |s, (x, y)| s & (x.to_bits() == y.to_bits())) {
            break;
        }
        k += 8;
    }
    (k..a.len())
        .find(|&p| a[p].to_bits() != b[p].to_bits())
        .map_or(to, |p| from + p)
}

/// The last `j` in `from..to` with `v[j] != v[j − 2]` bitwise, if any (`from >= 2`).
fn last_lag2_change(v: &[f64], from: usize, to: usize) -> Option<usize> {
    if from >= to {
        return None;
    }
    let (a, b) = (&v[from - 2..to - 2], &v[from..to]);
    let mut k = a.len();
    for (ca, cb) in a.rchunks_exact(8).zip(b.rchunks_exact(8)) {
        if !(ca.iter().zip(cb)).fold(true, |s, (x, y)| s & (x.to_bits() == y.to_bits())) {
            break;
        }
        k -= 8;
    }
    (0..k)
        .rev()
        .find(|&p| a[p].to_bits() != b[p].to_bits())
        .map(|p| from + p)
}

impl RawRows<'_> {
    /// Entries `lo..=hi` of the diagonal and the off-diagonal are the arrays' own. (The row-by-row
    /// reference of the block scans.)
    #[cfg(test)]
    fn raw_ok(&self, lo: usize, hi: usize) -> bool {
        self.changed.iter().all(|&c| c < lo || c > hi)
    }

    /// Whether top row `r` (r >= 3) reads the entries row `r − 1` read, shifted by two. (The row-by-row
    /// reference of the block scans.)
    #[cfg(test)]
    fn top_repeats(&self, r: usize) -> bool {
        let (rd, re, i) = (self.rd, self.re, 2 * r);
        let same = |a: f64, b: f64| a.to_bits() == b.to_bits();
        i + 2 < self.n
            && self.raw_ok(i - 3, i + 2)
            && same(rd[i], rd[i - 2])
            && same(re[i - 1], re[i - 3])
            && same(re[i], re[i - 2])
            && same(re[i + 1], re[i - 1])
            && same(rd[i + 1], rd[i - 1])
    }

    /// The same for bottom row `r` against row `r + 1`, swept before it. (The row-by-row
    /// reference of the block scans.)
    #[cfg(test)]
    fn bottom_repeats(&self, r: usize) -> bool {
        let (rd, re, i) = (self.rd, self.re, 2 * r);
        let same = |a: f64, b: f64| a.to_bits() == b.to_bits();
        i >= 2
            && i + 3 < self.n
            && self.raw_ok(i - 2, i + 3)
            && same(rd[i], rd[i + 2])
            && same(re[i - 2], re[i])
            && same(re[i - 1], re[i + 1])
            && same(re[i], re[i + 2])
            && same(rd[i - 1], rd[i + 1])
    }

    /// The first top row in `start..twist` that does not repeat (`twist` if all do), for
    /// `start >= 3`: what `while end < twist && top_repeats(end)` finds, with the entries
    /// compared in blocks. Row `r` compares `rd` at `2r, 2r + 1` and `re` at `2r − 1 ..= 2r + 1`
    /// with the entries two before; the first such entry that differs, `j`, is first read by
    /// row `⌊j/2⌋`.
    fn top_end(&self, start: usize, twist: usize) -> usize {
        // Rows from `(n − 1)/2` on fail `i + 2 < n`.
        let mut fail = twist.min(self.n.saturating_sub(1) / 2);
        for &c in self.changed {
            // Row `r` reads rows `2r − 3 ..= 2r + 2`.
            let (lo, hi) = (c.saturating_sub(1) / 2, (c + 3) / 2);
            if hi >= start && lo < fail {
                fail = fail.min(lo.max(start));
            }
        }
        if fail <= start {
            return start;
        }
        let j = first_lag2_change(self.re, 2 * start - 1, 2 * fail).min(first_lag2_change(
            self.rd,
            2 * start,
            2 * fail,
        ));
        if j < 2 * fail {
            fail = (j / 2).max(start);
        }
        fail
    }

    /// The first `k` in `start..` whose bottom row `ν − 1 − k` does not repeat, or `ν − 1 −
    /// twist` (the first row not swept), for `start >= 3`: what `while end + twist + 1 < ν &&
    /// bottom_repeats(ν − 1 − end)` finds. Row `r` compares `rd` at `2r + 1, 2r + 2` and `re` at
    /// `2r ..= 2r + 2` with the entries two before; going down, the first such entry that
    /// differs, `j`, is read by row `⌊(j − 1)/2⌋` (`rd`) or `⌊j/2⌋` (`re`).
    fn bottom_end(&self, start: usize, nu: usize, twist: usize) -> usize {
        if start + twist + 1 >= nu {
            return start;
        }
        // The rows swept, from the top down: `top` to `twist + 1`; `fail` the highest that
        // does not repeat (`twist`: none).
        let top = nu - 1 - start;
        let mut fail = twist;
        // `i + 3 < n`.
        if 2 * top + 3 >= self.n {
            return start;
        }
        for &c in self.changed {
            // Row `r` reads rows `2r − 2 ..= 2r + 3`.
            let (lo, hi) = (c.saturating_sub(2) / 2, (c + 2) / 2);
            if lo <= top && hi > fail {
                fail = fail.max(hi.min(top));
            }
        }
        if fail < top {
            let lo = fail + 1;
            if let Some(j) = last_lag2_change(self.rd, 2 * lo + 1, 2 * top + 3) {
                fail = fail.max((j - 1) / 2);
            }
            if let Some(j) = last_lag2_change(self.re, 2 * lo, 2 * top + 3) {
                fail = fail.max((j / 2).min(top));
            }
        }
        nu - 1 - fail
    }
}

impl Ldlt {
    pub fn factor(a: &SymTridiag) -> Result<Self, NotPositiveDefinite> {
        Self::factor_by(
            a.dim(),
            |i| a.diag[i],
            |i| a.off[i],
            (&a.diag, &a.off, &[]),
            [None, None],
        )
    }

    /// The factorisation of `a` with the rows and columns of `nodes` replaced by identity ones
    /// (the same entries the factorisation of that modified matrix reads, without copying it).
    pub fn factor_with_identity_rows(
        a: &SymTridiag,
        nodes: &[usize],
    ) -> Result<Self, NotPositiveDefinite> {
        Self::factor_with_rows_changed(a, nodes, RowChange::Identity, &[])
    }

    /// The factorisation of `a` with the rows of `nodes` changed by `change`, read from `a`
    /// without copying it. Each half is taken from a factorisation in `known` (made by this
    /// function from the same `a` with the same `change`, or the plain one with no nodes,
    /// given with its own nodes) whose changed rows among the nodes that half reads are the
    /// same: that half is then neither computed nor stored again. The top half reads nodes
    /// `0..=2μ`, the bottom half `2μ..n` (`2μ`, the twist node, both), so changed rows at one
    /// end leave the other end's half as it was.
    pub fn factor_with_rows_changed(
        a: &SymTridiag,
        nodes: &[usize],
        change: RowChange,
        known: &[(&[usize], &Ldlt)],
    ) -> Result<Self, NotPositiveDefinite> {
        let n = a.dim();
        let twist_node = 2 * (n.div_ceil(2) / 2);
        // The changed rows a half reads, as a sorted list.
        let seen = |nodes: &[usize], top: bool| {
            let mut v: Vec<usize> = (nodes.iter().copied())
                .filter(|&i| {
                    if top {
                        i <= twist_node
                    } else {
                        i >= twist_node
                    }
                })
                .collect();
            v.sort_unstable();
            v.dedup();
            v
        };
        let reuse = |top: bool| {
            let mine = seen(nodes, top);
            known.iter().find_map(|(their_nodes, f)| {
                (f.n == n && seen(their_nodes, top) == mine)
                    .then(|| Arc::clone(if top { &f.top } else { &f.bottom }))
            })
        };
        // A range test first: the sweeps ask about every row, and the solvers' nodes are at
        // most two, at the ends.
        let lo = nodes.iter().copied().min().unwrap_or(usize::MAX);
        let hi = nodes.iter().copied().max().unwrap_or(0);
        let changed = |i: usize| i >= lo && i <= hi && nodes.contains(&i);
        let halves = [reuse(true), reuse(false)];
        match change {
            RowChange::Identity => Self::factor_by(
                n,
                |i| if changed(i) { 1.0 } else { a.diag[i] },
                |i| {
                    if changed(i) || changed(i + 1) {
                        0.0
                    } else {
                        a.off[i]
                    }
                },
                (&a.diag, &a.off, nodes),
                halves,
            ),
            RowChange::AddToDiagonal(s) => Self::factor_by(
                n,
                |i| if changed(i) { a.diag[i] + s } else { a.diag[i] },
                |i| a.off[i],
                (&a.diag, &a.off, nodes),
                halves,
            ),
        }
    }

    /// The factorisation of the matrix with diagonal `d(i)` and off-diagonal `e(i) = A_i,i+1`;
    /// a half given in `reuse` (`[top, bottom]`, computed from the same entries) is taken as is.
    ///
    /// `raw = (diag, off, changed)`: `d(i) = diag[i]` and `e(i) = off[i]` except at the rows
    /// `changed` (`d(c)`, `e(c − 1)`, `e(c)` may differ there), for the stationary stretches'
    /// fast check.
    fn factor_by(
        n: usize,
        d: impl Fn(usize) -> f64,
        e: impl Fn(usize) -> f64,
        raw: (&[f64], &[f64], &[usize]),
        reuse: [Option<Arc<Half>>; 2],
    ) -> Result<Self, NotPositiveDefinite> {
        let (rd, re, changed) = raw;
        let raw_rows = RawRows { rd, re, changed, n };
        let [reuse_top, reuse_bottom] = reuse;
        let check = |index: usize, pivot: f64| {
            if pivot > 0.0 && pivot.is_finite() {
                Ok(pivot)
            } else {
                Err(NotPositiveDefinite { index, pivot })
            }
        };
        // Odd node `2k + 1`: [f1, f2, 1/d] (f2 = 0 for the last node); recomputed where
        // needed rather than stored, so the set-up holds nothing beyond the factorisation.
        // Every odd pivot `d(o)` positive and finite: one branch-free pass over the raw diagonal
        // plus the changed rows (`d` agrees with it elsewhere); the node-by-node loop, which
        // names the first bad pivot, runs only when that pass fails.
        let usable = |p: f64| (p > 0.0) & (p < f64::INFINITY);
        let raw_odd_ok = {
            // Sixteen entries from an odd one at a time: eight odd ones at even offsets.
            let mut blocks = rd.get(1..n).unwrap_or_default().chunks_exact(16);
            let mut ok = true;
            for block in &mut blocks {
                ok &= (0..8).fold(true, |all, k| all & usable(block[2 * k]));
            }
            (blocks.remainder().iter().step_by(2)).fold(ok, |ok, &p| ok & usable(p))
        };
        let changed_ok = changed
            .iter()
            .all(|&c| c % 2 == 0 || c >= n || usable(d(c)));
        if !(raw_odd_ok && changed_ok) {
            for o in (1..n).step_by(2) {
                check(o, d(o))?;
            }
        }
        let odd = |k: usize| {
            let o = 2 * k + 1;
            let f2 = if o + 1 < n { e(o) / d(o) } else { 0.0 };
            [e(o - 1) / d(o), f2, 1.0 / d(o)]
        };
        let nu = n.div_ceil(2);
        // The reduced matrix A' on the even nodes.
        let reduced_diag = |r: usize| {
            let i = 2 * r;
            let mut p = d(i);
            if r > 0 {
                p -= e(i - 1) * odd(r - 1)[1];
            }
            if i + 1 < n {
                p -= e(i) * odd(r)[0];
            }
            p
        };
        let reduced_off = |r: usize| -(e(2 * r) * odd(r)[1]);
        let twist = nu / 2;
        // The last multiplier of each half enters the twist pivot.
        let last_l = |half: &Half| half.rows.last().map_or(0.0, |row| row[0]);
        // The sweeps below carry each odd node's quotients and each reduced off-diagonal from
        // one row to the next instead of calling `odd` and `reduced_off` again (the same
        // operations on the same numbers: the same bits, a third of the divisions).
        let top = match reuse_top {
            Some(top) => top,
            None => {
                let mut top: Vec<[f64; 5]> = Vec::with_capacity(twist);
                let (mut l_prev, mut odd_prev, mut off_prev) = (0.0, [0.0; 3], 0.0);
                let mut steady = Steady::default();
                let mut r = 0;
                while r < twist {
                    // `2r + 1 < n` for every top row.
                    let i = 2 * r;
                    let inputs = [
                        d(i),
                        if r > 0 { e(i - 1) } else { 0.0 },
                        e(i),
                        if i + 2 < n { e(i + 1) } else { f64::NAN },
                        d(i + 1),
                    ];
                    if steady.repeats(r, inputs) {
                        // Row r repeats row r − 1; so do the rows after it that read the
                        // same entries (checked on the matrix's own arrays, away from the
                        // changed rows).
                        let end = raw_rows.top_end(r + 1, twist);
                        if end < twist {
                            top.resize(end, top[r - 1]);
                        }
                        r = end;
                        continue;
                    }
                    let cur = odd(r);
                    let mut diag = d(i);
                    if r > 0 {
                        diag -= e(i - 1) * odd_prev[1];
                    }
                    diag -= e(i) * cur[0];
                    let p = if r == 0 {
                        diag
                    } else {
                        diag - off_prev * l_prev
                    };
                    let p = check(i, p)?;
                    let off = -(e(i) * cur[1]);
                    l_prev = off / p;
                    let [f1, f2, inv_d] = cur;
                    top.push([l_prev, 1.0 / p, f1, f2, inv_d]);
                    steady.record(r, inputs, [l_prev, f1, f2, inv_d, off]);
                    (odd_prev, off_prev) = (cur, off);
                    r += 1;
                }
                top.shrink_to_fit();
                Arc::new(Half {
                    rows: top,
                    len: twist,
                })
            }
        };
        let bottom = match reuse_bottom {
            Some(bottom) => bottom,
            None => {
                let mut bottom = Vec::with_capacity(nu.saturating_sub(twist + 1));
                let mut l_next = 0.0;
                // `odd(r)` and `reduced_off(r)` of the row below (the last row's odd node
                // exists when `n` is even).
                let mut odd_next = if n.is_multiple_of(2) && nu > twist + 1 {
                    odd(nu - 1)
                } else {
                    [0.0; 3]
                };
                let mut off_next = 0.0;
                let mut steady = Steady::default();
                // Row `r = ν − 1 − k`, the `k`-th of the sweep.
                let mut k = 0;
                while k + twist + 1 < nu {
                    let r = nu - 1 - k;
                    let i = 2 * r;
                    let inputs = [
                        d(i),
                        e(i - 2),
                        e(i - 1),
                        if i + 1 < n { e(i) } else { f64::NAN },
                        d(i - 1),
                    ];
                    if steady.repeats(k, inputs) {
                        let end = raw_rows.bottom_end(k + 1, nu, twist);
                        if end + twist + 1 < nu {
                            bottom.resize(end, bottom[k - 1]);
                        }
                        k = end;
                        continue;
                    }
                    let lo = odd(r - 1);
                    let mut diag = d(i);
                    diag -= e(i - 1) * lo[1];
                    if i + 1 < n {
                        diag -= e(i) * odd_next[0];
                    }
                    let p = if r == nu - 1 {
                        diag
                    } else {
                        diag - off_next * l_next
                    };
                    let p = check(i, p)?;
                    let off = -(e(i - 2) * lo[1]);
                    l_next = off / p;
                    let [f1, f2, inv_d] = lo;
                    bottom.push([l_next, 1.0 / p, f1, f2, inv_d]);
                    steady.record(k, inputs, [l_next, f1, f2, inv_d, off]);
                    (odd_next, off_next) = (lo, off);
                    k += 1;
                }
                bottom.shrink_to_fit();
                Arc::new(Half {
                    rows: bottom,
                    len: nu.saturating_sub(twist + 1),
                })
            }
        };
        let (l_prev, l_next) = (last_l(&top), last_l(&bottom));
        let mut inv_twist = 0.0;
        if n > 0 {
            let mut g = reduced_diag(twist);
            if twist > 0 {
                g -= reduced_off(twist - 1) * l_prev;
            }
            if twist + 1 < nu {
                g -= reduced_off(twist) * l_next;
            }
            inv_twist = 1.0 / check(2 * twist, g)?;
        }
        let outer = (n.is_multiple_of(2) && n > 0).then(|| {
            let [f1, _, inv_d] = odd(n / 2 - 1);
            [f1, inv_d]
        });
        Ok(Self {
            top,
            bottom,
            outer,
            inv_twist,
            n,
        })
    }

    pub fn dim(&self) -> usize {
        self.n
    }

    /// Overwrites `b` with `A⁻¹ b`.
    pub fn solve_in_place(&self, b: &mut [f64]) {
        assert_eq!(b.len(), self.n, "right-hand side length");
        let x = Cell::from_mut(b).as_slice_of_cells();
        self.solve_from::<_, false>(x, x, x);
    }

    /// `x = A⁻¹ b` (the same bits as copying `b` into `x` and solving in place).
    pub fn solve_into(&self, b: &[f64], x: &mut [f64]) {
        assert_eq!(b.len(), self.n, "right-hand side length");
        assert_eq!(x.len(), self.n, "solution length");
        let x = Cell::from_mut(x).as_slice_of_cells();
        self.solve_from::<_, false>(b, x, x);
    }

    /// `x = A⁻¹ b`, then `u += x`: the bits of [`Ldlt::solve_into`] followed by the addition,
    /// made as each `x_i` is found (the time step's update without a second pass over the
    /// bar). Unlike [`add_in_place`](crate::linalg::update::add_in_place) it does not track `max |u_i|`: that running maximum, a
    /// chain of its own, made the fused sweep slower than the two passes.
    pub fn solve_into_and_add(&self, b: &[f64], x: &mut [f64], u: &mut [f64]) {
        assert_eq!(b.len(), self.n, "right-hand side length");
        assert_eq!(x.len(), self.n, "solution length");
        assert_eq!(u.len(), self.n, "state length");
        let x = Cell::from_mut(x).as_slice_of_cells();
        self.solve_from::<_, true>(b, x, Cell::from_mut(u).as_slice_of_cells());
    }

    /// The solve, reading the right-hand side from `b` (which may be `x` itself: every entry
    /// of `b` is read before `x` overwrites it). Inward, the two chains eliminate towards the
    /// twist row, folding in the odd nodes; outward, they substitute back, and each reduced
    /// row fills in its inner odd node. With `ADD`, each `x_i` is also added to `u_i`
    /// (otherwise `u` is not touched and may be `x`).
    fn solve_from<V: Value, const ADD: bool>(&self, b: &[V], x: &[Cell<f64>], u: &[Cell<f64>]) {
        dispatch::run(Solve::<V, ADD> {
            ldlt: self,
            b,
            x,
            u,
        });
    }

    /// The body of [`Ldlt::solve_from`], compiled into [`dispatch::run`]'s callers (AVX or
    /// baseline: the same operations, so the same bits).
    #[inline(always)]
    fn solve_body<V: Value, const ADD: bool>(&self, b: &[V], x: &[Cell<f64>], u: &[Cell<f64>]) {
        let n = self.n;
        if n == 0 {
            return;
        }
        // Row `k` of a half is `rows[k]` for `k < p` (the rows stored) and the stationary row
        // `rows[p − 1]` after that (see `Half`): each loop below runs in segments, reading
        // the stored rows from memory and the stationary one from a local.
        let (top_rows, bottom_rows) = (&self.top.rows[..], &self.bottom.rows[..]);
        let (top_still, bottom_still) = (
            top_rows.last().copied().unwrap_or_default(),
            bottom_rows.last().copied().unwrap_or_default(),
        );
        let still = |row: &[f64; 5]| std::iter::repeat(*row);
        let (m, bottom_len) = (self.top.len, self.bottom.len);
        // Top rows r < μ own nodes (2r, 2r+1); the twist is node 2μ; bottom rows own
        // (2r−1, 2r); then the outer odd node when n is even.
        let bottom_nodes = 2 * bottom_len;
        let (b_top, b_rest) = b.split_at(2 * m);
        let (b_mid, b_rest) = b_rest.split_at(1);
        let (b_bottom, b_outer) = b_rest.split_at(bottom_nodes);
        let (x_top, x_rest) = x.split_at(2 * m);
        let (x_mid, x_rest) = x_rest.split_at(1);
        let (x_bottom, x_outer) = x_rest.split_at(bottom_nodes);
        let (u_top, u_rest) = u.split_at(2 * m);
        let (u_mid, u_rest) = u_rest.split_at(1);
        let (u_bottom, u_outer) = u_rest.split_at(bottom_nodes);
        let common = m.min(bottom_len);
        let (pt, pb) = (top_rows.len().min(m), bottom_rows.len().min(bottom_len));
        // Links `0..common` of both chains in three segments: both stored (`..s1`), one stored
        // (`s1..s2`), neither (`s2..`).
        let (s1, s2) = (pt.min(pb).min(common), pt.max(pb).min(common));

        // Inward. Per chain: y (the elimination value), l (the multiplier of the row before)
        // and c, the term of the shared odd node (`f b_o`) the next row subtracts.
        let (mut yt, mut lt, mut ct) = (0.0, 0.0, 0.0);
        let (mut yb, mut lb) = (0.0, 0.0);
        let mut cb = match (self.outer, b_outer.first()) {
            (Some([f1, _]), Some(bo)) => f1 * bo.value(),
            _ => 0.0,
        };
        let inward_top =
            |b: &[V], x: &[Cell<f64>], f: &[f64; 5], y: &mut f64, l: &mut f64, c: &mut f64| {
                let (be, bo) = (b[0].value(), b[1].value());
                *y = ((be - *c) - f[2] * bo) - *l * *y;
                x[0].set(*y * f[1]);
                (*l, *c) = (f[0], f[3] * bo);
            };
        let inward_bottom =
            |b: &[V], x: &[Cell<f64>], f: &[f64; 5], y: &mut f64, l: &mut f64, c: &mut f64| {
                let (bo, be) = (b[0].value(), b[1].value());
                *y = ((be - f[3] * bo) - *c) - *l * *y;
                x[1].set(*y * f[1]);
                (*l, *c) = (f[0], f[2] * bo);
            };
        let mut top = b_top.chunks_exact(2).zip(x_top.chunks_exact(2));
        let mut bottom = b_bottom.rchunks_exact(2).zip(x_bottom.rchunks_exact(2));
        macro_rules! inward_both {
            ($links:expr, $top_rows:expr, $bottom_rows:expr) => {
                for (((bt, xt), ft), ((bb, xb), fb)) in (top.by_ref().take($links).zip($top_rows))
                    .zip(bottom.by_ref().take($links).zip($bottom_rows))
                {
                    inward_top(bt, xt, &ft, &mut yt, &mut lt, &mut ct);
                    inward_bottom(bb, xb, &fb, &mut yb, &mut lb, &mut cb);
                }
            };
        }
        inward_both!(
            s1,
            top_rows[..s1].iter().copied(),
            bottom_rows[..s1].iter().copied()
        );
        if pt <= pb {
            inward_both!(
                s2 - s1,
                still(&top_still),
                bottom_rows[s1..s2].iter().copied()
            );
        } else {
            inward_both!(
                s2 - s1,
                top_rows[s1..s2].iter().copied(),
                still(&bottom_still)
            );
        }
        inward_both!(common - s2, still(&top_still), still(&bottom_still));
        // The longer half's rest: stored rows, then the stationary one.
        let top_stored = top_rows[common.min(pt)..pt].iter().copied();
        for ((bt, xt), ft) in top.zip(top_stored.chain(still(&top_still))) {
            inward_top(bt, xt, &ft, &mut yt, &mut lt, &mut ct);
        }
        let bottom_stored = bottom_rows[common.min(pb)..pb].iter().copied();
        for ((bb, xb), fb) in bottom.zip(bottom_stored.chain(still(&bottom_still))) {
            inward_bottom(bb, xb, &fb, &mut yb, &mut lb, &mut cb);
        }
        // Twist row: the terms are 0 when a side is empty (l = 0, y = 0, c = 0).
        let xm = (((b_mid[0].value() - ct) - cb) - lt * yt - lb * yb) * self.inv_twist;
        x_mid[0].set(xm);

        let add = |u: &Cell<f64>, xi: f64| {
            if ADD {
                u.set(u.get() + xi);
            }
        };
        add(&u_mid[0], xm);

        // Outward: x_2r = y_r/D_r − l_r x_(next even), then the inner odd node from its two
        // even neighbours (left one first).
        let (mut xt_, mut xb_) = (xm, xm);
        let outward_top =
            |b: &[V], x: &[Cell<f64>], u: &[Cell<f64>], f: &[f64; 5], xn: &mut f64| {
                let xe = x[0].get() - f[0] * *xn;
                let xo = b[1].value() * f[4] - f[2] * xe - f[3] * *xn;
                x[1].set(xo);
                x[0].set(xe);
                add(&u[0], xe);
                add(&u[1], xo);
                *xn = xe;
            };
        let outward_bottom =
            |b: &[V], x: &[Cell<f64>], u: &[Cell<f64>], f: &[f64; 5], xn: &mut f64| {
                let xe = x[1].get() - f[0] * *xn;
                let xo = b[0].value() * f[4] - f[2] * *xn - f[3] * xe;
                x[0].set(xo);
                x[1].set(xe);
                add(&u[0], xo);
                add(&u[1], xe);
                *xn = xe;
            };
        let mut top = (b_top.chunks_exact(2).zip(x_top.chunks_exact(2)))
            .zip(u_top.chunks_exact(2))
            .rev();
        let mut bottom = (b_bottom.rchunks_exact(2).zip(x_bottom.rchunks_exact(2)))
            .zip(u_bottom.rchunks_exact(2))
            .rev();
        // The longer half's rest first, from the twist: the stationary row, then stored rows.
        let top_rest = std::iter::repeat_n(top_still, m - pt.max(common))
            .chain(top_rows[common.min(pt)..pt].iter().rev().copied());
        for (((bt, xt), ut), ft) in top.by_ref().take(m - common).zip(top_rest) {
            outward_top(bt, xt, ut, &ft, &mut xt_);
        }
        let bottom_rest = std::iter::repeat_n(bottom_still, bottom_len - pb.max(common))
            .chain(bottom_rows[common.min(pb)..pb].iter().rev().copied());
        for (((bb, xb), ub), fb) in bottom.by_ref().take(bottom_len - common).zip(bottom_rest) {
            outward_bottom(bb, xb, ub, &fb, &mut xb_);
        }
        macro_rules! outward_both {
            ($links:expr, $top_rows:expr, $bottom_rows:expr) => {
                for ((((bt, xt), ut), ft), (((bb, xb), ub), fb)) in
                    (top.by_ref().take($links).zip($top_rows))
                        .zip(bottom.by_ref().take($links).zip($bottom_rows))
                {
                    outward_top(bt, xt, ut, &ft, &mut xt_);
                    outward_bottom(bb, xb, ub, &fb, &mut xb_);
                }
            };
        }
        outward_both!(common - s2, still(&top_still), still(&bottom_still));
        if pt <= pb {
            outward_both!(
                s2 - s1,
                still(&top_still),
                bottom_rows[s1..s2].iter().rev().copied()
            );
        } else {
            outward_both!(
                s2 - s1,
                top_rows[s1..s2].iter().rev().copied(),
                still(&bottom_still)
            );
        }
        outward_both!(
            s1,
            top_rows[..s1].iter().rev().copied(),
            bottom_rows[..s1].iter().rev().copied()
        );
        if let (Some([f1, inv_d]), Some(bo), Some(xo), Some(uo)) = (
            self.outer,
            b_outer.first(),
            x_outer.first(),
            u_outer.first(),
        ) {
            let v = bo.value() * inv_d - f1 * xb_;
            xo.set(v);
            add(uo, v);
        }
    }
}

/// [`Ldlt::solve_from`] with its arguments, for [`dispatch::run`]: the chains are scalar, but
/// the three-operand AVX encoding of the same instructions saves the register copies.
struct Solve<'a, V, const ADD: bool> {
    ldlt: &'a Ldlt,
    b: &'a [V],
    x: &'a [Cell<f64>],
    u: &'a [Cell<f64>],
}

impl<V: Value, const ADD: bool> dispatch::Kernel for Solve<'_, V, ADD> {
    type Output = ();
    #[inline(always)]
    fn call(self) {
        self.ldlt.solve_body::<V, ADD>(self.b, self.x, self.u)
    }
}

impl Ldlt {
    /// `A⁻¹ e_j` as a new vector (set-up only).
    pub fn column_of_inverse(&self, j: usize) -> Vec<f64> {
        // Zeros written, not `vec!`'s calloc: a fresh mapped page that the solve reads before
        // writing would fault twice (the shared zero page, then its copy).
        let mut c = Vec::with_capacity(self.dim());
        c.resize(self.dim(), 0.0);
        c[j] = 1.0;
        self.solve_in_place(&mut c);
        c
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The halves and twist pivot by the formulas of [`Ldlt`]'s doc, each reduced entry
    /// computed from scratch where it is used (the sweeps of `factor_by` carry them instead).
    fn by_the_formulas(a: &SymTridiag) -> (Vec<[f64; 5]>, Vec<[f64; 5]>, f64) {
        let (d, e, n) = (&a.diag, &a.off, a.dim());
        let odd = |k: usize| {
            let o = 2 * k + 1;
            let f2 = if o + 1 < n { e[o] / d[o] } else { 0.0 };
            [e[o - 1] / d[o], f2, 1.0 / d[o]]
        };
        let reduced_diag = |r: usize| {
            let i = 2 * r;
            let mut p = d[i];
            if r > 0 {
                p -= e[i - 1] * odd(r - 1)[1];
            }
            if i + 1 < n {
                p -= e[i] * odd(r)[0];
            }
            p
        };
        let reduced_off = |r: usize| -(e[2 * r] * odd(r)[1]);
        let (nu, twist) = (n.div_ceil(2), n.div_ceil(2) / 2);
        let (mut top, mut l) = (Vec::new(), 0.0);
        for r in 0..twist {
            let mut p = reduced_diag(r);
            if r > 0 {
                p -= reduced_off(r - 1) * l;
            }
            l = reduced_off(r) / p;
            let [f1, f2, inv_d] = odd(r);
            top.push([l, 1.0 / p, f1, f2, inv_d]);
        }
        let (mut bottom, mut l) = (Vec::new(), 0.0);
        for r in (twist + 1..nu).rev() {
            let mut p = reduced_diag(r);
            if r < nu - 1 {
                p -= reduced_off(r) * l;
            }
            l = reduced_off(r - 1) / p;
            let [f1, f2, inv_d] = odd(r - 1);
            bottom.push([l, 1.0 / p, f1, f2, inv_d]);
        }
        let mut g = reduced_diag(twist);
        if let Some(row) = top.last() {
            g -= reduced_off(twist - 1) * row[0];
        }
        if let Some(row) = bottom.last() {
            g -= reduced_off(twist) * row[0];
        }
        (top, bottom, 1.0 / g)
    }

    /// The solve compiled for AVX gives the bits of the baseline build (see [`dispatch`]),
    /// for every parity and small size (empty halves, the outer odd node) and a large one,
    /// separate and in place, with and without the fused `u += x`.
    #[cfg(target_arch = "x86_64")]
    #[test]
    fn the_solve_gives_the_same_bits_with_and_without_avx() {
        if !dispatch::has_avx() {
            eprintln!("this CPU has no AVX: only the baseline build runs, nothing to compare");
            return;
        }
        for n in (1usize..=13).chain([100, 1001]) {
            let diag = (0..n).map(|i| 4.0 + (i as f64 * 0.7).sin()).collect();
            let off = (0..n.saturating_sub(1))
                .map(|i| -1.0 + 0.3 * (i as f64).cos())
                .collect();
            let f = Ldlt::factor(&SymTridiag::new(diag, off)).unwrap();
            let b: Vec<f64> = (0..n).map(|i| (i as f64 * 1.3 + 0.2).cos()).collect();
            let u0: Vec<f64> = (0..n).map(|i| 1e3 + (i as f64).sin()).collect();
            let bits = |x: &[f64]| x.iter().map(|v| v.to_bits()).collect::<Vec<_>>();
            let mut outputs = Vec::new();
            for avx in [false, true] {
                let (mut x, mut u, mut y) = (vec![0.0; n], u0.clone(), b.clone());
                fn cells(v: &mut [f64]) -> &[Cell<f64>] {
                    Cell::from_mut(v).as_slice_of_cells()
                }
                let (xc, uc) = (cells(&mut x), cells(&mut u));
                let separate = Solve::<f64, true> {
                    ldlt: &f,
                    b: &b,
                    x: xc,
                    u: uc,
                };
                let yc = cells(&mut y);
                let in_place = Solve::<Cell<f64>, false> {
                    ldlt: &f,
                    b: yc,
                    x: yc,
                    u: yc,
                };
                if avx {
                    dispatch::run(separate);
                    dispatch::run(in_place);
                } else {
                    dispatch::baseline(separate);
                    dispatch::baseline(in_place);
                }
                outputs.push((bits(&x), bits(&u), bits(&y)));
            }
            assert_eq!(outputs[0], outputs[1], "n = {n}");
        }
    }

    /// A solve with halves that store their stationary row once gives the bits of the same
    /// factorisation with every row stored, on uniform matrices (compact halves of different
    /// stored lengths: plain, one end or both ends changed), one uniform on each side of the
    /// twist with different stationary rows, and a non-uniform one (nothing to compact),
    /// separate and in place, with the fused update (mutation-checked: a segment taking its
    /// stationary row from the wrong half fails it).
    #[test]
    fn compact_halves_solve_like_stored_rows() {
        for n in (1usize..=14).chain([60, 61, 1000, 1001]) {
            let a = SymTridiag::new(vec![4.0; n], vec![-1.0; n.saturating_sub(1)]);
            let wobbly = SymTridiag::new(
                (0..n).map(|i| 4.0 + (i as f64).sin()).collect(),
                vec![-1.0; n.saturating_sub(1)],
            );
            // Uniform on each side of the twist node `2μ` with different diagonals: both halves
            // compact, with different stationary rows.
            let twist_node = 2 * (n.div_ceil(2) / 2);
            // Both ways round, so that each half is once the one storing fewer rows.
            let two_level = |left: f64, right: f64| {
                SymTridiag::new(
                    (0..n)
                        .map(|i| if i < twist_node { left } else { right })
                        .collect(),
                    vec![-1.0; n.saturating_sub(1)],
                )
            };
            let mut cases = vec![
                Ldlt::factor(&a).unwrap(),
                Ldlt::factor(&wobbly).unwrap(),
                Ldlt::factor(&two_level(4.0, 5.0)).unwrap(),
                Ldlt::factor(&two_level(5.0, 4.0)).unwrap(),
            ];
            if n == 1001 {
                let stored = |f: &Ldlt| (f.top.rows.len(), f.bottom.rows.len());
                for f in &cases[2..4] {
                    let (pt, pb) = stored(f);
                    assert!(pt < 64 && pb < 64);
                    assert_ne!(f.top.rows.last(), f.bottom.rows.last());
                }
                let ((t1, b1), (t2, b2)) = (stored(&cases[2]), stored(&cases[3]));
                assert!((t1 < b1) != (t2 < b2), "{t1}, {b1}; {t2}, {b2}");
            }
            if n >= 2 {
                for nodes in [&[0][..], &[n - 1], &[0, n - 1]] {
                    let f = Ldlt::factor_with_rows_changed(&a, nodes, RowChange::Identity, &[]);
                    cases.push(f.unwrap());
                }
            }
            let b: Vec<f64> = (0..n).map(|i| (i as f64 * 0.37 + 0.1).cos()).collect();
            let bits = |x: &[f64]| x.iter().map(|v| v.to_bits()).collect::<Vec<_>>();
            for f in cases {
                let stored = |h: &Half| {
                    Arc::new(Half {
                        rows: h.expanded(),
                        len: h.len,
                    })
                };
                let full = Ldlt {
                    top: stored(&f.top),
                    bottom: stored(&f.bottom),
                    ..f.clone()
                };
                let solve = |g: &Ldlt| {
                    let (mut x, mut u, mut y) = (vec![0.0; n], vec![1.0; n], b.clone());
                    g.solve_into_and_add(&b, &mut x, &mut u);
                    g.solve_in_place(&mut y);
                    (bits(&x), bits(&u), bits(&y))
                };
                assert_eq!(solve(&f), solve(&full), "n {n}");
            }
        }
    }

    /// The sweeps that carry the odd nodes' quotients and the reduced off-diagonals from row to
    /// row give the bits of the formulas, at every size from 1 to 13 and at 100, 101 and 1000.
    #[test]
    fn the_carried_sweeps_equal_the_formulas_bit_for_bit() {
        for n in (1usize..=13).chain([100, 101, 1000]) {
            let a = SymTridiag::new(
                (0..n).map(|i| 3.0 + (i as f64 * 0.7).sin()).collect(),
                (0..n.saturating_sub(1))
                    .map(|i| (i as f64 * 1.3).cos())
                    .collect(),
            );
            let f = Ldlt::factor(&a).unwrap();
            let (top, bottom, inv_twist) = by_the_formulas(&a);
            let bits = |h: &[[f64; 5]]| h.iter().flatten().map(|x| x.to_bits()).collect::<Vec<_>>();
            assert_eq!(bits(&f.top.expanded()), bits(&top), "n {n}: top");
            assert_eq!(bits(&f.bottom.expanded()), bits(&bottom), "n {n}: bottom");
            assert_eq!(f.inv_twist.to_bits(), inv_twist.to_bits(), "n {n}: twist");
        }
    }

    /// On matrices whose interior is uniform (where the sweeps become stationary and copy
    /// rows), also with a bump in the middle, identity rows or a shifted diagonal at the ends,
    /// and a step-matrix-like stiff case that converges slowly: the bits of the formulas.
    #[test]
    fn stationary_sweeps_equal_the_formulas_bit_for_bit() {
        let bits = |h: &[[f64; 5]]| h.iter().flatten().map(|x| x.to_bits()).collect::<Vec<_>>();
        let check = |a: &SymTridiag, f: &Ldlt, what: &str| {
            let (top, bottom, inv_twist) = by_the_formulas(a);
            assert_eq!(bits(&f.top.expanded()), bits(&top), "{what}: top");
            assert_eq!(bits(&f.bottom.expanded()), bits(&bottom), "{what}: bottom");
            assert_eq!(f.inv_twist.to_bits(), inv_twist.to_bits(), "{what}: twist");
        };
        for n in (1usize..=14).chain([100, 101, 1000, 4097]) {
            for (d, e, end) in [
                (4.0, 1.0, 2.0),
                (2.0 + 1e-4, -1.0, 1.0 + 5e-5),
                (1.0, 0.25, 0.6),
            ] {
                let mut diag = vec![d; n];
                if n > 1 {
                    diag[0] = end;
                    diag[n - 1] = end;
                }
                let mut a = SymTridiag::new(diag.clone(), vec![e; n.saturating_sub(1)]);
                let f = Ldlt::factor(&a).unwrap();
                check(&a, &f, &format!("n {n}, d {d}"));
                if n >= 1000 && d == 4.0 {
                    // Converged within a few dozen rows: each half stores its stationary row
                    // once.
                    for h in [&f.top, &f.bottom] {
                        assert!(h.rows.len() < 64 && h.len > 200, "n {n}: {}", h.rows.len());
                    }
                }
                if n > 6 {
                    diag[n / 2] *= 1.5;
                    a = SymTridiag::new(diag.clone(), vec![e; n - 1]);
                    check(
                        &a,
                        &Ldlt::factor(&a).unwrap(),
                        &format!("n {n}, d {d}, bump"),
                    );
                }
                if n > 20 {
                    // Identity rows inside a stationary stretch, on each side of the twist.
                    let inner = [n / 3, n / 2 + 3];
                    let (mut di, mut off) = (diag.clone(), vec![e; n - 1]);
                    for c in inner {
                        (di[c], off[c - 1], off[c]) = (1.0, 0.0, 0.0);
                    }
                    let f = Ldlt::factor_with_rows_changed(&a, &inner, RowChange::Identity, &[])
                        .unwrap();
                    check(&SymTridiag::new(di, off), &f, &format!("n {n}, inner"));
                }
                if n >= 2 {
                    let ends = [0, n - 1];
                    let mut di = diag.clone();
                    let mut off = vec![e; n - 1];
                    (di[0], di[n - 1], off[0], off[n - 2]) = (1.0, 1.0, 0.0, 0.0);
                    let f = Ldlt::factor_with_rows_changed(&a, &ends, RowChange::Identity, &[])
                        .unwrap();
                    check(&SymTridiag::new(di, off), &f, &format!("n {n}, identity"));
                    let mut ds = diag.clone();
                    ds[0] += 3.0;
                    ds[n - 1] += 3.0;
                    let f = Ldlt::factor_with_rows_changed(
                        &a,
                        &ends,
                        RowChange::AddToDiagonal(3.0),
                        &[],
                    )
                    .unwrap();
                    check(
                        &SymTridiag::new(ds, vec![e; n - 1]),
                        &f,
                        &format!("n {n}, shift"),
                    );
                }
            }
        }
    }

    /// Each factorisation made with halves taken from earlier ones (as the exact and penalty
    /// solvers make theirs) equals the one computed from scratch bit for bit, for identity rows
    /// and for a diagonal shift, at the ends, next to them, at the twist node and inside, at
    /// every size from 2 to 13 and at 101 and 1000; with both ends of a bar of 5 nodes or
    /// more, the plain factorisation and the three changed ones hold four distinct halves.
    #[test]
    fn shared_halves_equal_the_halves_computed_from_scratch() {
        let bits = |f: &Ldlt| {
            let half = |h: &[[f64; 5]]| h.iter().flatten().map(|x| x.to_bits()).collect::<Vec<_>>();
            (
                half(&f.top.expanded()),
                half(&f.bottom.expanded()),
                f.outer.map(|o| o.map(f64::to_bits)),
                f.inv_twist.to_bits(),
            )
        };
        for n in (2usize..=13).chain([101, 1000]) {
            let a = SymTridiag::new(
                (0..n).map(|i| 3.0 + (i as f64 * 0.7).sin()).collect(),
                (0..n - 1).map(|i| (i as f64 * 1.3).cos()).collect(),
            );
            let twist_node = 2 * (n.div_ceil(2) / 2);
            let plain = Ldlt::factor(&a).unwrap();
            let changes = [RowChange::Identity, RowChange::AddToDiagonal(7.5)];
            for (change, pair) in changes.into_iter().flat_map(|change| {
                [
                    [0, n - 1],
                    [1, n - 2],
                    [0, twist_node],
                    [twist_node, n - 1],
                    [n / 3, n - 1],
                ]
                .map(|pair| (change, pair))
            }) {
                let sets: [&[usize]; 3] = [&pair[..1], &pair[1..], &pair[..]];
                let mut made: Vec<Ldlt> = Vec::new();
                for set in sets {
                    let known: Vec<(&[usize], &Ldlt)> = std::iter::once((&[][..], &plain))
                        .chain(sets.iter().copied().zip(&made))
                        .collect();
                    let shared = Ldlt::factor_with_rows_changed(&a, set, change, &known).unwrap();
                    let fresh = Ldlt::factor_with_rows_changed(&a, set, change, &[]).unwrap();
                    assert_eq!(bits(&shared), bits(&fresh), "n {n}, {change:?} at {set:?}");
                    made.push(shared);
                }
                if pair == [0, n - 1] && n >= 5 {
                    let mut halves: Vec<&Arc<Half>> = Vec::new();
                    for f in std::iter::once(&plain).chain(&made) {
                        for h in [&f.top, &f.bottom] {
                            if !halves.iter().any(|k| Arc::ptr_eq(k, h)) {
                                halves.push(h);
                            }
                        }
                    }
                    assert_eq!(halves.len(), 4, "n {n}");
                }
            }
        }
    }

    /// `top_end` and `bottom_end` stop at the row where the row-by-row checks stop, on arrays
    /// that repeat with period two in stretches broken at random places, with changed rows
    /// anywhere, for every start and twist.
    #[test]
    fn the_block_scans_stop_where_the_row_checks_stop() {
        let mut seed = 0x9e37_79b9_7f4a_7c15_u64;
        let mut next = || {
            seed ^= seed << 13;
            seed ^= seed >> 7;
            seed ^= seed << 17;
            seed
        };
        let mut long = 0;
        for n in (4usize..=40).chain([67, 100, 101]) {
            for trial in 0..12 {
                // Period two, with a break every so often (none in the first trials).
                let mut rd = vec![2.0, 3.0];
                let mut re = vec![-1.0, 0.5];
                while rd.len() < n {
                    let i = rd.len();
                    let breaks = trial > 2 && next() % (4 + 3 * trial as u64) == 0;
                    rd.push(if breaks { rd[i - 2] + 1.0 } else { rd[i - 2] });
                    let breaks = trial > 2 && next() % (4 + 3 * trial as u64) == 0;
                    re.push(if breaks { re[i - 2] * 0.5 } else { re[i - 2] });
                }
                rd.truncate(n);
                re.truncate(n - 1);
                let changed: Vec<usize> = (0..trial % 4).map(|_| next() as usize % n).collect();
                let rows = RawRows {
                    rd: &rd,
                    re: &re,
                    changed: &changed,
                    n,
                };
                let nu = n.div_ceil(2);
                for twist in 0..=nu {
                    for start in 3..nu + 2 {
                        let mut end = start;
                        while end < twist && rows.top_repeats(end) {
                            end += 1;
                        }
                        assert_eq!(rows.top_end(start, twist), end, "top n {n} {twist} {start}");
                        long += usize::from(end > start + 2);
                        let mut end = start;
                        while end + twist + 1 < nu && rows.bottom_repeats(nu - 1 - end) {
                            end += 1;
                        }
                        let got = rows.bottom_end(start, nu, twist);
                        assert_eq!(got, end, "bottom n {n} {changed:?} {twist} {start}");
                    }
                }
            }
        }
        assert!(long > 1000, "{long} long stretches");
    }
}
