//! Contact at scale: the exact step refuses a scene only when its dense `S` would not fit in
//! memory (naming `m` and the bytes); OSQP and the penalty law take any number of normals, the
//! penalty beyond `PENALTY_CONDENSED_MAX_NORMALS` by the sparse Newton iteration, which agrees
//! with the condensed law.

use viscobar::output::run_plane_in_memory;
use viscobar::scene::plane::{PENALTY_CONDENSED_MAX_NORMALS, PlaneScene, plane_builtin_text};
use viscobar_certificate::solvers::scale::{EPSILONS, sparse_penalty_agreement};
use viscobar_certificate::tolerances::{PLANE_IDENTITY_TOL, SPARSE_PENALTY_AGREEMENT_TOL};

fn strip(overrides: &[&str]) -> PlaneScene {
    let text = plane_builtin_text("plane-strip").unwrap();
    let all: Vec<String> = overrides.iter().map(|s| s.to_string()).collect();
    PlaneScene::from_toml(text, &all).unwrap()
}

/// 200 002 normals: the exact step's `S` would take 16 m² bytes, 640 GB; refused naming `m`
/// and the bytes. The same scene is accepted with the penalty law and with OSQP.
#[test]
fn the_exact_step_is_refused_only_beyond_memory() {
    let text = plane_builtin_text("plane-strip").unwrap();
    let big = [
        "mesh.nx=100000".to_string(),
        "mesh.ny=1".into(),
        "edges.bottom={condition=\"signorini\", gap=0.1}".into(),
        "edges.top={condition=\"signorini\", gap=0.1}".into(),
    ];
    let e = PlaneScene::from_toml(text, &big).unwrap_err().to_string();
    assert!(
        e.contains("200002 contact normals") && e.contains("640012800064 bytes"),
        "{e}"
    );
    for method in ["penalty", "osqp"] {
        let mut with = big.to_vec();
        with.push(format!("solver.method=\"{method}\""));
        assert!(PlaneScene::from_toml(text, &with).is_ok(), "{method}");
    }
    // 6002 normals fit: accepted for the exact step.
    let mut fits = big.to_vec();
    fits[0] = "mesh.nx=3000".into();
    assert!(PlaneScene::from_toml(text, &fits).is_ok());
}

/// A strip on 4400 × 1 cells lying on a floor it is pushed into (4401 normals, beyond the
/// condensed switch) runs with the penalty law and with OSQP; the contact is real and the
/// energy identity closes.
#[test]
fn penalty_and_osqp_take_more_normals_than_the_condensed_switch() {
    let base = [
        "mesh.nx=4400",
        "mesh.ny=1",
        "plane.width=44.0",
        "time.end=0.03",
        "initial.displacement=[\"0\", \"0\"]",
        "initial.velocity=[\"0\", \"-1\"]",
        "edges.bottom={condition=\"signorini\", gap=0.005}",
    ];
    for method in ["penalty", "osqp"] {
        let mut set = base.to_vec();
        let m = format!("solver.method=\"{method}\"");
        set.push(&m);
        let scene = strip(&set);
        assert!(scene.contact_normals() > PENALTY_CONDENSED_MAX_NORMALS);
        let (records, summary, _) = run_plane_in_memory("wide", &scene).unwrap();
        assert_eq!(summary.solver, method);
        let last = records.last().unwrap();
        assert!(last.contact.total_reaction > 0.0, "{method}: {last:?}");
        for r in records.iter().skip(1) {
            assert!(r.identity_residual <= PLANE_IDENTITY_TOL, "{method}: {r:?}");
        }
    }
}

/// The sparse Newton iteration and the condensed LCP on `S + εI` solve the same penalty law:
/// on the tilted drop's step matrix, a sequence of right-hand sides that press a growing part
/// of the bottom edge into the floor, the same `z` and reactions to round-off.
#[test]
fn the_sparse_penalty_agrees_with_the_condensed_one() {
    for epsilon in EPSILONS {
        let worst = sparse_penalty_agreement(epsilon).unwrap();
        println!("ε = {epsilon:e}: worst relative difference {worst:e}");
        assert!(
            worst <= SPARSE_PENALTY_AGREEMENT_TOL,
            "ε = {epsilon}: {worst}"
        );
    }
}
