//! Snapshot regressions of the talk's figures: for every talk scene, the data its figure is drawn
//! from (`u` at 9 nodes by 11 steps, the energy `E^{n−1/2}` recorded by those steps, the contact
//! intervals per Signorini end and the solver iteration statistics), reduced to a small reviewed
//! YAML file in `snapshots/<scene>.snap`; README.md ("Snapshots") says how to review a change.
//!
//! Rounding: every quantity to [`SIGNIFICANT_DIGITS`] significant digits *of its largest
//! magnitude* (for `u` a quantum of about 1e-8 · max|u|): five orders above these runs'
//! round-off (about 1e-13 relative), so last-bit differences do not churn the snapshots, and
//! five below their discretisation error (1e-3 … 1e-2), so any change that could matter shows.
//! Rounding each value to its own digits would not be safe: `u(π/4, 0) = 0.3 cos(π/2)` is 2e-17
//! of pure round-off. A value within 1e-13 of a rounding boundary can still flip its last digit
//! (about once per 100 changes of machine or compiler); that shows as a one-digit diff.

use insta::with_settings;
use serde::Serialize;
use std::collections::BTreeMap;
use std::path::{Path, PathBuf};
use viscobar::internals::linalg::norms::max_abs;
use viscobar::internals::study::sampled_run::{self, Sampling};
use viscobar::study::figures;

mod common;

use common::snapshot::Row;

/// Significant digits kept, relative to the largest magnitude of each quantity.
const SIGNIFICANT_DIGITS: i32 = 8;
/// Grid of the snapshot: nodes by steps (8 and 10 intervals).
const X_POINTS: usize = 9;
const T_POINTS: usize = 11;

/// Rounds `x` to a multiple of the quantum `10^(e − SIGNIFICANT_DIGITS + 1)`, where `10^e` is the
/// order of magnitude of `scale` (the largest |value| of the same quantity). Rounding is done in
/// decimal by the formatter, so the stored value prints as the rounded decimal.
fn round_sig(x: f64, scale: f64) -> f64 {
    if x == 0.0 || scale == 0.0 || !x.is_finite() {
        return x;
    }
    let exponent = scale.abs().log10().floor() as i32 - (SIGNIFICANT_DIGITS - 1);
    let rounded: f64 = if exponent < 0 {
        format!("{x:.*}", (-exponent) as usize).parse().unwrap()
    } else {
        let q = 10f64.powi(exponent);
        (x / q).round() * q
    };
    rounded + 0.0 // -0.0 -> 0.0
}

/// The columns of a row.
#[derive(Serialize)]
struct Columns {
    /// `E^{n−1/2}`, recorded by step `n` (none at `n = 0`).
    energy: Option<f64>,
    u: Vec<f64>,
}

#[derive(Serialize)]
struct Iterations {
    mean: f64,
    max: u32,
}

#[derive(Serialize)]
struct Snapshot {
    scene: String,
    /// `bar.mass` when not the consistent default.
    #[serde(skip_serializing_if = "Option::is_none")]
    mass: Option<String>,
    solver: String,
    alpha: f64,
    elements: usize,
    dt: f64,
    steps: usize,
    rounding: String,
    /// The sampled nodes and their `x`.
    nodes: Vec<usize>,
    x: Vec<f64>,
    rows: Vec<Row<Columns>>,
    contact_intervals: BTreeMap<String, Vec<[f64; 2]>>,
    /// Distributed obstacles only: per time bin (between consecutive sampled steps), the
    /// extent `[x_min, x_max]` of the nodes in contact at some step of the bin (`~` if none).
    #[serde(skip_serializing_if = "Option::is_none")]
    contact_set_extent: Option<Vec<Option<[f64; 2]>>>,
    solver_iterations: Iterations,
}

/// Snapshots of a talk scene with another mass matrix: snapshot name, scene, the
/// `bar.mass` value.
const MASS_SNAPSHOTS: [(&str, &str, &str); 1] =
    [("one-end-mass-redistributed", "one-end", "redistributed")];

