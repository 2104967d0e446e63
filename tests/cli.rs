//! The `viscobar` command line: outputs of `run`, listing and showing scenes (bad input is in
//! `bad_input.rs`).

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

/// `viscobar scenes`: one entry per built-in scene, its name in a column as wide as the longest
/// name, then the first sentence of its description whole (continuation lines indented to the
/// description column).
#[test]
fn scenes_lists_every_builtin_with_a_whole_first_sentence() {
    let o = viscobar(&["scenes"]);
    assert!(o.status.success());
    let text = String::from_utf8_lossy(&o.stdout);
    let names = viscobar::scene::builtin_names();
    let longest = names.iter().map(|n| n.len()).max().unwrap();
    let indent = |line: &str| line.len() - line.trim_start().len();
    // Entries: a line starting with a name, then its indented continuation lines; every
    // description line starts in the same column, right of the longest name.
    let mut entries: Vec<(String, String)> = Vec::new();
    let mut columns = Vec::new();
    for line in text.lines() {
        if line.starts_with(' ') {
            let (_, description) = entries.last_mut().expect("a name line comes first");
            columns.push(indent(line));
            description.push(' ');
            description.push_str(line.trim());
        } else {
            let (name, rest) = line.split_once(' ').expect("name and description");
            columns.push(name.len() + 1 + indent(rest));
            entries.push((name.to_string(), rest.trim().to_string()));
        }
    }
    assert!(
        columns.iter().all(|c| *c == columns[0] && *c > longest),
        "descriptions not in one column right of the longest name:\n{text}"
    );
    let listed: Vec<&str> = entries.iter().map(|(n, _)| n.as_str()).collect();
    assert_eq!(listed, names);
    for (name, description) in &entries {
        assert!(
            description.ends_with('.') || description.ends_with(')'),
            "{name}: description cut mid-sentence: {description:?}"
        );
        let full = viscobar::Scene::from_toml(viscobar::scene::builtin_text(name).unwrap(), &[])
            .unwrap()
            .description
            .unwrap();
        let full = full.split_whitespace().collect::<Vec<_>>().join(" ");
        assert!(
            full.starts_with(description.as_str()),
            "{name}: not the description's opening: {description:?}"
        );
    }
}

/// The positional arguments a newcomer meets first are described in `--help`.
#[test]
fn help_describes_the_scene_arguments() {
    for (command, argument) in [
        ("run", "<SCENE>"),
        ("converge", "<SCENE>"),
        ("show", "<NAME>"),
    ] {
        let o = viscobar(&[command, "--help"]);
        assert!(o.status.success());
        let help = String::from_utf8_lossy(&o.stdout);
        let line = help
            .lines()
            .find(|l| l.trim_start().starts_with(argument))
            .unwrap_or_else(|| panic!("`{command} --help` lists no {argument}: {help}"));
        assert!(
            line.contains("viscobar scenes"),
            "`{command} --help` does not describe {argument}: {help}"
        );
    }
    let run = String::from_utf8_lossy(&viscobar(&["run", "--help"]).stdout).into_owned();
    assert!(run.contains("TOML scene file"), "{run}");
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

/// Summary fields that measure the machine, not the numerics: the only content allowed to
/// differ between two runs.
const TIMING_FIELDS: [&str; 3] = ["wall_time_s", "ns_per_node_step", "time_shares"];

#[test]
fn two_runs_give_byte_identical_outputs() {
    let (a, b) = (tmpdir("det-a"), tmpdir("det-b"));
    for d in [&a, &b] {
        let o = viscobar(&[
            "run",
            "both-ends-forced",
            "--out",
            d.to_str().unwrap(),
            "--set",
            "time.end=3",
        ]);
        assert!(o.status.success());
    }
    for file in ["history.csv", "displacement.csv"] {
        assert!(
            std::fs::read(a.join(file)).unwrap() == std::fs::read(b.join(file)).unwrap(),
            "{file} differs"
        );
    }
    let strip = |d: &std::path::Path| {
        let mut v: serde_json::Value =
            serde_json::from_str(&std::fs::read_to_string(d.join("summary.json")).unwrap())
                .unwrap();
        for f in TIMING_FIELDS {
            v.as_object_mut()
                .unwrap()
                .remove(f)
                .expect("timing field present");
        }
        v
    };
    assert_eq!(strip(&a), strip(&b));
}

/// The crates only the command line, its progress bar and the figures need: optional, so that
/// a library user depending on viscobar with `default-features = false` builds none of them.
const OPTIONAL_CRATES: [&str; 5] = ["clap", "indicatif", "plotters", "plotters-svg", "dejavu"];

/// The normal dependencies of the library, as `cargo tree` lists them, with `extra` flags.
fn dependency_names(extra: &[&str]) -> Vec<String> {
    let cargo = std::env::var("CARGO").unwrap_or_else(|_| "cargo".into());
    let manifest = concat!(env!("CARGO_MANIFEST_DIR"), "/Cargo.toml");
    let o = Command::new(cargo)
        .args([
            "tree",
            "--offline",
            "--manifest-path",
            manifest,
            "-p",
            "viscobar",
        ])
        .args(["-e", "normal", "--prefix", "none"])
        .args(extra)
        .output()
        .expect("cargo runs");
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    String::from_utf8_lossy(&o.stdout)
        .lines()
        .filter_map(|l| l.split_whitespace().next().map(str::to_string))
        .collect()
}

#[test]
fn without_default_features_the_library_needs_no_cli_or_plotting_crate() {
    let full = dependency_names(&[]);
    let bare = dependency_names(&["--no-default-features"]);
    for name in OPTIONAL_CRATES {
        assert!(full.iter().any(|n| n == name), "{name} is not a dependency");
        assert!(!bare.iter().any(|n| n == name), "{name} is not optional");
    }
    assert!(bare.iter().any(|n| n == "nalgebra"), "{bare:?}");
}
