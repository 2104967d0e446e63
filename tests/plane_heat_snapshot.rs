//! Snapshot regression of `plane-brake` (a brake pad heating up on a moving belt): its heat
//! balance and bottom temperature at 11 steps (`n = 1`, the start-up step, and `N/10, …, N`),
//! rounded, in the reviewed YAML file `snapshots/plane/plane-brake.snap` (never raw fields). A
//! change that moves the brake's numbers fails this test; the README ("Snapshots") says how to
//! review and accept it. Beside the snapshot, the test checks what the numbers must satisfy
//! whatever their values: the obstacle's share of the heat is `(1 − η)/η` of the body's, and
//! the body holds no more heat than friction has put in (the top lets heat out, never in).
//!
//! Rounding: each quantity to [`SIGNIFICANT_DIGITS`] digits of its largest magnitude over the
//! run, as `tests/friction_snapshot.rs`.

use insta::with_settings;
use serde::Serialize;
use viscobar::Body;
use viscobar::plane::{PlaneBody, PlaneSimulation};
use viscobar_certificate::plane::contact::plane_scene;
use viscobar_certificate::tolerances::SUM_TOL;

mod common;

/// Significant digits kept, relative to the largest magnitude of each quantity.
const SIGNIFICANT_DIGITS: i32 = 7;
/// Rows of the snapshot (10 intervals).
const T_POINTS: usize = 11;

/// [`common::round_to_digits`] with this file's [`SIGNIFICANT_DIGITS`].
fn round_sig(x: f64, scale: f64) -> f64 {
    common::round_to_digits(x, scale, SIGNIFICANT_DIGITS)
}

#[derive(Serialize)]
struct Row {
    step: usize,
    t: f64,
    /// `1ᵀ M θ`.
    heat_content: f64,
    /// `Σ η d_j` and `Σ (1 − η) d_j` up to this step (the start-up's included).
    frictional_heating: f64,
    heat_to_obstacle: f64,
    /// The bottom edge's mean (trapezoidal) and largest temperature.
    bottom_mean_theta: f64,
    bottom_max_theta: f64,
    /// Frictional nodes in contact that stick, and that slip.
    stick: usize,
    slip: usize,
    /// `Σ r_T`.
    tangential_force: f64,
}

#[test]
fn the_brake_matches_its_reviewed_snapshot() {
    let name = "plane-brake";
    let scene = plane_scene(name, &[]).unwrap();
    let heat = scene.heat.as_ref().expect("a temperature");
    let eta = heat
        .bottom
        .frictional_heating
        .expect("the bottom's share η");
    assert!(eta < 1.0, "some heat goes to the belt");
    let steps = scene.steps();
    let width = scene.plane.width;
    let mut sim = PlaneSimulation::new(&scene).unwrap();
    let mut rows = Vec::new();
    let mut record = sim.first_record();
    let (mut heating, mut to_obstacle) = (0.0, 0.0);
    for n in 1..=steps {
        if n > 1 {
            record = sim.step().unwrap();
        }
        let h = record.heat.expect("a temperature");
        heating += h.frictional_heating;
        to_obstacle += h.obstacle_heating;
        if n > 1 && !(n * (T_POINTS - 1)).is_multiple_of(steps) {
            continue;
        }
        let body: &PlaneBody = sim.body();
        let [nx, _] = body.lattice();
        let hx = width / (nx - 1) as f64;
        let theta = |i: usize| body.temperature(sim.displacement(), i).unwrap();
        let (mut mean, mut max) = (0.0, f64::NEG_INFINITY);
        for i in 0..nx {
            let weight = if i == 0 || i == nx - 1 { hx / 2.0 } else { hx };
            mean += weight * theta(i) / width;
            max = max.max(theta(i));
        }
        rows.push(Row {
            step: n,
            t: n as f64 * scene.time.step,
            heat_content: h.heat_content,
            frictional_heating: heating,
            heat_to_obstacle: to_obstacle,
            bottom_mean_theta: mean,
            bottom_max_theta: max,
            stick: record.stick_nodes,
            slip: record.slip_nodes,
            tangential_force: sim.tangential_reactions().iter().sum::<f64>() + 0.0,
        });
    }
    let scale = |f: &dyn Fn(&Row) -> f64| rows.iter().map(|r| f(r).abs()).fold(0.0, f64::max);
    let sq = scale(&|r| r.frictional_heating);
    for r in &rows {
        let share = (r.heat_to_obstacle - (1.0 - eta) / eta * r.frictional_heating).abs();
        assert!(share <= SUM_TOL * sq, "step {}: {share:e}", r.step);
        assert!(
            r.heat_content <= r.frictional_heating + SUM_TOL * sq,
            "step {}: more heat than friction put in",
            r.step
        );
    }
    let (sc, so, st) = (
        scale(&|r| r.heat_content),
        scale(&|r| r.heat_to_obstacle),
        scale(&|r| r.tangential_force),
    );
    let stheta = scale(&|r| r.bottom_max_theta.max(r.bottom_mean_theta.abs()));
    for r in &mut rows {
        r.t = round_sig(r.t, 1.0);
        r.heat_content = round_sig(r.heat_content, sc);
        r.frictional_heating = round_sig(r.frictional_heating, sq);
        r.heat_to_obstacle = round_sig(r.heat_to_obstacle, so);
        r.bottom_mean_theta = round_sig(r.bottom_mean_theta, stheta);
        r.bottom_max_theta = round_sig(r.bottom_max_theta, stheta);
        r.tangential_force = round_sig(r.tangential_force, st);
    }
    assert_eq!(rows.len(), T_POINTS);
    with_settings!({snapshot_path => "../snapshots/plane", prepend_module_to_snapshot => false}, {
        insta::assert_yaml_snapshot!(name, &rows);
    });
}
