//! The right-hand side of a plane step in increment form,
//! `b = F^n + M w/Δt² + K ((½ − α/(2Δt)) w − u^n)`, `w = u^n − u^{n−1}`, in one pass over the
//! shared pattern of `M` and `K` (the bar's [`crate::time::rhs`] in CSR).

use crate::plane::matrices::Pattern;

/// The matrices and coefficients of [`rhs_into`].
pub struct RhsTerms<'a> {
    pub pattern: &'a Pattern,
    pub mass: &'a [f64],
    pub stiffness: &'a [f64],
    /// `1/Δt²`.
    pub inv_dt2: f64,
    /// `½ − α/(2Δt)`.
    pub c_w: f64,
}

/// `b = F + M w/Δt² + K (c_w w − u)`; allocates nothing.
pub fn rhs_into(terms: &RhsTerms, u: &[f64], w: &[f64], force: &[f64], b: &mut [f64]) {
    let RhsTerms {
        pattern,
        mass,
        stiffness,
        inv_dt2,
        c_w,
    } = *terms;
    for (r, br) in b.iter_mut().enumerate() {
        let (mut mw, mut ky) = (0.0, 0.0);
        for k in pattern.row_ptr[r]..pattern.row_ptr[r + 1] {
            let c = pattern.cols[k];
            mw += mass[k] * w[c];
            ky += stiffness[k] * (c_w * w[c] - u[c]);
        }
        *br = force[r] + mw * inv_dt2 + ky;
    }
}
