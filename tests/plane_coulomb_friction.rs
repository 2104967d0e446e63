//! Coulomb friction on the plane body's edges: `μ = 0` bit for bit against the frictionless
//! runs, the rigid-limit closed forms (self tested) approached as the block stiffens, and the
//! frictional drop's convergence against a finer exact run (the identity with `D_f`, the
//! momentum balance, the audit and OSQP's Tresca fixed point are the solver checker's,
//! tests/solvers.rs). Run in release; the full convergence study is `#[ignore]`d (README,
//! "Friction").

use viscobar_certificate::friction::rigid::*;
use viscobar_certificate::friction::*;

// The tolerances of this file: in the registry (viscobar_certificate::tolerances), which measures
// their worst values (`viscobar-certificate verify --tolerances`).
use viscobar_certificate::tolerances::{
    RIGID_LIMIT_BOUND, RIGID_SELF_TEST_TOL, STICK_VELOCITY_BOUND, rigid_limit_worst,
};

#[test]
fn zero_friction_reproduces_every_frictionless_contact_run_bit_for_bit() {
    let cases = mu_zero_cases().unwrap();
    // The three frictionless contact scenes and the three friction scenes.
    assert!(cases.len() >= 6, "{cases:?}");
    for c in &cases {
        assert!(c.identical, "{}: friction = 0 changed the run", c.name);
    }
}

/// The observed rate `log10(e(1e3) / e(1e5)) / 2` of the rigid-limit errors against the
/// stiffness: measured 0.95 to 0.97 (VERIFICATION.md, "Plane friction"; elastic transients of
/// order 1/κ); the band is those ± 0.2.
const RIGID_RATE_BAND: (f64, f64) = (0.75, 1.17);
/// The launch's stop time from `κ = 100` up: friction acts from `t = 0`, so the mean velocity
/// follows the rigid law exactly (the momentum balance) but for `μ` times the vertical mean
/// velocity, decayed by the stop; measured at most 5.5e-10, the round-off of `C` at `κ = 1e5`
/// (whose identity residual is of the same size), the bound 20 times that.
const STOP_TIME_BOUND: f64 = 1e-8;

#[test]
fn the_rigid_limit_closed_forms_are_approached_as_the_block_stiffens() {
    let self_test = closed_form_self_test().unwrap();
    assert!(
        self_test.iter().all(|d| *d <= RIGID_SELF_TEST_TOL),
        "{self_test:?}"
    );
    let rows = rigid_table().unwrap();
    for r in &rows {
        eprintln!("{r:?}");
    }
    let (limit, stick) = rigid_limit_worst(&rows);
    assert!(limit <= RIGID_LIMIT_BOUND, "{limit:e}");
    assert!(stick <= STICK_VELOCITY_BOUND, "{stick:e}");
    for r in rows.iter().filter(|r| r.stiffness >= 100.0) {
        assert!(r.stop_error <= STOP_TIME_BOUND, "{r:?}");
    }
    let errors: [fn(&RigidRow) -> f64; 2] = [|r| r.slope_error, |r| r.distance_error];
    for e in errors {
        // Every stiffening brings the block closer to the rigid motion.
        assert!(rows.windows(2).all(|w| e(&w[1]) < e(&w[0])), "{rows:?}");
        let at = |k: f64| e(rows.iter().find(|r| r.stiffness == k).unwrap());
        let rate = (at(1e3) / at(1e5)).log10() / 2.0;
        assert!(
            (RIGID_RATE_BAND.0..=RIGID_RATE_BAND.1).contains(&rate),
            "rate {rate}"
        );
    }
}

/// Observed order of the frictional drop's max nodal error, levels 0 and 1 against level 2:
/// measured 1.72 (VERIFICATION.md gives the study against level 3 too, 1.10 and 1.37: the
/// coarse reference overstates the order); the band is the measured value ± 0.25.
const FRICTION_ORDER_BAND: (f64, f64) = (1.47, 1.97);

#[test]
fn the_frictional_drop_converges_against_a_finer_exact_run() {
    let levels = convergence().unwrap();
    let orders = viscobar_certificate::plane::contact::orders(&levels);
    assert_eq!(orders.len(), 1);
    for p in orders {
        assert!(
            (FRICTION_ORDER_BAND.0..=FRICTION_ORDER_BAND.1).contains(&p),
            "order {p}: {levels:?}"
        );
    }
}

/// The full study of VERIFICATION.md (levels 0, 1, 2 against level 3; about 25 s): orders
/// measured 1.10 and 1.37; the band is those ± 0.3.
const FRICTION_ORDER_FULL_BAND: (f64, f64) = (0.8, 1.67);

#[test]
#[ignore = "about 25 s: cargo test --release --test plane_coulomb_friction -- --ignored"]
fn the_frictional_drop_converges_on_three_levels_against_level_3() {
    let levels = full_convergence().unwrap();
    for p in viscobar_certificate::plane::contact::orders(&levels) {
        assert!(
            (FRICTION_ORDER_FULL_BAND.0..=FRICTION_ORDER_FULL_BAND.1).contains(&p),
            "order {p}: {levels:?}"
        );
    }
}
