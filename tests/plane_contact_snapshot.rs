//! Snapshot regression of `plane-tilted-drop`: statistics of the run at 11 steps (`n = 1`, the
//! start-up step, and `N/10, …, N`), rounded, in the reviewed YAML file `snapshots/plane/plane-tilted-drop.snap`
//! (never raw matrices or fields). A change that moves the drop's numbers fails this test; the
//! README ("Snapshots") says how to review and accept it.
//!
//! Rounding: each quantity to [`SIGNIFICANT_DIGITS`] digits of its largest magnitude over the
//! run (as `tests/snapshots.rs`): the run's round-off (1e-13 relative) is far below that
//! quantum, its discretisation error (1e-2, VERIFICATION.md "Plane contact") far above.

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
    /// Normals in contact, and the extent `[s_min, s_max]` of the touching nodes.
    in_contact: usize,
    contact_s: Option<[f64; 2]>,
    /// `Σ r_k` and the largest contact pressure `r_k / ω_k`.
    total_reaction: f64,
    max_pressure: f64,
    /// The mean displacement of the nodes (x, y), and the bottom edge's lowest `uy`.
    mean_u: [f64; 2],
    min_bottom_uy: f64,
}

#[test]
fn the_tilted_drop_matches_its_reviewed_snapshot() {
    let scene = plane_scene("plane-tilted-drop", &[]).unwrap();
    let steps = scene.steps();
    let mut sim = PlaneSimulation::new(&scene).unwrap();
    let mut rows = Vec::new();
    let mut energy = sim.first_record().energy;
    for n in 1..=steps {
        if n > 1 {
            energy = sim.step().unwrap().energy;
        }
        if !sampled(n, steps, T_POINTS) {
            continue;
        }
        let u = sim.displacement_dofs();
        let grid = &sim.discretisation().grid;
        let nodes = grid.nodes() as f64;
        let mean_u = [0, 1].map(|k| u.iter().skip(k).step_by(2).sum::<f64>() / nodes);
        let min_bottom_uy = (0..=grid.nx)
            .map(|i| u[2 * grid.node(i, 0) + 1])
            .fold(f64::INFINITY, f64::min);
        // The normals pressed by their obstacle (a positive reaction).
        let touching: Vec<_> = (sim.body().normals().iter())
            .zip(sim.reactions())
            .filter(|(_, r)| **r > 0.0)
            .collect();
        let columns = Columns {
            energy,
            in_contact: touching.len(),
            contact_s: (!touching.is_empty())
                .then(|| [touching[0].0.s, touching[touching.len() - 1].0.s]),
            total_reaction: touching.iter().map(|(_, r)| **r).sum::<f64>() + 0.0,
            max_pressure: touching
                .iter()
                .map(|(k, r)| **r / k.weight)
                .fold(0.0, f64::max),
            mean_u,
            min_bottom_uy,
        };
        let t = n as f64 * scene.time.step;
        rows.push(Row {
            step: n,
            t,
            columns,
        });
    }
    // Round each quantity relative to its largest magnitude.
    round_times(&mut rows, SIGNIFICANT_DIGITS);
    round_quantity(&mut rows, SIGNIFICANT_DIGITS, |c| vec![&mut c.energy]);
    round_quantity(&mut rows, SIGNIFICANT_DIGITS, |c| {
        vec![&mut c.total_reaction]
    });
    round_quantity(&mut rows, SIGNIFICANT_DIGITS, |c| vec![&mut c.max_pressure]);
    round_quantity(&mut rows, SIGNIFICANT_DIGITS, |c| {
        let [x, y] = &mut c.mean_u;
        vec![x, y, &mut c.min_bottom_uy]
    });
    assert_eq!(rows.len(), T_POINTS);
    with_settings!({snapshot_path => "../snapshots/plane", prepend_module_to_snapshot => false}, {
        insta::assert_yaml_snapshot!("plane-tilted-drop", &rows);
    });
}
