//! Snapshot regressions of the thermal built-in scenes (`heated-expansion`, `thermal-impact`):
//! at 11 steps (`n = 1` and `N/10, …, N`) the total and thermal energy, the left end's gap and
//! reaction, `u` and `θ` at 5 nodes, rounded, in the reviewed YAML files
//! `snapshots/thermal/<scene>.snap`; README ("Snapshots") says how to review a change.
//!
//! Rounding: each quantity to [`SIGNIFICANT_DIGITS`] digits of its largest magnitude over the
//! run (as `tests/snapshots.rs`): the runs' round-off (1e-14 relative) is far below that
//! quantum, their discretisation error (1e-3 and more) far above.

use insta::with_settings;
use serde::Serialize;
use viscobar::scene;
use viscobar::scheme::Body;
use viscobar::thermal::ThermalSimulation;

mod common;

use common::snapshot::{Row, round_quantity, round_times, sampled};

/// Significant digits kept, relative to the largest magnitude of each quantity.
const SIGNIFICANT_DIGITS: i32 = 7;
/// Rows of the snapshot (10 intervals) and nodes sampled (4 intervals).
const T_POINTS: usize = 11;
const X_POINTS: usize = 5;

/// The columns of a row.
#[derive(Serialize)]
struct Columns {
    energy: f64,
    thermal_energy: f64,
    gap_left: f64,
    reaction_left: f64,
    u: Vec<f64>,
    theta: Vec<f64>,
}

fn rows_of(name: &str) -> Vec<Row<Columns>> {
    let (_, scene) = scene::load(name, &[]).unwrap();
    let steps = scene.steps();
    let mut sim = ThermalSimulation::new(&scene).unwrap();
    let nodes = sim.body().nodes();
    let nodes_sampled: Vec<usize> = (0..X_POINTS)
        .map(|k| k * (nodes - 1) / (X_POINTS - 1))
        .collect();
    let mut rows = Vec::new();
    let mut record = sim.first_record();
    for n in 1..=steps {
        if n > 1 {
            record = sim.step().unwrap();
        }
        if !sampled(n, steps, T_POINTS) {
            continue;
        }
        let u = sim.displacement_dofs();
        let body = sim.body();
        let columns = Columns {
            energy: record.energy,
            thermal_energy: record.heat.unwrap_or_default().energy,
            gap_left: record.contact.groups[0].min_gap,
            reaction_left: record.contact.groups[0].reaction,
            u: nodes_sampled.iter().map(|&i| u[i]).collect(),
            theta: (nodes_sampled.iter())
                .map(|&i| body.temperature(sim.displacement(), i).unwrap())
                .collect(),
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
        vec![&mut c.thermal_energy]
    });
    round_quantity(&mut rows, SIGNIFICANT_DIGITS, |c| vec![&mut c.gap_left]);
    round_quantity(&mut rows, SIGNIFICANT_DIGITS, |c| {
        vec![&mut c.reaction_left]
    });
    round_quantity(&mut rows, SIGNIFICANT_DIGITS, |c| c.u.iter_mut().collect());
    round_quantity(&mut rows, SIGNIFICANT_DIGITS, |c| {
        c.theta.iter_mut().collect()
    });
    assert_eq!(rows.len(), T_POINTS);
    rows
}

#[test]
fn the_thermal_scenes_match_their_reviewed_snapshots() {
    for name in scene::thermal_builtin_names() {
        let rows = rows_of(name);
        with_settings!({snapshot_path => "../snapshots/thermal", prepend_module_to_snapshot => false}, {
            insta::assert_yaml_snapshot!(name, &rows);
        });
    }
}
