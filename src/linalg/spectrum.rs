//! Extreme eigenvalues and the condition number of a symmetric tridiagonal matrix, in O(n) per
//! iteration and O(1) extra memory, for the step matrix `C` at up to 1e6 nodes, where a dense
//! eigensolver is out of reach.
//!
//! Method: Sturm-sequence bisection (Golub & Van Loan, *Matrix Computations*, 4th ed., §8.4.1;
//! LAPACK `dstebz`): the pivots `d_0 = a_0 − x`, `d_i = a_i − x − e_{i−1}²/d_{i−1}` of
//! `A − xI = LDLᵀ` have as many negative entries as `A` has eigenvalues below `x` (Sylvester),
//! and the recurrence is backward stable in the absolute sense (Kahan 1966), so each eigenvalue
//! is found to a few ulps of `‖A‖`. Bisection starts from the Gershgorin interval; for the
//! smallest eigenvalue of an SPD matrix it is clipped at 0 and continued until the interval stops
//! shrinking, so a small eigenvalue is resolved to round-off of `‖A‖` (relative error `κ(A)ε`).

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

/// An upper bound on `κ₂(a)` of an SPD `a`, at most 6 times `κ₂(a)`, in a dozen Sturm counts
/// (set-up cost that a run does not feel, where [`condition_number`] bisects to round-off):
/// `λ_max <= hi`, the Gershgorin bound, at most `3 λ_max` (a row holds three entries, each at
/// most `‖a‖₂`), and `λ_min` bracketed in `[x, 2x)` with `x = hi · 2^−k` by bisection on `k`.
/// `None` when no positive `x` has every eigenvalue above it (numerically singular or
/// indefinite).
pub fn condition_bound(a: &SymTridiag) -> Option<f64> {
    let (_, hi) = gershgorin(a);
    if !(hi > 0.0 && hi.is_finite()) {
        return None;
    }
    let pivmin = pivot_floor(a);
    let clear = |k: i32| count_below_with(a, hi * 2f64.powi(-k), pivmin) == 0;
    // The smallest k whose x = hi 2^−k has no eigenvalue below it: k = 0 never (hi is above
    // λ_max), and past k = 1074 x underflows.
    let (mut lo, mut up) = (0, 1075);
    if !clear(up) {
        return None;
    }
    while up - lo > 1 {
        let mid = (lo + up) / 2;
        if clear(mid) { up = mid } else { lo = mid }
    }
    Some(2f64.powi(up))
}

/// The reference for the tests and the tolerance registry: eigenvalues of a symmetric
/// tridiagonal matrix in double-double arithmetic (no system library), resolved far below the
/// f64 bisection's round-off.
pub mod reference {
    use super::padded_gershgorin;
    use crate::linalg::tridiag::SymTridiag;

    /// Double-double numbers `hi + lo` (Dekker 1971; Hida, Li & Bailey's QD library), about
    /// 106 bits: a reference for the f64 bisection that needs no system library.
    #[derive(Clone, Copy, Debug, PartialEq, PartialOrd)]
    pub struct Dd {
        /// The leading double.
        pub hi: f64,
        /// The trailing double, `|lo| <= ulp(hi)/2`.
        pub lo: f64,
    }

    impl Dd {
        pub fn from(v: f64) -> Self {
            Self { hi: v, lo: 0.0 }
        }
        /// `a + b` exactly as `s + e` (Knuth's two-sum).
        fn two_sum(a: f64, b: f64) -> Self {
            let s = a + b;
            let bb = s - a;
            Self {
                hi: s,
                lo: (a - (s - bb)) + (b - bb),
            }
        }
        /// `s + e` renormalised, `|e| <= ulp(s)/2` assumed.
        fn quick(s: f64, e: f64) -> Self {
            let hi = s + e;
            Self {
                hi,
                lo: e - (hi - s),
            }
        }
        pub fn plus(self, o: Self) -> Self {
            let s = Self::two_sum(self.hi, o.hi);
            let t = Self::two_sum(self.lo, o.lo);
            let u = Self::quick(s.hi, s.lo + t.hi);
            Self::quick(u.hi, u.lo + t.lo)
        }
        pub fn negated(self) -> Self {
            Self {
                hi: -self.hi,
                lo: -self.lo,
            }
        }
        pub fn minus(self, o: Self) -> Self {
            self.plus(o.negated())
        }
        pub fn times(self, o: Self) -> Self {
            let p = self.hi * o.hi;
            let e = self.hi.mul_add(o.hi, -p) + (self.hi * o.lo + self.lo * o.hi);
            Self::quick(p, e)
        }
        pub fn over(self, o: Self) -> Self {
            let q1 = self.hi / o.hi;
            let r = self.minus(o.times(Self::from(q1)));
            let q2 = r.hi / o.hi;
            let r = r.minus(o.times(Self::from(q2)));
            let q3 = r.hi / o.hi;
            Self::quick(q1, q2).plus(Self::from(q3))
        }
        pub fn half(self) -> Self {
            Self {
                hi: 0.5 * self.hi,
                lo: 0.5 * self.lo,
            }
        }
    }

