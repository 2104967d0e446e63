//! Coulomb friction on the plane body's edges: `μ = 0` bit for bit against the frictionless
//! runs, the rigid-limit closed forms (self tested) approached as the block stiffens, the
//! frictional drop's convergence against a finer exact run, and friction as a field of `s` (a
//! constant expression has the number's bits, a field zero at every node is no friction, bad
//! fields are refused naming the key and `s`, Coulomb's law holds node by node with each node's
//! `μ`). The identity with `D_f`, the momentum balance, the audit and OSQP's Tresca fixed point
//! are the solver checker's, tests/solvers.rs. Run in release; the full convergence study is `#[ignore]`d (README,
//! "Friction").

use viscobar::RunError;
use viscobar::plane::PlaneSimulation;
use viscobar::scene::plane::{PlaneScene, plane_builtin_text};
use viscobar::scheme::NodeState;
use viscobar_certificate::friction::rigid::*;
use viscobar_certificate::friction::*;

// The tolerances of this file: in the registry (viscobar_certificate::tolerances), which measures
// their worst values (`viscobar-certificate verify --tolerances`).
use viscobar_certificate::tolerances::{
    RIGID_LIMIT_BOUND, RIGID_SELF_TEST_TOL, STICK_VELOCITY_BOUND, STOP_TIME_BOUND,
    rigid_limit_worst,
};

#[test]
fn zero_friction_reproduces_every_frictionless_contact_run_bit_for_bit() {
    let cases = mu_zero_cases().unwrap();
    // The three frictionless contact scenes and the three friction scenes.
    assert!(cases.len() >= 6, "{cases:?}");
    for c in &cases {
        assert!(c.identical, "{}: friction = 0 changed the run", c.name);
    }
}

/// The observed rate `log10(e(1e3) / e(1e5)) / 2` of the rigid-limit errors against the
/// stiffness: measured 0.95 to 0.97 (VERIFICATION.md, "Plane friction"; elastic transients of
/// order 1/κ); the band is those ± 0.2.
const RIGID_RATE_BAND: (f64, f64) = (0.75, 1.17);

#[test]
fn the_rigid_limit_closed_forms_are_approached_as_the_block_stiffens() {
    let self_test = closed_form_self_test().unwrap();
    assert!(
        self_test.iter().all(|d| *d <= RIGID_SELF_TEST_TOL),
        "{self_test:?}"
    );
    let rows = rigid_table().unwrap();
    for r in &rows {
        eprintln!("{r:?}");
    }
    let (limit, stick) = rigid_limit_worst(&rows);
    assert!(limit <= RIGID_LIMIT_BOUND, "{limit:e}");
    assert!(stick <= STICK_VELOCITY_BOUND, "{stick:e}");
    for r in rows.iter().filter(|r| r.stiffness >= 100.0) {
        assert!(r.stop_error <= STOP_TIME_BOUND, "{r:?}");
    }
    let errors: [fn(&RigidRow) -> f64; 2] = [|r| r.slope_error, |r| r.distance_error];
    for e in errors {
        // Every stiffening brings the block closer to the rigid motion.
        assert!(rows.windows(2).all(|w| e(&w[1]) < e(&w[0])), "{rows:?}");
        let at = |k: f64| e(rows.iter().find(|r| r.stiffness == k).unwrap());
        let rate = (at(1e3) / at(1e5)).log10() / 2.0;
        assert!(
            (RIGID_RATE_BAND.0..=RIGID_RATE_BAND.1).contains(&rate),
            "rate {rate}"
        );
    }
}

/// Observed order of the frictional drop's max nodal error, levels 0 and 1 against level 2:
/// measured 1.72 (VERIFICATION.md gives the study against level 3 too, 1.10 and 1.37: the
/// coarse reference overstates the order); the band is the measured value ± 0.25.
const FRICTION_ORDER_BAND: (f64, f64) = (1.47, 1.97);

