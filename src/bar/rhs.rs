//! The bar's right-hand side of a step, `b = F + M w/Δt² + R ((½ − α/(2Δt)) w − u)`, in one
//! pass with both products in difference form. The interior rows run through `dispatch::run`
//! (AVX when the CPU has it, the same bits).

use crate::linalg::dispatch;
use crate::linalg::tridiag::{Interior, SymTridiag};

/// Row `i` of `A x` in difference form, `s_i x_i + A_i,i−1 (x_{i−1} − x_i) + A_i,i+1 (x_{i+1} −
/// x_i)`, in the order of [`SymTridiag::mul_into`]; for the end rows (any `i`, with branches).
pub(crate) fn row_of(a: &SymTridiag, x: impl Fn(usize) -> f64, i: usize, n: usize) -> f64 {
    let mut r = a.row_sums()[i] * x(i);
    if i > 0 {
        r += a.off[i - 1] * (x(i - 1) - x(i));
    }
    if i + 1 < n {
        r += a.off[i] * (x(i + 1) - x(i));
    }
    r
}

/// `b = F + M w/Δt² + R ((½ − α/(2Δt)) w − u)` in one pass, both products in difference form.
/// The interior rows are [`RhsInterior`], run through [`dispatch::run`]; `LOAD = false` skips
/// the force.
#[allow(clippy::too_many_arguments)]
#[inline(never)]
pub(crate) fn rhs_into<const LOAD: bool, K: Interior>(
    mass: &SymTridiag,
    stiffness: &SymTridiag,
    (mi, ri): (K, K),
    c_w: f64,
    inv_dt2: f64,
    u: &[f64],
    w: &[f64],
    force: &[f64],
    rhs: &mut [f64],
) {
    let n = rhs.len();
    let (u, w) = (&u[..n], &w[..n]);
    let force = if LOAD { &force[..n] } else { &[][..] };
    let y = |i: usize| c_w * w[i] - u[i];
    let wi = |i: usize| w[i];
    for i in [0, n.saturating_sub(1)].into_iter().take(n.min(2)) {
        let b = row_of(stiffness, y, i, n) + row_of(mass, wi, i, n) * inv_dt2;
        rhs[i] = if LOAD { b + force[i] } else { b };
    }
    if n < 3 {
        return;
    }
    // R's interior rows sum to exactly 0 on a uniform mesh: its node term is then left out.
    macro_rules! kernel {
        ($s_r:literal) => {
            RhsInterior::<LOAD, $s_r, K> {
                coefficients: (mi, ri),
                c_w,
                inv_dt2,
                u,
                w,
                force,
                rhs,
            }
        };
    }
    if K::UNIFORM && ri.s(1) == 0.0 {
        dispatch::run(kernel!(false))
    } else {
        dispatch::run(kernel!(true))
    }
}

/// The interior rows of [`rhs_into`] with its arguments, for [`dispatch::run`].
///
/// Rows `1..n−1` (`n >= 3`). Row `i` of `A x` in difference form
/// is `s_i x_i + A_i,i−1 (x_i−1 − x_i) + A_i,i+1 (x_i+1 − x_i) = (s_i x_i − g_i−1) + g_i` with the
/// edge flux `g_i = A_i,i+1 (x_i+1 − x_i)`: the same bits as [`row_of`] (negation is exact).
/// Each flux is computed twice, once for each row it enters, rather than carried from row to
/// row: a carried value made the loop a recurrence, which the compiler left scalar, while
/// rows that share nothing vectorise. `S_R = false` drops `s_i y_i` from the stiffness rows
/// (for `s_i = 0`; only the sign of a zero result can differ).
pub(crate) struct RhsInterior<'a, const LOAD: bool, const S_R: bool, K> {
    pub(crate) coefficients: (K, K),
    pub(crate) c_w: f64,
    pub(crate) inv_dt2: f64,
    pub(crate) u: &'a [f64],
    pub(crate) w: &'a [f64],
    pub(crate) force: &'a [f64],
    pub(crate) rhs: &'a mut [f64],
}

