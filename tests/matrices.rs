//! Properties of the P1 matrices M and R, and the diagnosis of the talk's printed entries.

use viscobar::bar::matrices::{MatrixVariant, mass, stiffness};
use viscobar_certificate::verify::SolveCase;

// Defined beside their measurement in the tolerance registry (`viscobar-certificate verify
// --tolerances`).
use viscobar_certificate::tolerances::{
    BACKWARD_ULPS, MASS_SUM_TOL, MATRIX_SIZES as SIZES, ldlt_family_worst, mass_sum_worst,
};

fn is_bitwise_symmetric(a: &nalgebra::DMatrix<f64>) -> bool {
    (0..a.nrows()).all(|i| (0..a.ncols()).all(|j| a[(i, j)].to_bits() == a[(j, i)].to_bits()))
}

#[test]
fn consistent_mass_and_stiffness_are_symmetric_bitwise() {
    for nodes in SIZES {
        let dx = 1.7 / (nodes - 1) as f64;
        assert!(is_bitwise_symmetric(
            &mass(MatrixVariant::Consistent, nodes, dx).to_dense()
        ));
        assert!(is_bitwise_symmetric(
            &stiffness(MatrixVariant::Consistent, nodes, dx).to_dense()
        ));
    }
}

#[test]
fn consistent_mass_is_positive_definite_with_total_mass_l() {
    for nodes in SIZES {
        let length = 1.7;
        let dx = length / (nodes - 1) as f64;
        let m = mass(MatrixVariant::Consistent, nodes, dx);
        let eig = m.to_dense().symmetric_eigenvalues();
        // Smallest eigenvalue of the P1 mass matrix is dx/6 * (something >= 1) > 0.
        assert!(eig.min() > 0.0, "M not positive definite at {nodes} nodes");
    }
    // 1ᵀM1 = L, and the printed matrices' (4J + 6)/(3J + 3) L below: the registry's measurement.
    let (worst, _) = mass_sum_worst();
    assert!(worst <= MASS_SUM_TOL, "1'M1 off by {worst:e}");
}

#[test]
fn consistent_stiffness_annihilates_rigid_motion_exactly() {
    for nodes in SIZES {
        let dx = 1.7 / (nodes - 1) as f64;
        let r = stiffness(MatrixVariant::Consistent, nodes, dx);
        assert!(
            r.mul(&vec![3.25; nodes]).iter().all(|v| *v == 0.0),
            "R·1 != 0 at {nodes} nodes"
        );
        let eig = r.to_dense().symmetric_eigenvalues();
        assert!(eig.min() > -1e-9 / dx, "R must be positive semidefinite");
    }
}

/// The talk prints M with off-diagonal Δx/3 and end diagonals 2Δx/3, and R with end diagonals
/// 2/Δx. This test documents why those entries are not the P1 matrices: the printed M gives the
/// bar a mass `(4J + 6)/(3J + 3) · L → 4L/3`, and the printed R ties both ends to the ground
/// (`R·1 ≠ 0`), so a free bar could not translate rigidly.
#[test]
fn talk_printed_matrices_are_inconsistent() {
    let length = 1.0;
    for nodes in [11usize, 101, 1001] {
        let dx = length / (nodes - 1) as f64;
        let m = mass(MatrixVariant::TalkPrinted, nodes, dx);
        let total: f64 = m.mul(&vec![1.0; nodes]).iter().sum();
        assert!(
            total > 1.3 * length,
            "printed M should overweigh the bar (1'M1 = {total})"
        );
        let r = stiffness(MatrixVariant::TalkPrinted, nodes, dx);
        let r1 = r.mul(&vec![1.0; nodes]);
        assert_eq!(r1[0], 1.0 / dx, "printed R has a spring 1/dx at x = 0");
        assert_eq!(
            r1[nodes - 1],
            1.0 / dx,
            "printed R has a spring 1/dx at x = L"
        );
    }
}

/// The factorisation solves to round-off, for every size (the odd–even reduction and the twist
/// have edge cases at small and at even or odd n) and for matrices that are not diagonally
/// dominant.
#[test]
fn factorisation_solves_spd_tridiagonal_systems() {
    // n = 1 … 39, two shifts, off-diagonals of both signs: the registry's measurement.
    // Each system against its own bound SOLVE_ULPS ε ‖A‖∞ ‖x‖₂ / λ_min (the registry's).
    let (ratio, worst) = ldlt_family_worst();
    assert!(
        ratio <= 1.0,
        "|x̂ − x| / bound {ratio:e} (worst |x̂ − x| {worst:e})"
    );
}

// BACKWARD_ULPS: Higham's bound for the normwise backward error, in the registry.