#[test]
fn the_frictional_drop_converges_against_a_finer_exact_run() {
    let levels = convergence().unwrap();
    let orders = viscobar_certificate::plane::contact::orders(&levels);
    assert_eq!(orders.len(), 1);
    for p in orders {
        assert!(
            (FRICTION_ORDER_BAND.0..=FRICTION_ORDER_BAND.1).contains(&p),
            "order {p}: {levels:?}"
        );
    }
}

/// The full study of VERIFICATION.md (levels 0, 1, 2 against level 3; about 25 s): orders
/// measured 1.10 and 1.37; the band is those ± 0.3.
const FRICTION_ORDER_FULL_BAND: (f64, f64) = (0.8, 1.67);

#[test]
#[ignore = "about 25 s: cargo test --release --test plane_coulomb_friction -- --ignored"]
fn the_frictional_drop_converges_on_three_levels_against_level_3() {
    let levels = full_convergence().unwrap();
    for p in viscobar_certificate::plane::contact::orders(&levels) {
        assert!(
            (FRICTION_ORDER_FULL_BAND.0..=FRICTION_ORDER_FULL_BAND.1).contains(&p),
            "order {p}: {levels:?}"
        );
    }
}

/// The tilted drop with `overrides`, set up (`Err`: the exit code and the message).
fn friction_scene(overrides: &[&str]) -> Result<PlaneSimulation, (i32, String)> {
    let text = plane_builtin_text("plane-friction-tilted-drop").unwrap();
    let mut all = vec!["time.end=0.3".to_string()];
    all.extend(overrides.iter().map(|s| s.to_string()));
    let refused = |e: RunError| (e.exit_code(), e.to_string());
    let scene = PlaneScene::from_toml(text, &all).map_err(|e| refused(e.into()))?;
    PlaneSimulation::new(&scene).map_err(refused)
}

/// The records' bits and the final displacement's of `overrides`' run.
fn run_bits(overrides: &[&str]) -> (Vec<[u64; 4]>, Vec<u64>) {
    let mut sim = friction_scene(overrides).unwrap();
    let mut records = Vec::new();
    for _ in 1..60 {
        let r = sim.step().unwrap();
        records.push(
            [
                r.energy,
                r.friction_dissipation,
                r.contact.total_reaction,
                r.identity_residual,
            ]
            .map(f64::to_bits),
        );
    }
    (records, sim.state().u.iter().map(|v| v.to_bits()).collect())
}

/// A number and the same constant written as an expression (a string, a quotient, a sum with
/// `0*s`) give the same bits.
#[test]
fn a_constant_friction_expression_runs_to_the_bits_of_the_number() {
    let number = run_bits(&["edges.bottom.friction=0.3"]);
    for text in ["\"0.3\"", "\"3/10\"", "\"0.3 + 0*s\""] {
        let set = format!("edges.bottom.friction={text}");
        assert!(run_bits(&[&set]) == number, "{text}");
    }
}

/// An expression that is zero at every node of the edge is no key, as `friction = 0` is: the
/// penalty method accepts it and the run has the bits of the frictionless one; an expression
/// positive at one node only makes the step frictional (penalty refused, naming the edge).
#[test]
fn a_friction_zero_at_every_node_is_no_friction() {
    for solver in ["exact", "penalty"] {
        let method = format!("solver.method=\"{solver}\"");
        let none = run_bits(&["edges.bottom={condition=\"signorini\", gap=0.05}", &method]);
        for text in ["0", "\"0*s\"", "\"0.3*(s > 2)\""] {
            let set = format!("edges.bottom.friction={text}");
            assert!(run_bits(&[&set, &method]) == none, "{text}, {solver}");
        }
    }
    let one_node = [
        "edges.bottom.friction=\"0.3*(s > 0.99)\"",
        "solver.method=\"penalty\"",
    ];
    let (code, message) = friction_scene(&one_node).err().unwrap();
    assert_eq!(code, 2);
    assert!(
        message.contains("`solver.method`") && message.contains("edges.bottom.friction"),
        "{message}"
    );
}

