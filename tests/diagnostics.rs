//! Thinned diagnostics (`[output] diagnostics_every`): measuring the energy balance is
//! read-only, so thinning it leaves the trajectory bitwise unchanged; every measured step is a
//! complete one-step identity (its `E^{n−1/2}` is recomputed when the step before was not
//! measured); the last step is always measured.

mod common;
use common::{ENERGY_RISE_TOL, IDENTITY_TOL};
use viscobar::Simulation;
use viscobar::scene::builtin_names;

// Defined beside its measurement in the tolerance registry (`viscobar-certificate verify
// --tolerances`).
use viscobar_certificate::tolerances::{ENERGY_ROUNDOFF_TOL, THINNING, thinned_energy_error};

#[test]
fn thinning_leaves_the_trajectory_unchanged_and_measured_steps_close_the_identity() {
    for name in builtin_names() {
        let every = common::builtin(name, &[]);
        let thinned = common::builtin(name, &[&format!("output.diagnostics_every={THINNING}")]);
        let mut a = Simulation::new(&every).unwrap();
        let mut b = Simulation::new(&thinned).unwrap();
        let steps = every.steps();
        let mut measured = 0;
        for _ in 1..steps {
            let (ra, rb) = (a.step().unwrap(), b.step().unwrap());
            assert!(
                ra.measured,
                "{name}: step {} not measured by default",
                ra.step
            );
            assert_eq!(
                rb.measured,
                (rb.step as u64).is_multiple_of(THINNING) || rb.step == steps,
                "{name}: {}",
                rb.step
            );
            assert_eq!(
                a.displacement(),
                b.displacement(),
                "{name}: step {}",
                ra.step
            );
            let state =
                |r: &viscobar::StepRecord| r.contact.groups.map(|g| (g.min_gap, g.reaction));
            assert_eq!(state(&ra), state(&rb), "{name}");
            if rb.measured {
                measured += 1;
                assert!(
                    rb.identity_residual <= IDENTITY_TOL,
                    "{name}: step {}",
                    rb.step
                );
                assert!(
                    thinned_energy_error(ra.energy, rb.energy) <= ENERGY_ROUNDOFF_TOL,
                    "{name}: step {}: {} vs {}",
                    rb.step,
                    ra.energy,
                    rb.energy
                );
            } else {
                assert_eq!(rb.energy, 0.0);
            }
        }
        assert!(
            measured >= (steps - 1) / 7,
            "{name}: {measured} measured steps"
        );
    }
}

/// Without load the thinned run's energy never rises between measured steps either: the
/// identity telescopes, `E^{m+1/2} − E^{l−1/2} = Σ (−viscous + contact) ≤ 0`.
#[test]
fn thinned_energy_never_rises_without_load() {
    for name in builtin_names() {
        let scene = common::builtin(name, &["output.diagnostics_every=5"]);
        if scene.load.density.is_some() {
            continue;
        }
        let (_, summary, _) = viscobar::output::run_in_memory(name, &scene).unwrap();
        let rise = summary.max_energy_rise.expect("unforced");
        assert!(rise <= ENERGY_RISE_TOL, "{name}: {rise:e}");
    }
}
