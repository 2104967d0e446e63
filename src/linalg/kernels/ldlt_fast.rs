//! The optimised twin of [`super::ldlt`] for the per-step solve: one step of odd–even reduction,
//! then a twisted factorisation of the reduced system, so that a solve runs two dependent
//! chains at once, each link covering two nodes of the bar. Solutions agree with the plain
//! [`Ldlt`](super::ldlt::Ldlt) to round-off (both backward stable), not bit for bit.

use crate::linalg::kernels::dispatch;
use crate::linalg::kernels::ldlt::{
    NotPositiveDefinite, RowChange, changed_entries, checked_pivot,
};
use crate::linalg::tridiag::SymTridiag;
use std::cell::Cell;

/// A factorisation of a symmetric positive definite tridiagonal matrix `A` with a quarter of
/// the plain sweep's dependent latency, whose solve streams the right-hand side and the
/// solution but not the factor on a uniform interior ([`TwistedLdlt::solve_into_and_add`]);
/// what it buys on the bar's steps is measured in benches/README.md, "Plain kernels and their
/// twins".
///
/// *Reduction.* The odd nodes are not neighbours of each other, so eliminating them first
/// (pivots `d_o`) leaves a tridiagonal Schur complement `A'` on the even nodes (`ν = ⌈n/2⌉`
/// rows): `D'_r = d_2r − e_2r−1²/d_2r−1 − e_2r²/d_2r+1`, `E'_r = −e_2r e_2r+1/d_2r+1`, right-hand
/// side `b'_r = b_2r − f2_2r−1 b_2r−1 − f1_2r+1 b_2r+1` with `f1_o = e_o−1/d_o`, `f2_o = e_o/d_o`.
/// Once the even unknowns are known, `x_o = b_o/d_o − f1_o x_o−1 − f2_o x_o+1`.
///
/// *Twisted factorisation of `A'`* ("burn at both ends"): `L D Lᵀ` from the top for reduced
/// rows `0..μ`, `U D Uᵀ` from the bottom for rows `μ+1..ν`, joined at the twist row `μ = ν/2`;
/// a solve runs the top and bottom chains interleaved in one loop.
///
/// Both parts are Gaussian elimination without pivoting on the symmetrically permuted matrix
/// `P A Pᵀ`, which is positive definite, so the solve is backward stable like the plain sweep
/// (Higham, *Accuracy and Stability of Numerical Algorithms*, 2nd ed., Thm 10.5 and §9.5).
#[derive(Clone, Debug)]
pub struct TwistedLdlt {
    /// One row per reduced row in the order the inward sweep visits it, with the odd node on
    /// its inner side (towards the twist): `top[r] = [l_r, 1/D_r, f1_o, f2_o, 1/d_o]` with
    /// `o = 2r + 1` for rows `r = 0..μ` (`l_r = E'_r/D_r`); `bottom[k]` the same for row
    /// `r = ν−1−k > μ` with `o = 2r − 1` and `l_r = E'_r−1/D_r`.
    top: Half,
    bottom: Half,
    /// `[f1, 1/d]` of the last node when it is odd (`n` even): on no reduced row's inner side.
    outer: Option<[f64; 2]>,
    /// `1/D_μ`, the twist pivot.
    inv_twist: f64,
    n: usize,
}

impl TwistedLdlt {
    pub fn factor(a: &SymTridiag) -> Result<Self, NotPositiveDefinite> {
        Self::factor_with_rows_changed(a, &[], RowChange::Identity)
    }

    /// The factorisation of `a` with the rows of `nodes` changed by `change`.
    pub fn factor_with_rows_changed(
        a: &SymTridiag,
        nodes: &[usize],
        change: RowChange,
    ) -> Result<Self, NotPositiveDefinite> {
        let (diag, off) = changed_entries(a, nodes, change);
        Self::factor_by(a.dim(), diag, off)
    }

