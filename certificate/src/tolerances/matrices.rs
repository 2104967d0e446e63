//! The tolerances of the bar's matrices and their solves (`tests/matrices.rs`) and of the
//! spectrum's condition number (the tests of `src/linalg/spectrum.rs`), each beside the
//! measurement of what it guards.

use viscobar::internals::linalg::spectrum::reference::STURM_ERROR_ULPS;
use viscobar::internals::linalg::tridiag::SymTridiag;
use viscobar::scene::{self, MassVariant};

/// The step matrices of `linalg::spectrum`'s κ test, `(α, Δt/Δx)` on 21 nodes, κ from 4 to
/// 4e11.
pub const KAPPA_CASES: [(f64, f64); 4] = [(0.0, 1e-3), (0.0, 1.0), (1e3, 100.0), (1e6, 1e4)];

/// Against the double-double reference on [`KAPPA_CASES`]: the worst eigenvalue error of the
/// f64 bisection in units of `ε‖C‖∞`, and the worst κ error relative to its bound
/// `STURM_ERROR_ULPS ε ‖C‖∞ (1/λ_min + 1/λ_max)`.
pub fn kappa_reference_worst() -> (f64, f64) {
    use viscobar::bar::matrices::{MatrixVariant, mass, stiffness};
    use viscobar::internals::linalg::spectrum::{
        condition_number, extreme_eigenvalues, reference::eigenvalue_dd, smallest_eigenvalue_spd,
    };
    let nodes = 21;
    let dx = 1.0 / 20.0;
    let m = mass(MatrixVariant::Consistent, nodes, dx);
    let r = stiffness(MatrixVariant::Consistent, nodes, dx);
    let (mut eig, mut kappa) = (0.0f64, 0.0f64);
    for (alpha, ratio) in KAPPA_CASES {
        let dt = ratio * dx;
        let c = SymTridiag::combine(1.0 / (dt * dt), &m, 0.5 + alpha / (2.0 * dt), &r);
        let (lo, hi) = (eigenvalue_dd(&c, 0), eigenvalue_dd(&c, nodes - 1));
        let unit = f64::EPSILON * c.inf_norm();
        let (l, h) = extreme_eigenvalues(&c);
        for (got, reference) in [(l, lo), (smallest_eigenvalue_spd(&c), lo), (h, hi)] {
            eig = eig.max((got - reference.hi).abs() / unit);
        }
        let kappa_ref = hi.over(lo).hi;
        let rtol = STURM_ERROR_ULPS * unit * (1.0 / lo.hi + 1.0 / hi.hi);
        let got = condition_number(&c).unwrap_or(f64::NAN);
        kappa = kappa.max((got - kappa_ref).abs() / (rtol * kappa_ref));
    }
    (eig, kappa)
}

// ---- tests/matrices.rs ------------------------------------------------------------------------

/// `1ᵀM1` sums `J + 2` rounded entries: a few ulps of L.
pub const MASS_SUM_TOL: f64 = 1e-12;
/// The node counts of the consistent matrices' checks.
pub const MATRIX_SIZES: [usize; 4] = [2, 3, 10, 1001];

/// `1ᵀM1` against its closed form: `L` for the consistent mass (relative, [`MATRIX_SIZES`],
/// `L = 1.7`) and `(4J + 6)/(3J + 3) L` for the talk's printed one (`L = 1`, 11 to 1001
/// nodes): the worst error, and the smallest printed total over `L` (which must exceed 4/3's
/// neighbourhood, 1.3).
pub fn mass_sum_worst() -> (f64, f64) {
    use viscobar::bar::matrices::{MatrixVariant, mass};
    let mut worst = 0.0f64;
    for nodes in MATRIX_SIZES {
        let length = 1.7;
        let dx = length / (nodes - 1) as f64;
        let m = mass(MatrixVariant::Consistent, nodes, dx);
        let total: f64 = m.mul(&vec![1.0; nodes]).iter().sum();
        worst = worst.max((total - length).abs() / length);
    }
    let mut smallest_printed = f64::INFINITY;
    for nodes in [11usize, 101, 1001] {
        let dx = 1.0 / (nodes - 1) as f64;
        let j = (nodes - 2) as f64;
        let m = mass(MatrixVariant::TalkPrinted, nodes, dx);
        let total: f64 = m.mul(&vec![1.0; nodes]).iter().sum();
        worst = worst.max((total - (4.0 * j + 6.0) / (3.0 * j + 3.0)).abs());
        smallest_printed = smallest_printed.min(total);
    }
    (worst, smallest_printed)
}

