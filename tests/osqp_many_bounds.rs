//! OSQP against the exact many-bound solver (block principal pivoting) on random larger step
//! problems with many bounds: up to 400 unknowns, a bound on a random subset of the nodes or on
//! every node, two problems in a row so that OSQP's warm start and per-step updates are used.
//! The agreement is checked against an a-posteriori error bound that is a theorem, not a tuned
//! tolerance (Chen & Xiang, Math. Program. 106, 2006: `‖z − z'‖∞ <= κ_H (‖ν(z)‖∞ + ‖ν(z')‖∞)`
//! for the natural residuals `ν`; derivation: `docs/osqp-agreement-bound.md`), and the bound
//! must itself be small: below what OSQP's audited residuals allow ([`a_priori_tolerance`]).

mod common;

use proptest::prelude::*;
use viscobar::internals::linalg::kernels::ldlt::Ldlt;
use viscobar::internals::linalg::norms::{max_abs, max_distance};
use viscobar::internals::linalg::tridiag::SymTridiag;
use viscobar::internals::step::block_pivot::BlockPivoting;
use viscobar::internals::step::osqp::OSQP_DEFAULT_EPS;
use viscobar::internals::step::osqp::{Osqp, OsqpSettings};
use viscobar::step::StepSolver;
use viscobar::step::audit::{AUDIT_MARGIN, ROUNDOFF_ULPS};

/// Largest problem drawn: large enough for many simultaneous contact changes, small enough that
/// 200 cases of two OSQP solves each stay within seconds.
const MAX_UNKNOWNS: usize = 400;

/// Round-off in a recomputed `(Cz − b)_i`: the audit's floor, [`ROUNDOFF_ULPS`] ulps of the
/// magnitude of the terms.
fn residual_floor(c: &SymTridiag, b: &[f64], z: &[f64]) -> f64 {
    let c_norm = c.inf_norm();
    ROUNDOFF_ULPS * f64::EPSILON * (c_norm * max_abs(z) + max_abs(b))
}

/// `‖ν(z)‖∞` of the module comment plus the round-off of its evaluation.
fn natural_residual(c: &SymTridiag, b: &[f64], nodes: &[usize], lo: &[f64], z: &[f64]) -> f64 {
    let mut w = c.mul(z);
    for (wi, bi) in w.iter_mut().zip(b) {
        *wi -= bi;
    }
    let mut gap_floor = 0.0f64;
    for (&i, l) in nodes.iter().zip(lo) {
        w[i] = (z[i] - l).min(w[i]);
        gap_floor = gap_floor.max(z[i].abs() + l.abs());
    }
    max_abs(&w) + residual_floor(c, b, z) + ROUNDOFF_ULPS * f64::EPSILON * gap_floor
}

/// `κ_H = ‖C̃⁻¹ max(Λ, I)‖∞`: `C̃⁻¹ >= 0` (an M-matrix), so the norm is the largest entry of
/// `C̃⁻¹ max(Λ, I) 1`.
fn chen_xiang_constant(c: &SymTridiag) -> f64 {
    let comparison = SymTridiag::new(c.diag.clone(), c.off.iter().map(|v| -v.abs()).collect());
    let mut x: Vec<f64> = c.diag.iter().map(|d| d.max(1.0)).collect();
    Ldlt::factor(&comparison).unwrap().solve_in_place(&mut x);
    max_abs(&x)
}

/// The a-posteriori bound on `‖z − z'‖∞` of the module comment.
fn a_posteriori_bound(
    c: &SymTridiag,
    b: &[f64],
    nodes: &[usize],
    lo: &[f64],
    z: &[f64],
    z2: &[f64],
) -> f64 {
    chen_xiang_constant(c)
        * (natural_residual(c, b, nodes, lo, z) + natural_residual(c, b, nodes, lo, z2))
}

/// The bound above with OSQP's residuals at their audit caps (src/step/audit.rs with
/// `AUDIT_MARGIN·eps`: `t_f` in force, `t_z` in displacement) and the exact answer's at the
/// round-off floor. With `ρ = Cz − b − Σ r_j e_j`, `|ρ_i| <= t_f`, so `|ν_i| <= t_f` at a free
/// node; at a bound node `g = z_i − lo_j >= −t_z`, `r_j >= −t_f` and `|g r_j| <= t_z|r_j| + t_f|g|`
/// force `g <= 2t_z` or `r_j <= 2t_f`, so `|min(g, r_j + ρ_i)| <= max(2t_z, 3t_f)`.
fn a_priori_tolerance(
    c: &SymTridiag,
    b: &[f64],
    nodes: &[usize],
    lo: &[f64],
    z: &[f64],
    r: &[f64],
) -> f64 {
    let eps = AUDIT_MARGIN * OSQP_DEFAULT_EPS;
    let ulp = ROUNDOFF_ULPS * f64::EPSILON;
    let cz = c.mul(z);
    let floor = residual_floor(c, b, z) + ulp * max_abs(r);
    let t_f = eps * (1.0 + max_abs(b).max(max_abs(&cz)).max(max_abs(r))) + floor;
    let p_scale = nodes
        .iter()
        .zip(lo)
        .fold(0.0f64, |m, (&i, l)| m.max(z[i].abs()).max(l.abs()));
    let t_z = eps * (1.0 + p_scale) + ulp * p_scale;
    let exact_floor = floor + ulp * p_scale;
    chen_xiang_constant(c) * ((2.0 * t_z).max(3.0 * t_f) + 2.0 * exact_floor)
}