    /// The factorisation of the matrix with diagonal `d(i)` and off-diagonal `e(i) = A_i,i+1`,
    /// by the formulas of [`TwistedLdlt`]'s doc.
    fn factor_by(
        n: usize,
        d: impl Fn(usize) -> f64,
        e: impl Fn(usize) -> f64,
    ) -> Result<Self, NotPositiveDefinite> {
        for o in (1..n).step_by(2) {
            checked_pivot(o, d(o))?;
        }
        // Odd node `2k + 1`: [f1, f2, 1/d] (f2 = 0 for the last node).
        let odd = |k: usize| {
            let o = 2 * k + 1;
            let f2 = if o + 1 < n { e(o) / d(o) } else { 0.0 };
            [e(o - 1) / d(o), f2, 1.0 / d(o)]
        };
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
        let (nu, twist) = (n.div_ceil(2), n.div_ceil(2) / 2);
        let (mut top, mut l) = (Vec::with_capacity(twist), 0.0);
        for r in 0..twist {
            let mut p = reduced_diag(r);
            if r > 0 {
                p -= reduced_off(r - 1) * l;
            }
            let p = checked_pivot(2 * r, p)?;
            l = reduced_off(r) / p;
            let [f1, f2, inv_d] = odd(r);
            top.push([l, 1.0 / p, f1, f2, inv_d]);
        }
        let mut bottom = Vec::with_capacity(nu.saturating_sub(twist + 1));
        let mut l = 0.0;
        for r in (twist + 1..nu).rev() {
            let mut p = reduced_diag(r);
            if r < nu - 1 {
                p -= reduced_off(r) * l;
            }
            let p = checked_pivot(2 * r, p)?;
            l = reduced_off(r - 1) / p;
            let [f1, f2, inv_d] = odd(r - 1);
            bottom.push([l, 1.0 / p, f1, f2, inv_d]);
        }
        let mut inv_twist = 0.0;
        if n > 0 {
            let mut g = reduced_diag(twist);
            if let Some(row) = top.last() {
                g -= reduced_off(twist - 1) * row[0];
            }
            if let Some(row) = bottom.last() {
                g -= reduced_off(twist) * row[0];
            }
            inv_twist = 1.0 / checked_pivot(2 * twist, g)?;
        }
        let (top, bottom) = Half::pair(top, bottom);
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

    /// `x = A⁻¹ b`.
    pub fn solve_into(&self, b: &[f64], x: &mut [f64]) {
        let (b, u) = (Some(b), None);
        dispatch::run(Sweep {
            factor: self,
            b,
            x,
            u,
        })
    }

    /// `A⁻¹ e_j` as a new vector (set-up only).
    pub fn column_of_inverse(&self, j: usize) -> Vec<f64> {
        let mut c = vec![0.0; self.dim()];
        c[j] = 1.0;
        self.solve_in_place(&mut c);
        c
    }

    /// Overwrites `x` (holding `b`) with `A⁻¹ b`.
    pub fn solve_in_place(&self, x: &mut [f64]) {
        let (b, u) = (None, None);
        dispatch::run(Sweep {
            factor: self,
            b,
            x,
            u,
        })
    }

    /// `x = A⁻¹ b`, and `u += x` as each `x_i` is found: the time step's solve and update in
    /// one pass over the bar, with the bits of [`TwistedLdlt::solve_into`] and `u += x`.
    pub fn solve_into_and_add(&self, b: &[f64], x: &mut [f64], u: &mut [f64]) {
        assert_eq!(u.len(), self.n, "state length");
        let (b, u) = (Some(b), Some(u));
        dispatch::run(Sweep {
            factor: self,
            b,
            x,
            u,
        })
    }

    /// `x = A⁻¹ b`, reading `b` from `b` (which may be `x` itself: each entry of `b` is read
    /// before `x` overwrites it), and with `ADD` each `x_i` added to `u_i` (else `u` is not
    /// touched and may be `x`). Inward, the two chains eliminate towards the twist row,
    /// folding in the odd nodes, and leave `y_r/D_r` at each even node; outward, they
    /// substitute back, and each reduced row fills in its inner odd node from `b_o`.
    #[inline(always)]
    fn sweep<V: Value, const ADD: bool>(&self, b: &[V], x: &[Cell<f64>], u: &[Cell<f64>]) {
        assert_eq!(b.len(), self.n, "right-hand side length");
        assert_eq!(x.len(), self.n, "solution length");
        if self.n == 0 {
            return;
        }
        // Top rows r < μ own nodes (2r, 2r+1); the twist is node 2μ; bottom rows own
        // (2r−1, 2r), from the far end; then the outer odd node when n is even.
        let (m, k) = (self.top.len, self.bottom.len);
        let common = m.min(k);
        let (b_top, b_rest) = b.split_at(2 * m);
        let (b_mid, b_rest) = b_rest.split_at(1);
        let (b_bottom, b_outer) = b_rest.split_at(2 * k);
        let (x_top, x_rest) = x.split_at(2 * m);
        let (x_mid, x_rest) = x_rest.split_at(1);
        let (x_bottom, x_outer) = x_rest.split_at(2 * k);
        let (u_top, u_rest) = u.split_at(2 * m);
        let (u_mid, u_rest) = u_rest.split_at(1);
        let (u_bottom, u_outer) = u_rest.split_at(2 * k);

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
        // Links `0..p` read both halves' stored rows, links `p..common` their repeated rows
        // (from registers), then the longer half's rest.
        let p = self.top.rows.len().min(self.bottom.rows.len()).min(common);
        let (top_still, bottom_still) = (self.top.still(), self.bottom.still());
        let mut top = b_top.chunks_exact(2).zip(x_top.chunks_exact(2));
        let mut bottom = b_bottom.rchunks_exact(2).zip(x_bottom.rchunks_exact(2));
        let stored = self.top.rows[..p].iter().zip(&self.bottom.rows[..p]);
        // (`stored` first: a zip stops at its first exhausted part before advancing the next.)
        for ((ft, fb), ((bt, xt), (bb, xb))) in stored.zip(top.by_ref().zip(bottom.by_ref())) {
            inward_top(bt, xt, ft, &mut yt, &mut lt, &mut ct);
            inward_bottom(bb, xb, fb, &mut yb, &mut lb, &mut cb);
        }
        for ((bt, xt), (bb, xb)) in top.by_ref().zip(bottom.by_ref()).take(common - p) {
            inward_top(bt, xt, &top_still, &mut yt, &mut lt, &mut ct);
            inward_bottom(bb, xb, &bottom_still, &mut yb, &mut lb, &mut cb);
        }
        for (r, (bt, xt)) in (common..).zip(top) {
            inward_top(bt, xt, self.top.row(r), &mut yt, &mut lt, &mut ct);
        }
        for (j, (bb, xb)) in (common..).zip(bottom) {
            inward_bottom(bb, xb, self.bottom.row(j), &mut yb, &mut lb, &mut cb);
        }
        // The twist row: the terms are 0 when a side is empty (l = 0, y = 0, c = 0).
        let xm = (((b_mid[0].value() - ct) - cb) - lt * yt - lb * yb) * self.inv_twist;
        x_mid[0].set(xm);
        let add = |u: &Cell<f64>, v: f64| {
            if ADD {
                u.set(u.get() + v);
            }
        };
        add(&u_mid[0], xm);

        // Outward: x_2r = y_r/D_r − l_r x_(next even), then the inner odd node from its two
        // even neighbours (left one first); the longer half's rows nearest the twist first.
        let (mut xt_next, mut xb_next) = (xm, xm);
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
        for (r, ((bt, xt), ut)) in (common..m).rev().zip(top.by_ref()) {
            outward_top(bt, xt, ut, self.top.row(r), &mut xt_next);
        }
        for (j, ((bb, xb), ub)) in (common..k).rev().zip(bottom.by_ref()) {
            outward_bottom(bb, xb, ub, self.bottom.row(j), &mut xb_next);
        }
        for (((bt, xt), ut), ((bb, xb), ub)) in top.by_ref().zip(bottom.by_ref()).take(common - p) {
            outward_top(bt, xt, ut, &top_still, &mut xt_next);
            outward_bottom(bb, xb, ub, &bottom_still, &mut xb_next);
        }
        let stored = self.top.rows[..p].iter().zip(&self.bottom.rows[..p]).rev();
        for ((((bt, xt), ut), ((bb, xb), ub)), (ft, fb)) in top.zip(bottom).zip(stored) {
            outward_top(bt, xt, ut, ft, &mut xt_next);
            outward_bottom(bb, xb, ub, fb, &mut xb_next);
        }
        if let (Some([f1, inv_d]), Some(bo), Some(xo)) =
            (self.outer, b_outer.first(), x_outer.first())
        {
            let v = bo.value() * inv_d - f1 * xb_next;
            xo.set(v);
            add(&u_outer[0], v);
        }
    }
}

/// An entry of the right-hand side: a number, or a cell of `x` itself (a solve in place).
/// A solve's sweep (`b` apart or in `x`, `u += x` or not), for [`dispatch::run`]: compiled for
/// AVX where the CPU has it, the same operations in the same order (the same bits).
struct Sweep<'a> {
    factor: &'a TwistedLdlt,
    b: Option<&'a [f64]>,
    x: &'a mut [f64],
    u: Option<&'a mut [f64]>,
}