/// Forward error of the solve in units of `ε ‖A‖∞ ‖x‖₂ / λ_min(A)` (the family's own κ): LDLᵀ
/// with its substitutions is backward stable with `|ΔA| ≤ 4u |L||D||Lᵀ| = 4u |A|` on SPD
/// tridiagonal matrices (Higham, *Accuracy and Stability*, Thm 9.14; `D > 0`), forming
/// `b = A x` adds `γ₃ |A||x|`, and `‖|A|‖₂ ≤ ‖A‖∞`: `7u = 3.5ε`, rounded up.
pub const SOLVE_ULPS: f64 = 4.0;

/// The plain `Ldlt` and its twin `TwistedLdlt` on the family of `tests/matrices.rs` (n = 1 …
/// 39, two shifts, off-diagonals of both signs, not all diagonally dominant), `b = A x`: the
/// worst `|x̂ − x|∞` of either over its own bound `SOLVE_ULPS ε ‖A‖∞ ‖x‖₂ / λ_min(A)` (λ_min by
/// bisection), and the worst `|x̂ − x|∞`.
pub fn ldlt_family_worst() -> (f64, f64) {
    use viscobar::internals::linalg::kernels::ldlt::Ldlt;
    use viscobar::internals::linalg::kernels::ldlt_fast::TwistedLdlt;
    use viscobar::internals::linalg::spectrum::smallest_eigenvalue_spd;
    let (mut ratio, mut worst) = (0.0f64, 0.0f64);
    for n in 1..40usize {
        for shift in [0.05, 1.0] {
            let diag: Vec<f64> = (0..n)
                .map(|i| 2.0 + shift + 0.1 * (i as f64).sin())
                .collect();
            let off: Vec<f64> = (0..n.saturating_sub(1))
                .map(|i| if i % 3 == 0 { 0.9 } else { -1.0 })
                .collect();
            let a = SymTridiag::new(diag, off);
            let x: Vec<f64> = (0..n).map(|i| (i as f64 * 0.7).cos()).collect();
            let b = a.mul(&x);
            let (mut plain, mut twin) = (b.clone(), b);
            match (Ldlt::factor(&a), TwistedLdlt::factor(&a)) {
                (Ok(f), Ok(g)) => {
                    f.solve_in_place(&mut plain);
                    g.solve_in_place(&mut twin);
                }
                _ => return (f64::INFINITY, f64::INFINITY), // SPD: a refusal fails
            }
            let lambda_min = smallest_eigenvalue_spd(&a);
            let x_norm = x.iter().map(|v| v * v).sum::<f64>().sqrt();
            let bound = SOLVE_ULPS * f64::EPSILON * a.inf_norm() * x_norm / lambda_min;
            for solved in [&plain, &twin] {
                let error = (0..n).map(|i| (solved[i] - x[i]).abs()).fold(0.0, f64::max);
                worst = worst.max(error);
                ratio = ratio.max(if bound > 0.0 {
                    error / bound
                } else {
                    f64::INFINITY
                });
            }
        }
    }
    (ratio, worst)
}

/// `1ᵀM1` and `xᵀM1` of the mass variants sum `J + 2` rounded entries of size Δx (times
/// x ≤ L): a few ulps of `L` and `L²` per entry, far below the `Δx²/6` a lost moment
/// correction would leave.
pub const VARIANT_SUM_TOL: f64 = 1e-12;
/// A kernel eigenvalue of a mass variant's dense copy (n ≤ 65): the QR algorithm is backward
/// stable to a few `ε‖M‖`; eigenvalues within this many `ε‖M‖∞` of 0 count as the kernel.
pub const EIGEN_TOL_ULPS: f64 = 64.0;
/// An entry of the lumped and redistributed matrices at Δx = 0.1 (entries ≤ 0.2) against its
/// documented value: one or two roundings of an entry of size 0.2, i.e. a few `ε · 0.2`.
pub const ENTRY_TOL: f64 = 1e-15;
/// The bar length of the mass variants' checks.
pub const VARIANT_LENGTH: f64 = 1.7;

/// Every (variant, Signorini ends, elements) the mass variants' checks build: all element
/// counts from the least the variant allows to 64, and a long bar.
pub fn mass_variant_cases() -> Vec<(MassVariant, [bool; 2], usize)> {
    let mut v = Vec::new();
    for variant in MassVariant::ALL {
        for ends in [[false, false], [true, false], [false, true], [true, true]] {
            let from = match (variant, ends.iter().filter(|e| **e).count()) {
                (MassVariant::Redistributed, 1) => scene::REDISTRIBUTED_MIN_ELEMENTS_ONE_END,
                (MassVariant::Redistributed, 2) => scene::REDISTRIBUTED_MIN_ELEMENTS_TWO_ENDS,
                _ => 1,
            } as usize;
            for elements in (from..=64).chain([1000]) {
                v.push((variant, ends, elements));
            }
        }
    }
    v
}