impl<const LOAD: bool, const S_R: bool, K: Interior> dispatch::Kernel
    for RhsInterior<'_, LOAD, S_R, K>
{
    type Output = ();
    #[inline(always)]
    fn call(self) {
        let Self {
            coefficients: (mi, ri),
            c_w,
            inv_dt2,
            u,
            w,
            force,
            rhs,
        } = self;
        let n = rhs.len();
        // Row k = i + 1 reads nodes i, i + 1, i + 2: three windows of one length, so the
        // loop has no bounds checks and nothing carried from one row to the next.
        let out = &mut rhs[1..n - 1];
        let m = out.len();
        let (u_l, u_c, u_r) = (&u[..m], &u[1..m + 1], &u[2..m + 2]);
        let (w_l, w_c, w_r) = (&w[..m], &w[1..m + 1], &w[2..m + 2]);
        let force = if LOAD { &force[1..m + 1] } else { &[][..] };
        let y = |u: f64, w: f64| c_w * w - u;
        for i in 0..m {
            let k = i + 1;
            let (y_l, y_c, y_r) = (y(u_l[i], w_l[i]), y(u_c[i], w_c[i]), y(u_r[i], w_r[i]));
            let (g_y, g_y_next) = (ri.e(k - 1) * (y_c - y_l), ri.e(k) * (y_r - y_c));
            let (g_w, g_w_next) = (mi.e(k - 1) * (w_c[i] - w_l[i]), mi.e(k) * (w_r[i] - w_c[i]));
            let ry = if S_R {
                (ri.s(k) * y_c - g_y) + g_y_next
            } else {
                g_y_next - g_y
            };
            let mw = (mi.s(k) * w_c[i] - g_w) + g_w_next;
            let b = ry + mw * inv_dt2;
            out[i] = if LOAD { b + force[i] } else { b };
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::bar::matrices::{self, MatrixVariant};

    /// The interior kernel gives the bits of the row-by-row formula [`row_of`] on every row,
    /// for uniform and row-by-row coefficients, with and without a load, for every tail length
    /// of the vector loop (mutation-checked: a flux taken with the wrong coefficient index
    /// fails it on the non-uniform matrix).
    #[test]
    fn rhs_equals_the_row_formula_bit_for_bit() {
        for n in [2usize, 3, 4, 5, 6, 7, 8, 9, 10, 37, 1002] {
            let dx = 1.0 / n as f64;
            let m = matrices::mass(MatrixVariant::Consistent, n, dx);
            let r = matrices::stiffness(MatrixVariant::Consistent, n, dx);
            // A non-uniform pair: the consistent matrices with wobbling entries.
            let wobble = |a: &SymTridiag, amp: f64| {
                let d =
                    (a.diag.iter().enumerate()).map(|(i, v)| v * (1.0 + amp * (i as f64).sin()));
                let e = (a.off.iter().enumerate()).map(|(i, v)| v * (1.0 + amp * (i as f64).cos()));
                SymTridiag::new(d.collect(), e.collect())
            };
            let (m2, r2) = (wobble(&m, 0.3), wobble(&r, 0.2));
            let v = |a: f64, offset: f64| {
                (0..n)
                    .map(|i| offset + (a * i as f64 + 0.3).sin())
                    .collect::<Vec<_>>()
            };
            let (u, w, f) = (v(0.7, 1e2), v(2.1, 1e2 + 1e-3), v(0.4, -1.0));
            let (c_w, inv_dt2) = (-0.37, 1.0 / (dx * dx));
            let expected = |mass: &SymTridiag, stiffness: &SymTridiag, load: bool| {
                (0..n)
                    .map(|i| {
                        let y = |j: usize| c_w * w[j] - u[j];
                        let b = row_of(stiffness, y, i, n) + row_of(mass, |j| w[j], i, n) * inv_dt2;
                        if load { b + f[i] } else { b }
                    })
                    .map(f64::to_bits)
                    .collect::<Vec<_>>()
            };
            let bits = |x: &[f64]| x.iter().map(|v| v.to_bits()).collect::<Vec<_>>();
            let mut out = vec![0.0; n];
            if let Some(k) = m.uniform().zip(r.uniform()) {
                rhs_into::<true, _>(&m, &r, k, c_w, inv_dt2, &u, &w, &f, &mut out);
                assert_eq!(bits(&out), expected(&m, &r, true), "uniform, load, n = {n}");
                rhs_into::<false, _>(&m, &r, k, c_w, inv_dt2, &u, &w, &[], &mut out);
                assert_eq!(bits(&out), expected(&m, &r, false), "uniform, n = {n}");
            }
            let k = (m2.rows(), r2.rows());
            rhs_into::<true, _>(&m2, &r2, k, c_w, inv_dt2, &u, &w, &f, &mut out);
            assert_eq!(bits(&out), expected(&m2, &r2, true), "rows, load, n = {n}");
            rhs_into::<false, _>(&m2, &r2, k, c_w, inv_dt2, &u, &w, &[], &mut out);
            assert_eq!(bits(&out), expected(&m2, &r2, false), "rows, n = {n}");
        }
    }
}
