//! `viscobar run` on plane scenes through the binary: the outputs (and the figure), and bad
//! plane input refused with exit code 2 and a message naming the field, nothing written.

mod common;
use common::viscobar;

use std::path::PathBuf;

// The plane identity's tolerance: in the registry (viscobar_certificate::tolerances), measured
// there.
use viscobar_certificate::tolerances::PLANE_IDENTITY_TOL as IDENTITY_TOL;
/// A drawn figure is more than its headers: the smallest plausible PNG or SVG of a mesh.
const MIN_FIGURE_BYTES: u64 = 1000;
/// Three quotients of one total add up to 1 up to their four roundings (each at most ε/2 of
/// a number at most 1), with a factor 2 to spare.
const PHASE_SUM_TOL: f64 = 4.0 * f64::EPSILON;

fn fresh_dir(name: &str) -> PathBuf {
    common::fresh_dir("plane", name)
}

#[test]
fn run_writes_the_plane_outputs_and_the_figure() {
    let out = fresh_dir("run");
    let o = viscobar(&[
        "run",
        "plane-cantilever",
        "--out",
        out.to_str().unwrap(),
        "--set",
        "time.end=2.0",
        "--set",
        "output.every=20",
        "--figure",
    ]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let stdout = String::from_utf8_lossy(&o.stdout);
    assert!(stdout.contains("plane-cantilever: 40 steps"), "{stdout}");
    let summary: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(out.join("summary.json")).unwrap()).unwrap();
    assert_eq!(summary["steps"], 40);
    assert_eq!(summary["unknowns"], 2 * 64 * 9);
    assert!(summary["max_identity_residual"].as_f64().unwrap() <= IDENTITY_TOL);
    // The bar's phase shares: steps 1 -> 2 ... 39 -> 40 are timed one in 32, from the first
    // (n = 1 and 33).
    let shares = &summary["time_shares"];
    assert_eq!(shares["sampled_steps"], 2, "{shares}");
    let share = |k: &str| shares[k].as_f64().unwrap();
    let parts = ["solver", "rhs", "diagnostics"].map(share);
    assert!(parts.iter().all(|p| (0.0..=1.0).contains(p)), "{shares}");
    assert!(
        (parts.iter().sum::<f64>() - 1.0).abs() <= PHASE_SUM_TOL,
        "{shares}"
    );
    // Measured, not extrapolated: the step loop's share of the run's wall time.
    assert!(
        share("stepping") > 0.0 && share("stepping") <= 1.0,
        "{shares}"
    );
    let history = std::fs::read_to_string(out.join("history.csv")).unwrap();
    assert_eq!(history.lines().count(), 41);
    assert!(history.starts_with(
        "step,t,energy,work,viscous_dissipation,contact_dissipation,identity_residual,iterations\n"
    ));
    let disp = std::fs::read_to_string(out.join("displacement.csv")).unwrap();
    let mut lines = disp.lines();
    assert_eq!(lines.next(), Some("t,x,y,ux,uy,vx,vy"));
    // t = 0, steps 20 and 40: three fields of 65 × 9 nodes.
    assert_eq!(disp.lines().count(), 1 + 3 * 65 * 9);
    let times: std::collections::BTreeSet<&str> =
        lines.map(|l| l.split(',').next().unwrap()).collect();
    assert_eq!(times, ["0", "1", "2"].into_iter().collect());
    for f in ["deformed.png", "deformed.svg"] {
        let len = std::fs::metadata(out.join(f)).unwrap().len();
        assert!(len > MIN_FIGURE_BYTES, "{f}: {len} bytes");
    }
    let _ = std::fs::remove_dir_all(&out);
}

