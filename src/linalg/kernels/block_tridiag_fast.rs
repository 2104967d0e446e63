//! The optimised twin of [`BlockLdlt`]'s solve for the thermal step: a twisted block
//! factorisation, `L D Lᵀ` from the first block and from the last, joined at a middle twist
//! block, so that a solve runs two independent chains at once (the plain sweep is one chain,
//! bound by the latency of its 2 × 2 products); on a uniform interior each half's factor rows
//! settle bitwise on a fixed point, are read once, and each link of a chain covers two rows
//! (`y_{i+1} = (b_{i+1} − L b_i) + L² y_{i−1}`: one step of odd–even reduction, as the bar's
//! [`TwistedLdlt`](super::ldlt_fast::TwistedLdlt) takes). Solutions agree with the plain
//! [`BlockLdlt`] to round-off, not bit for bit; what it buys on a thermal step is measured in
//! benches/README.md, "Plain kernels and their twins".

use crate::linalg::kernels::block_tridiag::{
    Block, BlockLdlt, BlockTridiag, SingularBlock, d_inv_mul, mul, mul_transposed,
};
use crate::linalg::kernels::dispatch;
use std::ops::Range;

/// `A` factorised from both ends: `top` the block `LDLᵀ` of `A` (rows `0..m` used), `bottom`
/// that of `A` with its blocks in reverse order (rows `0..n − 1 − m` used, row `k` for block
/// `n − 1 − k`), and the twist pivot `T_m = A_mm − L_m A_{m,m−1}ᵀ − L'_{n−1−m} A_{m+1,m}`, the
/// Schur complement of `A` on block `m` (quasi-definite when `A` is).
#[derive(Clone, Debug)]
pub struct TwistedBlockLdlt {
    top: Half,
    bottom: Half,
    twist: usize,
    /// `T_m⁻¹ = [[a, b], [b, c]]` as `[a, b, c]`.
    inv_twist: [f64; 3],
    n: usize,
}

/// One direction's factor rows `(L_i, D_i⁻¹)`, with the longest stretch of bitwise-equal rows
/// (`still`, within `1..n − 1`) and that row kept apart.
#[derive(Clone, Debug)]
struct Half {
    factor: BlockLdlt,
    still: Range<usize>,
    row: (Block, [f64; 3]),
    /// `L²` of that row, the stretch's link over two rows.
    square: Block,
}

impl Half {
    fn new(factor: BlockLdlt) -> Self {
        let (l, inv_d) = (factor.l(), factor.inv_d());
        let n = inv_d.len();
        let bits = |i: usize| {
            (
                l[i].map(|r| r.map(f64::to_bits)),
                inv_d[i].map(f64::to_bits),
            )
        };
        let (mut still, mut start) = (1..1, 1);
        for i in 1..n.saturating_sub(1) {
            if bits(i) != bits(start) {
                start = i;
            }
            if i + 1 - start > still.len() {
                still = start..i + 1;
            }
        }
        let row = (l.get(still.start), inv_d.get(still.start));
        let row = (
            row.0.copied().unwrap_or_default(),
            row.1.copied().unwrap_or_default(),
        );
        let square = product(&row.0, &row.0);
        Self {
            factor,
            still,
            row,
            square,
        }
    }

    /// `L_i`.
    #[inline(always)]
    fn l(&self, i: usize) -> &Block {
        if self.still.contains(&i) {
            &self.row.0
        } else {
            &self.factor.l()[i]
        }
    }

    /// `D_i⁻¹`.
    #[inline(always)]
    fn inv_d(&self, i: usize) -> &[f64; 3] {
        if self.still.contains(&i) {
            &self.row.1
        } else {
            &self.factor.inv_d()[i]
        }
    }
}

/// `A B`.
fn product(a: &Block, b: &Block) -> Block {
    [0, 1].map(|r| [0, 1].map(|c| a[r][0] * b[0][c] + a[r][1] * b[1][c]))
}

fn transpose(b: &Block) -> Block {
    [[b[0][0], b[1][0]], [b[0][1], b[1][1]]]
}

