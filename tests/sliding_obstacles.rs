//! Obstacles sliding along a frictional edge (`edges.<edge>.velocity`, a belt): the Galilean
//! twin to round-off, the energy identity with the sliding obstacle's work of either sign and
//! `D_f >= 0` on the relative slip, a still belt that is the fixed floor bit for bit, and bad
//! input refused with exit code 2 naming the key.

mod common;

use viscobar::output::run_plane_in_memory;
use viscobar::scene::plane::{PlaneScene, plane_builtin_text};
use viscobar_certificate::friction::osqp_agreement;
use viscobar_certificate::plane::moving::{BELT_SPEED, galilean_belt};
use viscobar_certificate::tolerances::{
    FRICTION_DISSIPATION_TOL, PLANE_IDENTITY_TOL, friction_osqp_agreement_ratio,
};

fn launch(sets: &[&str]) -> PlaneScene {
    let text = plane_builtin_text("plane-friction-launch").unwrap();
    let sets: Vec<String> = sets.iter().map(|s| s.to_string()).collect();
    PlaneScene::from_toml(text, &sets).unwrap()
}

/// The block at rest on a belt at `v = −1` is the block launched at 1 on the fixed floor,
/// shifted by `v t`: displacements and reactions (normal and tangential) to round-off
/// accumulated per step (`GALILEAN_ULPS_PER_STEP`), through a slip phase and a stick phase.
#[test]
fn a_block_on_a_belt_is_the_launched_block_shifted_galilean_twin() {
    let g = galilean_belt().unwrap();
    println!("{g:?} ratio {:.3}", g.ratio());
    assert!(g.steps_in_contact > 100, "{g:?}");
    assert!(g.max_reaction > 0.0 && g.max_u > 0.5, "{g:?}");
    assert!(g.ratio() <= 1.0, "{g:?} ratio {}", g.ratio());
    // Both phases happen: the launched block slips, then sticks once stopped (t = 2).
    let (records, _, _) = run_plane_in_memory("launch", &launch(&[])).unwrap();
    assert!(records[10].slip_nodes > 0 && records[10].stick_nodes == 0);
    let last = records.last().unwrap();
    assert!(last.stick_nodes > 0 && last.slip_nodes == 0, "{last:?}");
}

/// A check that can fail: a belt slightly faster than the launch is far outside the bound.
#[test]
fn the_belt_twin_fails_for_a_mismatched_speed() {
    let fixed = launch(&[]);
    let belt = launch(&[
        "initial.velocity=[\"0\", \"0\"]",
        &format!("edges.bottom.velocity=\"{}\"", 1.001 * BELT_SPEED),
    ]);
    let (a, _, _) = run_plane_in_memory("a", &fixed).unwrap();
    let (b, _, sb) = run_plane_in_memory("b", &belt).unwrap();
    let diff = a
        .iter()
        .zip(&b)
        .map(|(x, y)| (x.friction_dissipation - y.friction_dissipation).abs())
        .fold(0.0, f64::max);
    assert!(diff > 1e-6, "{diff}");
    assert!(sb.tangential_reactions().iter().any(|&r| r != 0.0));
}

/// The identity closes with the sliding work: positive while a belt drags the block along its
/// motion (block at rest, belt at 1), negative while the block outruns a belt that holds it
/// back (launched at 1 on a belt at 0.5); `D_f >= 0` on the relative slip, and a run with a
/// sliding obstacle has no energy-rise bound.
#[test]
fn the_identity_gains_the_sliding_work_of_either_sign() {
    let cases: [(&[&str], f64); 2] = [
        (
            &[
                "initial.velocity=[\"0\", \"0\"]",
                "edges.bottom.velocity=\"1\"",
            ],
            1.0,
        ),
        (&["edges.bottom.velocity=\"0.5\""], -1.0),
    ];
    for (sets, sign) in cases {
        let (records, summary, sim) = run_plane_in_memory("belt", &launch(sets)).unwrap();
        assert!(sim.contact().is_sliding());
        let work: f64 = records.iter().map(|r| r.sliding_work).sum();
        assert!(sign * work > 0.0, "{sets:?}: sliding work {work}");
        for r in records.iter().skip(1) {
            assert!(r.identity_residual <= PLANE_IDENTITY_TOL, "{sets:?}: {r:?}");
            assert!(
                r.friction_dissipation >= -FRICTION_DISSIPATION_TOL * r.energy,
                "{sets:?}: {r:?}"
            );
        }
        assert!(summary.max_energy_rise.is_none(), "{sets:?}");
    }
}

