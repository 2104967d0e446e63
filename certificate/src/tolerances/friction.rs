//! The friction tolerances (`tests/plane_coulomb_friction.rs`, `tests/solvers.rs`), each beside
//! the measurement of what it guards ([`crate::friction`], [`crate::friction::rigid`]).

use super::{AGREEMENT_ULPS_PER_STEP, Measured};
use crate::friction::rigid::{RigidRow, STIFFNESSES, closed_form_self_test, rigid_table};
use crate::friction::{FrictionAgreement, osqp_agreements, scene_checks};
use viscobar::internals::step::osqp_tresca::FIXED_POINT_TOL;
use viscobar::scheme::RunError;

/// `D_f >= −tol · E^{n+1/2}`: a sticking node's central slip is the round-off of the increments,
/// so its `r_T δ` is a few ulps of the energy's terms (the plane's gap rule, 8 ε).
pub const FRICTION_DISSIPATION_TOL: f64 = 8.0 * f64::EPSILON;
/// The momentum balance along the tangent, relative to the magnitudes of its terms: sums of a
/// few hundred rounded terms whose roundings partly cancel; 64 ε.
pub const MOMENTUM_TOL: f64 = 64.0 * f64::EPSILON;
/// The closed forms against the exact integration of the rigid block: both exact, so only the
/// round-off of some thousand additions of order one separates them.
pub const RIGID_SELF_TEST_TOL: f64 = 1e-12;
/// The relative errors of the slope's acceleration, the launch's stop time and distance at the
/// stiffest block of the table (κ = 1e5): the elastic transients fall as 1/κ (measured about
/// 5e-6; twice that as the bound).
pub const RIGID_LIMIT_BOUND: f64 = 1e-5;
/// The stuck block's mean velocity over the second half of its run, relative to the
/// frictionless block's final velocity, from κ = 100 (the scene's) up: elastic creep only
/// (measured below 3e-10).
pub const STICK_VELOCITY_BOUND: f64 = 1e-9;
/// The launch's stop time from `κ = 100` up: friction acts from `t = 0`, so the mean velocity
/// follows the rigid law exactly (the momentum balance) but for `μ` times the vertical mean
/// velocity, decayed by the stop; measured at most 5.5e-10, the round-off of `C` at `κ = 1e5`
/// (whose identity residual is of the same size), the bound 20 times that.
pub const STOP_TIME_BOUND: f64 = 1e-8;
/// The resting block's step-to-step change of the floor's total reaction, relative to it, that
/// a start-up step without friction leaves: 9e-4 as first reported (1.5e-3 by this measure,
/// `period_two::PeriodTwo::reaction`, measured on the code before friction entered the start-up
/// step; the reference of [`RESTING_ALTERNATION_BOUND`], not a tolerance).
const FRICTIONLESS_START_ALTERNATION: f64 = 9e-4;
/// A hundredth of `FRICTIONLESS_START_ALTERNATION` (above): a start that leaves the period-2 mode
/// shows; friction from the start-up on leaves round-off.
pub const RESTING_ALTERNATION_BOUND: f64 = FRICTIONLESS_START_ALTERNATION / 100.0;

/// Exact against OSQP's Tresca fixed point over its a-posteriori bound: per step two
/// backward-stable solves ([`AGREEMENT_ULPS_PER_STEP`] ε) and the fixed point's stopping
/// tolerance ([`FIXED_POINT_TOL`], relative), accumulated linearly over the steps; the worst
/// of the displacement and both reactions (relative).
pub fn friction_osqp_agreement_ratio(a: &FrictionAgreement) -> f64 {
    let bound = a.steps as f64 * (AGREEMENT_ULPS_PER_STEP * f64::EPSILON + FIXED_POINT_TOL);
    a.displacement.max(a.normal).max(a.tangential) / bound
}