/// (what, --set arguments, text the message must contain)
const CASES: &[(&str, &[&str], &str)] = &[
    ("zero width", &["plane.width=0"], "plane.width"),
    ("nan height", &["plane.height=nan"], "plane.height"),
    ("zero mu", &["plane.mu=0"], "plane.mu"),
    ("lambda + mu <= 0", &["plane.lambda=-0.5"], "plane.lambda"),
    ("negative density", &["plane.density=-1"], "plane.density"),
    (
        "negative viscosity",
        &["plane.viscosity=-0.1"],
        "plane.viscosity",
    ),
    ("zero cells", &["mesh.nx=0"], "mesh.nx"),
    ("negative cells", &["mesh.ny=-3"], "mesh.ny"),
    ("zero grading", &["mesh.y_grading=0"], "mesh.y_grading"),
    (
        "huge mesh",
        &["mesh.nx=100000", "mesh.ny=100000"],
        "mesh.nx",
    ),
    ("step not dividing", &["time.step=0.03"], "time.step"),
    ("unknown key", &["plane.viscocity=1"], "viscocity"),
    (
        "unknown edge condition",
        &["edges.top={ condition = \"sticky\" }"],
        "edges.top.condition",
    ),
    (
        "one component",
        &["initial.displacement=[\"x\"]"],
        "two components",
    ),
    (
        "bad variable",
        &["initial.velocity=[\"0\", \"z\"]"],
        "initial.velocity[1]",
    ),
    (
        "t in initial data",
        &["initial.displacement=[\"t\", \"0\"]"],
        "initial.displacement[0]",
    ),
    (
        "load not finite",
        &["load.density=[\"1/(x-x)\", \"0\"]"],
        "load.density[0]",
    ),
    (
        "unknown solver method",
        &["solver.method=\"simplex\""],
        "solver.method",
    ),
    (
        "a number for a vector",
        &["initial.displacement=0.1"],
        "initial.displacement",
    ),
    (
        "an edge as a word",
        &["edges.left=\"clamped\""],
        "edges.left",
    ),
    (
        "no free node",
        &[
            "mesh.nx=1",
            "edges.left={condition=\"clamped\"}",
            "edges.right={condition=\"clamped\"}",
        ],
        "no node is free",
    ),
];

#[test]
fn bad_plane_input_exits_2_naming_the_field_and_writes_nothing() {
    common::assert_each_refused("plane-strip", CASES, &fresh_dir("bad"));
}

#[test]
fn a_scene_file_with_both_or_neither_table_is_refused() {
    let dir = fresh_dir("files");
    std::fs::create_dir_all(&dir).unwrap();
    let strip = String::from_utf8(viscobar(&["show", "plane-strip"]).stdout).unwrap();
    assert!(strip.contains("[plane]"));
    for (name, text, needle) in [
        ("both", format!("{strip}\n[bar]\nlength = 1.0\n"), "both"),
        (
            "neither",
            "[time]\nstep = 0.1\nend = 1.0\n".to_string(),
            "neither",
        ),
    ] {
        let path = dir.join(format!("{name}.toml"));
        std::fs::write(&path, text).unwrap();
        let out = dir.join(format!("out-{name}"));
        let o = viscobar(&[
            "run",
            path.to_str().unwrap(),
            "--out",
            out.to_str().unwrap(),
        ]);
        let stderr = String::from_utf8_lossy(&o.stderr);
        assert_eq!(o.status.code(), Some(2), "{name}: {stderr}");
        assert!(
            stderr.contains(needle) && stderr.contains("[plane]"),
            "{stderr}"
        );
        assert!(!out.exists());
    }
    // A plane scene file runs like a built-in one.
    let path = dir.join("mine.toml");
    std::fs::write(&path, strip.replace("end = 2.0", "end = 0.1")).unwrap();
    let out = dir.join("out-mine");
    let o = viscobar(&[
        "run",
        path.to_str().unwrap(),
        "--out",
        out.to_str().unwrap(),
    ]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    assert!(String::from_utf8_lossy(&o.stdout).starts_with("mine: 10 steps"));
    // `compare` and `converge` take plane scenes as bar scenes.
    let compared = dir.join("compare");
    let o = viscobar(&[
        "compare",
        path.to_str().unwrap(),
        "--solvers",
        "exact,penalty",
        "--out",
        compared.to_str().unwrap(),
    ]);
    assert!(compared.join("comparison.md").is_file());
    let stdout = String::from_utf8_lossy(&o.stdout);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    assert!(stdout.contains("| penalty vs exact | 10 |"), "{stdout}");
    let conv = dir.join("converge");
    let o = viscobar(&[
        "converge",
        path.to_str().unwrap(),
        "--solvers",
        "exact",
        "--levels",
        "2",
        "--repeats",
        "0",
        "--set",
        "mesh.nx=20",
        "--set",
        "mesh.ny=2",
        "--out",
        conv.to_str().unwrap(),
    ]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let csv = std::fs::read_to_string(conv.join("convergence.csv")).unwrap();
    assert_eq!(csv.lines().count(), 3, "{csv}");
    // The bar-only studies refuse a plane scene, naming it.
    let o = viscobar(&["converge", path.to_str().unwrap(), "--viscosity-sweep"]);
    let stderr = String::from_utf8_lossy(&o.stderr);
    assert_eq!(o.status.code(), Some(2), "{stderr}");
    assert!(stderr.contains("is a plane scene"), "{stderr}");
    let _ = std::fs::remove_dir_all(&dir);
}
