//! OSQP against the exact enumeration on random step problems: symmetric positive definite
//! tridiagonal `C` (the generator of tests/exact_solver.rs) with one or two bounds, each solver
//! solving two problems in a row so that OSQP's per-step updates and warm start are exercised.

mod common;

use proptest::prelude::*;
use viscobar::internals::linalg::norms::max_abs;
use viscobar::internals::linalg::tridiag::SymTridiag;
use viscobar::internals::step::end_enumeration::EndEnumeration;
use viscobar::internals::step::osqp::OSQP_DEFAULT_EPS;
use viscobar::internals::step::osqp::{Osqp, OsqpSettings};
use viscobar::step::StepSolver;
use viscobar::step::audit::AUDIT_MARGIN;

/// OSQP's tolerance carried to the answer. The audit accepts a displacement-unit stationarity
/// error and a primal violation up to `t_z = AUDIT_MARGIN·eps·(1 + ‖z‖)` and a multiplier (sign
/// or complementarity) error up to `t_f = AUDIT_MARGIN·eps·(1 + s_f)`, which moves `z` by at most
/// `‖C⁻¹‖_∞ t_f`; twice the sum covers both bounds of a two-bound problem. Returns the
/// tolerances for `z` and for `r` (`r_j = (Cz − b)_j`, so `‖C‖_∞` times the first plus `t_f`).
fn tolerances(c: &SymTridiag, b: &[f64], z: &[f64], r: &[f64]) -> (f64, f64) {
    let eps = AUDIT_MARGIN * OSQP_DEFAULT_EPS;
    let s_f = max_abs(b).max(max_abs(&c.mul(z))).max(max_abs(r));
    let t_z = eps * (1.0 + max_abs(z));
    let t_f = eps * (1.0 + s_f);
    let tol_z = 2.0 * (t_z + t_f / common::MIN_MARGIN);
    let c_norm = c.inf_norm();
    (tol_z, c_norm * tol_z + t_f)
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(2000))]

    #[test]
    fn osqp_agrees_with_exact_to_its_tolerance(
        c in common::spd_tridiag(23),
        seed_b in prop::collection::vec(-5.0f64..5.0, 48),
        lo in prop::collection::vec(-2.0f64..2.0, 4),
        which in 0usize..3,
    ) {
        let n = c.dim();
        let nodes: Vec<usize> = match which {
            0 => vec![0],
            1 => vec![n - 1],
            _ => vec![0, n - 1],
        };
        let k = nodes.len();
        let mut exact = EndEnumeration::new(&c, &nodes).unwrap();
        let mut osqp = Osqp::new(&c, &nodes, OsqpSettings::default()).unwrap();
        // Two problems in a row: the second starts from the first's answer.
        for (b, lower) in [(&seed_b[..n], &lo[..k]), (&seed_b[24..24 + n], &lo[2..2 + k])] {
            let (mut ze, mut re) = (vec![0.0; n], vec![0.0; k]);
            exact.solve(b, lower, &mut ze, &mut re).unwrap();
            let (mut zo, mut ro) = (vec![0.0; n], vec![0.0; k]);
            osqp.solve(b, lower, &mut zo, &mut ro).unwrap();
            let (tol_z, tol_r) = tolerances(&c, b, &ze, &re);
            for i in 0..n {
                prop_assert!((zo[i] - ze[i]).abs() <= tol_z,
                    "node {i}: osqp {} exact {} (tol {tol_z:e})", zo[i], ze[i]);
            }
            for j in 0..k {
                prop_assert!((ro[j] - re[j]).abs() <= tol_r,
                    "reaction {j}: osqp {} exact {} (tol {tol_r:e})", ro[j], re[j]);
            }
        }
        prop_assert_eq!(osqp.report().unwrap().audit.steps, 2);
    }
}
