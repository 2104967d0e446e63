//! Bad input is refused with exit code 2 and a message naming the problem; failures during a
//! run exit with 1 and name the step; nothing is written for either, and an earlier good result
//! in the output folder survives a failed rerun.

mod common;
use common::viscobar;

use std::path::{Path, PathBuf};

fn fresh_dir(name: &str) -> PathBuf {
    let d = common::fresh_dir("bad", name);
    std::fs::create_dir_all(&d).unwrap();
    d
}

/// (what, scene text edit or --set arguments, text the message must contain)
enum Edit {
    Set(&'static [&'static str]),
    /// Replace the first occurrence of `.0` by `.1` in the impact scene's TOML text.
    Replace(&'static str, &'static str),
}

const CASES: &[(&str, Edit, &str)] = &[
    (
        "negative step",
        Edit::Set(&["time.step=-0.01"]),
        "time.step",
    ),
    ("zero step", Edit::Set(&["time.step=0"]), "time.step"),
    ("nan step", Edit::Set(&["time.step=nan"]), "time.step"),
    ("infinite step", Edit::Set(&["time.step=inf"]), "time.step"),
    ("negative end", Edit::Set(&["time.end=-3"]), "time.end"),
    (
        "end shorter than a step",
        Edit::Set(&["time.end=0.001"]),
        "time.end",
    ),
    (
        "absurd step count",
        Edit::Set(&["time.step=1e-12"]),
        "time.end",
    ),
    ("zero length", Edit::Set(&["bar.length=0"]), "bar.length"),
    ("nan length", Edit::Set(&["bar.length=nan"]), "bar.length"),
    (
        "negative viscosity",
        Edit::Set(&["bar.viscosity=-1"]),
        "bar.viscosity",
    ),
    (
        "infinite viscosity",
        Edit::Set(&["bar.viscosity=inf"]),
        "bar.viscosity",
    ),
    ("negative gap", Edit::Set(&["left.gap=-0.1"]), "left.gap"),
    ("nan gap", Edit::Set(&["left.gap=nan"]), "left.gap"),
    (
        "gap on a free end",
        Edit::Set(&["right.gap=0.1"]),
        "right.gap",
    ),
    (
        "signorini without gap",
        Edit::Replace("gap = 0.1\n", ""),
        "left.gap",
    ),
    (
        "zero elements",
        Edit::Set(&["mesh.elements=0"]),
        "mesh.elements",
    ),
    (
        "negative elements",
        Edit::Set(&["mesh.elements=-5"]),
        "mesh.elements",
    ),
    (
        "fractional elements",
        Edit::Set(&["mesh.elements=10.5"]),
        "mesh.elements",
    ),
    (
        "more memory than the machine has",
        Edit::Set(&["mesh.elements=99000000", "time.step=1"]),
        "GiB",
    ),
    (
        "gap on a clamped end",
        Edit::Set(&["left.condition=\"clamped\""]),
        "only a signorini end has a gap",
    ),
    (
        "typo in a key",
        Edit::Set(&["bar.viscocity=0.1"]),
        "viscocity",
    ),
    (
        "unknown section",
        Edit::Set(&["solvr.method=\"exact\""]),
        "solvr",
    ),
    (
        "unknown condition",
        Edit::Set(&["right.condition=\"glued\""]),
        "glued",
    ),
    (
        "unknown matrices",
        Edit::Set(&["bar.matrices=\"lumped\""]),
        "lumped",
    ),
    ("unknown mass", Edit::Set(&["bar.mass=\"heavy\""]), "heavy"),
    (
        "mass variant with the talk's printed matrices",
        Edit::Set(&["bar.mass=\"lumped\"", "bar.matrices=\"talk-printed\""]),
        "`bar.matrices` = \"talk-printed\"",
    ),
    (
        "redistributed mass with an obstacle",
        Edit::Set(&["bar.mass=\"redistributed\"", "obstacle.gap=0.2"]),
        "`obstacle.gap`",
    ),
    (
        "redistributed mass on too short a bar",
        Edit::Set(&["bar.mass=\"redistributed\"", "mesh.elements=2"]),
        "must be at least 3 with `bar.mass`",
    ),
    (
        "unknown solver",
        Edit::Set(&["solver.method=\"magic\""]),
        "magic",
    ),
    (
        "wrong type",
        Edit::Set(&["mesh.elements=\"many\""]),
        "mesh.elements",
    ),
    ("--set without =", Edit::Set(&["time.step"]), "key=value"),
    (
        "--set key without section",
        Edit::Set(&["step=0.1"]),
        "section.field",
    ),
    (
        "unparsable expression",
        Edit::Set(&["initial.velocity=\"-1*(\""]),
        "initial.velocity",
    ),
    (
        "unknown variable",
        Edit::Set(&["initial.velocity=\"y\""]),
        "unknown variable `y`",
    ),
    (
        "t in initial data",
        Edit::Set(&["initial.displacement=\"t\""]),
        "initial.displacement",
    ),
    (
        "NaN in the load",
        Edit::Set(&["load.density=\"sqrt(x-0.5)\""]),
        "x = 0",
    ),
    (
        "infinite load at t = 1",
        Edit::Set(&["load.density=\"1/(t-1)\""]),
        "t = 1",
    ),
    (
        "initial state below the obstacle",
        Edit::Set(&["initial.displacement=\"-0.5\""]),
        "node 0 (x = 0)",
    ),
    (
        "clamped end not at rest",
        Edit::Set(&["right.condition=\"clamped\"", "initial.displacement=\"x\""]),
        "clamped right end",
    ),
    (
        "invalid TOML",
        Edit::Replace("[mesh]", "[mesh"),
        "not valid",
    ),
    (
        "zero output stride",
        Edit::Set(&["output.every=0"]),
        "output.every",
    ),
    (
        "zero diagnostics stride",
        Edit::Set(&["output.diagnostics_every=0"]),
        "output.diagnostics_every",
    ),
];