    /// [`count_below`] in double-double arithmetic on the same f64 entries.
    fn count_below_dd(a: &SymTridiag, x: Dd) -> usize {
        let pivmin = Dd::from(1e-280);
        let mut count = 0;
        let mut d = Dd::from(1.0);
        for i in 0..a.dim() {
            let coupling = if i > 0 {
                let e = Dd::from(a.off[i - 1]);
                e.times(e).over(d)
            } else {
                Dd::from(0.0)
            };
            d = Dd::from(a.diag[i]).minus(x).minus(coupling);
            if d.hi.abs() < pivmin.hi {
                d = pivmin.negated();
            }
            if d.hi < 0.0 {
                count += 1;
            }
        }
        count
    }

    /// The `k`-th smallest eigenvalue of `a` (its f64 entries taken exactly) by double-double
    /// bisection from the padded Gershgorin interval, until the interval is below
    /// [`DD_WIDTH`] times `‖a‖`.
    pub fn eigenvalue_dd(a: &SymTridiag, k: usize) -> Dd {
        let (lo, hi) = padded_gershgorin(a);
        let norm = lo.abs().max(hi.abs());
        let (mut lo, mut hi) = (Dd::from(lo), Dd::from(hi));
        while hi.minus(lo).hi > DD_WIDTH * norm {
            let mid = lo.plus(hi).half();
            if count_below_dd(a, mid) > k {
                hi = mid;
            } else {
                lo = mid;
            }
        }
        lo.plus(hi).half()
    }

    /// Width of the double-double bisection's final interval relative to `‖a‖`: above the
    /// recurrence's own round-off (a few units of 2⁻¹⁰⁶ ≈ 1.2e-32 of `‖a‖`, backward stable
    /// as in f64) and far below f64 precision of the smallest eigenvalue at `κ = 4e11`
    /// (`ε λ_min ≈ 2e-16 · ‖a‖/4e11 ≈ 5e-28 ‖a‖`).
    pub const DD_WIDTH: f64 = 1e-30;

    /// The f64 bisection's error on an eigenvalue, in units of `ε ‖a‖∞`: the Sturm count is
    /// exact for a matrix whose entries are perturbed by a few ulps (Kahan 1966; LAPACK
    /// Working Note 3), so by Weyl's theorem each eigenvalue is within a few `ε ‖a‖`; the
    /// bisection then stops at one ulp of it. 4 units.
    pub const STURM_ERROR_ULPS: f64 = 4.0;
}

#[cfg(test)]
mod tests {
    /// The bar's P1 step matrix `M/Δt² + (½ + α/(2Δt)) K` on `n` elements of `[0, 1]`, free
    /// ends (`M = Δx/6 (1, 4, 1)`, `K = (−1, 2, −1)/Δx`, halved diagonals at the ends).
    fn step_matrix(n: usize, alpha: f64, ratio: f64) -> SymTridiag {
        let dx = 1.0 / n as f64;
        let dt = ratio * dx;
        let (a, b) = (1.0 / (dt * dt), 0.5 + alpha / (2.0 * dt));
        let mut diag = vec![a * 4.0 * dx / 6.0 + b * 2.0 / dx; n + 1];
        diag[0] = a * 2.0 * dx / 6.0 + b / dx;
        diag[n] = diag[0];
        SymTridiag::new(diag, vec![a * dx / 6.0 - b / dx; n])
    }

    /// The bound lies in `[κ, 6κ]` of the bisected condition number, on step matrices from
    /// `κ ≈ 3` to `1e12` (α and Δt/Δx over the stiff matrix's corners) and a singular one.
    #[test]
    fn the_condition_bound_is_within_six_of_the_condition_number() {
        for (n, alpha, ratio) in [
            (20, 0.0, 1.0),
            (20, 1e6, 1.0),
            (64, 1e6, 1e4),
            (1000, 0.0, 1e-3),
        ] {
            let c = step_matrix(n, alpha, ratio);
            let kappa = condition_number(&c).unwrap();
            let bound = condition_bound(&c).unwrap();
            assert!(
                bound >= kappa && bound <= 6.0 * kappa,
                "{n} {alpha} {ratio}: {bound} {kappa}"
            );
        }
        // Free-free stiffness alone: the rigid mode makes it singular.
        let singular = SymTridiag::new(vec![1.0, 2.0, 2.0, 1.0], vec![-1.0; 3]);
        assert_eq!(condition_bound(&singular), None);
    }

    use super::reference::{STURM_ERROR_ULPS, eigenvalue_dd};
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

