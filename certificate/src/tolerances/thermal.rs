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

/// How far `θ` may leave the data's range `[0, 1]` after a sudden end temperature: the runs
/// measure no excursion at all (0 above 1, 0 below 0, at every node and step), so the bound is
/// round-off on values of order 1. Crank–Nicolson from the start left it by 0.648
/// (`heated-expansion`, x = 0.995).
pub const MAX_PRINCIPLE_TOL: f64 = 1e-12;
/// An exchange end's measured decay rate, relative to the analytic slowest rate: the
/// discretisation errs by about `(μ Δx)²/12 + (λ Δt)²/12`, below 1e-4 here; a ringing mode left
/// by the start (Crank–Nicolson from `t = 0`) makes the decay look several times slower.
pub const DECAY_RATE_TOL: f64 = 1e-3;

/// The registry's entries for the thermal tolerances.
pub fn thermal_measured() -> Result<Vec<Measured>, RunError> {
    let (identity, _) = identity_worst()?;
    let tc = closing_temperature();
    let steady = steady_deviation(0.9 * tc)?.max(steady_deviation(2.0 * tc)?);
    let excursion = crate::thermal::smoothing::max_principle_worst()?;
    let (rate, exact) = crate::thermal::smoothing::exchange_decay_rate()?;
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
        Measured {
            name: "MAX_PRINCIPLE_TOL".into(),
            used_in: "tests/thermal_smoothing.rs",
            tolerance: MAX_PRINCIPLE_TOL,
            worst: excursion,
            note: "heated-expansion and an end switched on and off, κΔt/Δx² 0.5 to 100; no \
                   excursion measured",
        },
        Measured {
            name: "DECAY_RATE_TOL".into(),
            used_in: "tests/thermal_smoothing.rs",
            tolerance: DECAY_RATE_TOL,
            worst: (rate - exact).abs() / exact,
            note: "the exchange end's largest |θ| between t = 4 and t = 5",
        },
    ])
}