/// Worst values over [`mass_variant_cases`] of what the mass variants' tolerances guard.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct VariantWorst {
    /// `max(|1ᵀM1 − L|/L, |xᵀM1 − L²/2|/(L²/2))`.
    pub sum: f64,
    /// The kernel eigenvalues (the massless nodes' count, smallest in magnitude) and the
    /// negative part of the smallest eigenvalue, in units of `ε‖M‖∞` (dense copies, n ≤ 65).
    pub kernel_ulps: f64,
    /// The smallest other eigenvalue in the same units (must exceed [`EIGEN_TOL_ULPS`]).
    pub smallest_other_ulps: f64,
}

/// [`VariantWorst`] over [`mass_variant_cases`].
pub fn mass_variant_worst() -> Result<VariantWorst, viscobar::bar::matrices::TooFewElements> {
    use viscobar::bar::matrices::mass_matrix;
    let mut w = VariantWorst {
        smallest_other_ulps: f64::INFINITY,
        ..VariantWorst::default()
    };
    for (variant, ends, elements) in mass_variant_cases() {
        let nodes = elements + 1;
        let dx = VARIANT_LENGTH / elements as f64;
        let m = mass_matrix(variant, ends, nodes, dx)?;
        let m1 = m.mul(&vec![1.0; nodes]);
        let total: f64 = m1.iter().sum();
        let moment: f64 = m1.iter().enumerate().map(|(i, v)| i as f64 * dx * v).sum();
        let half_square = VARIANT_LENGTH * VARIANT_LENGTH / 2.0;
        w.sum = w
            .sum
            .max((total - VARIANT_LENGTH).abs() / VARIANT_LENGTH)
            .max((moment - half_square).abs() / half_square);
        if nodes <= 65 {
            let unit = f64::EPSILON * m.inf_norm();
            let mut eig: Vec<f64> = m
                .to_dense()
                .symmetric_eigenvalues()
                .iter()
                .copied()
                .collect();
            eig.sort_by(|a, b| a.abs().total_cmp(&b.abs()));
            let kernel = if variant == MassVariant::Redistributed {
                ends.iter().filter(|e| **e).count()
            } else {
                0
            };
            for e in &eig[..kernel] {
                w.kernel_ulps = w.kernel_ulps.max(e.abs() / unit);
            }
            for e in &eig[kernel..] {
                w.kernel_ulps = w.kernel_ulps.max(-e / unit);
                w.smallest_other_ulps = w.smallest_other_ulps.min(e.abs() / unit);
            }
        }
    }
    Ok(w)
}

/// The documented entries at 10 elements (Δx = 0.1): lumped `diag(Δx/2, Δx, …, Δx/2)`;
/// redistributed from a Signorini end at the left, row sums `(0, 2Δx, Δx/2, Δx, Δx)` and
/// `Δx/2` at the free end, diagonals `11Δx/6` and `Δx/6` at nodes 1 and 2: the worst
/// `|entry − documented|`, and whether the lumped off-diagonals are exactly 0.
pub fn documented_entries_worst() -> Result<(f64, bool), viscobar::bar::matrices::TooFewElements> {
    use viscobar::bar::matrices::mass_matrix;
    let elements = 10;
    let dx = 1.0 / elements as f64;
    let l = mass_matrix(MassVariant::Lumped, [true, true], elements + 1, dx)?;
    let mut pairs = vec![(l.diag[0], dx / 2.0), (l.diag[elements], dx / 2.0)];
    pairs.extend(l.diag[1..elements].iter().map(|d| (*d, dx)));
    let r = mass_matrix(MassVariant::Redistributed, [true, false], elements + 1, dx)?;
    let sums = r.row_sums();
    for (i, want) in [0.0, 2.0 * dx, dx / 2.0, dx, dx].into_iter().enumerate() {
        pairs.push((sums[i], want));
    }
    pairs.push((sums[elements], dx / 2.0));
    pairs.push((r.diag[1], 11.0 * dx / 6.0));
    pairs.push((r.diag[2], dx / 6.0));
    let worst = pairs.iter().map(|(a, b)| (a - b).abs()).fold(0.0, f64::max);
    Ok((worst, l.off.iter().all(|e| *e == 0.0)))
}

/// Normwise backward error of the solve, in units of ε: Gaussian elimination on a tridiagonal
/// SPD matrix gives `(A + ΔA) x̂ = b` with `|ΔA| ≤ γ₃ |A|` (for tridiagonal SPD `|L||D||Lᵀ| = |A|`;
/// Higham, *Accuracy and Stability*, Thm 9.3 and 10.5), and evaluating `b − A x̂` adds at most
/// four roundings of `|A||x̂| + |b|`.
pub const BACKWARD_ULPS: f64 = 8.0;
