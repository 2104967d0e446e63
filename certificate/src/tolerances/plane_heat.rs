//! The plane body's temperature's tolerances (`tests/plane_heat.rs`), each beside the
//! measurement of what it guards ([`crate::plane_heat`]).

use super::Measured;
use crate::plane_heat::{
    belt, brake_heat_sums, coupled_strip_against_bar, exchange_decay, heat_balance,
    initial_jump_monotonicity, sudden_edge_excursion, uniform_end,
};
use viscobar::scheme::RunError;

/// The heat-content balance per step, relative to the largest heat content of the run: the
/// content and the step's heat are sums of a few hundred products, the solve backward stable.
pub const HEAT_BALANCE_TOL: f64 = 1e-13;
/// A uniform or a linear steady temperature, relative to its size: a few hundred ulps, the
/// round-off of a steady state the decaying modes have reached (their slowest factor is below
/// 1e-20 at the end; the start-up's heat left out moves the launch's by 3e-3).
pub const STEADY_TEMPERATURE_TOL: f64 = 1e-13;
/// The slowest decay rate of an exchanging floor, relative to the analytic one: the Q1 and
/// Crank–Nicolson errors of the slowest mode at 32 cells over the height and `Δt = 0.005`.
pub const PLANE_DECAY_RATE_TOL: f64 = 2e-3;
/// The excursion of θ outside the data's range [0, 1]: round-off of the steps' sums (a
/// Crank–Nicolson start leaves an overshoot of order 1e-3).
pub const PLANE_MAX_PRINCIPLE_TOL: f64 = 1e-12;

/// The largest decrease of θ along `x` on the plane after an initial jump (whose exact solution
/// stays nondecreasing): round-off of the steps' sums (none measured); a Crank–Nicolson start
/// leaves a ringing decrease of order 1e-3.
pub const PLANE_MONOTONE_TOL: f64 = 1e-12;
/// The same on the bar (100 elements, `κΔt/Δx² = 100`): the two implicit steps after the
/// start-up leave the stiff modes' remainder, measured 2.0e-9, the bound five times that; a
/// Crank–Nicolson start leaves a decrease of 0.78.
pub const BAR_MONOTONE_TOL: f64 = 1e-8;

/// The brake's heat sums against each other, relative to the largest frictional heating: sums
/// of a few hundred steps' heat (each `η d_j` and `(1 − η) d_j` of one `d_j`, the content a
/// backward-stable solve's).
pub const SUM_TOL: f64 = 1e-13;

/// The coupled strip against the thermal bar, relative to each field's largest value: two
/// independent solvers of the same equations (the bar's block-tridiagonal `LDLᵀ` and end
/// enumeration, the plane's sparse quasi-definite `LDLᵀ` and condensed LCP), whose round-off
/// differs at each of the 150 steps.
pub const COUPLED_STRIP_TOL: f64 = 1e-12;

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
        Measured {
            name: "PLANE_MONOTONE_TOL".into(),
            used_in: "tests/plane_heat.rs",
            tolerance: PLANE_MONOTONE_TOL,
            worst: initial_jump_monotonicity()?,
            note: "an initial jump inside a cell, κΔt/h² = 100, every row and step; no decrease \
                   measured",
        },
        Measured {
            name: "SUM_TOL".into(),
            used_in: "tests/plane_heat_snapshot.rs",
            tolerance: SUM_TOL,
            worst: {
                let (share, excess) = brake_heat_sums()?;
                share.max(excess)
            },
            note: "plane-brake, every step: the belt's heat against the body's share, and the \
                   heat content's excess over the frictional heating",
        },
        Measured {
            name: "COUPLED_STRIP_TOL".into(),
            used_in: "tests/plane_heat_coupled.rs",
            tolerance: COUPLED_STRIP_TOL,
            worst: {
                let (u, theta, _) = coupled_strip_against_bar()?;
                u.max(theta)
            },
            note: "u and θ at every node and step of the heated strip against the thermal bar",
        },
        Measured {
            name: "BAR_MONOTONE_TOL".into(),
            used_in: "tests/thermal_smoothing.rs",
            tolerance: BAR_MONOTONE_TOL,
            worst: crate::thermal::smoothing::initial_jump_monotonicity()?.0,
            note: "an initial jump inside an element, κΔt/Δx² = 100, every step",
        },
    ])
}