/// The rigid-limit errors at the stiffest block, and the stick velocities from κ = 100 up.
pub fn rigid_limit_worst(rows: &[RigidRow]) -> (f64, f64) {
    let last = rows.last().copied().unwrap_or_default();
    let limit = last
        .slope_error
        .max(last.stop_error)
        .max(last.distance_error);
    let stick = (rows.iter())
        .filter(|r| r.stiffness >= 100.0)
        .map(|r| r.stick_velocity)
        .fold(0.0, f64::max);
    (limit, stick)
}

/// The registry's rows of the friction tolerances.
pub fn friction_measured() -> Result<Vec<Measured>, RunError> {
    let err = |e: viscobar::study::converge::ConvergeError| RunError::SolverSetup {
        solver: "exact".into(),
        reason: e.to_string(),
    };
    let checks = scene_checks().map_err(err)?;
    let dissipation = (checks.iter())
        .map(|c| -c.min_dissipation_ratio)
        .fold(0.0, f64::max);
    let momentum = checks.iter().map(|c| c.momentum).fold(0.0, f64::max);
    let self_test = closed_form_self_test().map_err(err)?;
    let rows = rigid_table().map_err(err)?;
    assert_eq!(rows.len(), STIFFNESSES.len());
    let (limit, stick) = rigid_limit_worst(&rows);
    let stop = (rows.iter())
        .filter(|r| r.stiffness >= 100.0)
        .map(|r| r.stop_error)
        .fold(0.0, f64::max);
    let resting = crate::friction::period_two::resting(0.01)
        .map_err(err)?
        .reaction;
    let agreement = (osqp_agreements().map_err(err)?.iter())
        .map(friction_osqp_agreement_ratio)
        .fold(0.0, f64::max);
    let rows = [
        (
            "FRICTION_DISSIPATION_TOL",
            FRICTION_DISSIPATION_TOL,
            dissipation,
            "−min D_f / E over the friction scenes; a sticking node's r_T δ is round-off",
        ),
        (
            "MOMENTUM_TOL",
            MOMENTUM_TOL,
            momentum,
            "sums of rounded terms, relative to their magnitudes (the K terms' sum vanishes)",
        ),
        (
            "RIGID_SELF_TEST_TOL",
            RIGID_SELF_TEST_TOL,
            self_test.into_iter().fold(0.0, f64::max),
            "two exact computations of the rigid block: additions of order one only",
        ),
        (
            "RIGID_LIMIT_BOUND",
            RIGID_LIMIT_BOUND,
            limit,
            "κ = 1e5: elastic transients of order 1/κ",
        ),
        (
            "STICK_VELOCITY_BOUND",
            STICK_VELOCITY_BOUND,
            stick,
            "κ >= 100: the stuck block creeps elastically only",
        ),
        (
            "STOP_TIME_BOUND",
            STOP_TIME_BOUND,
            stop,
            "κ >= 100: the launch's stop time against the rigid block's",
        ),
        (
            "RESTING_ALTERNATION_BOUND",
            RESTING_ALTERNATION_BOUND,
            resting,
            "the resting block at Δt = 0.01; a hundredth of what a frictionless start-up leaves",
        ),
        (
            "friction OSQP |Δu|, |Δr| / (steps · (AGREEMENT_ULPS_PER_STEP ε + FIXED_POINT_TOL))",
            1.0,
            agreement,
            "per step two backward-stable solves and the fixed point's stopping tolerance, \
             accumulated linearly",
        ),
    ];
    Ok(rows
        .into_iter()
        .map(|(name, tolerance, worst, note)| Measured {
            name: name.into(),
            // The solver checker's rows; the rigid limit's are the friction tests'.
            used_in: match name {
                "RIGID_SELF_TEST_TOL"
                | "RIGID_LIMIT_BOUND"
                | "STICK_VELOCITY_BOUND"
                | "STOP_TIME_BOUND" => "tests/plane_coulomb_friction.rs",
                "RESTING_ALTERNATION_BOUND" => "tests/friction_period_two.rs",
                _ => "tests/solvers.rs",
            },
            tolerance,
            worst,
            note,
        })
        .collect())
}
