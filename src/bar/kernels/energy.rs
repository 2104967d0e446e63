//! The sums of the discrete energy balance of a step (`zᵀMz`, `|u|²_R`, `|z + w|²_R`,
//! `F·(z + w)`) in one read-only pass, quadratic forms in difference form so that rigid motion
//! adds no round-off. On a uniform mesh the step runs the optimised twin
//! [`super::energy_fast`].

use crate::linalg::tridiag::SymTridiag;
use crate::scheme::body::EnergySums;

/// The energy sums of a step, after `u += z` (so `u = u^{n+1}`), with `w` the previous
/// increment and `z` this one: `zᵀMz`, `|u|²_R`, `|d|²_R` with `d = z + w`, and `F·d`. Each
/// quadratic form in difference form, `xᵀAx = Σ_i s_i x_i² − Σ_i A_i,i+1 (x_{i+1} − x_i)²`
/// (`s_i` the row sums, [`SymTridiag::quad`]): exact for rigid motion, not an optimisation.
pub fn energy_sums(
    mass: &SymTridiag,
    stiffness: &SymTridiag,
    u: &[f64],
    z: &[f64],
    w: &[f64],
    force: Option<&[f64]>,
) -> EnergySums {
    let n = u.len();
    let (sm, sr) = (mass.row_sums(), stiffness.row_sums());
    let (em, er) = (&mass.off, &stiffness.off);
    let d = |i: usize| z[i] + w[i];
    let mut sums = EnergySums::default();
    for i in 0..n {
        sums.kinetic += sm[i] * z[i] * z[i];
        sums.potential += sr[i] * u[i] * u[i];
        sums.viscous += sr[i] * d(i) * d(i);
        if let Some(f) = force {
            sums.work += f[i] * d(i);
        }
        if i + 1 < n {
            let (dz, du, dd) = (z[i + 1] - z[i], u[i + 1] - u[i], d(i + 1) - d(i));
            sums.kinetic -= em[i] * dz * dz;
            sums.potential -= er[i] * du * du;
            sums.viscous -= er[i] * dd * dd;
        }
    }
    sums
}

/// `|u − w|²_R` in difference form (`u^{n−1} = u^n − w` for a step whose predecessor was not
/// measured; not on the per-step path).
pub fn potential_of_difference(stiffness: &SymTridiag, u: &[f64], w: &[f64]) -> f64 {
    let v = |i: usize| u[i] - w[i];
    let n = u.len();
    let mut q = 0.0;
    for i in 0..n {
        q += stiffness.row_sums()[i] * v(i) * v(i);
    }
    for i in 0..n.saturating_sub(1) {
        let d = v(i + 1) - v(i);
        q -= stiffness.off[i] * d * d;
    }
    q
}
