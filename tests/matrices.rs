//! Properties of the P1 matrices M and R, and the diagnosis of the talk's printed entries.

use viscobar::bar::matrices::{MatrixVariant, mass, stiffness};
use viscobar::study::verify::SolveCase;

/// `1ᵀM1` sums `J + 2` rounded entries: a few ulps of L.
const MASS_SUM_TOL: f64 = 1e-12;

const SIZES: [usize; 4] = [2, 3, 10, 1001];

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
        let total: f64 = m.mul(&vec![1.0; nodes]).iter().sum();
        assert!(
            (total - length).abs() <= MASS_SUM_TOL * length,
            "1'M1 = {total}, L = {length}"
        );
    }
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
        let j = (nodes - 2) as f64;
        let m = mass(MatrixVariant::TalkPrinted, nodes, dx);
        let total: f64 = m.mul(&vec![1.0; nodes]).iter().sum();
        let predicted = (4.0 * j + 6.0) / (3.0 * j + 3.0) * length;
        assert!(
            (total - predicted).abs() <= MASS_SUM_TOL,
            "printed 1'M1 = {total}, expected {predicted}"
        );
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
    use viscobar::linalg::ldlt::Ldlt;
    use viscobar::linalg::tridiag::SymTridiag;
    // Backward-stable solve with condition number below 1e3 here.
    const SOLVE_TOL: f64 = 1e-12;
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
            let mut b = a.mul(&x);
            Ldlt::factor(&a).unwrap().solve_in_place(&mut b);
            for i in 0..n {
                assert!(
                    (b[i] - x[i]).abs() <= SOLVE_TOL,
                    "n = {n}, i = {i}: {} vs {}",
                    b[i],
                    x[i]
                );
            }
        }
    }
}

/// Normwise backward error of the solve, in units of ε: Gaussian elimination on a tridiagonal
/// SPD matrix gives `(A + ΔA) x̂ = b` with `|ΔA| ≤ γ₃ |A|` (for tridiagonal SPD `|L||D||Lᵀ| = |A|`;
/// Higham, *Accuracy and Stability*, Thm 9.3 and 10.5), and evaluating `b − A x̂` adds at most
/// four roundings of `|A||x̂| + |b|`.
const BACKWARD_ULPS: f64 = 8.0;

/// The solve is backward stable on the step matrices `C = M/Δt² + (½ + α/(2Δt)) R` from
/// mass-dominated to stiff (`α = 10⁶`, `Δt = 10⁴ Δx`), at even and odd node counts, and
/// `solve_into` gives the bits of `solve_in_place` (`verify::solve_study`, whose figures
/// VERIFICATION.md shows). A look-ahead recurrence `y_i = (b_i − l b_i−1) + l l' y_i−2`, tried
/// for speed in a one-off probe (not in the tree), measured 31 ε on these matrices.
#[test]
fn factorisation_is_backward_stable_on_the_step_matrices() {
    use viscobar::study::verify::{SOLVE_STUDY_CASES, SOLVE_STUDY_NODES, solve_study};
    let nodes: Vec<usize> = (2..=24).chain(SOLVE_STUDY_NODES).collect();
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