/// A belt at speed 0 is the fixed floor bit for bit (`− 0.0` is exact): every record, with a
/// sliding work of exactly 0.
#[test]
fn a_still_belt_is_the_fixed_floor_bitwise() {
    let (a, _, sa) = run_plane_in_memory("a", &launch(&[])).unwrap();
    let (b, _, sb) = run_plane_in_memory("b", &launch(&["edges.bottom.velocity=\"0*t\""])).unwrap();
    assert!(sb.contact().is_sliding() && !sa.contact().is_sliding());
    for (x, y) in sa.displacement().iter().zip(sb.displacement()) {
        assert_eq!(x.to_bits(), y.to_bits());
    }
    for (x, y) in a.iter().zip(&b) {
        assert_eq!(y.sliding_work, 0.0);
        let y = viscobar::scheme::StepRecord {
            sliding_work: x.sliding_work,
            ..*y
        };
        assert_eq!(format!("{x:?}"), format!("{y:?}"));
    }
}

const CASES: &[(&str, &[&str], &str)] = &[
    (
        "velocity on a frictionless edge",
        &["edges.bottom={condition=\"signorini\", gap=0.05, velocity=1}"],
        "edges.bottom.velocity",
    ),
    (
        "velocity on a clamped edge",
        &["edges.left={condition=\"clamped\", velocity=1}"],
        "edges.left.velocity",
    ),
    (
        "velocity on a free edge",
        &["edges.top={condition=\"free\", velocity=\"t\"}"],
        "edges.top.velocity",
    ),
    (
        "velocity not finite at t = 0",
        &["edges.bottom={condition=\"signorini\", gap=0.05, friction=0.3, velocity=\"1/t\"}"],
        "edges.bottom.velocity",
    ),
    (
        "velocity not finite later",
        &[
            "edges.bottom={condition=\"signorini\", gap=0.05, friction=0.3, velocity=\"sqrt(0.25 - t)\"}",
        ],
        "edges.bottom.velocity",
    ),
    (
        "velocity in s",
        &["edges.bottom={condition=\"signorini\", gap=0.05, friction=0.3, velocity=\"s\"}"],
        "edges.bottom.velocity",
    ),
    (
        "velocity of NaN",
        &["edges.bottom={condition=\"signorini\", gap=0.05, friction=0.3, velocity=nan}"],
        "edges.bottom.velocity",
    ),
];

#[test]
fn bad_velocity_input_exits_2_naming_the_key_and_writes_nothing() {
    let out = common::fresh_dir("sliding", "bad");
    common::assert_each_refused("plane-tilted-drop", CASES, &out);
}

/// The built-in stick–slip scene sticks and slips in turn: in every half period of the belt
/// after the first, most of the bottom sticks at some step (where the belt turns) and all of
/// it slips at another; its identity closes with `D_f >= 0` at every step.
#[test]
fn the_stick_slip_scene_sticks_and_slips_in_turn() {
    let text = plane_builtin_text("plane-friction-stick-slip").unwrap();
    let scene = PlaneScene::from_toml(text, &[]).unwrap();
    let (records, _, sim) = run_plane_in_memory("stick-slip", &scene).unwrap();
    let nodes = sim.contact().friction().len();
    let half = (0.5 / scene.time.step).round() as usize;
    for (k, period) in records.chunks(half).enumerate().skip(1) {
        let most_stick = period.iter().any(|r| 2 * r.stick_nodes > nodes);
        let all_slip = period.iter().any(|r| r.slip_nodes == nodes);
        assert!(most_stick && all_slip, "half period {k}");
    }
    for r in records.iter().skip(1) {
        assert!(r.identity_residual <= PLANE_IDENTITY_TOL, "{r:?}");
        assert!(
            r.friction_dissipation >= -FRICTION_DISSIPATION_TOL * r.energy,
            "{r:?}"
        );
    }
}

/// OSQP's Tresca fixed point agrees with the exact Lemke step on the relative slip, within the
/// friction agreement bound, its answers audited against the Tresca law with the sliding
/// obstacle: the first period of the stick–slip belt.
#[test]
fn osqp_agrees_with_the_exact_step_on_a_sliding_obstacle() {
    let text = plane_builtin_text("plane-friction-stick-slip").unwrap();
    let scene = PlaneScene::from_toml(text, &["time.end=1.0".into()]).unwrap();
    let a = osqp_agreement("stick-slip", &scene).unwrap();
    let ratio = friction_osqp_agreement_ratio(&a);
    println!("{a:?} ratio {ratio:.3e}");
    assert!(ratio <= 1.0, "{ratio:e} of the bound: {a:?}");
    assert!(a.audit_worst_ratio <= 1.0, "{a:?}");
    // The fixed point iterates: Coulomb is more than one Tresca problem.
    assert!(a.max_iterations > 2 && a.mean_iterations > 1.0, "{a:?}");
}