impl TwistedBlockLdlt {
    pub fn factor(a: &BlockTridiag) -> Result<Self, SingularBlock> {
        let n = a.blocks();
        let reversed = BlockTridiag {
            diag: a.diag.iter().rev().copied().collect(),
            lower: (0..n)
                .map(|k| match k {
                    0 => [[0.0; 2]; 2],
                    _ => transpose(&a.lower[n - k]),
                })
                .collect(),
        };
        let (top, bottom) = (BlockLdlt::factor(a)?, BlockLdlt::factor(&reversed)?);
        let twist = n.saturating_sub(1) / 2;
        let mut inv_twist = [0.0; 3];
        if n >= 3 {
            let [[mut p, mut q], [_, mut s]] = a.diag[twist];
            let k = n - 1 - twist;
            for (l, e) in [
                (&top.l()[twist], &a.lower[twist]),
                (&bottom.l()[k], &reversed.lower[k]),
            ] {
                p -= l[0][0] * e[0][0] + l[0][1] * e[0][1];
                q -= l[0][0] * e[1][0] + l[0][1] * e[1][1];
                s -= l[1][0] * e[1][0] + l[1][1] * e[1][1];
            }
            let d = p * s - q * q;
            if !(d.is_finite() && d != 0.0) {
                return Err(SingularBlock {
                    block: twist,
                    determinant: d,
                });
            }
            inv_twist = [s / d, -q / d, p / d];
        }
        Ok(Self {
            top: Half::new(top),
            bottom: Half::new(bottom),
            twist,
            inv_twist,
            n,
        })
    }

    /// [`BlockLdlt::solve_fields`] by the twisted factorisation, in place (the same layout:
    /// every block but possibly the first and the last has its entries in both fields). The
    /// two chains run inward (`y_i = b_i − L_i y_{i−1}`, kept in the fields), meet at the twist
    /// (`x_m = T_m⁻¹ (b_m − L_m y_{m−1} − L'_k y'_{k−1})`) and run outward
    /// (`x_i = D_i⁻¹ y_i − L_{i+1}ᵀ x_{i+1}`). Allocates nothing. Compiled for AVX where the
    /// CPU has it (`dispatch::run`: the same operations, the same bits).
    pub fn solve_fields(&self, fields: [(&mut [f64], usize); 2]) {
        dispatch::run(Solve {
            factor: self,
            fields,
        })
    }

