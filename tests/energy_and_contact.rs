//! The discrete energy identity, energy decay and complementarity, at every step of every
//! built-in scene.

mod common;
use viscobar::run::run_in_memory;
use viscobar::scene::builtin_names;

/// Relative residual of the energy identity: the identity is exact algebra, so only round-off
/// remains (measured: below 1e-14 on every built-in scene, see VERIFICATION.md).
const IDENTITY_TOL: f64 = 1e-12;
/// A one-step energy increase of an unforced run, relative to E^{1/2}, that round-off can make.
const ENERGY_RISE_TOL: f64 = 1e-13;
/// Gap and reaction may be negative by round-off only: the exact solver puts an active node on
/// the obstacle up to the rounding of `u^n + z` with |u| <= 1.
const GAP_TOL: f64 = 1e-14;
const REACTION_TOL: f64 = 1e-12;
/// `|gap · reaction|`: round-off in the gap times a reaction of order 10.
const COMPLEMENTARITY_TOL: f64 = 1e-12;

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

#[test]
fn energy_never_rises_without_load() {
    for name in builtin_names() {
        let scene = common::builtin(name, &[]);
        if scene.load.density.is_some() {
            continue;
        }
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
        let k = scene.signorini_ends().len();
        let (records, summary, _) = run_in_memory(name, &scene).unwrap();
        for r in &records {
            for j in 0..k {
                let (g, l) = (r.gap[j], r.reaction[j]);
                assert!(g >= -GAP_TOL, "{name}: gap {g:e} at step {}", r.step);
                assert!(
                    l >= -REACTION_TOL,
                    "{name}: reaction {l:e} at step {}",
                    r.step
                );
                assert!(
                    (g * l).abs() <= COMPLEMENTARITY_TOL,
                    "{name}: |gap·reaction| = {:e}",
                    (g * l).abs()
                );
            }
        }
        // The talk scenes are chosen so that every Signorini end touches at least once.
        for (side, intervals) in &summary.contact_intervals {
            assert!(
                !intervals.is_empty(),
                "{name}: the {side} end never touches its obstacle"
            );
        }
    }
}

#[test]
fn clamped_impact_conserves_the_energy_one_eighth() {
    // Closed form: E = 1/8; the elastic scheme conserves E^{n+1/2} exactly when contact does no
    // work, and the discrete contact work is of the order of the discretisation error.
    let scene = common::builtin(
        "clamped-impact",
        &["mesh.elements=800", "time.step=0.00125"],
    );
    let (records, _, _) = run_in_memory("clamped-impact", &scene).unwrap();
    let e_final = records.last().unwrap().energy;
    // Discretisation error of E^{1/2} at this mesh (O(dx) from the kink of u0 at x = 1, measured).
    const ENERGY_DISCRETISATION_TOL: f64 = 5e-3;
    assert!(
        (records[0].energy - 0.125).abs() <= ENERGY_DISCRETISATION_TOL,
        "E^1/2 = {}",
        records[0].energy
    );
    assert!(e_final <= records[0].energy * (1.0 + 1e-12));
}
