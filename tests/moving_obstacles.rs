//! Moving obstacles (gaps `g(s, t)` of the plane's edges, `a(t)` of the bar's ends): Galilean
//! invariance on both bodies, the energy identity with the obstacle's work, and the outputs.

use viscobar::output::{run_in_memory, run_plane_in_memory};
use viscobar::scene::plane::{PlaneScene, plane_builtin_text};
use viscobar::scene::{Scene, builtin_text};
use viscobar_certificate::plane::moving::{galilean_bar, galilean_plane};
use viscobar_certificate::tolerances::{IDENTITY_TOL, PLANE_GAP_TOL, PLANE_IDENTITY_TOL};

/// The body at rest under an approaching obstacle is the moving body shifted by `v t` onto the
/// fixed obstacle, to round-off accumulated per step (not bitwise: the shift `v t_n` is
/// rounded, and `K` annihilates a translation only to round-off); both runs touch the obstacle.
#[test]
fn an_approaching_obstacle_is_the_moving_body_shifted_galilean_invariance() {
    for (body, g) in [
        ("plane", galilean_plane().unwrap()),
        ("bar", galilean_bar().unwrap()),
    ] {
        println!("{body}: {g:?} ratio {:.3}", g.ratio());
        assert!(g.steps_in_contact > 10, "{body}: {g:?}");
        assert!(g.max_reaction > 0.0, "{body}: {g:?}");
        assert!(g.ratio() <= 1.0, "{body}: {g:?} ratio {}", g.ratio());
    }
}

/// A check that can fail: a floor rising at a slightly different speed than the body falls is
/// far outside the round-off bound.
#[test]
fn the_galilean_check_fails_for_a_mismatched_speed() {
    let text = plane_builtin_text("plane-tilted-drop").unwrap();
    let scene = |v: &str| {
        PlaneScene::from_toml(
            text,
            &[
                "initial.velocity=[\"0\", \"0\"]".into(),
                format!("edges.bottom.gap=\"0.05 - {v}*t\""),
            ],
        )
        .unwrap()
    };
    let (a, _, _) = run_plane_in_memory("a", &scene("0.5")).unwrap();
    let (b, _, _) = run_plane_in_memory("b", &scene("0.501")).unwrap();
    let diff = a
        .iter()
        .zip(&b)
        .map(|(x, y)| (x.contact.total_reaction - y.contact.total_reaction).abs())
        .fold(0.0, f64::max);
    assert!(diff > 1e-6, "{diff}");
}

/// The energy identity with the obstacle's work closes to round-off on both bodies, for an
/// obstacle that advances (positive work) and one that retreats (negative), and the contact
/// dissipation stays >= 0: contact only dissipates, the obstacle's work has no sign.
#[test]
fn the_energy_identity_gains_the_obstacle_work_of_either_sign() {
    let text = plane_builtin_text("plane-tilted-drop").unwrap();
    for (gap, sign) in [("0.05 - 0.2*t", 1.0), ("0.05 + 0.1*t*t", -1.0)] {
        let scene = PlaneScene::from_toml(text, &[format!("edges.bottom.gap=\"{gap}\"")]).unwrap();
        let (records, summary, _) = run_plane_in_memory("moving", &scene).unwrap();
        let work: f64 = records.iter().map(|r| r.obstacle_work).sum();
        assert!(sign * work > 0.0, "{gap}: obstacle work {work}");
        for r in records.iter().skip(1) {
            assert!(r.identity_residual <= PLANE_IDENTITY_TOL, "{gap}: {r:?}");
            assert!(
                r.contact_dissipation >= -PLANE_GAP_TOL * r.energy,
                "{gap}: {r:?}"
            );
        }
        assert!(
            summary.max_energy_rise.is_none(),
            "a moving obstacle feeds energy in"
        );
    }
    let text = builtin_text("impact").unwrap();
    for (gap, sign) in [("0.1 - 0.5*t", 1.0), ("0.1 + 0.3*t", -1.0)] {
        let scene = Scene::from_toml(text, &[format!("left.gap=\"{gap}\"")]).unwrap();
        let (records, _, _) = run_in_memory("moving", &scene).unwrap();
        let work: f64 = records.iter().map(|r| r.obstacle_work).sum();
        assert!(sign * work > 0.0, "{gap}: obstacle work {work}");
        for r in records.iter().skip(1) {
            assert!(r.identity_residual <= IDENTITY_TOL, "{gap}: {r:?}");
            assert!(
                r.contact_dissipation >= -PLANE_GAP_TOL * r.energy,
                "{gap}: {r:?}"
            );
        }
    }
}

/// A fixed obstacle written as an expression in `t` that does not move is the fixed run, bit
/// for bit (the motion is only evaluated for gaps that depend on `t`); a gap `0.05 + 0*t`
/// moves by exactly 0: the same trajectory and reactions, no obstacle work.
#[test]
fn an_obstacle_that_does_not_move_gives_the_fixed_run_bitwise() {
    let text = plane_builtin_text("plane-tilted-drop").unwrap();
    let fixed = PlaneScene::from_toml(text, &[]).unwrap();
    let still = PlaneScene::from_toml(text, &["edges.bottom.gap=\"0.05 + 0*t\"".into()]).unwrap();
    let (a, _, sa) = run_plane_in_memory("a", &fixed).unwrap();
    let (b, _, sb) = run_plane_in_memory("b", &still).unwrap();
    assert!(sb.contact().is_moving() && !sa.contact().is_moving());
    for (x, y) in sa.displacement().iter().zip(sb.displacement()) {
        assert_eq!(x.to_bits(), y.to_bits());
    }
    for (x, y) in a.iter().zip(&b) {
        // Debug text: the extents of an edge out of contact are NaN.
        assert_eq!(format!("{:?}", x.contact), format!("{:?}", y.contact));
        assert_eq!(y.obstacle_work, 0.0);
        assert_eq!(x.energy.to_bits(), y.energy.to_bits());
    }
}

/// A gap that starts admissible may later reach into the body's reference position (a floor
/// rising above `y = 0`): the run goes on, the body is lifted; an inadmissible start is refused.
#[test]
fn only_the_initial_state_must_be_admissible() {
    let text = plane_builtin_text("plane-tilted-drop").unwrap();
    let scene = PlaneScene::from_toml(text, &["edges.bottom.gap=\"0.05 - 0.5*t\"".into()]).unwrap();
    let (records, _, sim) = run_plane_in_memory("rising", &scene).unwrap();
    let last = records.last().unwrap();
    assert!(last.contact.groups[0].min_gap >= -PLANE_GAP_TOL, "{last:?}");
    let gaps = sim.contact().gaps();
    assert!(
        gaps.iter().all(|&g| g < -0.5),
        "the floor is above y = 0: {gaps:?}"
    );
    let refused = PlaneScene::from_toml(text, &["edges.bottom.gap=\"-0.1 + t\"".into()]).unwrap();
    let e = viscobar::plane::PlaneSimulation::new(&refused)
        .err()
        .unwrap()
        .to_string();
    assert!(
        e.contains("initial.displacement") && e.contains("edges.bottom.gap"),
        "{e}"
    );
}