impl dispatch::Kernel for Sweep<'_> {
    type Output = ();
    #[inline(always)]
    fn call(self) {
        let x = Cell::from_mut(self.x).as_slice_of_cells();
        match (self.b, self.u) {
            (Some(b), Some(u)) => {
                (self.factor).sweep::<_, true>(b, x, Cell::from_mut(u).as_slice_of_cells())
            }
            (Some(b), None) => self.factor.sweep::<_, false>(b, x, x),
            (None, _) => self.factor.sweep::<_, false>(x, x, x),
        }
    }
}

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

/// The rows of one half of the twisted factorisation, in the order its chain visits them.
/// On a uniform interior the pivots converge and the rows become bitwise equal: only the rows
/// up to the first of those are stored, and the iterators repeat it, so that a solve streams
/// the right-hand side and the solution but not the factor.
#[derive(Clone, Debug)]
struct Half {
    rows: Vec<[f64; 5]>,
    len: usize,
}

impl Half {
    /// The two halves without their bitwise-repeated tails, each keeping as many rows as the
    /// other needs (so that a solve's links read stored rows on both sides, or neither).
    fn pair(top: Vec<[f64; 5]>, bottom: Vec<[f64; 5]>) -> (Self, Self) {
        let needed = |rows: &[[f64; 5]]| {
            let bits = |row: &[f64; 5]| row.map(f64::to_bits);
            let mut p = rows.len();
            while p >= 2 && bits(&rows[p - 2]) == bits(&rows[p - 1]) {
                p -= 1;
            }
            p
        };
        let keep = needed(&top).max(needed(&bottom));
        let half = |mut rows: Vec<[f64; 5]>| {
            let len = rows.len();
            rows.truncate(keep);
            rows.shrink_to_fit();
            Self { rows, len }
        };
        (half(top), half(bottom))
    }

