//! `viscobar run` on scenes with friction through the binary: the friction columns of
//! history.csv and the summary's total against the library's run, the figure of the
//! stick/slip/open state, bad friction input refused with exit code 2 naming the key and a
//! failed frictional step with exit code 1 naming the step, nothing written.

mod common;
use common::viscobar;

fn fresh_dir(name: &str) -> std::path::PathBuf {
    common::fresh_dir("friction", name)
}

#[test]
fn run_writes_the_friction_columns_and_the_total_dissipation() {
    let out = fresh_dir("run");
    let scene = "plane-friction-tilted-drop";
    let o = viscobar(&["run", scene, "--out", out.to_str().unwrap()]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let stdout = String::from_utf8_lossy(&o.stdout);
    assert!(stdout.contains("friction dissipation"), "{stdout}");
    let history = std::fs::read_to_string(out.join("history.csv")).unwrap();
    let mut lines = history.lines();
    assert_eq!(
        lines.next(),
        Some(
            "step,t,energy,work,viscous_dissipation,contact_dissipation,identity_residual,\
             friction_dissipation,stick_nodes,slip_nodes,contact_nodes_bottom,\
             contact_s_min_bottom,contact_s_max_bottom,min_gap_bottom,reaction_bottom,\
             tangential_reaction_bottom,iterations"
        )
    );
    let rows: Vec<Vec<&str>> = lines.map(|l| l.split(',').collect()).collect();
    let column = |k: usize| -> Vec<f64> { rows.iter().map(|r| r[k].parse().unwrap()).collect() };
    let (dissipation, stick, slip) = (column(7), column(8), column(9));
    // The library's run: the same records, bit for bit.
    let AnyScene::Plane(plane) = viscobar::scene::load_any(scene, &[]).unwrap().1 else {
        panic!("a plane scene")
    };
    let (records, summary, _) = viscobar::output::run_plane_in_memory(scene, &plane).unwrap();
    assert_eq!(records.len(), rows.len());
    for (r, (d, (st, sl))) in records
        .iter()
        .zip(dissipation.iter().zip(stick.iter().zip(&slip)))
    {
        assert_eq!(
            r.friction_dissipation.to_bits(),
            d.to_bits(),
            "step {}",
            r.step
        );
        assert_eq!((r.stick_nodes as f64, r.slip_nodes as f64), (*st, *sl));
    }
    assert!(stick.iter().any(|v| *v > 0.0) && slip.iter().any(|v| *v > 0.0));
    let json: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(out.join("summary.json")).unwrap()).unwrap();
    // The library's total is the column's sum; the file's reads back within serde_json's
    // parsing (not correctly rounded without its `float_roundtrip` feature: an ulp).
    let total = summary.friction_dissipation.unwrap();
    assert_eq!(total.to_bits(), dissipation.iter().sum::<f64>().to_bits());
    let written = json["friction_dissipation"].as_f64().unwrap();
    assert!((written - total).abs() <= f64::EPSILON * total && total > 0.0);
    for check in ["friction_cone", "slip_law", "stationarity"] {
        assert!(json["audit"][check]["max_over_tolerance"].as_f64().unwrap() <= 1.0);
    }
    let _ = std::fs::remove_dir_all(&out);
}

use viscobar::scene::AnyScene;

/// A drawn figure is more than its headers: the smallest plausible PNG or SVG of a map.
const MIN_FIGURE_BYTES: u64 = 1000;

#[test]
fn run_figure_draws_the_stick_slip_state_and_the_forces() {
    let out = fresh_dir("figure");
    let o = viscobar(&[
        "run",
        "plane-friction-tilted-drop",
        "--out",
        out.to_str().unwrap(),
        "--figure",
    ]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    for f in ["friction-state.png", "friction-state.svg"] {
        let len = std::fs::metadata(out.join(f)).unwrap().len();
        assert!(len > MIN_FIGURE_BYTES, "{f}: {len} bytes");
    }
    assert!(!out.join("temperature.png").exists(), "no [heat], no θ");
    let _ = std::fs::remove_dir_all(&out);
}

/// With `[heat]`, `--figure` adds the temperature: the field and the edge over `(s, t)`.
#[test]
fn run_figure_draws_the_temperature_of_a_scene_with_heat() {
    let out = fresh_dir("heat-figure");
    let o = viscobar(&[
        "run",
        "plane-brake",
        "--out",
        out.to_str().unwrap(),
        "--figure",
    ]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    for f in ["temperature.png", "temperature.svg", "friction-state.png"] {
        let len = std::fs::metadata(out.join(f)).unwrap().len();
        assert!(len > MIN_FIGURE_BYTES, "{f}: {len} bytes");
    }
    let svg = std::fs::read_to_string(out.join("temperature.svg")).unwrap();
    assert!(
        svg.contains("plane-brake: temperature θ at t = 2.995"),
        "title"
    );
    let _ = std::fs::remove_dir_all(&out);
}

const CASES: &[(&str, &[&str], &str)] = &[
    (
        "negative friction",
        &["edges.bottom={condition=\"signorini\", gap=0.05, friction=-0.1}"],
        "edges.bottom.friction",
    ),
    (
        "NaN friction",
        &["edges.bottom={condition=\"signorini\", gap=0.05, friction=nan}"],
        "edges.bottom.friction",
    ),
    (
        "infinite friction",
        &["edges.bottom={condition=\"signorini\", gap=0.05, friction=inf}"],
        "edges.bottom.friction",
    ),
    (
        "friction on a free edge",
        &["edges.top={condition=\"free\", friction=0.3}"],
        "edges.top.friction",
    ),
    (
        "friction on a clamped edge",
        &["edges.left={condition=\"clamped\", friction=0.3}"],
        "edges.left.friction",
    ),
    (
        "friction with the penalty method",
        &[
            "edges.bottom={condition=\"signorini\", gap=0.05, friction=0.3}",
            "solver.method=\"penalty\"",
        ],
        "solver.method",
    ),
    (
        "frictional problem too large",
        &[
            "mesh.nx=1500",
            "edges.bottom={condition=\"signorini\", gap=0.05, friction=0.3}",
        ],
        "edges.bottom.friction",
    ),
];

#[test]
fn bad_friction_input_exits_2_naming_the_key_and_writes_nothing() {
    common::assert_each_refused("plane-tilted-drop", CASES, &fresh_dir("bad"));
}

#[test]
fn a_failed_frictional_step_exits_1_naming_the_step_and_writes_nothing() {
    // OSQP stopped after one iteration cannot solve the first Tresca problem: the run fails
    // at that step, through the same path as a Lemke ray or a failed friction audit.
    let out = fresh_dir("fails");
    let o = viscobar(&[
        "run",
        "plane-friction-tilted-drop",
        "--solver",
        "osqp",
        "--set",
        "solver.max_iter=1",
        "--out",
        out.to_str().unwrap(),
    ]);
    let stderr = String::from_utf8_lossy(&o.stderr);
    assert_eq!(o.status.code(), Some(1), "{stderr}");
    assert!(
        stderr.contains("step 1 (t = 0.005)") && stderr.contains("maximum iterations reached"),
        "{stderr}"
    );
    assert!(!out.exists(), "wrote {}", out.display());
}