    /// The sweeps of [`TwistedBlockLdlt::solve_fields`].
    #[inline(always)]
    fn sweeps(&self, [(u, fu), (t, ft)]: [(&mut [f64], usize); 2]) {
        let n = self.n;
        if n < 3 {
            let mut y = [[0.0; 2]; 2];
            return self
                .top
                .factor
                .solve_fields([(u, fu), (t, ft)], &mut y[..n]);
        }
        let (m, last) = (self.twist, n - 1);
        let entry = |v: &[f64], f: usize, i: usize| v.get(i.wrapping_sub(f)).copied();
        let b = |u: &[f64], t: &[f64], i: usize| {
            [
                entry(u, fu, i).unwrap_or(0.0),
                entry(t, ft, i).unwrap_or(0.0),
            ]
        };
        let (b_first, b_last) = (b(u, t, 0), b(u, t, last));
        // The interior blocks 1..n − 1: the top half's (1..m), the twist, the bottom half's.
        let (ui, ti) = (&mut u[1 - fu..last - fu], &mut t[1 - ft..last - ft]);
        let (u_top, u_rest) = ui.split_at_mut(m - 1);
        let (t_top, t_rest) = ti.split_at_mut(m - 1);
        let (u_mid, u_bottom) = u_rest.split_at_mut(1);
        let (t_mid, t_bottom) = t_rest.split_at_mut(1);
        let (top, bottom) = (&self.top, &self.bottom);
        let (nt, nb) = (u_top.len(), u_bottom.len());
        let common = nt.min(nb);

        // Inward: top block 1 + j, bottom block n − 2 − j (its row 1 + j). The two chains run
        // interleaved over their common length (with the rows held in locals where both read
        // their still rows), then the longer one's rest alone.
        let y_first = sub(b_first, mul(top.l(0), [0.0; 2]));
        let y_last = sub(b_last, mul(bottom.l(0), [0.0; 2]));
        let mut fields = [u_top, t_top, u_bottom, t_bottom];
        let mut y = [y_first, y_last];
        let still = meet_ascending(&top.still, &bottom.still, common);
        let rows = |j: usize| (top.l(1 + j), bottom.l(1 + j));
        let (lt, lb) = (top.row.0, bottom.row.0);
        inward(&mut fields, 0..still.start, &mut y, rows);
        let squares = (&top.square, &bottom.square);
        inward_in_pairs(&mut fields, still.clone(), &mut y, (&lt, &lb), squares);
        inward(&mut fields, still.end..common, &mut y, rows);
        let [u_top, t_top, u_bottom, t_bottom] = fields;
        let [mut yt, mut yb] = y;
        for j in common..nt {
            yt = step_in(&mut u_top[j], &mut t_top[j], top.l(1 + j), yt);
        }
        for j in common..nb {
            let jb = nb - 1 - j;
            yb = step_in(&mut u_bottom[jb], &mut t_bottom[jb], bottom.l(1 + j), yb);
        }
        // The twist.
        let r = sub(
            sub([u_mid[0], t_mid[0]], mul(top.l(m), yt)),
            mul(bottom.l(last - m), yb),
        );
        let x_mid = d_inv_mul(&self.inv_twist, r);
        (u_mid[0], t_mid[0]) = (x_mid[0], x_mid[1]);

        // Outward: top block m − 1 − j (row m − 1 − j), bottom block m + 1 + j (its row
        // last − m − 1 − j), interleaved in the same way.
        let mut fields = [u_top, t_top, u_bottom, t_bottom];
        let mut x = [x_mid, x_mid];
        let (kt, kb) = (m - 1, last - m - 1);
        let still = meet_descending(&top.still, &bottom.still, [kt, kb], common);
        let rows = |j: usize| {
            let (i, k) = (kt - j, kb - j);
            (
                (top.inv_d(i), top.l(i + 1)),
                (bottom.inv_d(k), bottom.l(k + 1)),
            )
        };
        let (rt, rb) = (top.row, bottom.row);
        outward(&mut fields, 0..still.start, &mut x, rows);
        let rows_still = ((&rt.1, &rt.0), (&rb.1, &rb.0));
        outward_in_pairs(&mut fields, still.clone(), &mut x, rows_still, squares);
        outward(&mut fields, still.end..common, &mut x, rows);
        let [u_top, t_top, u_bottom, t_bottom] = fields;
        let [mut xt, mut xb] = x;
        for j in common..nt {
            let i = kt - j;
            let row = (top.inv_d(i), top.l(i + 1));
            xt = step_out(&mut u_top[nt - 1 - j], &mut t_top[nt - 1 - j], row, xt);
        }
        for j in common..nb {
            let k = kb - j;
            let row = (bottom.inv_d(k), bottom.l(k + 1));
            xb = step_out(&mut u_bottom[j], &mut t_bottom[j], row, xb);
        }
        let x_first = sub(
            d_inv_mul(top.inv_d(0), y_first),
            mul_transposed(top.l(1), xt),
        );
        let x_last = sub(
            d_inv_mul(bottom.inv_d(0), y_last),
            mul_transposed(bottom.l(1), xb),
        );
        for (i, x) in [(0, x_first), (last, x_last)] {
            if let Some(v) = u.get_mut(i.wrapping_sub(fu)) {
                *v = x[0];
            }
            if let Some(v) = t.get_mut(i.wrapping_sub(ft)) {
                *v = x[1];
            }
        }
    }
}

/// A solve's sweeps with their arguments, for [`dispatch::run`].
struct Solve<'a> {
    factor: &'a TwistedBlockLdlt,
    fields: [(&'a mut [f64], usize); 2],
}

impl dispatch::Kernel for Solve<'_> {
    type Output = ();
    #[inline(always)]
    fn call(self) {
        self.factor.sweeps(self.fields)
    }
}

/// `x ← D⁻¹ [u, t] − Lᵀ x`, written back to `(u, t)`.
#[inline(always)]
fn step_out(u: &mut f64, t: &mut f64, (inv_d, l): (&[f64; 3], &Block), x: [f64; 2]) -> [f64; 2] {
    let x = sub(d_inv_mul(inv_d, [*u, *t]), mul_transposed(l, x));
    (*u, *t) = (x[0], x[1]);
    x
}

type OutRow<'a> = (&'a [f64; 3], &'a Block);

