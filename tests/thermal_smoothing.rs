//! Rannacher's start of the heat step (`docs/thermal.md`, "Non-smooth data: Rannacher's
//! start"): a sudden end temperature, at `t = 0` or midway, keeps `θ` within the data's range
//! (a discrete maximum principle, up to a measured bound) at every step; the implicit steps'
//! numerical dissipation is its own term of the exact identity, `>= 0`, and 0 on the
//! Crank–Nicolson steps; an exchange end's temperature decays at the analytic slowest rate.

use viscobar::scene;
use viscobar_certificate::thermal::smoothing::{
    SWITCHED_DIFFUSIVITIES, exchange_decay_rate, excursions, initial_jump_monotonicity,
    switched_end,
};
use viscobar_certificate::tolerances::{BAR_MONOTONE_TOL, DECAY_RATE_TOL, MAX_PRINCIPLE_TOL};

/// `heated-expansion` at every step (its end raised from 0 to 1 at `t = 0`, `κΔt/Δx² = 100`)
/// stays within `[0, 1]`; so does a bar without coupling whose end temperature is switched on
/// at `t = 0` and off again at `t = 0.5` (a jump within a step, recognised there), over a range
/// of `κΔt/Δx²`. Every implicit step's smoothing term is `>= 0`, every Crank–Nicolson step's 0.
#[test]
fn a_sudden_end_temperature_keeps_theta_within_the_datas_range() {
    let (_, expansion) = scene::load("heated-expansion", &[]).unwrap();
    let e = excursions(&expansion).unwrap();
    eprintln!("heated-expansion: {e:?}");
    assert!(e.consistent);
    assert!(e.above <= MAX_PRINCIPLE_TOL && e.below <= MAX_PRINCIPLE_TOL);
    // The start-up and the next two steps (records 1, 2, 3) are implicit, and no other.
    assert_eq!(e.implicit, vec![2, 3]);
    for diffusivity in SWITCHED_DIFFUSIVITIES {
        let e = excursions(&switched_end(diffusivity).unwrap()).unwrap();
        eprintln!("κ = {diffusivity}: {e:?}");
        assert!(e.consistent, "κ = {diffusivity}");
        assert!(
            e.above <= MAX_PRINCIPLE_TOL && e.below <= MAX_PRINCIPLE_TOL,
            "κ = {diffusivity}: above {:e}, below {:e}",
            e.above,
            e.below
        );
        // The jump at t = 0.5 = t_{100}: within the step from t_{99.5} to t_{100.5}, step 100
        // (record 101), and the next.
        assert_eq!(e.implicit, vec![2, 3, 101, 102], "κ = {diffusivity}");
    }
}

/// A bar at rest on its obstacle (gap 0: in contact throughout), at temperature 1, the
/// obstacle at 0, exchanging through `h = 8` (`κ = 2`, `κΔt/Δx² = 100`): the largest `|θ|`
/// decays between `t = 4` and `t = 5` at the analytic slowest rate.
#[test]
fn an_exchange_end_decays_at_the_slowest_rate() {
    let (rate, exact) = exchange_decay_rate().unwrap();
    eprintln!("measured decay rate {rate}, analytic {exact}");
    assert!(
        (rate - exact).abs() <= DECAY_RATE_TOL * exact,
        "rate {rate} against {exact}"
    );
}

/// An initial temperature that jumps inside an element is non-smooth data at `t = 0`: the
/// start-up and the next two steps are implicit, and θ stays nondecreasing in `x` at every
/// step, as the exact solution does (a Crank–Nicolson start rings).
#[test]
fn an_initial_jump_starts_implicitly_and_keeps_theta_monotone() {
    let (decrease, implicit) = initial_jump_monotonicity().unwrap();
    eprintln!("largest decrease {decrease:e}, implicit steps {implicit:?}");
    assert_eq!(implicit, vec![2, 3]);
    assert!(decrease <= BAR_MONOTONE_TOL, "{decrease:e}");
}
