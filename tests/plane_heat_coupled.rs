//! The plane body with a coupled temperature (`γ > 0`): the manufactured solution of the coupled
//! problem converges at order 2 in `u` and `θ`; a frictional launch solved by Lemke's method
//! through the coupled system keeps the energy identity to round-off at every step, with the
//! coupling acting on the mechanics; an exchanging floor switches the step's coupled matrix
//! with its contact, and keeps the identity.

use viscobar::{Body, StepRecord};
use viscobar_certificate::plane_heat::{self, coupled_launch, coupled_manufactured_errors, orders};
use viscobar_certificate::tolerances::COUPLED_STRIP_TOL;

/// The observed orders of the coupled manufactured solution's nodal errors in `u` and `θ`
/// (Q1 and the centred scheme both second order; VERIFICATION.md gives the measured orders).
const COUPLED_ORDER_BAND: (f64, f64) = (1.9, 2.1);

/// Every step measured, each residual within its bound.
fn assert_identity_every_step(records: &[StepRecord]) {
    for r in &records[1..] {
        assert!(r.measured, "step {} not measured", r.step);
        assert!(
            r.identity_residual <= r.identity_bound,
            "step {}: residual {:e} over {:e}",
            r.step,
            r.identity_residual,
            r.identity_bound
        );
    }
}

#[test]
fn the_coupled_scheme_converges_at_order_two_in_u_and_theta() {
    let errors = coupled_manufactured_errors().unwrap();
    let (u, theta): (Vec<f64>, Vec<f64>) = errors.iter().copied().unzip();
    let (low, high) = COUPLED_ORDER_BAND;
    for order in orders(&u).into_iter().chain(orders(&theta)) {
        assert!(
            (low..=high).contains(&order),
            "errors {errors:?}: order {order}"
        );
    }
}

/// The launch with `γ = 0.5` (Lemke's method on the condensed coupled `S`, every answer
/// audited): the identity at every step, the coupling moves the mechanics, and the block
/// still stops.
#[test]
fn a_coupled_frictional_launch_keeps_the_identity_at_every_step() {
    let (records, sim) = plane_heat::run(&coupled_launch(0.5)).unwrap();
    assert_identity_every_step(&records);
    let (_, plain) = plane_heat::run(&coupled_launch(0.0)).unwrap();
    assert_ne!(sim.displacement(), plain.displacement());
    let last = records.last().unwrap();
    assert!(last.slip_nodes == 0, "still slipping at the end: {last:?}");
    assert!(records.iter().any(|r| r.slip_nodes > 0));
    let report = sim
        .solver_report()
        .expect("the exact solver keeps an audit");
    assert!(report.audit.steps as usize >= records.len() - 1);
}

/// A block on a floor that takes its heat while in contact, bouncing: each contact state of
/// the floor's nodes has its own coupled matrix, made when first met.
#[test]
fn an_exchanging_floor_switches_the_coupled_matrix_with_its_contact() {
    let text = r#"
[plane]
width = 1.0
height = 0.5
lambda = 2.0
mu = 1.0

[edges]
bottom = { condition = "signorini", gap = 0.002 }

[initial]
velocity = ["0", "-0.2"]

[mesh]
nx = 8
ny = 4

[time]
step = 0.005
end = 0.3

[heat]
coupling = 0.4
diffusivity = 0.5
temperature = "1"
bottom = { condition = "exchange", coefficient = 2.0, obstacle = 0 }

[output]
diagnostics_every = 1
"#;
    let scene = viscobar::PlaneScene::from_toml(text, &[]).unwrap();
    let (records, _) = plane_heat::run(&scene).unwrap();
    assert_identity_every_step(&records);
    let exchanged: Vec<f64> = records
        .iter()
        .filter_map(|r| r.heat)
        .map(|h| h.exchange)
        .collect();
    assert!(exchanged.iter().any(|&e| e > 0.0), "the floor took no heat");
    assert!(exchanged.contains(&0.0), "never out of contact");
}

/// The bar is the plane's special case with a coupled temperature too: a strip of one row of
/// cells held in `y` by its edges' obstacles runs the thermal bar (clamped, one end heated by a
/// ramp; the bar's block-tridiagonal solver against the plane's sparse `S`), step by step; `θ`
/// stays at or above 0, so the obstacles keep pressing (or touch without force).
#[test]
fn a_coupled_strip_runs_the_thermal_bar() {
    let (du, dtheta, least) = plane_heat::coupled_strip_against_bar().unwrap();
    assert!(
        least >= 0.0,
        "θ fell to {least}: the strip's edges may open"
    );
    assert!(du <= COUPLED_STRIP_TOL, "u: {du:e}");
    assert!(dtheta <= COUPLED_STRIP_TOL, "θ: {dtheta:e}");
}

/// A coupled body at rest at a uniform temperature has the stress `−γθ` on the diagonal (the
/// outputs' nodal stress, `σ_zz` included) and no shear; uncoupled, none.
#[test]
fn the_output_stress_carries_the_thermal_stress() {
    for (gamma, expected) in [(0.5, -0.75), (0.0, 0.0)] {
        let text = format!(
            "[plane]\nwidth = 1.0\nheight = 0.5\nlambda = 1.0\nmu = 1.0\n[mesh]\nnx = 4\nny = 2\n\
             [time]\nstep = 0.01\nend = 0.1\n[heat]\ncoupling = {gamma:?}\ndiffusivity = 0.1\n\
             temperature = \"1.5\"\n"
        );
        let scene = viscobar::PlaneScene::from_toml(&text, &[]).unwrap();
        let unstarted = viscobar::PlaneSimulation::prepare(&scene).unwrap();
        let state = unstarted.state();
        let stress = unstarted.body().nodal_stress(state.u, state.w).unwrap();
        for s in stress {
            assert_eq!(
                [s[0], s[1], s[2], s[3]],
                [expected, expected, 0.0, expected]
            );
        }
    }
}
