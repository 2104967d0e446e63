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

use common::snapshot::{Row, round_quantity, round_times, sampled};

/// Significant digits kept, relative to the largest magnitude of each quantity.
const SIGNIFICANT_DIGITS: i32 = 7;
/// Rows of the snapshot (10 intervals).
const T_POINTS: usize = 11;

/// The columns of a row.
#[derive(Serialize)]
struct Columns {
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
        if !sampled(n, steps, T_POINTS) {
            continue;
        }
        let u = sim.displacement_dofs();
        let nodes = sim.discretisation().grid.nodes() as f64;
        let mean_u = [0, 1].map(|k| u.iter().skip(k).step_by(2).sum::<f64>() / nodes);
        let columns = Columns {
            energy: record.energy,
            friction_dissipation: dissipated,
            stick: record.stick_nodes,
            slip: record.slip_nodes,
            normal_force: sim.reactions().iter().sum::<f64>() + 0.0,
            tangential_force: sim.tangential_reactions().iter().sum::<f64>() + 0.0,
            mean_u,
            sliding_work: sliding.then_some(sliding_work),
        };
        let t = n as f64 * scene.time.step;
        rows.push(Row {
            step: n,
            t,
            columns,
        });
    }
    round_times(&mut rows, SIGNIFICANT_DIGITS);
    round_quantity(&mut rows, SIGNIFICANT_DIGITS, |c| vec![&mut c.energy]);
    round_quantity(&mut rows, SIGNIFICANT_DIGITS, |c| {
        vec![&mut c.friction_dissipation]
    });
    round_quantity(&mut rows, SIGNIFICANT_DIGITS, |c| vec![&mut c.normal_force]);
    round_quantity(&mut rows, SIGNIFICANT_DIGITS, |c| {
        vec![&mut c.tangential_force]
    });
    round_quantity(&mut rows, SIGNIFICANT_DIGITS, |c| {
        c.mean_u.iter_mut().collect()
    });
    round_quantity(&mut rows, SIGNIFICANT_DIGITS, |c| {
        c.sliding_work.iter_mut().collect()
    });
    assert_eq!(rows.len(), T_POINTS);
    with_settings!({snapshot_path => "../snapshots/plane", prepend_module_to_snapshot => false}, {
        insta::assert_yaml_snapshot!(name, &rows);
    });
}