/// The two outward chains over `js`: the top one at index `len − 1 − j`, the bottom one at
/// `j`, with the rows `rows(j)` (top, bottom).
#[inline(always)]
fn outward<'a>(
    [u_top, t_top, u_bottom, t_bottom]: &mut [&mut [f64]; 4],
    js: Range<usize>,
    [xt, xb]: &mut [[f64; 2]; 2],
    rows: impl Fn(usize) -> (OutRow<'a>, OutRow<'a>),
) {
    let nt = u_top.len();
    for j in js {
        let (rt, rb) = rows(j);
        *xt = step_out(&mut u_top[nt - 1 - j], &mut t_top[nt - 1 - j], rt, *xt);
        *xb = step_out(&mut u_bottom[j], &mut t_bottom[j], rb, *xb);
    }
}

/// The `j` in `0..common` at which both halves' outward rows `first − j` and `first − j + 1`
/// lie in their still stretches.
fn meet_descending(
    top: &Range<usize>,
    bottom: &Range<usize>,
    [ft, fb]: [usize; 2],
    common: usize,
) -> Range<usize> {
    // Row i and i + 1 in still.start..still.end: i in still.start..still.end − 1, so
    // j = first − i in (first + 2 − still.end)..(first + 1 − still.start).
    let js =
        |s: &Range<usize>, f: usize| (f + 2).saturating_sub(s.end)..(f + 1).saturating_sub(s.start);
    let (a, b) = (js(top, ft), js(bottom, fb));
    let end = a.end.min(b.end).min(common);
    a.start.max(b.start).min(end)..end
}

/// [`outward`] over a stretch where both halves' rows are constant, two rows per link of each
/// chain ([`pair_out`]); an odd last row by [`outward`].
#[inline(always)]
fn outward_in_pairs<'a>(
    fields: &mut [&mut [f64]; 4],
    js: Range<usize>,
    x: &mut [[f64; 2]; 2],
    (rt, rb): (OutRow<'a>, OutRow<'a>),
    (st, sb): (&Block, &Block),
) {
    let [u_top, t_top, u_bottom, t_bottom] = fields;
    let [xt, xb] = x;
    let nt = u_top.len();
    let pairs = js.start..js.start + js.len() / 2 * 2;
    for j in pairs.clone().step_by(2) {
        let top = [nt - 1 - j, nt - 2 - j];
        *xt = pair_out((u_top, t_top), top, rt, st, *xt);
        *xb = pair_out((u_bottom, t_bottom), [j, j + 1], rb, sb, *xb);
    }
    outward(fields, pairs.end..js.end, x, |_| (rt, rb));
}

/// Rows `a` then `b` of the outward sweep with constant rows `(D⁻¹, L)`: with `e = D⁻¹ y`,
/// `x_a = e_a − Lᵀ x` hangs off the chain and `x_b = (e_b − Lᵀ e_a) + (L²)ᵀ x` carries it.
#[inline(always)]
fn pair_out(
    (u, t): (&mut [f64], &mut [f64]),
    [a, b]: [usize; 2],
    (inv_d, l): OutRow<'_>,
    square: &Block,
    x: [f64; 2],
) -> [f64; 2] {
    let (ea, eb) = (
        d_inv_mul(inv_d, [u[a], t[a]]),
        d_inv_mul(inv_d, [u[b], t[b]]),
    );
    let xa = sub(ea, mul_transposed(l, x));
    let xb = add(sub(eb, mul_transposed(l, ea)), mul_transposed(square, x));
    (u[a], t[a], u[b], t[b]) = (xa[0], xa[1], xb[0], xb[1]);
    xb
}

/// [`inward`] over a stretch where both halves' rows are constant, two rows per link of each
/// chain ([`pair_in`]): a chain waits on one 2 × 2 product per two rows. An odd last row by
/// [`inward`].
#[inline(always)]
fn inward_in_pairs(
    fields: &mut [&mut [f64]; 4],
    js: Range<usize>,
    y: &mut [[f64; 2]; 2],
    (lt, lb): (&Block, &Block),
    (st, sb): (&Block, &Block),
) {
    let [u_top, t_top, u_bottom, t_bottom] = fields;
    let [yt, yb] = y;
    let nb = u_bottom.len();
    let pairs = js.start..js.start + js.len() / 2 * 2;
    for j in pairs.clone().step_by(2) {
        *yt = pair_in((u_top, t_top), [j, j + 1], lt, st, *yt);
        let bottom = [nb - 1 - j, nb - 2 - j];
        *yb = pair_in((u_bottom, t_bottom), bottom, lb, sb, *yb);
    }
    inward(fields, pairs.end..js.end, y, |_| (lt, lb));
}

