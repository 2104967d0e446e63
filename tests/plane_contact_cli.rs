//! `viscobar run` on plane scenes with Signorini edges through the binary: the contact columns
//! and summary, each `[solver]` method bit for bit against the library run of that method, and
//! bad contact or solver input refused with exit code 2 naming the field, nothing written.

mod common;
use common::viscobar;

use std::path::{Path, PathBuf};

// The plane identity's and gap's tolerances: in the registry (viscobar_certificate::tolerances),
// measured there.
use viscobar_certificate::tolerances::{
    PLANE_GAP_TOL as GAP_TOL, PLANE_IDENTITY_TOL as IDENTITY_TOL,
};

fn fresh_dir(name: &str) -> PathBuf {
    common::fresh_dir("contact", name)
}

#[test]
fn run_writes_the_contact_columns_and_summary() {
    let out = fresh_dir("run");
    let o = viscobar(&["run", "plane-tilted-drop", "--out", out.to_str().unwrap()]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let summary: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(out.join("summary.json")).unwrap()).unwrap();
    assert!(summary["max_identity_residual"].as_f64().unwrap() <= IDENTITY_TOL);
    // The bottom edge's episodes; displacements and gaps of order 0.1 here, so round-off is
    // far below GAP_TOL in absolute terms too.
    let episodes = summary["contact_episodes"]["bottom"].as_array().unwrap();
    assert!(!episodes.is_empty());
    let dissipated: f64 = (episodes.iter())
        .map(|e| e["contact_dissipation"].as_f64().unwrap())
        .sum();
    assert!(dissipated > 0.0);
    assert!(summary["max_violation"].as_f64().unwrap() <= GAP_TOL);
    assert!(summary["max_complementarity"].as_f64().unwrap() <= GAP_TOL * 10.0);
    let history = std::fs::read_to_string(out.join("history.csv")).unwrap();
    let mut lines = history.lines();
    assert_eq!(
        lines.next(),
        Some(
            "step,t,energy,work,viscous_dissipation,contact_dissipation,identity_residual,\
             contact_nodes_bottom,contact_s_min_bottom,contact_s_max_bottom,min_gap_bottom,\
             reaction_bottom,iterations"
        )
    );
    let rows: Vec<&str> = lines.collect();
    assert!(rows.iter().all(|l| l.split(',').count() == 13));
    // The block comes to rest on its whole bottom: all 17 nodes in contact.
    let most = (rows.iter())
        .map(|l| l.split(',').nth(7).unwrap().parse::<usize>().unwrap())
        .max();
    assert_eq!(most, Some(17), "the bottom edge's 17 nodes");
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
        "unknown solver method",
        &["solver.method=\"lemke\""],
        "solver.method",
    ),
    (
        "unknown solver key",
        &["solver.colour=1"],
        "unknown field `colour`",
    ),
    (
        "penalty epsilon zero",
        &["solver.method=\"penalty\"", "solver.epsilon=0"],
        "solver.epsilon",
    ),
    (
        "penalty epsilon not finite",
        &["solver.method=\"penalty\"", "solver.epsilon=inf"],
        "solver.epsilon",
    ),
    (
        "osqp eps negative",
        &["solver.method=\"osqp\"", "solver.eps_rel=-1e-9"],
        "solver.eps_rel",
    ),
    (
        "osqp eps both zero",
        &[
            "solver.method=\"osqp\"",
            "solver.eps_abs=0",
            "solver.eps_rel=0",
        ],
        "solver.eps_abs",
    ),
    (
        "osqp max_iter zero",
        &["solver.method=\"osqp\"", "solver.max_iter=0"],
        "solver.max_iter",
    ),
    (
        "epsilon with osqp",
        &["solver.method=\"osqp\"", "solver.epsilon=1e-6"],
        "solver.epsilon",
    ),
    (
        "osqp key with the exact method",
        &["solver.polish=false"],
        "solver.polish",
    ),
    (
        "too many contact normals for the exact step's memory",
        &[
            "mesh.nx=100000",
            "mesh.ny=1",
            "edges.bottom={condition=\"signorini\", gap=0.1}",
            "edges.top={condition=\"signorini\", gap=0.1}",
        ],
        "200002 contact normals",
    ),
];

