//! What a user running a plane contact study trips on, through the binary: nested `--set`
//! keys, the `--figure` help and files of both bodies, the edge gap's variables `s` and `t`
//! and its errors, a moving obstacle's outputs, and the printed numbers.

mod common;
use common::{fresh_dir, viscobar};

fn out_dir(name: &str) -> std::path::PathBuf {
    fresh_dir("study", name)
}

/// `--set edges.bottom.gap=0.1` sets the key inside the edge's table, exactly as the whole
/// table given inline does: the same history, byte for byte.
#[test]
fn a_nested_set_key_sets_the_edge_field() {
    let (a, b) = (out_dir("nested-a"), out_dir("nested-b"));
    let run = |out: &std::path::Path, set: &str| {
        let o = viscobar(&[
            "run",
            "plane-tilted-drop",
            "--out",
            out.to_str().unwrap(),
            "--set",
            set,
        ]);
        assert!(
            o.status.success(),
            "{set}: {}",
            String::from_utf8_lossy(&o.stderr)
        );
        std::fs::read_to_string(out.join("history.csv")).unwrap()
    };
    let nested = run(&a, "edges.bottom.gap=0.1");
    let inline = run(&b, "edges.bottom={condition=\"signorini\", gap=0.1}");
    assert_eq!(nested, inline);
    // 0.1, not the scene's 0.05: the first step's least gap is above 0.05.
    let first = nested.lines().nth(1).unwrap();
    let min_gap: f64 = first.split(',').nth(10).unwrap().parse().unwrap();
    assert!(min_gap > 0.09, "{first}");
    // A key below a value that is not a table is refused naming it.
    let o = viscobar(&[
        "run",
        "plane-tilted-drop",
        "--out",
        a.to_str().unwrap(),
        "--set",
        "plane.width.x=1",
    ]);
    assert_eq!(o.status.code(), Some(2));
    assert!(String::from_utf8_lossy(&o.stderr).contains("`plane.width` is not a table"));
    for d in [a, b] {
        let _ = std::fs::remove_dir_all(d);
    }
}

/// `run --help` names the files `--figure` writes, and `run BAR --figure` draws the bar's
/// figure into the output folder (rather than pointing to a command that takes no scene).
#[test]
fn figure_help_names_the_files_and_a_bar_scene_gets_its_figure() {
    let o = viscobar(&["run", "--help"]);
    let help = String::from_utf8_lossy(&o.stdout);
    let flat: String = help.split_whitespace().collect::<Vec<_>>().join(" ");
    assert!(
        flat.contains("deformed.png") && flat.contains("contact-pressure.png"),
        "{help}"
    );
    assert!(!flat.contains("plane.png"), "{help}");
    let out = out_dir("bar-figure");
    let o = viscobar(&["run", "impact", "--figure", "--out", out.to_str().unwrap()]);
    let (stdout, stderr) = (
        String::from_utf8_lossy(&o.stdout),
        String::from_utf8_lossy(&o.stderr),
    );
    assert!(o.status.success(), "{stderr}");
    assert!(!stderr.contains("viscobar figures"), "{stderr}");
    for ext in ["png", "svg"] {
        let f = out.join(format!("impact.{ext}"));
        assert!(
            std::fs::metadata(&f).unwrap().len() > 1000,
            "{}",
            f.display()
        );
        assert!(stdout.contains(&format!("impact.{ext}")), "{stdout}");
    }
    assert!(out.join("history.csv").exists());
    let _ = std::fs::remove_dir_all(&out);
}