/// The solve is backward stable on the step matrices `C = M/Δt² + (½ + α/(2Δt)) R` from
/// mass-dominated to stiff (`α = 10⁶`, `Δt = 10⁴ Δx`), at even and odd node counts, and
/// `solve_into` gives the bits of `solve_in_place` (`verify::solve_study`, whose figures
/// VERIFICATION.md shows). A look-ahead recurrence `y_i = (b_i − l b_i−1) + l l' y_i−2`, tried
/// for speed in a one-off probe (not in the tree), measured 31 ε on these matrices.
#[test]
fn factorisation_is_backward_stable_on_the_step_matrices() {
    use viscobar_certificate::verify::{SOLVE_STUDY_CASES, backward_error_nodes, solve_study};
    let nodes = backward_error_nodes();
    let cases = solve_study(&nodes);
    assert_eq!(
        cases.len(),
        nodes.len() * SOLVE_STUDY_CASES.len(),
        "a factorisation failed"
    );
    for case in cases {
        let SolveCase {
            alpha,
            dt_over_dx,
            nodes,
            backward_error,
            into_same_bits,
        } = case;
        assert!(
            into_same_bits,
            "n = {nodes}: solve_into differs from solve_in_place"
        );
        assert!(
            backward_error <= BACKWARD_ULPS,
            "n = {nodes}, alpha = {alpha}, dt/dx = {dt_over_dx}: backward error {backward_error:.2} ε"
        );
    }
}

// ---- the mass variants of `[bar] mass` ----------------------------------------------------

mod mass_variants {
    use viscobar::bar::matrices::{MassVariant, MatrixVariant, mass_matrix, stiffness};
    use viscobar::internals::linalg::kernels::ldlt::Ldlt;
    use viscobar::internals::linalg::tridiag::SymTridiag;
    use viscobar::scene::{
        REDISTRIBUTED_MIN_ELEMENTS_ONE_END, REDISTRIBUTED_MIN_ELEMENTS_TWO_ENDS,
    };

    // Defined beside their measurement in the tolerance registry (`viscobar-certificate verify
    // --tolerances`).
    use viscobar_certificate::tolerances::{
        EIGEN_TOL_ULPS, ENTRY_TOL, VARIANT_LENGTH as LENGTH, VARIANT_SUM_TOL,
        documented_entries_worst, mass_variant_cases as cases, mass_variant_worst,
    };

    fn least(ends: [bool; 2]) -> usize {
        match ends.iter().filter(|e| **e).count() {
            0 => 1,
            1 => REDISTRIBUTED_MIN_ELEMENTS_ONE_END as usize,
            _ => REDISTRIBUTED_MIN_ELEMENTS_TWO_ENDS as usize,
        }
    }

    fn build(variant: MassVariant, ends: [bool; 2], elements: usize) -> (SymTridiag, f64) {
        let dx = LENGTH / elements as f64;
        let m = mass_matrix(variant, ends, elements + 1, dx)
            .unwrap_or_else(|e| panic!("{variant:?} {ends:?} {elements}: {e}"));
        (m, dx)
    }

    /// The nodes a variant leaves without mass.
    fn massless(variant: MassVariant, ends: [bool; 2], nodes: usize) -> Vec<usize> {
        if variant != MassVariant::Redistributed {
            return Vec::new();
        }
        [0, nodes - 1]
            .into_iter()
            .zip(ends)
            .filter_map(|(n, e)| e.then_some(n))
            .collect()
    }

    #[test]
    fn every_variant_is_symmetric_and_keeps_total_mass_and_first_moment() {
        for (variant, ends, elements) in cases() {
            let (m, _) = build(variant, ends, elements);
            let nodes = elements + 1;
            let at = format!("{variant:?} ends {ends:?} J+1 = {elements}");
            let d = m.to_dense();
            assert!(
                (0..nodes).all(|i| (0..nodes).all(|j| d[(i, j)].to_bits() == d[(j, i)].to_bits())),
                "{at}: not symmetric"
            );
        }
        // 1ᵀM1 = L and xᵀM1 = ∫ x dx = L²/2 (the consistent matrix's, kept by every variant)
        // over the same cases: the registry's measurement.
        let w = mass_variant_worst().unwrap();
        assert!(w.sum <= VARIANT_SUM_TOL, "1'M1 or x'M1 off by {:e}", w.sum);
    }

