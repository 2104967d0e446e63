//! The many-bound exact solver (block principal pivoting with Murty's safeguard) against the
//! brute-force oracle on small problems, against KKT on large ones, and on the hard cases an
//! independent probe found for plain primal-dual active sets.

mod common;
use common::{AGREEMENT_TOL, kkt};

use proptest::prelude::*;
use viscobar::bar::matrices::{MatrixVariant, mass, stiffness};
use viscobar::linalg::norms::max_abs;
use viscobar::linalg::tridiag::SymTridiag;
use viscobar::step::StepSolver;
use viscobar::step::block_pivot::BlockPivotSolver;
use viscobar::step::oracle::brute_force;

fn solve(c: &SymTridiag, b: &[f64], nodes: &[usize], lo: &[f64]) -> (Vec<f64>, Vec<f64>, u32) {
    let mut s = BlockPivotSolver::new(c, nodes).unwrap();
    let (mut z, mut r) = (vec![0.0; b.len()], vec![0.0; nodes.len()]);
    let info = s.solve(b, lo, &mut z, &mut r).unwrap();
    (z, r, info.iterations)
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(1000))]

    #[test]
    fn small_problems_match_brute_force(
        c in common::spd_tridiag(10),
        b in prop::collection::vec(-5.0f64..5.0, 10),
        lo in prop::collection::vec(-2.0f64..2.0, 10),
        mask in 0u32..1024,
    ) {
        let n = c.dim();
        let b = &b[..n];
        let nodes: Vec<usize> = (0..n).filter(|i| mask & (1 << i) != 0).collect();
        let lo: Vec<f64> = nodes.iter().map(|&i| lo[i]).collect();
        let (z, r, _) = solve(&c, b, &nodes, &lo);
        let oracle = brute_force(&c.to_dense(), b, &nodes, &lo, 1e-12).unwrap().unwrap();
        let scale = 1.0 + max_abs(&z);
        for (i, (zi, oi)) in z.iter().zip(&oracle.z).enumerate() {
            prop_assert!((zi - oi).abs() <= AGREEMENT_TOL * scale, "node {i}: {zi} vs {oi}");
        }
        for (rk, ok) in r.iter().zip(&oracle.reactions) {
            prop_assert!((rk - ok.max(0.0)).abs() <= AGREEMENT_TOL * scale * 10.0);
        }
    }

    #[test]
    fn large_problems_satisfy_kkt(
        c in common::spd_tridiag(3000),
        seed in any::<u64>(),
    ) {
        let n = c.dim();
        let mut rnd = common::stream(seed);
        let b: Vec<f64> = (0..n).map(|_| 4.0 * rnd() - 2.0).collect();
        let nodes: Vec<usize> = (0..n).collect();
        let lo: Vec<f64> = (0..n).map(|_| 2.0 * rnd() - 1.0).collect();
        let (z, r, _) = solve(&c, &b, &nodes, &lo);
        prop_assert!(kkt(&c, &b, &nodes, &lo, &z, &r) <= AGREEMENT_TOL);
    }
}

/// `C = M/dt² + (½ + α/(2dt)) R` of the bar with `elements` elements on [0, 1].
fn step_matrix(elements: usize, dt_over_dx: f64, alpha: f64) -> SymTridiag {
    let nodes = elements + 1;
    let dx = 1.0 / elements as f64;
    let dt = dt_over_dx * dx;
    let m = mass(MatrixVariant::Consistent, nodes, dx);
    let r = stiffness(MatrixVariant::Consistent, nodes, dx);
    SymTridiag::combine(1.0 / (dt * dt), &m, 0.5 + alpha / (2.0 * dt), &r)
}

/// A bar pushed down onto a flat obstacle under every node: with `b` from a uniform load the
/// whole bar ends in contact; the contact boundary must sweep the whole mesh.
#[test]
fn stiff_steps_with_contact_along_the_whole_length() {
    for (elements, ratio) in [(1000, 10.0), (1000, 1e4), (10_000, 10.0)] {
        let c = step_matrix(elements, ratio, 0.1);
        let n = c.dim();
        let b: Vec<f64> = (0..n).map(|i| -1.0 - (i as f64 / n as f64)).collect();
        let nodes: Vec<usize> = (0..n).collect();
        let lo = vec![-1e-3; n];
        let (z, r, iterations) = solve(&c, &b, &nodes, &lo);
        assert!(
            kkt(&c, &b, &nodes, &lo, &z, &r) <= AGREEMENT_TOL,
            "{elements} elements, dt/dx {ratio}"
        );
        println!(
            "contact along the whole length, J+1 = {elements}, dt/dx = {ratio}: {iterations} iterations"
        );
    }
}

/// Small dt/dx makes C's off-diagonals positive (not an M-matrix), where plain primal-dual
/// active sets can cycle; a wavy load and an obstacle at varying heights create many contact
/// islands.
#[test]
fn non_m_matrix_and_many_contact_islands() {
    for ratio in [1e-3, 0.1, 1.0] {
        let c = step_matrix(2000, ratio, 0.0);
        assert!(
            c.off[0] > 0.0 || ratio >= 1.0,
            "small dt/dx gives positive off-diagonals"
        );
        let n = c.dim();
        let b: Vec<f64> = (0..n)
            .map(|i| (i as f64 * 0.37).sin() * c.diag[i])
            .collect();
        let nodes: Vec<usize> = (0..n).collect();
        let lo: Vec<f64> = (0..n).map(|i| 0.5 * (i as f64 * 0.05).cos()).collect();
        let (z, r, _) = solve(&c, &b, &nodes, &lo);
        assert!(
            kkt(&c, &b, &nodes, &lo, &z, &r) <= AGREEMENT_TOL,
            "dt/dx {ratio}"
        );
    }
}

/// Near-ties: the unconstrained solution touches the obstacle to within round-off at many nodes.
#[test]
fn near_ties_terminate_deterministically() {
    let c = step_matrix(500, 1.0, 0.1);
    let n = c.dim();
    let z_free: Vec<f64> = (0..n).map(|i| (i as f64 * 0.1).sin()).collect();
    let b = c.mul(&z_free);
    let nodes: Vec<usize> = (0..n).collect();
    // Bounds equal to the free solution up to ±1 ulp: every index is a tie.
    let lo: Vec<f64> = z_free
        .iter()
        .enumerate()
        .map(|(i, v)| {
            if i % 2 == 0 {
                v.next_up()
            } else {
                v.next_down()
            }
        })
        .collect();
    let first = solve(&c, &b, &nodes, &lo);
    assert!(kkt(&c, &b, &nodes, &lo, &first.0, &first.1) <= AGREEMENT_TOL);
    let second = solve(&c, &b, &nodes, &lo);
    assert!(
        first.0 == second.0 && first.1 == second.1,
        "same input, same bits"
    );
}

#[test]
fn the_oracle_refuses_more_than_16_bounds() {
    let c = step_matrix(20, 1.0, 0.0);
    let n = c.dim();
    let nodes: Vec<usize> = (0..17).collect();
    let e = brute_force(&c.to_dense(), &vec![0.0; n], &nodes, &[0.0; 17], 1e-12).unwrap_err();
    assert_eq!(e.0, 17);
}
