//! `viscobar run` on plane scenes with Signorini edges through the binary: the contact columns
//! and summary, and bad contact input refused with exit code 2 naming the field, nothing
//! written.

use std::path::{Path, PathBuf};
use std::process::Command;

// The plane identity's and gap's tolerances: in the registry (study::tolerances), measured there.
use viscobar::study::tolerances::{PLANE_GAP_TOL as GAP_TOL, PLANE_IDENTITY_TOL as IDENTITY_TOL};

fn viscobar(args: &[&str]) -> std::process::Output {
    Command::new(env!("CARGO_BIN_EXE_viscobar"))
        .args(args)
        .output()
        .expect("binary runs")
}

fn fresh_dir(name: &str) -> PathBuf {
    let d = std::env::temp_dir().join(format!("viscobar-contact-{}-{name}", std::process::id()));
    let _ = std::fs::remove_dir_all(&d);
    d
}

#[test]
fn run_writes_the_contact_columns_and_summary() {
    let out = fresh_dir("run");
    let o = viscobar(&["run", "plane-tilted-drop", "--out", out.to_str().unwrap()]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let summary: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(out.join("summary.json")).unwrap()).unwrap();
    assert!(summary["max_identity_residual"].as_f64().unwrap() <= IDENTITY_TOL);
    let c = &summary["contact"];
    assert_eq!(c["normals"], 17, "the bottom edge's 17 nodes");
    assert_eq!(
        c["max_active"], 17,
        "the block comes to rest on its whole bottom"
    );
    assert!(c["dissipation"].as_f64().unwrap() > 0.0);
    assert!(c["max_penetration"].as_f64().unwrap() <= GAP_TOL);
    assert!(c["max_complementarity"].as_f64().unwrap() <= GAP_TOL * 10.0);
    let history = std::fs::read_to_string(out.join("history.csv")).unwrap();
    let mut lines = history.lines();
    assert_eq!(
        lines.next(),
        Some(
            "step,t,energy,work,viscous_dissipation,identity_residual,contact_dissipation,\
             contact_normals,total_reaction,max_penetration,iterations"
        )
    );
    assert!(lines.all(|l| l.split(',').count() == 11));
    let _ = std::fs::remove_dir_all(&out);
}

const CASES: &[(&str, &[&str], &str)] = &[
    (
        "NaN gap",
        &["edges.bottom={condition=\"signorini\", gap=nan}"],
        "edges.bottom.gap",
    ),
    (
        "gap not finite on the edge",
        &["edges.bottom={condition=\"signorini\", gap=\"1/(s-1)^2\"}"],
        "edges.bottom.gap",
    ),
    (
        "x in a gap",
        &["edges.top={condition=\"signorini\", gap=\"x\"}"],
        "edges.top.gap",
    ),
    (
        "gap on a free edge",
        &["edges.top={condition=\"free\", gap=0.1}"],
        "edges.top.gap",
    ),
    (
        "signorini without gap",
        &["edges.left={condition=\"signorini\"}"],
        "edges.left.gap",
    ),
    (
        "initial state beyond the obstacle",
        &["edges.bottom={condition=\"signorini\", gap=-0.01}"],
        "initial.displacement",
    ),
    (
        "negative gap at a clamped corner",
        &[
            "edges.left={condition=\"clamped\"}",
            "edges.bottom={condition=\"signorini\", gap=\"s - 0.001\"}",
        ],
        "edges.bottom.gap",
    ),
    (
        "too many contact normals",
        &[
            "mesh.nx=3000",
            "mesh.ny=1",
            "edges.bottom={condition=\"signorini\", gap=0.1}",
            "edges.top={condition=\"signorini\", gap=0.1}",
        ],
        "6002 contact normals",
    ),
];

#[test]
fn bad_contact_input_exits_2_naming_the_field_and_writes_nothing() {
    for (what, sets, needle) in CASES {
        let out = fresh_dir("bad");
        let mut args = vec!["run", "plane-strip", "--out", out.to_str().unwrap()];
        for s in *sets {
            args.extend(["--set", s]);
        }
        let o = viscobar(&args);
        let stderr = String::from_utf8_lossy(&o.stderr);
        assert_eq!(o.status.code(), Some(2), "{what}: {stderr}");
        assert!(stderr.contains(needle), "{what}: {stderr}");
        assert!(!Path::new(&out).exists(), "{what}: wrote {}", out.display());
    }
}

/// A drawn figure is more than its headers: the smallest plausible PNG or SVG of a map.
const MIN_FIGURE_BYTES: u64 = 1000;

#[test]
fn run_figure_draws_the_contact_pressure_beside_the_deformed_mesh() {
    let out = fresh_dir("figure");
    let o = viscobar(&[
        "run",
        "plane-curved-obstacle",
        "--out",
        out.to_str().unwrap(),
        "--figure",
    ]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    for f in [
        "deformed.png",
        "deformed.svg",
        "contact-pressure.png",
        "contact-pressure.svg",
    ] {
        let len = std::fs::metadata(out.join(f)).unwrap().len();
        assert!(len > MIN_FIGURE_BYTES, "{f}: {len} bytes");
    }
    let _ = std::fs::remove_dir_all(&out);
}