fn snapshot_of(name: &str, mass: Option<&str>) -> Snapshot {
    let set = mass.map(|m| format!("bar.mass={m}"));
    let scene = common::builtin(name, &set.iter().map(String::as_str).collect::<Vec<_>>());
    let sampling = Sampling::exact(&scene, X_POINTS, T_POINTS).unwrap_or_else(|| {
        panic!(
            "{name}: {} elements and {} steps hold no {X_POINTS} x {T_POINTS} grid of mesh points",
            scene.elements(),
            scene.steps()
        )
    });
    let run = sampled_run::sample_run(name, &scene, sampling).expect("talk scene runs");
    let u_scale = max_abs(&run.u);
    let e_scale = max_abs(run.energy.iter().flatten());
    let t_scale = run.final_time();
    let rows = (0..run.ts.len())
        .map(|k| Row {
            step: run.steps_sampled[k],
            t: round_sig(run.ts[k], t_scale),
            columns: Columns {
                energy: run.energy[k].map(|e| round_sig(e, e_scale)),
                u: run
                    .u_row(k)
                    .iter()
                    .map(|&u| round_sig(u, u_scale))
                    .collect(),
            },
        })
        .collect();
    let contact_intervals = run
        .summary
        .contact_intervals
        .iter()
        .map(|(end, spans)| {
            let spans = spans
                .iter()
                .map(|&[a, b]| [round_sig(a, t_scale), round_sig(b, t_scale)])
                .collect();
            (end.clone(), spans)
        })
        .collect();
    let h = &run.contact;
    let contact_set_extent = (h.constraints() > 2).then(|| {
        (0..h.times.len())
            .map(|b| {
                let xs: Vec<f64> = (0..h.constraints())
                    .filter(|&j| h.in_contact(b, j))
                    .map(|j| h.xs[j])
                    .collect();
                let (lo, hi) = (xs.first()?, xs.last()?);
                Some([round_sig(*lo, run.length), round_sig(*hi, run.length)])
            })
            .collect()
    });
    let it = run.summary.solver_iterations;
    Snapshot {
        scene: name.to_string(),
        mass: mass.map(str::to_string),
        solver: run.solver.clone(),
        alpha: run.alpha,
        elements: run.elements,
        dt: run.dt,
        steps: run.steps,
        rounding: format!(
            "{SIGNIFICANT_DIGITS} significant digits of the largest |value| of each quantity"
        ),
        nodes: run.nodes.clone(),
        x: run.xs.iter().map(|&x| round_sig(x, run.length)).collect(),
        rows,
        contact_intervals,
        contact_set_extent,
        solver_iterations: Iterations {
            mean: round_sig(it.mean, it.mean),
            max: it.max,
        },
    }
}

fn snapshot_dir() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("snapshots")
}

/// As insta decides it: `CI` set to anything but empty, `0` or `false`.
fn under_ci() -> bool {
    std::env::var("CI").is_ok_and(|v| !matches!(v.as_str(), "" | "0" | "false"))
}

/// Every talk scene matches its reviewed snapshot. All scenes are checked (and pending
/// `.snap.new` files written outside CI) before the test fails.
#[test]
fn talk_scenes_match_their_reviewed_snapshots() {
    let mut failed = Vec::new();
    let cases = figures::talk_scenes()
        .map(|n| (n, n, None))
        .chain(MASS_SNAPSHOTS.iter().map(|(s, n, m)| (*s, *n, Some(*m))));
    for (name, scene, mass) in cases {
        let data = snapshot_of(scene, mass);
        let missing = !snapshot_dir().join(format!("{name}.snap")).exists();
        let outcome = std::panic::catch_unwind(|| {
            with_settings!({snapshot_path => "../snapshots", prepend_module_to_snapshot => false}, {
                insta::assert_yaml_snapshot!(name, &data);
            });
        });
        // insta already fails a missing snapshot under CI; this also holds if CI sets
        // INSTA_UPDATE=always or INSTA_FORCE_PASS.
        if outcome.is_err() || (missing && under_ci()) {
            failed.push(name);
        }
    }
    assert!(
        failed.is_empty(),
        "snapshots differ or are missing for {failed:?}: review the diffs above \
         (README, \"Snapshots\")"
    );
}

/// No snapshot outlives its scene: every `snapshots/*.snap` is a talk scene's (or one of
/// [`MASS_SNAPSHOTS`]).
#[test]
fn every_snapshot_belongs_to_a_talk_scene() {
    let scenes: Vec<&str> = figures::talk_scenes()
        .chain(MASS_SNAPSHOTS.iter().map(|(s, ..)| *s))
        .collect();
    for entry in std::fs::read_dir(snapshot_dir()).expect("snapshots/ exists") {
        let name = entry.unwrap().file_name().to_string_lossy().into_owned();
        if let Some(stem) = name.strip_suffix(".snap") {
            assert!(
                scenes.contains(&stem),
                "snapshots/{name} is no talk scene's"
            );
        }
    }
}

#[test]
fn rounding_keeps_digits_relative_to_the_scale() {
    assert_eq!(round_sig(0.123456789012, 0.3), 0.12345679);
    assert_eq!(
        round_sig(2.0e-17, 0.3),
        0.0,
        "round-off below the quantum vanishes"
    );
    assert_eq!(round_sig(-1.0e-17, 0.3), 0.0);
    assert!(
        round_sig(-1.0e-17, 0.3).is_sign_positive(),
        "no -0 in snapshots"
    );
    assert_eq!(round_sig(1.1300000000000001, 12.0), 1.13);
    assert_eq!(round_sig(123456789.0, 123456789.0), 123456790.0);
    assert_eq!(round_sig(-0.00012345678949, 0.00012), -0.00012345679);
}