/// Slack on the dense check of the cited inequality: the dense inverse is computed by an LU
/// with partial pivoting on matrices of condition below about 1e3, good to ~1e-13 relative.
const DENSE_INVERSE_TOL: f64 = 1e-10;

proptest! {
    #![proptest_config(ProptestConfig::with_cases(200))]

    #[test]
    fn osqp_agrees_with_the_exact_many_bound_solver(
        c in common::spd_tridiag(MAX_UNKNOWNS),
        seed in any::<u64>(),
        every_node in any::<bool>(),
    ) {
        let n = c.dim();
        let mut rnd = common::stream(seed);
        let nodes: Vec<usize> = (0..n).filter(|_| every_node || rnd() < 0.5).collect();
        let k = nodes.len();
        let mut exact = BlockPivoting::new(&c, &nodes).unwrap();
        let mut osqp = Osqp::new(&c, &nodes, OsqpSettings::default()).unwrap();
        // Two problems in a row: the second warm-starts both solvers from the first's answer.
        for _ in 0..2 {
            // Loads and obstacle heights of comparable size: a mixed contact set.
            let b: Vec<f64> = (0..n).map(|_| 4.0 * rnd() - 2.0).collect();
            let lo: Vec<f64> = (0..k).map(|_| 2.0 * rnd() - 1.0).collect();
            let (mut ze, mut re) = (vec![0.0; n], vec![0.0; k]);
            exact.solve(&b, &lo, &mut ze, &mut re).unwrap();
            // The exact answer's KKT residual within its per-case round-off bound (the registry's
            // `kkt_ratio`, measured by `viscobar-certificate verify --tolerances` on a seeded
            // sample).
            prop_assert!(common::kkt_ratio(&c, &b, &nodes, &lo, &ze, &re) <= 1.0);
            let (mut zo, mut ro) = (vec![0.0; n], vec![0.0; k]);
            osqp.solve(&b, &lo, &mut zo, &mut ro)
                .map_err(|e| TestCaseError::fail(format!("osqp: {e}")))?;
            let distance = max_distance(&zo, &ze);
            let bound = a_posteriori_bound(&c, &b, &nodes, &lo, &zo, &ze);
            prop_assert!(distance <= bound, "‖z_osqp − z_exact‖∞ = {distance:e} > bound {bound:e}");
            let tolerance = a_priori_tolerance(&c, &b, &nodes, &lo, &zo, &ro);
            prop_assert!(bound <= tolerance, "bound {bound:e} > OSQP's tolerance {tolerance:e}");
        }
    }

    /// The cited inequality `‖(I − D + DC)⁻¹‖∞ <= ‖C̃⁻¹ max(Λ, I)‖∞`, densely, on random `d`.
    #[test]
    fn chen_xiang_bound_holds(
        c in common::spd_tridiag(8),
        d in prop::collection::vec(0.0f64..=1.0, 8),
    ) {
        let n = c.dim();
        let dense = c.to_dense();
        let a = nalgebra::DMatrix::from_fn(n, n, |i, j| {
            let identity = if i == j { 1.0 - d[i] } else { 0.0 };
            identity + d[i] * dense[(i, j)]
        });
        let inverse = a.try_inverse().unwrap();
        let norm = (0..n)
            .map(|i| (0..n).map(|j| inverse[(i, j)].abs()).sum::<f64>())
            .fold(0.0, f64::max);
        let kappa = chen_xiang_constant(&c);
        prop_assert!(norm <= kappa * (1.0 + DENSE_INVERSE_TOL), "{norm} > {kappa}");
    }
}

/// The checks can fail: a wrong active set (the node with the largest reaction lifted off the
/// obstacle, its reaction dropped, stationarity kept exact) lies far outside OSQP's tolerance.
#[test]
fn a_wrong_active_set_exceeds_the_tolerance() {
    let n = 50;
    let c = SymTridiag::new(vec![2.5; n], vec![-1.0; n - 1]);
    let b = vec![-1.0; n];
    let nodes: Vec<usize> = (0..n).collect();
    let lo = vec![-0.5; n];
    let mut exact = BlockPivoting::new(&c, &nodes).unwrap();
    let (mut z, mut r) = (vec![0.0; n], vec![0.0; n]);
    exact.solve(&b, &lo, &mut z, &mut r).unwrap();
    let j = r
        .iter()
        .enumerate()
        .fold(0, |m, (i, v)| if *v > r[m] { i } else { m });
    assert!(r[j] > 0.0, "the load must push some node onto the obstacle");
    let mut wrong_r = r.clone();
    wrong_r[j] = 0.0;
    let mut wrong_z = b.clone();
    for (&i, rj) in nodes.iter().zip(&wrong_r) {
        wrong_z[i] += rj;
    }
    Ldlt::factor(&c).unwrap().solve_in_place(&mut wrong_z);
    let distance = max_distance(&wrong_z, &z);
    let bound = a_posteriori_bound(&c, &b, &nodes, &lo, &wrong_z, &z);
    let tolerance = a_priori_tolerance(&c, &b, &nodes, &lo, &wrong_z, &wrong_r);
    assert!(
        distance <= bound,
        "the bound is a theorem: {distance:e} > {bound:e}"
    );
    assert!(
        bound > tolerance,
        "the wrong answer's bound {bound:e} must exceed OSQP's tolerance {tolerance:e}"
    );
}
