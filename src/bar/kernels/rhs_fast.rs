//! The optimised twin of [`super::rhs`] on a uniform mesh: the interior rows read the matrices'
//! two interior coefficients as numbers, rows that share nothing so that the compiler
//! vectorises them, compiled for AVX when the CPU has it ([`dispatch`]). The same bits as
//! the plain [`rhs_into`](super::rhs::rhs_into) (up to the sign of a zero).

use crate::bar::kernels::rhs::row_of;
use crate::linalg::kernels::dispatch;
use crate::linalg::tridiag::{SymTridiag, Uniform};

/// [`rhs_into`](super::rhs::rhs_into) on a uniform mesh, `(mi, ri)` the interior coefficients
/// of `M` and `R`; `LOAD = false` skips the force.
#[allow(clippy::too_many_arguments)]
#[inline(never)]
pub fn rhs_into_uniform<const LOAD: bool>(
    mass: &SymTridiag,
    stiffness: &SymTridiag,
    (mi, ri): (Uniform, Uniform),
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
            RhsInterior::<LOAD, $s_r> {
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
    if ri.s == 0.0 {
        dispatch::run(kernel!(false))
    } else {
        dispatch::run(kernel!(true))
    }
}

/// The interior rows of [`rhs_into_uniform`] with its arguments, for [`dispatch::run`].
///
/// Rows `1..n−1` (`n >= 3`). Row `i` of `A x` in difference form is
/// `(s x_i − g_i−1) + g_i` with the edge flux `g_i = e (x_i+1 − x_i)`: the bits of [`row_of`]
/// (negation is exact). Each flux is computed twice, once for each row it enters, rather than
/// carried from row to row: a carried value made the loop a recurrence, which the compiler
/// left scalar. `S_R = false` drops `s_i y_i` from the stiffness rows (for `s_i = 0`; only the
/// sign of a zero result can differ).
pub(crate) struct RhsInterior<'a, const LOAD: bool, const S_R: bool> {
    pub(crate) coefficients: (Uniform, Uniform),
    pub(crate) c_w: f64,
    pub(crate) inv_dt2: f64,
    pub(crate) u: &'a [f64],
    pub(crate) w: &'a [f64],
    pub(crate) force: &'a [f64],
    pub(crate) rhs: &'a mut [f64],
}

impl<const LOAD: bool, const S_R: bool> dispatch::Kernel for RhsInterior<'_, LOAD, S_R> {
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
            let (y_l, y_c, y_r) = (y(u_l[i], w_l[i]), y(u_c[i], w_c[i]), y(u_r[i], w_r[i]));
            let (g_y, g_y_next) = (ri.e * (y_c - y_l), ri.e * (y_r - y_c));
            let (g_w, g_w_next) = (mi.e * (w_c[i] - w_l[i]), mi.e * (w_r[i] - w_c[i]));
            let ry = if S_R {
                (ri.s * y_c - g_y) + g_y_next
            } else {
                g_y_next - g_y
            };
            let mw = (mi.s * w_c[i] - g_w) + g_w_next;
            let b = ry + mw * inv_dt2;
            out[i] = if LOAD { b + force[i] } else { b };
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::bar::kernels::rhs::rhs_into;
    use crate::bar::matrices::{self, MatrixVariant};

    /// The twin gives the bits of the plain right-hand side on every row, with and without a
    /// load, for every tail length of the vector loop, on data with large common parts and
    /// tiny differences (where round-off would show); a zero may differ in sign only.
    #[test]
    fn the_uniform_rhs_has_the_bits_of_the_plain_one() {
        for n in [2usize, 3, 4, 5, 6, 7, 8, 9, 10, 37, 1002] {
            let dx = 1.0 / n as f64;
            let m = matrices::mass(MatrixVariant::Consistent, n, dx);
            let r = matrices::stiffness(MatrixVariant::Consistent, n, dx);
            let k = m.uniform().zip(r.uniform()).expect("a uniform mesh");
            let v = |a: f64, offset: f64| {
                (0..n)
                    .map(|i| offset + (a * i as f64 + 0.3).sin())
                    .collect::<Vec<_>>()
            };
            let (u, w, f) = (v(0.7, 1e2), v(2.1, 1e2 + 1e-3), v(0.4, -1.0));
            let (c_w, inv_dt2) = (-0.37, 1.0 / (dx * dx));
            // Zeros compared as +0.
            let bits = |x: &[f64]| x.iter().map(|v| (v + 0.0).to_bits()).collect::<Vec<_>>();
            let (mut plain, mut fast) = (vec![0.0; n], vec![0.0; n]);
            rhs_into(&m, &r, c_w, inv_dt2, &u, &w, Some(&f), &mut plain);
            rhs_into_uniform::<true>(&m, &r, k, c_w, inv_dt2, &u, &w, &f, &mut fast);
            assert_eq!(bits(&fast), bits(&plain), "load, n = {n}");
            rhs_into(&m, &r, c_w, inv_dt2, &u, &w, None, &mut plain);
            rhs_into_uniform::<false>(&m, &r, k, c_w, inv_dt2, &u, &w, &[], &mut fast);
            assert_eq!(bits(&fast), bits(&plain), "n = {n}");
        }
    }
}
