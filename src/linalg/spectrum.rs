//! Extreme eigenvalues and the condition number of a symmetric tridiagonal matrix, in O(n) per
//! iteration and O(1) extra memory, for the step matrix `C = M/Δt² + (½ + α/(2Δt)) R` at up to
//! 1e6 nodes, where a dense eigensolver is out of reach.
//!
//! Method: Sturm-sequence bisection (Golub & Van Loan, *Matrix Computations*, 4th ed., §8.4.1;
//! LAPACK `dstebz`). The pivots of `A − x I = L D Lᵀ`,
//!
//! ```text
//!   d_0 = a_0 − x,   d_i = a_i − x − e_{i−1}² / d_{i−1},
//! ```
//!
//! have as many negative entries as `A` has eigenvalues below `x` (Sylvester's law of inertia);
//! the recurrence is backward stable in the absolute sense (Kahan 1966), so each eigenvalue is
//! found to within a few ulps of `‖A‖`. Bisection starts from the Gershgorin interval. For the
//! smallest eigenvalue of an SPD matrix the interval is clipped at 0 and bisection continues
//! until the interval stops shrinking, so a small eigenvalue is resolved to round-off of `‖A‖`
//! (relative error about `κ(A)·ε`, which is what the condition number is needed for).

use crate::linalg::tridiag::SymTridiag;

/// Number of eigenvalues of `a` strictly below `x` (Sturm count). A zero pivot is replaced by
/// `−pivmin` (LAPACK `dlaebz`), the smallest perturbation that keeps the recurrence finite.
pub fn count_below(a: &SymTridiag, x: f64) -> usize {
    count_below_with(a, x, pivot_floor(a))
}

/// [`count_below`] with the pivot floor computed once by the caller (an O(n) pass of its own).
fn count_below_with(a: &SymTridiag, x: f64, pivmin: f64) -> usize {
    let n = a.dim();
    let mut count = 0;
    let mut d = 1.0;
    for i in 0..n {
        let coupling = if i > 0 {
            a.off[i - 1] * a.off[i - 1] / d
        } else {
            0.0
        };
        d = a.diag[i] - x - coupling;
        if d.abs() < pivmin {
            d = -pivmin;
        }
        if d < 0.0 {
            count += 1;
        }
    }
    count
}

/// `max(e_i², 1) · MIN_POSITIVE`: below this a pivot is indistinguishable from zero.
fn pivot_floor(a: &SymTridiag) -> f64 {
    let e2 = a.off.iter().fold(1.0f64, |m, e| m.max(e * e));
    f64::MIN_POSITIVE * e2
}

/// The Gershgorin interval `[min_i (a_i − r_i), max_i (a_i + r_i)]`, `r_i = |e_{i−1}| + |e_i|`,
/// which contains every eigenvalue.
pub fn gershgorin(a: &SymTridiag) -> (f64, f64) {
    let n = a.dim();
    let (mut lo, mut hi) = (f64::INFINITY, f64::NEG_INFINITY);
    for i in 0..n {
        let r = if i > 0 { a.off[i - 1].abs() } else { 0.0 }
            + if i + 1 < n { a.off[i].abs() } else { 0.0 };
        lo = lo.min(a.diag[i] - r);
        hi = hi.max(a.diag[i] + r);
    }
    (lo, hi)
}

/// The `k`-th smallest eigenvalue (`k = 0` the smallest) by bisection inside `[lo, hi]`, which
/// must contain it; stops when the midpoint no longer splits the interval (full precision).
fn bisect(a: &SymTridiag, k: usize, mut lo: f64, mut hi: f64) -> f64 {
    let pivmin = pivot_floor(a);
    loop {
        let mid = 0.5 * (lo + hi);
        if mid <= lo || mid >= hi {
            return mid;
        }
        if count_below_with(a, mid, pivmin) > k {
            hi = mid;
        } else {
            lo = mid;
        }
    }
}

/// The smallest and the largest eigenvalue of `a`. `a` must be non-empty with finite entries.
pub fn extreme_eigenvalues(a: &SymTridiag) -> (f64, f64) {
    let (lo, hi) = padded_gershgorin(a);
    (bisect(a, 0, lo, hi), bisect(a, a.dim() - 1, lo, hi))
}

/// The largest eigenvalue of `a` (non-empty, finite entries).
fn largest_eigenvalue(a: &SymTridiag) -> f64 {
    let (lo, hi) = padded_gershgorin(a);
    bisect(a, a.dim() - 1, lo, hi)
}

/// The Gershgorin interval widened by a few ulps: the Sturm count at the exact bound is itself
/// rounded.
fn padded_gershgorin(a: &SymTridiag) -> (f64, f64) {
    assert!(a.dim() > 0, "empty matrix has no eigenvalues");
    let (lo, hi) = gershgorin(a);
    let pad = 4.0 * f64::EPSILON * lo.abs().max(hi.abs()).max(f64::MIN_POSITIVE);
    (lo - pad, hi + pad)
}

/// The smallest eigenvalue of a matrix known to be positive definite: bisection on `[0, hi]`,
/// which resolves a small eigenvalue to round-off of `‖a‖` even when the Gershgorin lower bound
/// is far below zero.
pub fn smallest_eigenvalue_spd(a: &SymTridiag) -> f64 {
    let (lo, hi) = gershgorin(a);
    let pad = 4.0 * f64::EPSILON * hi.abs();
    bisect(a, 0, lo.max(0.0), hi + pad)
}

