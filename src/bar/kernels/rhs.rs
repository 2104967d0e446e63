//! The bar's right-hand side of a step, `b = F + M w/Δt² + R ((½ − α/(2Δt)) w − u)`, row by
//! row with both products in difference form. On a uniform mesh the step runs the optimised
//! twin [`super::rhs_fast`].

use crate::linalg::tridiag::SymTridiag;

/// Row `i` of `A x` in difference form, `s_i x_i + A_i,i−1 (x_{i−1} − x_i) + A_i,i+1 (x_{i+1} −
/// x_i)` (`s_i` the row sum), in the order of [`SymTridiag::mul_into`]: for the stiffness
/// matrix (`s = 0`) the round-off is relative to the differences of `x`, so a rigid offset of
/// the bar adds none.
pub fn row_of(a: &SymTridiag, x: impl Fn(usize) -> f64, i: usize, n: usize) -> f64 {
    let mut r = a.row_sums()[i] * x(i);
    if i > 0 {
        r += a.off[i - 1] * (x(i - 1) - x(i));
    }
    if i + 1 < n {
        r += a.off[i] * (x(i + 1) - x(i));
    }
    r
}

/// `b = F + M w/Δt² + R y` with `y = c_w w − u`, `c_w = ½ − α/(2Δt)`, `inv_dt2 = 1/Δt²`: row
/// `i` is `(R y)_i + (M w)_i/Δt² + F_i`, each product by [`row_of`] (no force without a load).
#[allow(clippy::too_many_arguments)]
pub fn rhs_into(
    mass: &SymTridiag,
    stiffness: &SymTridiag,
    c_w: f64,
    inv_dt2: f64,
    u: &[f64],
    w: &[f64],
    force: Option<&[f64]>,
    rhs: &mut [f64],
) {
    let n = rhs.len();
    let y = |j: usize| c_w * w[j] - u[j];
    for i in 0..n {
        let b = row_of(stiffness, y, i, n) + row_of(mass, |j| w[j], i, n) * inv_dt2;
        rhs[i] = match force {
            Some(f) => b + f[i],
            None => b,
        };
    }
}