    /// PSD with kernel exactly the massless nodes: their rows and columns are zero and the rest
    /// of `M` is positive definite (pivots of the L D Lᵀ recurrence, for every size up to 64 and
    /// a long bar; eigenvalues for the dense copies). Redistributed diagonals from the left
    /// end, in units of Δx/6: `0, 11, 1, 4, 4, …`; the pivots `11, 10/11, 2.9, …` increase
    /// towards `2 + √3` and a last pivot `2 − 1/p` (free end) or `1 − 1/p` (a mirrored
    /// redistributed end, `p >= 2.9`) stays positive, which is why two ends need a plain node
    /// between their changes.
    #[test]
    fn every_variant_is_positive_semidefinite_with_kernel_the_massless_nodes() {
        for (variant, ends, elements) in cases() {
            let (m, _) = build(variant, ends, elements);
            let nodes = elements + 1;
            let at = format!("{variant:?} ends {ends:?} J+1 = {elements}");
            let zero = massless(variant, ends, nodes);
            for &k in &zero {
                assert_eq!(m.diag[k], 0.0, "{at}: node {k} keeps mass");
                let edge = if k == 0 { 0 } else { k - 1 };
                assert_eq!(m.off[edge], 0.0, "{at}: node {k} keeps a coupling");
            }
            let lo = usize::from(zero.contains(&0));
            let hi = nodes - usize::from(zero.contains(&(nodes - 1)));
            let block = m.sub(lo, hi - 1);
            // The L D Lᵀ pivots of the massive block.
            let mut pivot = block.diag[0];
            assert!(pivot > 0.0, "{at}: pivot 0 is {pivot}");
            for i in 1..block.dim() {
                pivot = block.diag[i] - block.off[i - 1] * block.off[i - 1] / pivot;
                assert!(pivot > 0.0, "{at}: pivot {i} is {pivot}");
            }
        }
        // Dense eigenvalues (n <= 65), the registry's measurement: the massless nodes' count of
        // them within EIGEN_TOL_ULPS ε‖M‖∞ of 0 and none negative beyond it, the others above it.
        let w = mass_variant_worst().unwrap();
        assert!(
            w.kernel_ulps <= EIGEN_TOL_ULPS,
            "kernel {:e} ε‖M‖",
            w.kernel_ulps
        );
        assert!(w.smallest_other_ulps > EIGEN_TOL_ULPS, "{w:?}");
    }

    /// `C = M/Δt² + (½ + α/(2Δt)) R` stays positive definite (the massless node is held by R),
    /// from mass-dominated to stiff, on the free-free bar (R singular) and with clamped ends
    /// removed (here: the sub-matrices without the first or last node).
    #[test]
    fn the_step_matrix_stays_positive_definite() {
        for (variant, ends, elements) in cases() {
            let (m, dx) = build(variant, ends, elements);
            let r = stiffness(MatrixVariant::Consistent, elements + 1, dx);
            for (alpha, ratio) in [(0.0, 0.01), (0.0, 1.0), (0.1, 1.0), (1e6, 1e4)] {
                let dt = ratio * dx;
                let c = SymTridiag::combine(1.0 / (dt * dt), &m, 0.5 + alpha / (2.0 * dt), &r);
                Ldlt::factor(&c).unwrap_or_else(|e| {
                    panic!("{variant:?} {ends:?} J+1 = {elements} α {alpha} Δt/Δx {ratio}: {e}")
                });
            }
        }
    }

    /// The entries the doc states: lumped `diag(Δx/2, Δx, …, Δx/2)`; redistributed row sums
    /// `(0, 2Δx, Δx/2, Δx, …)` from a Signorini end, `11Δx/6` and `Δx/6` on the diagonal.
    #[test]
    fn lumped_and_redistributed_entries_are_the_documented_ones() {
        let elements = 10;
        let dx = 1.0 / elements as f64;
        // The lumped diagonal, the redistributed row sums and diagonals: the registry's.
        let (worst, lumped_off_zero) = documented_entries_worst().unwrap();
        assert!(lumped_off_zero);
        assert!(worst <= ENTRY_TOL, "an entry off by {worst:e}");
        // Without Signorini ends, redistribution changes nothing.
        let none = mass_matrix(MassVariant::Redistributed, [false, false], elements + 1, dx);
        let consistent = mass_matrix(MassVariant::Consistent, [true, true], elements + 1, dx);
        assert_eq!(none, consistent);
    }

    /// Bars too short for the redistribution are refused with the least element count. Why
    /// two ends need 6: with 5 the formula would give the diagonals `0, 11, 1, 1, 11, 0` (units
    /// Δx/6, off-diagonals 1 inside), whose third pivot is `1 − 11/10 < 0`.
    #[test]
    fn too_short_bars_are_refused() {
        let pivots = [11.0, 1.0, 1.0, 11.0]
            .into_iter()
            .scan(None, |p: &mut Option<f64>, d| {
                let next = p.map_or(d, |q| d - 1.0 / q);
                *p = Some(next);
                Some(next)
            });
        assert!(
            pivots.clone().any(|p| p < 0.0),
            "{:?}",
            pivots.collect::<Vec<_>>()
        );
        for ends in [[true, false], [false, true], [true, true]] {
            let least = least(ends);
            for elements in 1..least {
                let err =
                    mass_matrix(MassVariant::Redistributed, ends, elements + 1, 1.0).unwrap_err();
                assert_eq!((err.least, err.elements), (least, elements), "{ends:?}");
                assert!(err.to_string().contains("elements"), "{err}");
            }
        }
    }
}