/// `κ₂(a) = λ_max / λ_min` for a symmetric positive definite `a`, or `None` when the computed
/// smallest eigenvalue is not positive (numerically singular or indefinite).
pub fn condition_number(a: &SymTridiag) -> Option<f64> {
    let hi = largest_eigenvalue(a);
    let lo = smallest_eigenvalue_spd(a);
    (lo > 0.0).then(|| hi / lo)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Dense symmetric eigenvalues (nalgebra), ascending.
    fn dense_eigenvalues(a: &SymTridiag) -> Vec<f64> {
        let mut v: Vec<f64> = a
            .to_dense()
            .symmetric_eigenvalues()
            .iter()
            .copied()
            .collect();
        v.sort_by(f64::total_cmp);
        v
    }

    /// Bisection and the dense QR algorithm are each accurate to a few ulps of `‖A‖`
    /// (backward stable); 64 ulps leaves a margin for both.
    const DENSE_AGREEMENT_ULPS: f64 = 64.0;

    fn check_against_dense(a: &SymTridiag) {
        let dense = dense_eigenvalues(a);
        let norm = dense[0].abs().max(dense[dense.len() - 1].abs());
        let tol = DENSE_AGREEMENT_ULPS * f64::EPSILON * norm;
        let (lo, hi) = extreme_eigenvalues(a);
        assert!((lo - dense[0]).abs() <= tol, "{lo} vs {}", dense[0]);
        assert!((hi - dense[dense.len() - 1]).abs() <= tol);
        for (k, &x) in dense.iter().enumerate() {
            // Just above each eigenvalue the count includes it (up to ties of equal values).
            let above = count_below(a, x + tol);
            assert!(above > k, "count below {x} + tol = {above}, expected > {k}");
        }
    }

    /// A deterministic pseudo-random sequence in [-1, 1) (SplitMix64), so the test needs no
    /// random crate and gives the same matrices every run.
    fn sequence(seed: u64) -> impl FnMut() -> f64 {
        let mut s = seed;
        move || {
            s = s.wrapping_add(0x9E37_79B9_7F4A_7C15);
            let mut z = s;
            z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
            z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
            z ^= z >> 31;
            (z >> 11) as f64 / (1u64 << 52) as f64 - 1.0
        }
    }

    #[test]
    fn extreme_eigenvalues_match_dense_on_random_symmetric_matrices() {
        let mut next = sequence(6);
        for n in 1..=40 {
            let diag: Vec<f64> = (0..n).map(|_| 3.0 * next()).collect();
            let off: Vec<f64> = (0..n - 1).map(|_| next()).collect();
            check_against_dense(&SymTridiag::new(diag, off));
        }
    }

    #[test]
    fn step_matrices_match_dense_from_mass_dominated_to_stiff() {
        use crate::bar::matrices::{MatrixVariant, mass, stiffness};
        let nodes = 21;
        let dx = 1.0 / 20.0;
        let m = mass(MatrixVariant::Consistent, nodes, dx);
        let r = stiffness(MatrixVariant::Consistent, nodes, dx);
        for (alpha, ratio) in [(0.0, 1e-3), (0.0, 1.0), (1e3, 100.0), (1e6, 1e4)] {
            let dt = ratio * dx;
            let c = SymTridiag::combine(1.0 / (dt * dt), &m, 0.5 + alpha / (2.0 * dt), &r);
            check_against_dense(&c);
            // The condition number: relative error about κ ε in the smallest eigenvalue.
            let dense = dense_eigenvalues(&c);
            let exact = dense[nodes - 1] / dense[0];
            let kappa = condition_number(&c).unwrap();
            let tol = DENSE_AGREEMENT_ULPS * f64::EPSILON * exact;
            assert!((kappa - exact).abs() <= tol * exact, "{kappa} vs {exact}");
        }
    }

    /// `tridiag(e, d, e)` of size n has the eigenvalues `d + 2e cos(kπ/(n+1))`, k = 1..n.
    #[test]
    fn toeplitz_matrices_match_the_closed_form_at_a_million_rows() {
        for n in [1usize, 2, 7, 1000, 1_000_000] {
            let (d, e) = (2.0, -1.0);
            let a = SymTridiag::new(vec![d; n], vec![e; n - 1]);
            let h = std::f64::consts::PI / (n + 1) as f64;
            let exact_lo = 4.0 * (0.5 * h).sin().powi(2); // d + 2e cos h, without cancellation
            let exact_hi = d - 2.0 * e * h.cos();
            let (lo, hi) = extreme_eigenvalues(&a);
            let tol = DENSE_AGREEMENT_ULPS * f64::EPSILON * exact_hi;
            assert!((hi - exact_hi).abs() <= tol, "n = {n}: {hi} vs {exact_hi}");
            assert!((lo - exact_lo).abs() <= tol, "n = {n}: {lo} vs {exact_lo}");
            let spd_lo = smallest_eigenvalue_spd(&a);
            assert!(
                (spd_lo - exact_lo).abs() <= tol,
                "n = {n}: {spd_lo} vs {exact_lo}"
            );
        }
    }

    #[test]
    fn an_indefinite_matrix_has_no_condition_number() {
        let a = SymTridiag::new(vec![1.0, -1.0], vec![0.0]);
        assert_eq!(condition_number(&a), None);
        assert_eq!(extreme_eigenvalues(&a), (-1.0, 1.0));
    }
}
