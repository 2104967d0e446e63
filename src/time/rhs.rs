//! The right-hand side of a step, `b = F + M w/Δt² + R ((½ − α/(2Δt)) w − u)`, in one pass
//! with both products in difference form, and the load vector `F^n = M (l(x_i, t_n))_i`. The
//! interior rows run through `dispatch::run` (AVX when the CPU has it, the same bits).

use crate::bar::discretisation::Discretisation;
use crate::bar::matrices;
use crate::linalg::dispatch;
use crate::linalg::tridiag::{Interior, SymTridiag};

/// `(M_full x)_i` at the unknowns `i`, row by row (the same arithmetic as
/// [`SymTridiag::mul_into`]), without keeping the full-mesh mass matrix beyond this call.
pub(crate) fn load_rows_into(disc: &Discretisation, x: impl Fn(usize) -> f64, out: &mut [f64]) {
    let mass_full = matrices::mass(disc.variant, disc.nodes, disc.dx);
    for (k, o) in out.iter_mut().enumerate() {
        *o = row_of(&mass_full, &x, disc.first + k, disc.nodes);
    }
}

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
/// edge flux `g_i = A_i,i+1 (x_i+1 − x_i)`: the same bits as [`row_of`] (negation is exact),
/// but each flux is computed once, for the two rows it enters, and carried to the next row.
/// `S_R = false` drops `s_i y_i` from the stiffness rows (for `s_i = 0`; only the sign of a
/// zero result can differ). No branch in the loop, so it vectorises, carried values included.
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
        let y = |i: usize| c_w * w[i] - u[i];
        let (mut y_i, mut w_i) = (y(1), w[1]);
        let mut g_y = ri.e(0) * (y_i - y(0));
        let mut g_w = mi.e(0) * (w_i - w[0]);
        for i in 1..n - 1 {
            let (y_next, w_next) = (y(i + 1), w[i + 1]);
            let (g_y_next, g_w_next) = (ri.e(i) * (y_next - y_i), mi.e(i) * (w_next - w_i));
            let ry = if S_R {
                (ri.s(i) * y_i - g_y) + g_y_next
            } else {
                g_y_next - g_y
            };
            let mw = (mi.s(i) * w_i - g_w) + g_w_next;
            let b = ry + mw * inv_dt2;
            rhs[i] = if LOAD { b + force[i] } else { b };
            (y_i, w_i, g_y, g_w) = (y_next, w_next, g_y_next, g_w_next);
        }
    }
}
