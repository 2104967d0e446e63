//! `displacement.csv` holds the run's own numbers: every `u` and `v` reads back to the bits the
//! simulation held (shortest round-trip formatting), at every kept step.

mod common;
use viscobar::Simulation;
use viscobar::output::run_to_dir;

#[test]
fn displacement_csv_reads_back_to_the_simulation_bits() {
    // Values of every size: a kink, contact, and a displacement crossing zero.
    let scene = common::builtin("impact", &["output.every=7"]);
    let dir = std::env::temp_dir().join(format!("viscobar-output-files-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    run_to_dir("impact", &scene, &dir, false).unwrap();
    let text = std::fs::read_to_string(dir.join("displacement.csv")).unwrap();
    std::fs::remove_dir_all(&dir).unwrap();

    let mut sim = Simulation::new(&scene).unwrap();
    let nodes = sim.discretisation().nodes;
    let (mut u, mut v) = (vec![0.0; nodes], vec![0.0; nodes]);
    let mut rows = text.lines().skip(1);
    let mut check = |u: &[f64], v: &[f64]| {
        for i in 0..nodes {
            let row = rows.next().expect("a row a node");
            let f: Vec<f64> = row.split(',').map(|c| c.parse().unwrap()).collect();
            assert_eq!(f[2].to_bits(), u[i].to_bits(), "u in {row}");
            assert_eq!(f[3].to_bits(), v[i].to_bits(), "v in {row}");
        }
    };
    sim.body().initial_state_into(&mut u, &mut v);
    check(&u, &v);
    let steps = scene.steps();
    let keep = |n: usize| n.is_multiple_of(7) || n == steps;
    let mut kept = 1;
    for n in 1..=steps {
        if n > 1 {
            sim.step().unwrap();
        }
        if keep(n) {
            sim.displacement_into(&mut u);
            sim.velocity_into(&mut v);
            check(&u, &v);
            kept += 1;
        }
    }
    assert!(kept > 2);
    assert!(rows.next().is_none(), "no rows beyond the kept steps");
}

/// Runs `scene` into a fresh folder; returns the `x` of each row of `displacement.csv`, grouped
/// by kept step, and summary.json.
fn written(scene: &viscobar::Scene, tag: &str) -> (Vec<Vec<f64>>, serde_json::Value) {
    let dir = std::env::temp_dir().join(format!("viscobar-output-{tag}-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    run_to_dir("impact", scene, &dir, false).unwrap();
    let text = std::fs::read_to_string(dir.join("displacement.csv")).unwrap();
    let summary =
        serde_json::from_str(&std::fs::read_to_string(dir.join("summary.json")).unwrap()).unwrap();
    std::fs::remove_dir_all(&dir).unwrap();
    let mut steps: Vec<(String, Vec<f64>)> = Vec::new();
    for row in text.lines().skip(1) {
        let mut cells = row.split(',');
        let t = cells.next().unwrap().to_string();
        let x: f64 = cells.next().unwrap().parse().unwrap();
        match steps.last_mut() {
            Some((last, xs)) if *last == t => xs.push(x),
            _ => steps.push((t, vec![x])),
        }
    }
    (steps.into_iter().map(|s| s.1).collect(), summary)
}

/// `x` is written rounded to 12 significant digits (README, "Output files").
const X_ROUNDING_TOL: f64 = 1e-12;

#[test]
fn every_node_is_written_while_the_rows_stay_within_max_rows() {
    let scene = common::builtin("impact", &["output.every=50"]);
    let sampling = scene.output_sampling();
    let (steps, summary) = written(&scene, "all");
    assert_eq!(sampling.node_stride, 1);
    assert!(steps.iter().all(|xs| xs.len() == scene.elements() + 1));
    assert_eq!(steps.len() as u64, sampling.kept_steps);
    assert_eq!(summary["output"]["rows"], sampling.rows);
}

#[test]
fn a_run_past_max_rows_is_thinned_to_strided_nodes_with_both_ends() {
    for (overrides, tag) in [
        (&["output.every=50", "output.max_rows=300"][..], "bounded"),
        (&["output.every=50", "output.nodes=7"][..], "nodes"),
    ] {
        let scene = common::builtin("impact", overrides);
        let s = scene.output_sampling();
        let (steps, summary) = written(&scene, tag);
        let length = scene.bar.length;
        for xs in &steps {
            assert_eq!(xs.len() as u64, s.nodes_written, "{tag}");
            assert_eq!(xs[0], 0.0);
            assert!(
                (xs[xs.len() - 1] - length).abs() <= X_ROUNDING_TOL * length,
                "{tag}: last x"
            );
        }
        let rows = (steps.len() * steps[0].len()) as u64;
        assert_eq!(rows, s.rows);
        assert_eq!(summary["output"]["node_stride"], s.node_stride);
        if tag == "bounded" {
            assert!(rows <= 300, "{rows} rows");
            // The fewest nodes dropped: one stride less would pass the bound.
            let n = scene.elements() as u64;
            let at = |k: u64| n / k + 1 + u64::from(!n.is_multiple_of(k));
            assert!(s.node_stride > 1 && s.kept_steps * at(s.node_stride - 1) > 300);
        } else {
            assert!(s.nodes_written <= 7 && s.nodes_written >= 6, "{s:?}");
        }
    }
}

#[test]
fn output_nodes_below_two_is_refused_naming_the_key() {
    let err = viscobar::scene::load("impact", &["output.nodes=1".into()]).unwrap_err();
    assert!(err.to_string().contains("output.nodes"), "{err}");
}

#[test]
fn an_unknown_output_format_is_refused_naming_the_key() {
    let err = viscobar::scene::load("impact", &["output.format=hdf5".into()]).unwrap_err();
    assert!(err.to_string().contains("format"), "{err}");
    assert!(err.to_string().contains("hdf5"), "{err}");
}

#[test]
fn summary_json_names_the_csv_profile_file_and_format() {
    let scene = common::builtin("impact", &["output.every=50"]);
    let (_, summary) = written(&scene, "format");
    assert_eq!(summary["output"]["file"], "displacement.csv");
    assert_eq!(summary["output"]["format"], "csv");
    // The default stays out of the printed scene.
    assert!(!scene.to_toml().contains("format"));
}

/// A build without the `npy` feature refuses `format = "npy"` naming `output.format` and the
/// feature, at load and in `run_to_dir` (a scene built by hand), writing nothing.
#[cfg(not(feature = "npy"))]
#[test]
fn npy_output_without_the_feature_is_refused_naming_the_key_and_the_feature() {
    let err = viscobar::scene::load("impact", &["output.format=npy".into()]).unwrap_err();
    let text = err.to_string();
    assert!(text.contains("output.format"), "{text}");
    assert!(text.contains("--features npy"), "{text}");

    let mut scene = common::builtin("impact", &[]);
    scene.output.format = viscobar::scene::OutputFormat::Npy;
    let dir = std::env::temp_dir().join(format!("viscobar-no-npy-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    let err = run_to_dir("impact", &scene, &dir, false).unwrap_err();
    assert!(err.to_string().contains("output.format"), "{err}");
    assert_eq!(err.exit_code(), 2);
    assert!(!dir.exists(), "nothing written");
}

/// The same through the command line: exit code 2, the key named, nothing written.
#[cfg(all(feature = "cli", not(feature = "npy")))]
#[test]
fn cli_run_with_npy_output_without_the_feature_exits_2_writing_nothing() {
    let dir = std::env::temp_dir().join(format!("viscobar-no-npy-cli-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    let out = std::process::Command::new(env!("CARGO_BIN_EXE_viscobar"))
        .args(["run", "impact", "--set", "output.format=npy", "--out"])
        .arg(&dir)
        .output()
        .unwrap();
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert_eq!(out.status.code(), Some(2), "{stderr}");
    assert!(stderr.contains("output.format"), "{stderr}");
    assert!(stderr.contains("--features npy"), "{stderr}");
    assert!(!dir.exists(), "nothing written");
}

/// `t` and `x` are written as `Display` of the rounded value (`output_time`), whichever path
/// formats them: `x` fields narrow (`0.0125,`), wide (`0.000000246,`) and longer than a field
/// (a bar of 1e24), and times needing every digit.
#[test]
fn t_and_x_are_the_display_of_the_rounded_values() {
    use viscobar::internals::output::text::output_time;
    for (tag, sets) in [
        ("unit", vec!["mesh.elements=80"]),
        ("short", vec!["bar.length=1.23e-5", "mesh.elements=50"]),
        ("shorter", vec!["bar.length=2.5e-7", "mesh.elements=50"]),
        ("long", vec!["bar.length=3e13", "mesh.elements=50"]),
        ("longer", vec!["bar.length=1e24", "mesh.elements=50"]),
        (
            "odd-step",
            vec![
                "mesh.elements=30",
                "time.step=0.0123456789",
                "time.end=3.0123456516",
                "output.every=1",
            ],
        ),
    ] {
        let scene = common::builtin("impact", &sets);
        let dir = std::env::temp_dir().join(format!("viscobar-tx-{tag}-{}", std::process::id()));
        let _ = std::fs::remove_dir_all(&dir);
        run_to_dir("impact", &scene, &dir, false).unwrap();
        let text = std::fs::read_to_string(dir.join("displacement.csv")).unwrap();
        std::fs::remove_dir_all(&dir).unwrap();
        let sim = Simulation::new(&scene).unwrap();
        let disc = sim.discretisation();
        let mut rows = 0;
        for (j, row) in text.lines().skip(1).enumerate() {
            let mut cells = row.split(',');
            let (t, x) = (cells.next().unwrap(), cells.next().unwrap());
            let step = j / disc.nodes;
            let every = if tag == "odd-step" { 1 } else { 5 };
            let n = (step * every).min(scene.steps());
            assert_eq!(
                t,
                output_time(n as f64 * disc.dt).to_string(),
                "{tag}: {row}"
            );
            assert_eq!(
                x,
                output_time(disc.x(j % disc.nodes)).to_string(),
                "{tag}: {row}"
            );
            rows += 1;
        }
        assert!(rows > 3 * disc.nodes, "{tag}: {rows} rows");
    }
}

/// `history.csv`'s `tangential_reaction_<edge>` follows `reaction_<edge>` on an edge with
/// frictional nodes only: none for a frictionless plane (its columns as before) or a friction
/// zero at every node, one for the frictional floor beside a frictionless Signorini wall.
#[test]
fn the_tangential_total_is_written_beside_the_reaction_of_frictional_edges_only() {
    let columns = |overrides: &[&str]| {
        let mut set = vec!["time.end=0.05".to_string()];
        set.extend(overrides.iter().map(|s| s.to_string()));
        let (_, scene) = viscobar::scene::load_any("plane-tilted-drop", &set).unwrap();
        viscobar::output::memory::record_any("drop", &scene)
            .unwrap()
            .history_columns
    };
    let plain = columns(&[]);
    assert!(
        !plain.iter().any(|c| c.starts_with("tangential")),
        "{plain:?}"
    );
    assert_eq!(columns(&["edges.bottom.friction=\"0*s\""]), plain);
    let wall = "edges.left={condition=\"signorini\", gap=0.5}";
    let frictional = columns(&[wall, "edges.bottom.friction=\"0.3*(s > 0.5)\""]);
    let at = |c: &str| frictional.iter().position(|x| x == c);
    assert_eq!(
        at("tangential_reaction_bottom"),
        at("reaction_bottom").map(|k| k + 1),
        "{frictional:?}"
    );
    assert!(at("reaction_left").is_some() && at("tangential_reaction_left").is_none());
}