/// Rows `a` then `b` of the inward sweep with a constant `L`: `y_a = b_a − L y` hangs off the
/// chain and `y_b = (b_b − L b_a) + L² y` carries it.
#[inline(always)]
fn pair_in(
    (u, t): (&mut [f64], &mut [f64]),
    [a, b]: [usize; 2],
    l: &Block,
    square: &Block,
    y: [f64; 2],
) -> [f64; 2] {
    let (ba, bb) = ([u[a], t[a]], [u[b], t[b]]);
    let ya = sub(ba, mul(l, y));
    let yb = add(sub(bb, mul(l, ba)), mul(square, y));
    (u[a], t[a], u[b], t[b]) = (ya[0], ya[1], yb[0], yb[1]);
    yb
}

/// `y ← [u, t] − L y`, written back to `(u, t)`.
#[inline(always)]
fn step_in(u: &mut f64, t: &mut f64, l: &Block, y: [f64; 2]) -> [f64; 2] {
    let y = sub([*u, *t], mul(l, y));
    (*u, *t) = (y[0], y[1]);
    y
}

/// The two inward chains over `js` in `[u_top, t_top, u_bottom, t_bottom]`: the top one at
/// index `j`, the bottom one at `len − 1 − j`, with the rows `rows(j)` (top, bottom).
#[inline(always)]
fn inward<'a>(
    [u_top, t_top, u_bottom, t_bottom]: &mut [&mut [f64]; 4],
    js: Range<usize>,
    [yt, yb]: &mut [[f64; 2]; 2],
    rows: impl Fn(usize) -> (&'a Block, &'a Block),
) {
    let nb = u_bottom.len();
    for j in js {
        let (lt, lb) = rows(j);
        *yt = step_in(&mut u_top[j], &mut t_top[j], lt, *yt);
        *yb = step_in(
            &mut u_bottom[nb - 1 - j],
            &mut t_bottom[nb - 1 - j],
            lb,
            *yb,
        );
    }
}

/// The `j` in `0..common` at which both halves' inward rows `1 + j` lie in their still
/// stretches.
fn meet_ascending(top: &Range<usize>, bottom: &Range<usize>, common: usize) -> Range<usize> {
    let js = |s: &Range<usize>| s.start.saturating_sub(1)..s.end.saturating_sub(1);
    let (a, b) = (js(top), js(bottom));
    let end = a.end.min(b.end).min(common);
    a.start.max(b.start).min(end)..end
}

#[inline(always)]
fn sub(a: [f64; 2], b: [f64; 2]) -> [f64; 2] {
    [a[0] - b[0], a[1] - b[1]]
}