#[test]
fn bad_scenes_exit_2_and_name_the_problem() {
    assert!(CASES.len() >= 30);
    let base = viscobar::scene::builtin_text("impact").unwrap();
    for (what, edit, needle) in CASES {
        let dir = fresh_dir("case");
        let scene = dir.join("impact.toml");
        let out = dir.join("out");
        let mut args = vec![
            "run".to_string(),
            scene.display().to_string(),
            "--out".into(),
            out.display().to_string(),
        ];
        let text = match edit {
            Edit::Set(sets) => {
                for s in *sets {
                    args.push("--set".into());
                    args.push(s.to_string());
                }
                base.to_string()
            }
            Edit::Replace(a, b) => base.replacen(a, b, 1),
        };
        std::fs::write(&scene, text).unwrap();
        let args: Vec<&str> = args.iter().map(String::as_str).collect();
        let o = viscobar(&args);
        let err = String::from_utf8_lossy(&o.stderr);
        assert_eq!(o.status.code(), Some(2), "{what}: exit code; stderr: {err}");
        assert!(
            err.contains(needle),
            "{what}: message should contain `{needle}`: {err}"
        );
        assert!(!err.contains("panicked"), "{what}: panic: {err}");
        assert!(!out.exists(), "{what}: the output folder was created");
    }
}

