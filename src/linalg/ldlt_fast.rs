//! The optimised twin of [`super::ldlt`] for the per-step solve: one step of odd–even reduction,
//! then a twisted factorisation of the reduced system, so that a solve runs two dependent
//! chains at once, each link covering two nodes of the bar. Solutions agree with the plain
//! [`Ldlt`](super::ldlt::Ldlt) to round-off (both backward stable), not bit for bit.

use crate::linalg::ldlt::{NotPositiveDefinite, RowChange, changed_entries, checked_pivot};
use crate::linalg::tridiag::SymTridiag;

/// A factorisation of a symmetric positive definite tridiagonal matrix `A` with a quarter of
/// the plain sweep's dependent latency: measured 2.5–3x faster than the plain solve on the
/// bar's unconstrained step at J = 1e4 … 1e6 (benches/README.md, "Plain kernels and their
/// twins").
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
    top: Vec<[f64; 5]>,
    bottom: Vec<[f64; 5]>,
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
        x.copy_from_slice(b);
        self.solve_in_place(x);
    }

    /// `A⁻¹ e_j` as a new vector (set-up only).
    pub fn column_of_inverse(&self, j: usize) -> Vec<f64> {
        let mut c = vec![0.0; self.dim()];
        c[j] = 1.0;
        self.solve_in_place(&mut c);
        c
    }

    /// Overwrites `x` (holding `b`) with `A⁻¹ b`. Inward, the two chains eliminate towards the
    /// twist row, folding in the odd nodes, and leave `y_r/D_r` at each even node; outward,
    /// they substitute back, and each reduced row fills in its inner odd node (whose `b_o` the
    /// inward sweep left in place).
    pub fn solve_in_place(&self, x: &mut [f64]) {
        assert_eq!(x.len(), self.n, "right-hand side length");
        if self.n == 0 {
            return;
        }
        // Top rows r < μ own nodes (2r, 2r+1); the twist is node 2μ; bottom rows own
        // (2r−1, 2r), from the far end; then the outer odd node when n is even.
        let (m, k) = (self.top.len(), self.bottom.len());
        let common = m.min(k);
        let (x_top, rest) = x.split_at_mut(2 * m);
        let (x_mid, rest) = rest.split_first_mut().expect("the twist node");
        let (x_bottom, x_outer) = rest.split_at_mut(2 * k);

        // Inward. Per chain: y (the elimination value), l (the multiplier of the row before)
        // and c, the term of the shared odd node (`f b_o`) the next row subtracts.
        let (mut yt, mut lt, mut ct) = (0.0, 0.0, 0.0);
        let (mut yb, mut lb) = (0.0, 0.0);
        let mut cb = match (self.outer, x_outer.first()) {
            (Some([f1, _]), Some(bo)) => f1 * bo,
            _ => 0.0,
        };
        let inward_top = |x: &mut [f64], f: &[f64; 5], y: &mut f64, l: &mut f64, c: &mut f64| {
            let (be, bo) = (x[0], x[1]);
            *y = ((be - *c) - f[2] * bo) - *l * *y;
            x[0] = *y * f[1];
            (*l, *c) = (f[0], f[3] * bo);
        };
        let inward_bottom = |x: &mut [f64], f: &[f64; 5], y: &mut f64, l: &mut f64, c: &mut f64| {
            let (bo, be) = (x[0], x[1]);
            *y = ((be - f[3] * bo) - *c) - *l * *y;
            x[1] = *y * f[1];
            (*l, *c) = (f[0], f[2] * bo);
        };
        let mut top = x_top.chunks_exact_mut(2).zip(&self.top);
        let mut bottom = x_bottom.rchunks_exact_mut(2).zip(&self.bottom);
        for ((xt, ft), (xb, fb)) in (top.by_ref().take(common)).zip(bottom.by_ref().take(common)) {
            inward_top(xt, ft, &mut yt, &mut lt, &mut ct);
            inward_bottom(xb, fb, &mut yb, &mut lb, &mut cb);
        }
        for (xt, ft) in top {
            inward_top(xt, ft, &mut yt, &mut lt, &mut ct);
        }
        for (xb, fb) in bottom {
            inward_bottom(xb, fb, &mut yb, &mut lb, &mut cb);
        }
        // The twist row: the terms are 0 when a side is empty (l = 0, y = 0, c = 0).
        let xm = (((*x_mid - ct) - cb) - lt * yt - lb * yb) * self.inv_twist;
        *x_mid = xm;

        // Outward: x_2r = y_r/D_r − l_r x_(next even), then the inner odd node from its two
        // even neighbours (left one first); the longer half's rows nearest the twist first.
        let (mut xt_next, mut xb_next) = (xm, xm);
        let outward_top = |x: &mut [f64], f: &[f64; 5], xn: &mut f64| {
            let xe = x[0] - f[0] * *xn;
            x[1] = x[1] * f[4] - f[2] * xe - f[3] * *xn;
            x[0] = xe;
            *xn = xe;
        };
        let outward_bottom = |x: &mut [f64], f: &[f64; 5], xn: &mut f64| {
            let xe = x[1] - f[0] * *xn;
            x[0] = x[0] * f[4] - f[2] * *xn - f[3] * xe;
            x[1] = xe;
            *xn = xe;
        };
        let mut top = x_top.chunks_exact_mut(2).zip(&self.top).rev();
        let mut bottom = x_bottom.rchunks_exact_mut(2).zip(&self.bottom).rev();
        for (xt, ft) in top.by_ref().take(m - common) {
            outward_top(xt, ft, &mut xt_next);
        }
        for (xb, fb) in bottom.by_ref().take(k - common) {
            outward_bottom(xb, fb, &mut xb_next);
        }
        for ((xt, ft), (xb, fb)) in top.zip(bottom) {
            outward_top(xt, ft, &mut xt_next);
            outward_bottom(xb, fb, &mut xb_next);
        }
        if let (Some([f1, inv_d]), Some(xo)) = (self.outer, x_outer.first_mut()) {
            *xo = *xo * inv_d - f1 * xb_next;
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::linalg::ldlt::Ldlt;
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
            for (d, e) in [(4.0, -1.0), (2.0 + 1e-4, -1.0), (1.0, 0.25)] {
                // Wobbling entries that keep the diagonal dominance of (d, e): SPD.
                let a = SymTridiag::new(
                    (0..n)
                        .map(|i| d + 0.1 * (i as f64 * 0.7).sin().abs())
                        .collect(),
                    (0..n.saturating_sub(1))
                        .map(|i| e * (1.0 - 0.2 * (i as f64).cos().abs()))
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

    /// A matrix that is not positive definite is refused.
    #[test]
    fn an_indefinite_matrix_is_refused() {
        let a = SymTridiag::new(vec![1.0, 1.0, 1.0], vec![0.5, 1.0]);
        assert!(TwistedLdlt::factor(&a).is_err());
    }
}