#[inline(always)]
fn add(a: [f64; 2], b: [f64; 2]) -> [f64; 2] {
    [a[0] + b[0], a[1] + b[1]]
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Agreement of two backward-stable solves of the same well-conditioned system (blocks of
    /// condition below 100): a few hundred ε per block row of the solution's size.
    const AGREEMENT_TOL: f64 = 100.0 * f64::EPSILON;

    /// Componentwise backward error allowed of a block solve, in units of ε: elimination with
    /// 2 × 2 pivots on rows of at most six terms (the plain sweep measures 1.3 ε, the twin 1.8 ε,
    /// on the stiff step matrix).
    const BACKWARD_ULPS: f64 = 8.0;

    /// A quasi-definite block-tridiagonal matrix of `n` blocks (an SPD field, a negative
    /// definite one, full couplings), its diagonal varying node by node unless `uniform`.
    fn matrix(n: usize, uniform: bool) -> BlockTridiag {
        let mut a = BlockTridiag::zeros(n);
        for i in 0..n {
            let t = if uniform { 0.0 } else { i as f64 };
            a.diag[i] = [[4.0 + t.sin(), 0.7], [0.7, -(3.0 + t.cos())]];
            if i > 0 {
                a.lower[i] = [[-1.0, -0.5], [0.4, 0.9]];
            }
        }
        // Ends unlike the interior, as a bar's end rows are.
        a.diag[0][0][0] = 2.5;
        a.diag[n - 1][1][1] = -1.5;
        a
    }

    /// Both fields complete, the first missing in block 0, the second in the last block (a
    /// clamped end and a fixed temperature): the twisted solve agrees with the plain sweep.
    #[test]
    fn the_twisted_solve_agrees_with_the_plain_one_to_round_off() {
        for n in [1usize, 2, 3, 4, 5, 6, 7, 40, 41, 2000] {
            // Varying, uniform, and uniform but for one block in the top half, at the twist or
            // in the bottom half: stretches that end or start inside the interleaved loops.
            let bumps = [None, None, Some(n / 5), Some((n - 1) / 2), Some(4 * n / 5)];
            let bumps = if n >= 40 { &bumps[..] } else { &bumps[..2] };
            for (case, bump) in bumps.iter().enumerate() {
                let uniform = case > 0;
                let mut a = matrix(n, uniform);
                if let Some(p) = *bump {
                    a.diag[p][0][0] += 1.5;
                    a.diag[p][1][1] -= 0.5;
                }
                let plain = BlockLdlt::factor(&a).unwrap();
                let twisted = TwistedBlockLdlt::factor(&a).unwrap();
                let layouts = if n > 1 {
                    vec![(0, n, 0, n), (1, n - 1, 0, n - 1)]
                } else {
                    vec![(0, n, 0, n)]
                };
                for (fu, nu, ft, nt) in layouts {
                    let b = |k: usize, f: f64| (0.37 * k as f64 + f).cos();
                    let mut up: Vec<f64> = (0..nu).map(|k| b(k, 0.0)).collect();
                    let mut tp: Vec<f64> = (0..nt).map(|k| b(k, 1.0)).collect();
                    let (mut ut, mut tt) = (up.clone(), tp.clone());
                    let mut y = vec![[0.0; 2]; n];
                    plain.solve_fields([(&mut up, fu), (&mut tp, ft)], &mut y);
                    let (mut ub, mut tb) = (ut.clone(), tt.clone());
                    twisted.solve_fields([(&mut ut, fu), (&mut tt, ft)]);
                    // Dispatched (AVX where the CPU has it) and called directly (the
                    // baseline): the same bits.
                    let fields = [(&mut ub[..], fu), (&mut tb[..], ft)];
                    dispatch::Kernel::call(Solve {
                        factor: &twisted,
                        fields,
                    });
                    let bits = |v: &[f64]| v.iter().map(|x| x.to_bits()).collect::<Vec<_>>();
                    assert_eq!((bits(&ub), bits(&tb)), (bits(&ut), bits(&tt)), "n {n}");
                    let scale = up.iter().chain(&tp).fold(1.0f64, |m, v| m.max(v.abs()));
                    for (p, q) in up.iter().chain(&tp).zip(ut.iter().chain(&tt)) {
                        assert!(
                            (p - q).abs() <= AGREEMENT_TOL * n as f64 * scale,
                            "n {n}, uniform {uniform}, bump {bump:?}, first {fu}: {p} vs {q}"
                        );
                    }
                }
            }
        }
    }

    /// The thermal bar's coupled step matrix `[[C, −γ/2 G], [−γ/2 Gᵀ, −H]]` node by node on a
    /// uniform mesh of `n` nodes, at the thermal bench's `α = 0.1`, `γ = 0.1`, `κ = 0.05`,
    /// `Δt = Δx`: stiffness-dominated, its factor rows close to a marginal chain.
    fn step_matrix(n: usize) -> BlockTridiag {
        let (h, alpha, gamma, kappa) = (1.0 / (n - 1) as f64, 0.1, 0.1, 0.05);
        let dt = h;
        let s = 0.5 + alpha / (2.0 * dt);
        let (md, mo, kd, ko) = (2.0 * h / 3.0, h / 6.0, 2.0 / h, -1.0 / h);
        let (cd, co) = (md / (dt * dt) + s * kd, mo / (dt * dt) + s * ko);
        let (hd, ho) = (md + 0.5 * dt * kappa * kd, mo + 0.5 * dt * kappa * ko);
        let g = 0.5 * gamma * 0.5;
        let mut a = BlockTridiag::zeros(n);
        for i in 0..n {
            let end = if i == 0 || i == n - 1 { 0.5 } else { 1.0 };
            let gi = if i == 0 {
                g
            } else if i == n - 1 {
                -g
            } else {
                0.0
            };
            a.diag[i] = [[end * cd, gi], [gi, -end * hd]];
            if i > 0 {
                a.lower[i] = [[co, -g], [g, -ho]];
            }
        }
        a
    }

    /// The componentwise backward error `max_i |b − A x|_i / (|A| |x| + |b|)_i` of `x`
    /// (Oettli–Prager): the relative change of `A` and `b`, entry by entry, that makes `x`
    /// exact; meaningful across the two fields' different scales.
    fn backward_error(a: &BlockTridiag, x: &[[f64; 2]], b: &[[f64; 2]]) -> f64 {
        let abs = |m: &Block| m.map(|r| r.map(f64::abs));
        let abs_a = BlockTridiag {
            diag: a.diag.iter().map(abs).collect(),
            lower: a.lower.iter().map(abs).collect(),
        };
        let abs_x: Vec<[f64; 2]> = x.iter().map(|v| v.map(f64::abs)).collect();
        let (mut ax, mut size) = (vec![[0.0; 2]; x.len()], vec![[0.0; 2]; x.len()]);
        a.mul_into(x, &mut ax);
        abs_a.mul_into(&abs_x, &mut size);
        (0..x.len())
            .flat_map(|i| [0, 1].map(move |r| (i, r)))
            .map(|(i, r)| (b[i][r] - ax[i][r]).abs() / (size[i][r] + b[i][r].abs()))
            .fold(0.0, f64::max)
    }

    /// On the thermal step's own matrix, stiffness-dominated (its still rows' `L` has
    /// eigenvalues near −1, so a chain carries a value far along), the twin with its two-row
    /// links is as backward stable as the plain sweep: each solve is the exact solution for
    /// `A` and `b` changed by a few ε entry by entry.
    #[test]
    fn on_the_stiff_step_matrix_both_solves_are_backward_stable() {
        for n in [2000usize, 20001] {
            let a = step_matrix(n);
            let plain = BlockLdlt::factor(&a).unwrap();
            let twisted = TwistedBlockLdlt::factor(&a).unwrap();
            assert!(twisted.top.still.len() > n / 2, "{:?}", twisted.top.still);
            let b: Vec<[f64; 2]> = (0..n)
                .map(|k| [0, 1].map(|f| (0.37 * k as f64 + f as f64).cos()))
                .collect();
            let (mut up, mut tp): (Vec<f64>, Vec<f64>) = b.iter().map(|v| (v[0], v[1])).unzip();
            let (mut ut, mut tt) = (up.clone(), tp.clone());
            plain.solve_fields([(&mut up, 0), (&mut tp, 0)], &mut vec![[0.0; 2]; n]);
            twisted.solve_fields([(&mut ut, 0), (&mut tt, 0)]);
            for (name, u, t) in [("plain", &up, &tp), ("twisted", &ut, &tt)] {
                let x: Vec<[f64; 2]> = u.iter().zip(t).map(|(u, t)| [*u, *t]).collect();
                let error = backward_error(&a, &x, &b);
                assert!(
                    error <= BACKWARD_ULPS * f64::EPSILON,
                    "n {n}, {name}: backward error {:.2} ε",
                    error / f64::EPSILON
                );
            }
        }
    }

    /// On a uniform interior both halves settle on one row, read once; a varying diagonal
    /// leaves no stretch to speak of.
    #[test]
    fn a_uniform_interior_is_read_as_one_row() {
        let n = 2000;
        let uniform = TwistedBlockLdlt::factor(&matrix(n, true)).unwrap();
        for half in [&uniform.top, &uniform.bottom] {
            assert!(half.still.len() > n - 200, "{:?}", half.still);
        }
        let varying = TwistedBlockLdlt::factor(&matrix(n, false)).unwrap();
        assert!(varying.top.still.len() <= 2, "{:?}", varying.top.still);
    }

    #[test]
    fn a_singular_block_is_refused() {
        let mut a = matrix(5, true);
        a.diag[2] = [[0.0; 2]; 2];
        a.lower[2] = [[0.0; 2]; 2];
        a.lower[3] = [[0.0; 2]; 2];
        assert_eq!(TwistedBlockLdlt::factor(&a).unwrap_err().block, 2);
    }
}