/// A scene whose initial data cannot be evaluated (NaN on the whole bar) passes the checks of
/// its TOML and is refused while the run is set up: nothing may be created then, not even an
/// empty output folder, and no folder above it.
#[test]
fn a_scene_refused_during_set_up_creates_nothing() {
    let dir = fresh_dir("set-up");
    let scene = dir.join("nan-start.toml");
    let base = viscobar::scene::builtin_text("impact").unwrap();
    let text = base.replacen("displacement = \"0\"", "displacement = \"sqrt(x-100)\"", 1);
    assert_ne!(text, base, "the edit applies");
    std::fs::write(&scene, text).unwrap();
    let out = dir.join("results").join("nan-start");
    let o = viscobar(&[
        "run",
        scene.to_str().unwrap(),
        "--out",
        out.to_str().unwrap(),
    ]);
    let err = String::from_utf8_lossy(&o.stderr);
    assert_eq!(o.status.code(), Some(2), "{err}");
    assert!(err.contains("initial.displacement"), "{err}");
    assert!(!err.contains("panicked"), "{err}");
    assert!(!dir.join("results").exists(), "created {}", out.display());
}

/// A run that fails at a step (exit 1) into a folder that did not exist removes the folders it
/// created; what was there before stays.
#[test]
fn a_failed_run_into_a_new_folder_leaves_no_folder() {
    let dir = fresh_dir("new-folder");
    let out = dir.join("a").join("b");
    let o = viscobar(&[
        "run",
        "impact",
        "--out",
        out.to_str().unwrap(),
        "--set",
        "load.density=\"1e300*t*t\"",
    ]);
    let err = String::from_utf8_lossy(&o.stderr);
    assert_eq!(o.status.code(), Some(1), "{err}");
    assert!(!dir.join("a").exists(), "left {}", dir.join("a").display());
    assert!(dir.exists());
}

#[test]
fn unknown_scene_name_exits_2() {
    let o = viscobar(&["run", "no-such-scene"]);
    assert_eq!(o.status.code(), Some(2));
    assert!(String::from_utf8_lossy(&o.stderr).contains("no-such-scene"));
}

fn snapshot(dir: &Path) -> Vec<(String, Vec<u8>)> {
    let mut files: Vec<(String, Vec<u8>)> = std::fs::read_dir(dir)
        .unwrap()
        .map(|e| {
            let e = e.unwrap();
            (
                e.file_name().to_string_lossy().into_owned(),
                std::fs::read(e.path()).unwrap(),
            )
        })
        .collect();
    files.sort();
    files
}

#[test]
fn a_failed_run_exits_1_names_the_step_and_keeps_the_earlier_result() {
    let dir = fresh_dir("keep");
    let out = dir.to_str().unwrap();
    let ok = viscobar(&["run", "impact", "--out", out, "--set", "time.end=0.5"]);
    assert!(ok.status.success());
    let before = snapshot(&dir);
    // The load overflows f64 at the second step: a run-time failure, not bad input.
    let failed = viscobar(&[
        "run",
        "impact",
        "--out",
        out,
        "--set",
        "load.density=\"1e300*t*t\"",
    ]);
    let err = String::from_utf8_lossy(&failed.stderr);
    assert_eq!(failed.status.code(), Some(1), "{err}");
    assert!(err.contains("step 2") && err.contains("exact"), "{err}");
    assert_eq!(
        snapshot(&dir),
        before,
        "the earlier result must survive, and nothing else appear"
    );
}

#[test]
fn a_rerun_removes_what_an_interrupted_run_left_behind() {
    let dir = fresh_dir("interrupted");
    // What a run killed mid-way leaves: its hidden temporary folder with half-written files.
    // PID 0 is never a user process, so the folder cannot belong to a running viscobar.
    let stale = dir.join(".viscobar-partial-0");
    std::fs::create_dir_all(&stale).unwrap();
    std::fs::write(stale.join("history.csv"), "step,t\n1,").unwrap();
    let o = viscobar(&[
        "run",
        "impact",
        "--out",
        dir.to_str().unwrap(),
        "--set",
        "time.end=0.2",
    ]);
    assert!(o.status.success());
    let names: Vec<String> = snapshot(&dir).into_iter().map(|(n, _)| n).collect();
    assert_eq!(names, ["displacement.csv", "history.csv", "summary.json"]);
}