    /// The step matrices `C` of a 21-node bar from mass-dominated (`Δt = 1e-3 Δx`, κ ≈ 4) to
    /// stiff (`α = 1e6`, `Δt = 1e4 Δx`, κ ≈ 4e11).
    fn step_matrices() -> Vec<(f64, f64, SymTridiag)> {
        use crate::bar::matrices::{MatrixVariant, mass, stiffness};
        let nodes = 21;
        let dx = 1.0 / 20.0;
        let m = mass(MatrixVariant::Consistent, nodes, dx);
        let r = stiffness(MatrixVariant::Consistent, nodes, dx);
        [(0.0, 1e-3), (0.0, 1.0), (1e3, 100.0), (1e6, 1e4)]
            .into_iter()
            .map(|(alpha, ratio)| {
                let dt = ratio * dx;
                let c = SymTridiag::combine(1.0 / (dt * dt), &m, 0.5 + alpha / (2.0 * dt), &r);
                (alpha, ratio, c)
            })
            .collect()
    }

    #[test]
    fn step_matrices_match_dense_from_mass_dominated_to_stiff() {
        for (_, _, c) in step_matrices() {
            check_against_dense(&c);
            // κ: against the double-double reference, below (the dense QR values are
            // themselves only within a few ε‖C‖).
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
    fn double_double_reference_matches_closed_forms() {
        // R + σI, R the consistent free-free stiffness of 21 nodes: eigenvalues
        // σ + (4/Δx) sin²(mπ/(2n)), m = 0..n−1 (eigenvectors cos((i + ½) mπ/n)); the smallest
        // is σ exactly, at κ ≈ 8e9, where f64 bisection resolves it only to ~1e-6 relative.
        use crate::bar::matrices::{MatrixVariant, stiffness};
        let (n, sigma) = (21usize, 1e-8);
        let r = stiffness(MatrixVariant::Consistent, n, 1.0 / 20.0);
        let a = SymTridiag::new(r.diag.iter().map(|v| v + sigma).collect(), r.off.clone());
        // The diagonal 20 + σ, 40 + σ is rounded (by up to ε · 40), which moves σ by as much.
        let lo = eigenvalue_dd(&a, 0);
        assert!(
            (lo.hi - sigma).abs() <= 2.0 * f64::EPSILON * 40.0,
            "{lo:?} against {sigma}"
        );
        // tridiag(−1, 2, −1) of n = 1000: λ_min = 4 sin²(π/(2(n + 1))) to a few ulps.
        let n = 1000;
        let t = SymTridiag::new(vec![2.0; n], vec![-1.0; n - 1]);
        let exact = 4.0 * (0.5 * std::f64::consts::PI / (n + 1) as f64).sin().powi(2);
        let lo = eigenvalue_dd(&t, 0);
        assert!(
            (lo.hi - exact).abs() <= 4.0 * f64::EPSILON * exact,
            "{lo:?} against {exact}"
        );
        let hi = eigenvalue_dd(&t, n - 1);
        let exact_hi = 2.0 + 2.0 * (std::f64::consts::PI / (n + 1) as f64).cos();
        assert!((hi.hi - exact_hi).abs() <= 4.0 * f64::EPSILON * exact_hi);
    }

    /// The step matrices of [`step_matrices_match_dense_from_mass_dominated_to_stiff`], from
    /// κ ≈ 4 to κ ≈ 4e11: each extreme eigenvalue within [`STURM_ERROR_ULPS`] `ε‖C‖∞` of the
    /// double-double reference, and κ within the relative error that implies,
    /// `STURM_ERROR_ULPS ε ‖C‖∞ (1/λ_min + 1/λ_max)` (about 3.7e-4 at κ = 4e11, where the dense
    /// comparison allowed 64 ε κ ≈ 6, i.e. 600 %). Measured worst: 0.69 units on an eigenvalue,
    /// κ off by 7.7e-6 relative at 4e11 (`viscobar-certificate verify --tolerances` prints
    /// both ratios).
    #[test]
    fn condition_numbers_match_the_double_double_reference() {
        for (alpha, ratio, c) in step_matrices() {
            let (lo, hi) = (eigenvalue_dd(&c, 0), eigenvalue_dd(&c, c.diag.len() - 1));
            let tol = STURM_ERROR_ULPS * f64::EPSILON * c.inf_norm();
            let (l, h) = extreme_eigenvalues(&c);
            for (got, reference) in [(l, lo), (smallest_eigenvalue_spd(&c), lo), (h, hi)] {
                assert!(
                    (got - reference.hi).abs() <= tol,
                    "α {alpha:e}, Δt/Δx {ratio:e}: {got:e} against {reference:?}"
                );
            }
            let kappa_ref = hi.over(lo).hi;
            let kappa = condition_number(&c).unwrap();
            let rtol = tol * (1.0 / lo.hi + 1.0 / hi.hi);
            assert!(
                (kappa - kappa_ref).abs() <= rtol * kappa_ref,
                "α {alpha:e}, Δt/Δx {ratio:e}: κ {kappa:e} against {kappa_ref:e}"
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
