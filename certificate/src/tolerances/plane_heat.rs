//! The plane body's temperature's tolerances (`tests/plane_heat.rs`), each beside the
//! measurement of what it guards ([`crate::plane_heat`]).

use super::Measured;
use crate::plane_heat::{belt, exchange_decay, heat_balance, sudden_edge_excursion, uniform_end};
use viscobar::scheme::RunError;

/// The heat-content balance per step, relative to the largest heat content of the run: the
/// content and the step's heat are sums of a few hundred products, the solve backward stable.
pub const HEAT_BALANCE_TOL: f64 = 1e-13;
/// A uniform or a linear steady temperature, relative to its size: the round-off of a steady
/// state the decaying modes have reached (their slowest factor is below 1e-20 at the end).
pub const STEADY_TEMPERATURE_TOL: f64 = 1e-10;
/// The slowest decay rate of an exchanging floor, relative to the analytic one: the Q1 and
/// Crank–Nicolson errors of the slowest mode at 32 cells over the height and `Δt = 0.005`.
pub const PLANE_DECAY_RATE_TOL: f64 = 2e-3;
/// The excursion of θ outside the data's range [0, 1]: round-off of the steps' sums (a
/// Crank–Nicolson start leaves an overshoot of order 1e-3).
pub const PLANE_MAX_PRINCIPLE_TOL: f64 = 1e-12;

/// The registry's entries for the plane body's temperature.
pub fn plane_heat_measured() -> Result<Vec<Measured>, RunError> {
    let balance = heat_balance(1.0)?.0.max(heat_balance(0.25)?.0);
    let [_, flux, mean, _] = belt()?;
    let steady = uniform_end()?.0.max(flux).max(mean);
    Ok(vec![
        Measured {
            name: "HEAT_BALANCE_TOL".into(),
            used_in: "tests/plane_heat.rs",
            tolerance: HEAT_BALANCE_TOL,
            worst: balance,
            note: "every step of the frictional launch, η = 1 and η = ¼",
        },
        Measured {
            name: "STEADY_TEMPERATURE_TOL".into(),
            used_in: "tests/plane_heat.rs",
            tolerance: STEADY_TEMPERATURE_TOL,
            worst: steady,
            note: "the launch's uniform end temperature, the belt's flux and edge-mean temperature",
        },
        Measured {
            name: "PLANE_DECAY_RATE_TOL".into(),
            used_in: "tests/plane_heat.rs",
            tolerance: PLANE_DECAY_RATE_TOL,
            worst: exchange_decay()?.0,
            note: "the exchanging floor's heat content between t = 0.6 and t = 1",
        },
        Measured {
            name: "PLANE_MAX_PRINCIPLE_TOL".into(),
            used_in: "tests/plane_heat.rs",
            tolerance: PLANE_MAX_PRINCIPLE_TOL,
            worst: sudden_edge_excursion()?,
            note: "every node and step at κΔt/h² = 0.5, 5, 100; no excursion measured",
        },
    ])
}