#[test]
fn bad_contact_input_exits_2_naming_the_field_and_writes_nothing() {
    common::assert_each_refused("plane-strip", CASES, &fresh_dir("bad"));
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

/// Reads `displacement.csv` and `history.csv` of a run: per kept step the `ux, uy, vx, vy`
/// of every node (in node order), and the `energy` column of every step.
fn read_run(out: &Path) -> (Vec<Vec<[f64; 4]>>, Vec<f64>) {
    let disp = std::fs::read_to_string(out.join("displacement.csv")).unwrap();
    let mut kept: Vec<Vec<[f64; 4]>> = Vec::new();
    let mut last_t = String::new();
    for line in disp.lines().skip(1) {
        let cells: Vec<&str> = line.split(',').collect();
        if cells[0] != last_t {
            kept.push(Vec::new());
            last_t = cells[0].to_string();
        }
        let v = [3, 4, 5, 6].map(|k| cells[k].parse::<f64>().unwrap());
        kept.last_mut().unwrap().push(v);
    }
    let hist = std::fs::read_to_string(out.join("history.csv")).unwrap();
    let energy = hist
        .lines()
        .skip(1)
        .map(|l| l.split(',').nth(2).unwrap().parse::<f64>().unwrap())
        .collect();
    (kept, energy)
}

/// The same run in the library with the `[solver]` table `solver` set in code (not read from
/// the scene file or the flags): `ux, uy, vx, vy` at the steps `keep` selects (and `t = 0`),
/// and every step's energy.
fn library_run(
    scene: &viscobar::PlaneScene,
    solver: viscobar::scene::SolverSpec,
) -> (Vec<Vec<[f64; 4]>>, Vec<f64>) {
    use viscobar::plane::PlaneSimulation;
    let mut scene = scene.clone();
    scene.solver = solver;
    let prepared = PlaneSimulation::prepare(&scene).unwrap();
    let nodes = prepared.body().discretisation().grid.nodes();
    let field = |u: &[f64], v: &[f64]| -> Vec<[f64; 4]> {
        (0..nodes)
            .map(|k| [u[2 * k], u[2 * k + 1], v[2 * k], v[2 * k + 1]])
            .collect()
    };
    let (mut u0, mut v0) = (vec![0.0; 2 * nodes], vec![0.0; 2 * nodes]);
    let state = prepared.state();
    prepared.body().scatter_into(state.u, 1.0, &mut u0);
    prepared.body().scatter_into(state.w, state.scale, &mut v0);
    let mut sim = prepared.start().unwrap();
    let mut kept = vec![field(&u0, &v0)];
    let mut energy = vec![sim.first_record().energy];
    let (steps, every) = (scene.steps(), scene.output.every as usize);
    let mut u = vec![0.0; 2 * nodes];
    let mut v = vec![0.0; 2 * nodes];
    for n in 1..=steps {
        if n > 1 {
            energy.push(sim.step().unwrap().energy);
        }
        if n % every == 0 || n == steps {
            sim.displacement_into(&mut u);
            sim.velocity_into(&mut v);
            kept.push(field(&u, &v));
        }
    }
    (kept, energy)
}

fn bits(rows: &[Vec<[f64; 4]>]) -> Vec<u64> {
    rows.iter()
        .flatten()
        .flatten()
        .map(|x| x.to_bits())
        .collect()
}

/// `--set solver.epsilon` of the penalty run (a setting, not a tolerance).
const PENALTY_EPSILON: &str = "1e-7";
/// `--set solver.eps_abs` and `eps_rel` of the OSQP run: not the default, so that the settings
/// are seen to reach OSQP.
const OSQP_EPS: &str = "1e-9";

#[test]
fn each_solver_method_runs_through_the_binary_bit_for_bit_as_in_the_library() {
    use viscobar::scene::{SolverMethod, SolverSpec};
    let eps: f64 = OSQP_EPS.parse().unwrap();
    let epsilon: f64 = PENALTY_EPSILON.parse().unwrap();
    let dir = fresh_dir("methods");
    std::fs::create_dir_all(&dir).unwrap();
    // The penalty through a scene file with a [solver] table, the others through flags.
    let shown = String::from_utf8(viscobar(&["show", "plane-tilted-drop"]).stdout).unwrap();
    assert!(
        shown.contains("[plane]") && !shown.contains("[solver]"),
        "{shown}"
    );
    let file = dir.join("drop-penalty.toml");
    std::fs::write(
        &file,
        format!("{shown}\n[solver]\nmethod = \"penalty\"\nepsilon = {PENALTY_EPSILON}\n"),
    )
    .unwrap();
    let osqp_eps = [
        format!("solver.eps_abs={OSQP_EPS}"),
        format!("solver.eps_rel={OSQP_EPS}"),
    ];
    let runs: [(&str, Vec<&str>, SolverSpec); 3] = [
        ("exact", vec!["plane-tilted-drop"], SolverSpec::default()),
        (
            "osqp",
            vec![
                "plane-tilted-drop",
                "--solver",
                "osqp",
                "--set",
                &osqp_eps[0],
                "--set",
                &osqp_eps[1],
            ],
            SolverSpec {
                method: SolverMethod::Osqp,
                eps_abs: Some(eps),
                eps_rel: Some(eps),
                ..SolverSpec::default()
            },
        ),
        (
            "penalty",
            vec![file.to_str().unwrap()],
            SolverSpec {
                method: SolverMethod::Penalty,
                epsilon: Some(epsilon),
                ..SolverSpec::default()
            },
        ),
    ];
    let scene = match viscobar::scene::load_any("plane-tilted-drop", &[])
        .unwrap()
        .1
    {
        viscobar::scene::AnyScene::Plane(s) => *s,
        _ => unreachable!(),
    };
    let mut all = Vec::new();
    for (name, args, method) in runs {
        let out = dir.join(name);
        let mut a = vec!["run"];
        a.extend(&args);
        a.extend(["--out", out.to_str().unwrap()]);
        let o = viscobar(&a);
        assert!(
            o.status.success(),
            "{name}: {}",
            String::from_utf8_lossy(&o.stderr)
        );
        let summary: serde_json::Value =
            serde_json::from_str(&std::fs::read_to_string(out.join("summary.json")).unwrap())
                .unwrap();
        assert_eq!(summary["solver"], name);
        assert_eq!(summary["audit"].is_object(), name == "osqp", "{name}");
        assert!(
            !summary["contact_episodes"]["bottom"]
                .as_array()
                .unwrap()
                .is_empty(),
            "{name}"
        );
        let (kept, energy) = read_run(&out);
        let (lib_kept, lib_energy) = library_run(&scene, method);
        assert_eq!(kept.len(), lib_kept.len(), "{name}: kept steps");
        assert!(bits(&kept) == bits(&lib_kept), "{name}: u, v differ");
        let e_bits = |e: &[f64]| e.iter().map(|x| x.to_bits()).collect::<Vec<_>>();
        assert!(
            e_bits(&energy) == e_bits(&lib_energy),
            "{name}: energies differ"
        );
        all.push(bits(&kept));
    }
    // The three methods give three different runs (a method ignored would repeat one).
    assert!(all[0] != all[1] && all[0] != all[2] && all[1] != all[2]);
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn without_signorini_edges_the_method_is_named_and_penalty_is_the_exact_step() {
    let dir = fresh_dir("no-edges");
    let mut outs = Vec::new();
    for method in ["exact", "penalty", "osqp"] {
        let out = dir.join(method);
        let o = viscobar(&[
            "run",
            "plane-strip",
            "--solver",
            method,
            "--set",
            "time.end=0.1",
            "--out",
            out.to_str().unwrap(),
        ]);
        assert!(
            o.status.success(),
            "{method}: {}",
            String::from_utf8_lossy(&o.stderr)
        );
        let summary: serde_json::Value =
            serde_json::from_str(&std::fs::read_to_string(out.join("summary.json")).unwrap())
                .unwrap();
        assert_eq!(summary["solver"], method);
        assert!(
            summary["contact_episodes"].as_object().unwrap().is_empty(),
            "{method}"
        );
        // OSQP runs (on the unconstrained problem, as the bar's does) and is audited.
        assert_eq!(
            summary["audit"]["steps"].as_u64().is_some(),
            method == "osqp"
        );
        outs.push(std::fs::read(out.join("displacement.csv")).unwrap());
    }
    // No contact normal: the penalty's step is the exact one, byte for byte; OSQP's ADMM
    // answer is not.
    assert!(outs[0] == outs[1]);
    assert!(outs[0] != outs[2]);
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn an_osqp_failure_exits_1_naming_the_step_and_writes_nothing() {
    let out = fresh_dir("osqp-fails");
    let o = viscobar(&[
        "run",
        "plane-tilted-drop",
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
