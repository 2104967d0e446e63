//! The thermal bar with fixed end temperatures that vary in time (`docs/thermal.md`,
//! "Manufactured solution with time-varying end temperatures"): the closed form solves its
//! equations with the scene's data (finite differences), and the scheme converges to it at
//! order 2 in `u` and `θ`. A fixed end taken at another time than `t_{n+1/2}` is an `O(Δt)`
//! shift of the boundary data that the energy identity does not see; this order does.

use viscobar_certificate::thermal::boundary::{self_test, study};

/// The self-test's fourth-order differences of step 1e-2 err by about `d⁴/30` times a fifth
/// derivative (`π⁵ · 0.3 ≈ 90` for `B sin πx`; nested for `u_xxt`): about 1e-6; the scene's
/// expressions and the closed form agree to round-off. A wrong term of the derivation is
/// of order 0.1 or more.
const SELF_TEST_TOL: f64 = 1e-5;
/// Least observed order (least squares over four levels, `Δt = Δx`) of `u` and `θ`: second
/// order, less the drift of its constant at the coarse levels; an `O(Δt)` shift of the end
/// data gives about 1 (printed by `cargo test --release --test thermal_boundary --
/// --nocapture`).
const BOUNDARY_CONVERGENCE_RATE_MIN: f64 = 1.8;

#[test]
fn the_time_varying_end_temperatures_solution_solves_its_equations_with_the_scenes_data() {
    let [equations, data] = self_test().unwrap();
    eprintln!("equations {equations:e}, data {data:e}");
    assert!(equations <= SELF_TEST_TOL, "equations: {equations:e}");
    assert!(data <= SELF_TEST_TOL, "data: {data:e}");
}

#[test]
fn time_varying_end_temperatures_converge_at_order_two() {
    let (rows, pu, pt) = study().unwrap();
    eprintln!("{rows:?}: orders {pu} (u), {pt} (θ)");
    assert!(
        pu >= BOUNDARY_CONVERGENCE_RATE_MIN && pt >= BOUNDARY_CONVERGENCE_RATE_MIN,
        "observed orders {pu} (u), {pt} (θ) below {BOUNDARY_CONVERGENCE_RATE_MIN}: {rows:?}"
    );
}