    /// The last stored row, which the rows after it repeat (zeros for an empty half).
    fn still(&self) -> [f64; 5] {
        self.rows.last().copied().unwrap_or_default()
    }

    /// Row `k < len`.
    #[inline(always)]
    fn row(&self, k: usize) -> &[f64; 5] {
        &self.rows[k.min(self.rows.len() - 1)]
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::linalg::kernels::dispatch::Kernel;
    use crate::linalg::kernels::ldlt::Ldlt;
    use crate::linalg::tridiag::backward_error;

    /// Normwise backward error allowed of either solve, in units of ε: Higham's `γ₃`-type
    /// bound for tridiagonal SPD elimination plus the rounding of the residual's evaluation
    /// (the bound `tests/matrices.rs` holds the step's solve to).
    const BACKWARD_ULPS: f64 = 8.0;

    /// Matrices of every parity and small size (empty halves, the outer odd node) and larger
    /// ones, from mass-dominated to nearly singular, with identity rows and diagonal shifts at
    /// the ends: the twin and the plain solve are both backward stable, agree to their
    /// round-off bound `2 BACKWARD_ULPS ε κ∞(A) ‖x‖∞` (each is the exact solution of a nearby
    /// system), and `solve_into` gives the bits of `solve_in_place`.
    #[test]
    fn the_twisted_solve_agrees_with_the_plain_one_to_round_off() {
        for n in (1usize..=14).chain([60, 61, 1000, 1001]) {
            for (d, e, wobble) in [
                (4.0, -1.0, 1.0),
                (2.0 + 1e-4, -1.0, 1.0),
                (1.0, 0.25, 1.0),
                (4.0, -1.0, 0.0),
            ] {
                // Wobbling entries that keep the diagonal dominance of (d, e): SPD; without
                // the wobble, a uniform matrix whose rows repeat (stored once).
                let a = SymTridiag::new(
                    (0..n)
                        .map(|i| d + wobble * 0.1 * (i as f64 * 0.7).sin().abs())
                        .collect(),
                    (0..n.saturating_sub(1))
                        .map(|i| e * (1.0 - wobble * 0.2 * (i as f64).cos().abs()))
                        .collect(),
                );
                let ends = [0, n.saturating_sub(1)];
                let changes = [
                    (&[][..], RowChange::Identity),
                    (&ends[..1], RowChange::Identity),
                    (&ends[..], RowChange::Identity),
                    (&ends[1..], RowChange::AddToDiagonal(3.0)),
                ];
                for (nodes, change) in changes {
                    let (diag, off) = changed_entries(&a, nodes, change);
                    let written = SymTridiag::new(
                        (0..n).map(&diag).collect(),
                        (0..n.saturating_sub(1)).map(&off).collect(),
                    );
                    let fast = TwistedLdlt::factor_with_rows_changed(&a, nodes, change).unwrap();
                    let plain = Ldlt::factor(&written).unwrap();
                    let b: Vec<f64> = (0..n).map(|i| (i as f64 * 1.3 + 0.2).cos()).collect();
                    let (mut x, mut y, mut p) = (b.clone(), vec![0.0; n], b.clone());
                    fast.solve_in_place(&mut x);
                    fast.solve_into(&b, &mut y);
                    plain.solve_in_place(&mut p);
                    let bits = |v: &[f64]| v.iter().map(|x| x.to_bits()).collect::<Vec<_>>();
                    assert_eq!(bits(&x), bits(&y), "n {n}");
                    // The fused update: the bits of the solve, then of `u += x`.
                    let u0: Vec<f64> = (0..n).map(|i| (i as f64 * 0.9).sin()).collect();
                    let (mut u, mut w) = (u0.clone(), vec![0.0; n]);
                    fast.solve_into_and_add(&b, &mut w, &mut u);
                    assert_eq!(bits(&w), bits(&x), "n {n}");
                    let added: Vec<f64> = u0.iter().zip(&x).map(|(a, b)| a + b).collect();
                    assert_eq!(bits(&u), bits(&added), "n {n}");
                    // The solves run the sweep compiled for AVX where the CPU has it; called
                    // directly, it is compiled for the baseline: the same bits.
                    let (mut ub, mut wb) = (u0.clone(), vec![0.0; n]);
                    let (x_b, u_b) = (&mut wb, Some(&mut ub[..]));
                    Sweep {
                        factor: &fast,
                        b: Some(&b),
                        x: x_b,
                        u: u_b,
                    }
                    .call();
                    assert_eq!((bits(&wb), bits(&ub)), (bits(&w), bits(&u)), "n {n}");
                    let what = format!("n {n}, d {d}, {nodes:?}");
                    assert!(backward_error(&written, &x, &b) <= BACKWARD_ULPS, "{what}");
                    assert!(backward_error(&written, &p, &b) <= BACKWARD_ULPS, "{what}");
                    let max_abs = |v: &[f64]| v.iter().fold(0.0f64, |m, x| m.max(x.abs()));
                    let inverse_norm = (0..n)
                        .map(|j| max_abs(&plain.column_of_inverse(j)))
                        .fold(0.0, f64::max)
                        * n as f64;
                    let kappa = written.inf_norm() * inverse_norm;
                    let bound = 2.0 * BACKWARD_ULPS * f64::EPSILON * kappa * max_abs(&p);
                    for (u, v) in x.iter().zip(&p) {
                        assert!(
                            (u - v).abs() <= bound,
                            "{what}: {u} vs {v}, bound {bound:e}"
                        );
                    }
                }
            }
        }
    }

    /// On a uniform matrix the pivots converge and the rows repeat: a long bar stores a few
    /// dozen rows per half, and a matrix with wobbling entries stores them all.
    #[test]
    fn a_uniform_interior_stores_its_repeated_row_once() {
        let n = 100_001;
        let uniform = SymTridiag::new(vec![4.0; n], vec![-1.0; n - 1]);
        let f = TwistedLdlt::factor(&uniform).unwrap();
        assert!(f.top.rows.len() < 100 && f.bottom.rows.len() < 100);
        assert_eq!((f.top.len, f.bottom.len), (25_000, 25_000));
        let wobbling = SymTridiag::new(
            (0..n).map(|i| 4.0 + (i as f64).sin().abs()).collect(),
            vec![-1.0; n - 1],
        );
        let f = TwistedLdlt::factor(&wobbling).unwrap();
        assert_eq!(f.top.rows.len(), f.top.len);
    }

    /// A matrix that is not positive definite is refused.
    #[test]
    fn an_indefinite_matrix_is_refused() {
        let a = SymTridiag::new(vec![1.0, 1.0, 1.0], vec![0.5, 1.0]);
        assert!(TwistedLdlt::factor(&a).is_err());
    }
}
