//! The exact step solver against KKT and against the dense brute-force oracle, on random
//! symmetric positive definite tridiagonal problems with zero, one or two bounds.

mod common;
// Defined beside its measurement in the tolerance registry (`viscobar-certificate verify
// --tolerances`).
use viscobar_certificate::tolerances::{TIE_TOL, exact_tie, oracle_agreement};

use proptest::prelude::*;
use viscobar::internals::linalg::tridiag::SymTridiag;
use viscobar::internals::step::end_enumeration::EndEnumeration;
use viscobar::step::StepSolver;

/// KKT residuals of `(z, r)` against their per-case round-off bound (`kkt_ratio`) and its distance
/// to the dense brute-force oracle against the a-posteriori bound of both answers
/// (`oracle_agreement`, measured by `viscobar-certificate verify --tolerances` on a seeded sample
/// of this distribution).
fn check_against_oracle(
    c: &SymTridiag,
    b: &[f64],
    nodes: &[usize],
    lower: &[f64],
    z: &[f64],
    r: &[f64],
) -> Result<(), TestCaseError> {
    let ratio = oracle_agreement(c, b, nodes, lower, z, r);
    prop_assert!(
        ratio <= 1.0,
        "distance to the oracle over its bound: {ratio:e}"
    );
    let kkt = common::kkt_ratio(c, b, nodes, lower, z, r);
    prop_assert!(kkt <= 1.0, "KKT residual over its round-off bound: {kkt:e}");
    Ok(())
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(2000))]

    /// Two problems in a row on one solver, the second a rescaled first (`s b`, bounds moved
    /// by `t`): the first is enumerated, the second usually answered by the warm start on the
    /// first's active set, or enumerated after a miss. Both must meet KKT and match the oracle.
    #[test]
    fn exact_solver_satisfies_kkt_and_matches_brute_force(
        c in common::spd_tridiag(23),
        seed_b in prop::collection::vec(-5.0f64..5.0, 24),
        lo in prop::collection::vec(-2.0f64..2.0, 2),
        which in 0usize..4,
        s in 0.5f64..1.5,
        t in -0.2f64..0.2,
    ) {
        let n = c.dim();
        let b = &seed_b[..n];
        let nodes: Vec<usize> = match which {
            0 => vec![],
            1 => vec![0],
            2 => vec![n - 1],
            _ => vec![0, n - 1],
        };
        let lower = &lo[..nodes.len()];
        let mut solver = EndEnumeration::new(&c, &nodes).unwrap();
        let mut z = vec![0.0; n];
        let mut r = vec![0.0; nodes.len()];
        solver.solve(b, lower, &mut z, &mut r).unwrap();
        check_against_oracle(&c, b, &nodes, lower, &z, &r)?;

        let b2: Vec<f64> = b.iter().map(|v| s * v).collect();
        let lower2: Vec<f64> = lower.iter().map(|v| v + t).collect();
        solver.solve(&b2, &lower2, &mut z, &mut r).unwrap();
        check_against_oracle(&c, &b2, &nodes, &lower2, &z, &r)?;
    }
}

/// The proptest above reaches the warm start: over a fixed sample of its distribution, most
/// second problems with an active bound are answered warm.
#[test]
fn the_warm_start_is_exercised_by_the_random_problems() {
    use proptest::strategy::ValueTree;
    use proptest::test_runner::{Config, RngAlgorithm, TestRng, TestRunner};
    let mut runner = TestRunner::new_with_rng(
        Config::default(),
        TestRng::from_seed(RngAlgorithm::ChaCha, &[7; 32]),
    );
    let (mut warm, mut active) = (0, 0);
    for _ in 0..500 {
        let c = common::spd_tridiag(23)
            .new_tree(&mut runner)
            .unwrap()
            .current();
        let n = c.dim();
        let b: Vec<f64> = (0..n).map(|i| ((i * 7 + n) as f64).sin() * 5.0).collect();
        let nodes = [0, n - 1];
        let (mut z, mut r) = (vec![0.0; n], vec![0.0; 2]);
        let mut solver = EndEnumeration::new(&c, &nodes).unwrap();
        solver.solve(&b, &[0.5, 0.5], &mut z, &mut r).unwrap();
        if r.iter().any(|v| *v > 0.0) {
            active += 1;
            let b2: Vec<f64> = b.iter().map(|v| 1.1 * v).collect();
            solver.solve(&b2, &[0.55, 0.45], &mut z, &mut r).unwrap();
            warm += solver.warm_steps();
        }
    }
    assert!(
        active >= 100 && 2 * warm >= active,
        "warm {warm} of {active}"
    );
}

/// A tie: the unconstrained minimiser sits exactly on both bounds, so in exact arithmetic every
/// active set gives the same point with zero reactions, and in floating point the candidates
/// differ by round-off. The solver must return that point, reactions zero to round-off and not
/// negative, and the same bits on every call (the registry's measurement, `exact_tie`).
#[test]
fn ties_resolve_to_the_unconstrained_point_deterministically() {
    let (worst, bounds_and_signs, same_bits) = exact_tie().unwrap();
    assert!(worst <= TIE_TOL, "worst |z − 1|, r: {worst:e}");
    assert!(
        bounds_and_signs,
        "bounds hold exactly and reactions are not negative"
    );
    assert!(same_bits, "same input, same bits");
}
