//! The thermal bar's tolerances (`tests/thermal.rs`, `tests/solvers.rs`), each beside the measurement of what it
//! guards ([`crate::thermal`]).

use super::Measured;
use crate::thermal::{closing_temperature, identity_worst, steady_deviation};
use viscobar::scheme::RunError;

/// The thermal bar's total-energy identity bound: the run's own
/// (`viscobar::scheme::certify`), measured here.
pub use viscobar::scheme::certify::THERMAL_IDENTITY_TOL;
/// Deviation from the closed-form steady state at t = 40: what is left of the transient after
/// 40 time units (measured about 1e-12; the discrete steady state is the closed form itself,
/// P1 being exact for linear u and constant θ). A Crank–Nicolson start on the sudden end
/// temperature left a ringing mode of about 1e-8 there; a wrong reaction or closing
/// temperature is off by more than 1e-3.
pub const STEADY_TOL: f64 = 1e-9;

/// The registry's entries for the thermal tolerances.
pub fn thermal_measured() -> Result<Vec<Measured>, RunError> {
    let (identity, _) = identity_worst()?;
    let tc = closing_temperature();
    let steady = steady_deviation(0.9 * tc)?.max(steady_deviation(2.0 * tc)?);
    Ok(vec![
        Measured {
            name: "THERMAL_IDENTITY_TOL".into(),
            used_in: "tests/solvers.rs",
            tolerance: THERMAL_IDENTITY_TOL,
            worst: identity,
            note: "every step of every thermal scene, with contact and exchange",
        },
        Measured {
            name: "STEADY_TOL".into(),
            used_in: "tests/thermal.rs",
            tolerance: STEADY_TOL,
            worst: steady,
            note: "the transient's remainder at t = 40, below and above the closing temperature",
        },
    ])
}
