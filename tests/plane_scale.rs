//! Contact at scale: the exact step refuses a scene only when its dense `S` would not fit in
//! memory (naming `m` and the bytes); OSQP and the penalty law take any number of normals, the
//! penalty beyond `PENALTY_CONDENSED_MAX_NORMALS` by the sparse Newton iteration, which agrees
//! with the condensed law (runs beyond the switch: the solver checker, tests/solvers.rs).

use viscobar::scene::plane::{PlaneScene, plane_builtin_text};
use viscobar_certificate::solvers::scale::{EPSILONS, sparse_penalty_agreement};
use viscobar_certificate::tolerances::SPARSE_PENALTY_AGREEMENT_TOL;

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