/// Bad friction fields are refused at set-up with exit code 2, the message naming the key and,
/// for a value at a node, its `s`.
#[test]
fn a_bad_friction_field_is_refused_naming_the_key_and_s() {
    let cases: [(&str, &[&str]); 4] = [
        ("\"0.3 - s\"", &["edges.bottom.friction", "s = 0.3125"]),
        ("\"1/(s - 0.5)^2\"", &["edges.bottom.friction", "s = 0.5"]),
        ("\"0.3*t\"", &["edges.bottom.friction", "in s"]),
        ("\"0.3 + x*y\"", &["edges.bottom.friction"]),
    ];
    for (text, wanted) in cases {
        let set = format!("edges.bottom.friction={text}");
        let (code, message) = friction_scene(&[&set]).err().expect(text);
        assert_eq!(code, 2, "{text}: {message}");
        for w in wanted {
            assert!(message.contains(w), "{text}: {message}");
        }
    }
}

/// `|r_T| <= μ_j r_N` at a node and `|r_T| = μ_j r_N` where it slips, up to this relative to the
/// step's largest `μ r_N`: Lemke's pivots solve Coulomb's law exactly but for their rounding
/// (measured: 0, a slipping node's `r_T` is `±μ r_N` to the bit).
const COULOMB_ROUNDING: f64 = 1e-12;

/// A friction varying along the floor, `0.3 + 0.4 (s > 0.5)`, under the launched block: each
/// frictional node carries its own `μ(s)` (against the formula evaluated here), and at every
/// step Coulomb's law holds node by node with that `μ`: inside the cone, on it and against the
/// slip where the node slips; slipping nodes on both sides show both coefficients.
#[test]
fn coulombs_law_holds_node_by_node_with_each_nodes_own_friction() {
    let text = plane_builtin_text("plane-friction-launch").unwrap();
    let set = ["edges.bottom.friction=\"0.3 + 0.4*(s > 0.5)\"".to_string()];
    let scene = PlaneScene::from_toml(text, &set).unwrap();
    let mut sim = PlaneSimulation::new(&scene).unwrap();
    let friction = sim.contact().friction().clone();
    let mu = |s: f64| 0.3 + 0.4 * f64::from(u8::from(s > 0.5));
    for (j, &k) in friction.normals.iter().enumerate() {
        let s = sim.contact().position(k);
        assert_eq!(
            friction.coefficients[j].to_bits(),
            mu(s).to_bits(),
            "s = {s}"
        );
    }
    let (mut slipping_on, mut worst) = ([0usize; 2], 0.0f64);
    for _ in 1..scene.steps() {
        sim.step().unwrap();
        let [z, w] = sim.increments();
        let (u, r_n, r_t) = (sim.state().u, sim.reactions(), sim.tangential_reactions());
        let largest = (0..friction.len())
            .map(|j| friction.coefficients[j] * r_n[friction.normals[j]])
            .fold(0.0, f64::max);
        let rounding = COULOMB_ROUNDING * largest;
        for j in 0..friction.len() {
            let cone = friction.coefficients[j] * r_n[friction.normals[j]];
            worst = worst.max((r_t[j].abs() - cone) / largest);
            assert!(
                r_t[j].abs() <= cone + rounding,
                "node {j}: {} > {cone}",
                r_t[j]
            );
            if sim.contact().node_state(j, (u, z, w)) == NodeState::Slip {
                let t = friction.tangents[j];
                worst = worst.max((r_t[j].abs() - cone).abs() / largest);
                assert!(
                    (r_t[j].abs() - cone).abs() <= rounding,
                    "node {j}: on the cone"
                );
                assert!(r_t[j] * (z[t] + w[t]) <= 0.0, "node {j}: against the slip");
                slipping_on[usize::from(friction.coefficients[j] > 0.5)] += 1;
            }
        }
    }
    eprintln!("worst departure from Coulomb's law: {worst:e} of the largest mu r_N");
    assert!(slipping_on.iter().all(|&n| n > 0), "{slipping_on:?}");
}