/// An edge's gap is an expression in `s` and `t`: `x` is refused naming both, a value that is
/// not finite is reported at `s` (and `t`, also when it turns up during the run, nothing
/// written), and an admissibility error prints `u·n = 0`, never `-0`.
#[test]
fn edge_gap_errors_name_s_and_t() {
    let out = out_dir("gap-errors");
    common::assert_each_refused(
        "plane-tilted-drop",
        &[
            (
                "x in a gap",
                &["edges.bottom.gap=\"0.05 + x\""],
                "(allowed: s, t,",
            ),
            (
                "NaN at t = 0",
                &["edges.bottom.gap=\"sqrt(s - 0.5)\""],
                "evaluates to NaN at s = 0, t = 0",
            ),
            (
                "NaN during the run",
                &["edges.bottom.gap=\"0.05 + sqrt(0.5 - t)\""],
                "`edges.bottom.gap` = \"0.05 + sqrt(0.5 - t)\" evaluates to NaN at s = 0, t = 0.505",
            ),
        ],
        &out,
    );
    let o = viscobar(&[
        "run",
        "plane-block-drop",
        "--out",
        out.to_str().unwrap(),
        "--set",
        "edges.bottom.gap=-0.01",
    ]);
    let stderr = String::from_utf8_lossy(&o.stderr);
    assert_eq!(o.status.code(), Some(2), "{stderr}");
    assert!(
        stderr.contains("u·n = 0 at node 0") && !stderr.contains("-0 "),
        "{stderr}"
    );
    assert!(!out.exists());
}

/// A moving obstacle's run writes the obstacle's work as a history column, whose identity
/// closes; a fixed one's history has no such column.
#[test]
fn a_moving_obstacle_adds_the_obstacle_work_column() {
    let out = out_dir("moving");
    let o = viscobar(&[
        "run",
        "plane-tilted-drop",
        "--out",
        out.to_str().unwrap(),
        "--set",
        "edges.bottom.gap=\"0.05 - 0.2*t\"",
    ]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let history = std::fs::read_to_string(out.join("history.csv")).unwrap();
    let header: Vec<&str> = history.lines().next().unwrap().split(',').collect();
    assert_eq!(header[7], "obstacle_work");
    let work: f64 = (history.lines().skip(1))
        .map(|l| l.split(',').nth(7).unwrap().parse::<f64>().unwrap())
        .sum();
    assert!(work > 0.0, "a rising floor does positive work: {work}");
    let _ = std::fs::remove_dir_all(&out);
}

/// README's plane study, as written there: its scene file runs with `--figure` and writes the
/// ParaView files, and `converge` takes it (shortened here: two levels to `t = 0.1`).
#[test]
fn the_readme_plane_study_runs_as_written() {
    let readme =
        std::fs::read_to_string(concat!(env!("CARGO_MANIFEST_DIR"), "/README.md")).unwrap();
    let section = &readme[readme.find("### A plane study, step by step").unwrap()..];
    let start = section.find("```toml\n").unwrap() + "```toml\n".len();
    let toml = &section[start..start + section[start..].find("```").unwrap()];
    let dir = out_dir("readme");
    std::fs::create_dir_all(&dir).unwrap();
    let file = dir.join("study.toml");
    std::fs::write(&file, toml).unwrap();
    let out = dir.join("out");
    let o = viscobar(&[
        "run",
        file.to_str().unwrap(),
        "--out",
        out.to_str().unwrap(),
        "--figure",
    ]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    for f in [
        "solution.pvd",
        "vtu/step-000.vtu",
        "vtu/step-240.vtu",
        "deformed.png",
        "contact-pressure.png",
    ] {
        assert!(out.join(f).exists(), "{f}");
    }
    let history = std::fs::read_to_string(out.join("history.csv")).unwrap();
    assert!(history.lines().next().unwrap().contains(",obstacle_work,"));
    let conv = dir.join("converge");
    let o = viscobar(&[
        "converge",
        file.to_str().unwrap(),
        "--levels",
        "2",
        "--reference-level",
        "2",
        "--solvers",
        "exact",
        "--repeats",
        "0",
        "--set",
        "time.end=0.1",
        "--out",
        conv.to_str().unwrap(),
    ]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    assert!(conv.join("convergence.csv").exists());
    let _ = std::fs::remove_dir_all(&dir);
}
