//! Snapshot regression of `plane-friction-tilted-drop` and `plane-friction-stick-slip` (a block
//! on a reciprocating belt): statistics of each run at 11 steps (`n = 1`, the start-up step,
//! and `N/10, …, N`), rounded, in the reviewed YAML files `snapshots/plane/<scene>.snap` (never
//! raw matrices or fields). A change that moves a frictional scene's numbers fails this test;
//! the README ("Snapshots") says how to review and accept it.
//!
//! Rounding: each quantity to [`SIGNIFICANT_DIGITS`] digits of its largest magnitude over the
//! run, as `tests/plane_contact_snapshot.rs`: far above the run's round-off, far below its
//! discretisation error.

use insta::with_settings;
use serde::Serialize;
use viscobar::plane::PlaneSimulation;
use viscobar_certificate::plane::contact::plane_scene;

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
    energy: f64,
    /// `Σ D_f` up to this step.
    friction_dissipation: f64,
    /// Frictional nodes in contact that stick, and that slip.
    stick: usize,
    slip: usize,
    /// `Σ r_N` and `Σ r_T`.
    normal_force: f64,
    tangential_force: f64,
    /// The mean displacement of the nodes (x, y).
    mean_u: [f64; 2],
    /// `Σ W_T` up to this step: the sliding obstacle's work (absent without one).
    #[serde(skip_serializing_if = "Option::is_none")]
    sliding_work: Option<f64>,
}

#[test]
fn the_frictional_tilted_drop_matches_its_reviewed_snapshot() {
    snapshot("plane-friction-tilted-drop");
}

#[test]
fn the_stick_slip_belt_matches_its_reviewed_snapshot() {
    snapshot("plane-friction-stick-slip");
}

fn snapshot(name: &str) {
    let scene = plane_scene(name, &[]).unwrap();
    let steps = scene.steps();
    let mut sim = PlaneSimulation::new(&scene).unwrap();
    let mut rows = Vec::new();
    let mut record = sim.first_record();
    let mut dissipated = 0.0;
    let mut sliding_work = 0.0;
    let sliding = sim.contact().is_sliding();
    for n in 1..=steps {
        if n > 1 {
            record = sim.step().unwrap();
            dissipated += record.friction_dissipation;
            sliding_work += record.sliding_work;
        }
        if n > 1 && !(n * (T_POINTS - 1)).is_multiple_of(steps) {
            continue;
        }
        let u = sim.displacement_dofs();
        let nodes = sim.discretisation().grid.nodes() as f64;
        let mean_u = [0, 1].map(|k| u.iter().skip(k).step_by(2).sum::<f64>() / nodes);
        rows.push(Row {
            step: n,
            t: n as f64 * scene.time.step,
            energy: record.energy,
            friction_dissipation: dissipated,
            stick: record.stick_nodes,
            slip: record.slip_nodes,
            normal_force: sim.reactions().iter().sum::<f64>() + 0.0,
            tangential_force: sim.tangential_reactions().iter().sum::<f64>() + 0.0,
            mean_u,
            sliding_work: sliding.then_some(sliding_work),
        });
    }
    let scale = |f: &dyn Fn(&Row) -> f64| rows.iter().map(|r| f(r).abs()).fold(0.0, f64::max);
    let (se, sd, sn, st) = (
        scale(&|r| r.energy),
        scale(&|r| r.friction_dissipation),
        scale(&|r| r.normal_force),
        scale(&|r| r.tangential_force),
    );
    let su = scale(&|r| r.mean_u[0].abs().max(r.mean_u[1].abs()));
    let sw = scale(&|r| r.sliding_work.unwrap_or(0.0));
    for r in &mut rows {
        r.t = round_sig(r.t, 1.0);
        r.energy = round_sig(r.energy, se);
        r.friction_dissipation = round_sig(r.friction_dissipation, sd);
        r.normal_force = round_sig(r.normal_force, sn);
        r.tangential_force = round_sig(r.tangential_force, st);
        r.mean_u = r.mean_u.map(|v| round_sig(v, su));
        r.sliding_work = r.sliding_work.map(|v| round_sig(v, sw));
    }
    assert_eq!(rows.len(), T_POINTS);
    with_settings!({snapshot_path => "../snapshots/plane", prepend_module_to_snapshot => false}, {
        insta::assert_yaml_snapshot!(name, &rows);
    });
}
