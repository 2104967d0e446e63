//! The discrete energy identity, energy decay and complementarity, at every step of every
//! built-in scene.

mod common;
use common::{COMPLEMENTARITY_TOL, ENERGY_RISE_TOL, GAP_TOL, IDENTITY_TOL, REACTION_TOL};
use viscobar::output::run_in_memory;
use viscobar::scene::{self, MassVariant, builtin_names};
// Defined beside their measurement in the tolerance registry (`viscobar-certificate verify
// --tolerances`).
use viscobar_certificate::tolerances::{
    RESTING_TOL, START_ENERGY_ERROR_PER_DX, resting_bar_worst, start_energy_errors,
};

#[test]
fn energy_identity_holds_at_every_step_of_every_builtin_scene() {
    for name in builtin_names() {
        let scene = common::builtin(name, &[]);
        let (records, summary, _) = run_in_memory(name, &scene).unwrap();
        assert_eq!(records.len(), scene.steps());
        for r in &records {
            assert!(
                r.identity_residual <= IDENTITY_TOL,
                "{name}: step {} residual {:e}",
                r.step,
                r.identity_residual
            );
        }
        assert!(summary.max_identity_residual <= IDENTITY_TOL);
    }
}

/// For every mass variant (`bar.mass`; the identity holds for any symmetric `M`, and each
/// dissipation term keeps its sign with a semidefinite one), where the scene allows it.
#[test]
fn energy_never_rises_without_load() {
    let cases = builtin_names()
        .into_iter()
        .flat_map(|n| MassVariant::ALL.map(|m| (n, m)));
    for (scene_name, mass) in cases {
        let scene = match scene::load(scene_name, &[format!("bar.mass={}", mass.name())]) {
            Ok((_, scene)) => scene,
            // A redistributed mass with an obstacle is refused (tests/mass.rs).
            Err(e) if mass == MassVariant::Redistributed => {
                assert!(e.to_string().contains("obstacle.gap"), "{scene_name}: {e}");
                continue;
            }
            Err(e) => panic!("{scene_name} {mass:?}: {e}"),
        };
        if scene.load.density.is_some() {
            continue;
        }
        let label = format!("{scene_name} [mass {}]", mass.name());
        let name = label.as_str();
        let (records, _, _) = run_in_memory(name, &scene).unwrap();
        let e0 = records[0].energy;
        for pair in records.windows(2) {
            let rise = pair[1].energy - pair[0].energy;
            assert!(
                rise <= ENERGY_RISE_TOL * e0,
                "{name}: energy rises by {rise:e} at step {}",
                pair[1].step
            );
            // Each dissipation is non-negative, so the balance can only lose energy.
            assert!(
                pair[1].viscous_dissipation >= 0.0
                    && pair[1].contact_dissipation >= -ENERGY_RISE_TOL * e0
            );
        }
    }
}

#[test]
fn complementarity_holds_at_every_step_and_constrained_node() {
    for name in builtin_names() {
        let scene = common::builtin(name, &[]);
        let (records, summary, sim) = run_in_memory(name, &scene).unwrap();
        let sim = sim
            .mechanical()
            .expect("the built-in bar scenes have no [heat]");
        let constrained = sim.discretisation().constraints.len();
        for r in &records {
            // The record's aggregates run over every constrained node (ends and obstacle).
            if constrained > 0 {
                assert!(
                    r.contact.min_gap >= -GAP_TOL,
                    "{name}: gap {:e} at step {}",
                    r.contact.min_gap,
                    r.step
                );
                assert!(
                    r.contact.min_reaction >= -REACTION_TOL,
                    "{name}: reaction {:e} at step {}",
                    r.contact.min_reaction,
                    r.step
                );
                assert!(
                    r.contact.max_complementarity <= COMPLEMENTARITY_TOL,
                    "{name}: |gap·reaction| = {:e} at step {}",
                    r.contact.max_complementarity,
                    r.step
                );
            }
        }
        // The talk scenes are chosen so that every Signorini end (or the obstacle) is touched.
        for (side, intervals) in &summary.contact_intervals {
            assert!(
                !intervals.is_empty(),
                "{name}: the {side} constraint is never in contact"
            );
        }
    }
}

/// A bar resting on a flat obstacle under a uniform downward load stays at rest on it: the
/// closed form is `u = −g` at every node, with nodal reactions `r = −F = M·1` (the load each
/// node carries), at every step; contact along the whole length from the start.
#[test]
fn bar_resting_on_the_obstacle_stays_with_the_static_reactions() {
    // The registry's measurement: worst |u + 0.25| and |r − M·1| (RESTING_TOL).
    let (worst, all_in_contact) = resting_bar_worst().unwrap();
    assert!(worst <= RESTING_TOL, "worst deviation {worst:e}");
    assert!(all_in_contact, "a node left the obstacle");
}

#[test]
fn clamped_impact_starts_with_energy_one_eighth_to_first_order_and_never_gains() {
    // Closed form: E = 1/8. The kink of u0 at x = 1 makes the start-up energy first order in dx.
    // 400 and 800 elements, Δt = Δx: the registry's measurement (START_ENERGY_ERROR_PER_DX).
    let levels = start_energy_errors().unwrap();
    let mut errors = Vec::new();
    for (error, dx, final_over_start) in levels {
        assert!(
            error.abs() <= START_ENERGY_ERROR_PER_DX * dx,
            "E^1/2 - 1/8 = {error:e}"
        );
        assert!(final_over_start <= ENERGY_RISE_TOL, "energy gained");
        errors.push(error);
    }
    let ratio = errors[0] / errors[1];
    // First order: halving dx halves the error (measured ratio 2.000).
    assert!((ratio - 2.0).abs() <= 0.1, "error ratio {ratio}");
}
