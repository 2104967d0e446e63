//! The `viscobar` command line: outputs of `run`, listing and showing scenes, and refusal of
//! bad input with exit code 2 and a message naming the problem.

use std::path::Path;
use std::process::Command;

fn viscobar(args: &[&str]) -> std::process::Output {
    Command::new(env!("CARGO_BIN_EXE_viscobar"))
        .args(args)
        .output()
        .expect("binary runs")
}

fn tmpdir(name: &str) -> std::path::PathBuf {
    let d = std::env::temp_dir().join(format!("viscobar-cli-{}-{name}", std::process::id()));
    let _ = std::fs::remove_dir_all(&d);
    d
}

#[test]
fn run_writes_summary_history_and_displacement() {
    let out = tmpdir("run");
    let o = viscobar(&[
        "run",
        "impact",
        "--out",
        out.to_str().unwrap(),
        "--set",
        "time.end=0.5",
    ]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let summary: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(out.join("summary.json")).unwrap()).unwrap();
    for key in [
        "scene",
        "solver",
        "nodes",
        "dt",
        "steps",
        "wall_time_s",
        "ns_per_node_step",
        "energy_initial",
        "energy_final",
        "max_energy_rise",
        "max_identity_residual",
        "max_complementarity",
        "max_violation",
        "contact_intervals",
        "solver_iterations",
    ] {
        assert!(summary.get(key).is_some(), "summary.json lacks {key}");
    }
    assert_eq!(summary["steps"], 50);
    let history = std::fs::read_to_string(out.join("history.csv")).unwrap();
    let mut lines = history.lines();
    assert_eq!(
        lines.next().unwrap(),
        "step,t,energy,work,viscous_dissipation,contact_dissipation,identity_residual,gap_left,reaction_left,iterations"
    );
    assert_eq!(lines.count(), 50, "one row per step");
    let disp = std::fs::read_to_string(out.join("displacement.csv")).unwrap();
    assert_eq!(disp.lines().next().unwrap(), "t,x,u,v");
    // Kept steps: t = 0, every 5th step and the last; 101 nodes each.
    assert_eq!(disp.lines().count() - 1, 101 * (1 + 10));
    assert!(
        !out.read_dir()
            .unwrap()
            .any(|e| e.unwrap().file_name().to_string_lossy().starts_with('.'))
    );
}

#[test]
fn scenes_and_show_list_the_builtins() {
    let o = viscobar(&["scenes"]);
    assert!(o.status.success());
    let text = String::from_utf8_lossy(&o.stdout);
    for name in viscobar::scene::builtin_names() {
        assert!(text.contains(name), "`scenes` lacks {name}");
        let shown = viscobar(&["show", name]);
        assert!(shown.status.success());
        let toml = String::from_utf8_lossy(&shown.stdout);
        viscobar::Scene::from_toml(&toml, &[]).expect("`show` prints a valid scene");
    }
}

#[test]
fn bad_input_exits_with_2_and_names_the_problem() {
    let dir = tmpdir("bad");
    std::fs::create_dir_all(&dir).unwrap();
    let base = viscobar::scene::builtin_text("impact").unwrap();
    let cases: &[(&str, &[&str], &str)] = &[
        ("negative step", &["--set", "time.step=-0.01"], "time.step"),
        ("nan step", &["--set", "time.step=nan"], "time.step"),
        (
            "negative viscosity",
            &["--set", "bar.viscosity=-1"],
            "bar.viscosity",
        ),
        ("negative gap", &["--set", "left.gap=-0.1"], "left.gap"),
        (
            "zero elements",
            &["--set", "mesh.elements=0"],
            "mesh.elements",
        ),
        ("typo key", &["--set", "bar.viscocity=0.1"], "viscocity"),
        (
            "bad expression",
            &["--set", "initial.velocity=\"-1*(\""],
            "initial.velocity",
        ),
        (
            "unknown variable",
            &["--set", "initial.velocity=\"y\""],
            "unknown variable",
        ),
        (
            "below obstacle",
            &["--set", "initial.displacement=\"-0.5\""],
            "node 0",
        ),
        (
            "bad condition",
            &["--set", "right.condition=\"glued\""],
            "glued",
        ),
        ("not key=value", &["--set", "time.step"], "key=value"),
    ];
    for (what, args, needle) in cases {
        let scene = dir.join("impact.toml");
        std::fs::write(&scene, base).unwrap();
        let mut all = vec![
            "run",
            scene.to_str().unwrap(),
            "--out",
            dir.to_str().unwrap(),
        ];
        all.extend_from_slice(args);
        let o = viscobar(&all);
        let err = String::from_utf8_lossy(&o.stderr);
        assert_eq!(o.status.code(), Some(2), "{what}: exit code, stderr: {err}");
        assert!(
            err.contains(needle),
            "{what}: message should name `{needle}`: {err}"
        );
        assert!(
            !Path::new(&dir.join("summary.json")).exists(),
            "{what}: no result written"
        );
    }
    let o = viscobar(&["run", "no-such-scene"]);
    assert_eq!(o.status.code(), Some(2));
    assert!(String::from_utf8_lossy(&o.stderr).contains("no-such-scene"));
}
