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

/// Significant digits kept, relative to the largest magnitude of each quantity.
const SIGNIFICANT_DIGITS: i32 = 7;
/// Rows of the snapshot (10 intervals) and nodes sampled (4 intervals).
const T_POINTS: usize = 11;
const X_POINTS: usize = 5;

/// [`common::round_to_digits`] with this file's [`SIGNIFICANT_DIGITS`].
fn round_sig(x: f64, scale: f64) -> f64 {
    common::round_to_digits(x, scale, SIGNIFICANT_DIGITS)
}

#[derive(Serialize)]
struct Row {
    step: usize,
    t: f64,
    energy: f64,
    thermal_energy: f64,
    gap_left: f64,
    reaction_left: f64,
    u: Vec<f64>,
    theta: Vec<f64>,
}

fn rows_of(name: &str) -> Vec<Row> {
    let (_, scene) = scene::load(name, &[]).unwrap();
    let steps = scene.steps();
    let mut sim = ThermalSimulation::new(&scene).unwrap();
    let nodes = sim.body().nodes();
    let sampled: Vec<usize> = (0..X_POINTS)
        .map(|k| k * (nodes - 1) / (X_POINTS - 1))
        .collect();
    let mut rows = Vec::new();
    let mut record = sim.first_record();
    for n in 1..=steps {
        if n > 1 {
            record = sim.step().unwrap();
        }
        if n > 1 && !(n * (T_POINTS - 1)).is_multiple_of(steps) {
            continue;
        }
        let u = sim.displacement_dofs();
        let body = sim.body();
        rows.push(Row {
            step: n,
            t: n as f64 * scene.time.step,
            energy: record.energy,
            thermal_energy: record.heat.unwrap_or_default().energy,
            gap_left: record.contact.groups[0].min_gap,
            reaction_left: record.contact.groups[0].reaction,
            u: sampled.iter().map(|&i| u[i]).collect(),
            theta: (sampled.iter())
                .map(|&i| body.temperature(sim.displacement(), i).unwrap())
                .collect(),
        });
    }
    let scale = |f: &dyn Fn(&Row) -> f64| rows.iter().map(|r| f(r).abs()).fold(0.0, f64::max);
    let (se, sh, sg, sr) = (
        scale(&|r| r.energy),
        scale(&|r| r.thermal_energy),
        scale(&|r| r.gap_left),
        scale(&|r| r.reaction_left),
    );
    let su = scale(&|r| r.u.iter().fold(0.0, |m, v| m.max(v.abs())));
    let st = scale(&|r| r.theta.iter().fold(0.0, |m, v| m.max(v.abs())));
    for r in &mut rows {
        r.t = round_sig(r.t, 1.0);
        r.energy = round_sig(r.energy, se);
        r.thermal_energy = round_sig(r.thermal_energy, sh);
        r.gap_left = round_sig(r.gap_left, sg);
        r.reaction_left = round_sig(r.reaction_left, sr);
        r.u = r.u.iter().map(|v| round_sig(*v, su)).collect();
        r.theta = r.theta.iter().map(|v| round_sig(*v, st)).collect();
    }
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
