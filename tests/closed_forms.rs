//! Convergence to the closed-form solutions shipped with the built-in scenes.
//!
//! The refinement study behind the bounds is `cargo run --release -p viscobar-certificate --
//! verify` (five levels, dx and dt halved together): modal order 1.995; impact 0.686;
//! clamped-impact 0.680, with L2 errors 2.10e-2 and 1.09e-2 at the scenes' own meshes.

mod common;
use common::{KINK_ORDER_BAND, MODAL_ORDER, MODAL_ORDER_TOL};
use viscobar::bar::closed_form::{self, ClosedForm, FallingBar, ForcedMode};
use viscobar::study::accuracy::{error_against, observed_order};

// Error bounds at the scenes' own meshes: 1.25x the measured L2 error, defined beside their
// measurement in the tolerance registry (`viscobar-certificate verify --tolerances`).
use viscobar_certificate::tolerances::{
    CLAMPED_IMPACT_L2_BOUND, CONTACT_TIME_TOL, FALLING_BAR_L2_BOUND, FALLING_BAR_ROUNDOFF, FD_STEP,
    IMPACT_L2_BOUND, MEAN_REACTION_TOL, builtin_falling_bar, falling_bar_identities_worst,
    falling_bar_quadrature, falling_bar_reaction_fd_ratio, impact_contact_errors,
};

fn study(name: &str, levels: u32) -> (Vec<f64>, Vec<f64>) {
    let base = common::builtin(name, &[]);
    let exact = closed_form::for_scene(name, &base).expect("scene has a closed form");
    (0..levels)
        .map(|l| {
            let s = base.refined(l);
            (s.dx(), error_against(&s, exact.as_ref()).unwrap().l2)
        })
        .unzip()
}

#[test]
fn modal_converges_with_order_two() {
    let (h, e) = study("modal", 4);
    let p = observed_order(&h, &e);
    assert!(
        (p - MODAL_ORDER).abs() <= MODAL_ORDER_TOL,
        "observed order {p:.3}, errors {e:?}"
    );
}

/// A kinked closed form: L2 error at the scene's own mesh below `bound`, and the observed
/// order over three levels in [`KINK_ORDER_BAND`].
fn assert_kinked_convergence(name: &str, bound: f64) {
    let (h, e) = study(name, 3);
    assert!(
        e[0] <= bound,
        "{name}: L2 error {:.3e} at the scene's mesh",
        e[0]
    );
    let p = observed_order(&h, &e);
    assert!(
        p >= KINK_ORDER_BAND.0 && p <= KINK_ORDER_BAND.1,
        "{name}: observed order {p:.3}, errors {e:?}"
    );
}

#[test]
fn impact_error_is_bounded_and_decreases_at_the_kink_rate() {
    assert_kinked_convergence("impact", IMPACT_L2_BOUND);
}

#[test]
fn clamped_impact_error_is_bounded_and_decreases_at_the_kink_rate() {
    assert_kinked_convergence("clamped-impact", CLAMPED_IMPACT_L2_BOUND);
}

#[test]
fn impact_contact_interval_and_reaction_match_the_closed_form() {
    // Contact on [t1, t1 + 2L] = [0.1, 2.1] with mean reaction v0 = 1 (the momentum change
    // 2 v0 L over 2L; nodal force = -s(0)), at 400 elements: tolerances::impact_contact_errors.
    let (episodes, time_error, mean_error) = impact_contact_errors().unwrap();
    assert_eq!(episodes, 1, "one contact episode");
    assert!(
        time_error <= CONTACT_TIME_TOL,
        "contact times off by {time_error}"
    );
    assert!(
        mean_error <= MEAN_REACTION_TOL,
        "mean reaction off by {mean_error}"
    );
}

/// The built-in falling bar's closed form (the scene's own data).
fn falling_bar() -> FallingBar {
    builtin_falling_bar().unwrap()
}

#[test]
fn falling_bar_closed_form_solves_the_wave_equation_with_its_boundary_conditions() {
    let fb = falling_bar();
    let p = fb.period();
    // Data: V1 = 3gL, period 16, contact on [3, 5] and [11, 13] (the scene's description).
    assert_eq!((fb.impact_speed(), fb.fall_time(), p), (0.375, 3.0, 16.0));
    let contact = fb.contact_intervals(2.0 * p).unwrap();
    assert_eq!(contact[..2], [[3.0, 5.0], [11.0, 13.0]]);
    assert_eq!(contact.len(), 4);
    // The diamond identities, the ends and the release at 4000 points over two periods (the
    // registry's measurement, which also checks the contact phases' reaction and gap signs).
    let worst = falling_bar_identities_worst(&fb).unwrap();
    assert!(worst <= FALLING_BAR_ROUNDOFF, "worst residual {worst:e}");
}

// FD_STEP and FD_ROUNDOFF (difference quotients of the closed form): in the registry.

#[test]
fn falling_bar_closed_form_is_continuous_conserves_energy_and_has_its_reaction() {
    let fb = falling_bar();
    let (l, g) = (fb.length, fb.gravity);
    let u = |x: f64, t: f64| fb.displacement(x, t);
    let v1 = fb.impact_speed();
    // |u_t|, |u_x| ≤ V1 + 2gL + V1 + 2gL (two waves of slope h' ≤ V1 + 2gL on −V1 − gτ).
    let slope = 2.0 * (v1 + 2.0 * g * l);
    // Total energy with gravity's potential g∫u: zero, as at the release; and ∫u in closed
    // form. The quadrature, its cut at the kink and its bounds: tolerances::falling_bar_quadrature.
    let q = falling_bar_quadrature(&fb);
    assert!(
        q.energy_worst <= q.energy_tol && q.mass_worst <= q.mass_tol,
        "{q:?}"
    );
    // The reaction −u_x(0) by a one-sided difference (u is linear in x near 0 within a phase,
    // slope g), within g·FD_STEP + FD_ROUNDOFF.
    let fd = falling_bar_reaction_fd_ratio(&fb);
    assert!(fd <= 1.0, "reaction difference over its bound {fd:e}");
    // Continuous across the phase boundaries: impact, release, mid-flight, second contact.
    let (t1, p) = (fb.fall_time(), fb.period());
    for tb in [t1, t1 + 2.0 * l, 0.5 * p, p - t1 - 2.0 * l, p - t1, p] {
        for j in 0..=10 {
            let x = l * j as f64 / 10.0;
            let jump = u(x, tb + FD_STEP) - u(x, tb - FD_STEP);
            assert!(
                jump.abs() <= 2.0 * slope * FD_STEP,
                "t {tb} x {x}: {jump:e}"
            );
        }
    }
}

#[test]
fn falling_bar_error_is_bounded_and_decreases_at_the_kink_rate() {
    assert_kinked_convergence("falling-bar", FALLING_BAR_L2_BOUND);
}

#[test]
fn closed_forms_are_refused_when_overrides_leave_their_assumptions() {
    let fits = |name: &str, o: &[&str]| closed_form::for_scene(name, &common::builtin(name, o));
    assert!(fits("falling-bar", &[]).is_some());
    // a0 = 1: V1/(gL) = 4, another whole number: still periodic, still a closed form.
    assert!(fits("falling-bar", &["left.gap=1.0"]).is_some());
    for o in [
        "left.gap=2.0",              // V1/(gL) = 5.66: the second impact is not derived
        "load.density=\"-0.1\"",     // V1/(gL) = 3.35
        "load.density=\"-0.125*x\"", // not uniform gravity
        "bar.viscosity=0.01",
        "initial.velocity=\"-0.1\"",
        "right.condition=\"clamped\"",
    ] {
        assert!(fits("falling-bar", &[o]).is_none(), "{o}");
    }
    // A non-uniform initial velocity leaves every closed form (they all start uniform).
    assert!(fits("impact", &["initial.velocity=\"-1 + x\""]).is_none());
    assert!(fits("modal", &["initial.velocity=\"1\""]).is_none());
    // The manufactured load must match the viscosity it was derived for.
    assert!(fits("forced-mode", &[]).is_some());
    assert!(fits("forced-mode", &["bar.viscosity=0.2"]).is_none());
    assert!(fits("forced-mode", &["load.density=\"cos(2*t)*cos(pi*x)\""]).is_none());
}

/// The manufactured solution `u = cos 2t cos πx` with a load varying in `x` and `t` converges at
/// second order, elastic and viscous: the guard on where in time the load is evaluated (taking
/// it at `t_{n+1}` instead of `t_n` drops the observed order to about 1).
#[test]
fn forced_mode_converges_with_order_two_for_alpha_zero_and_positive() {
    for alpha in [0.0, 0.1] {
        let exact = ForcedMode { length: 1.0, alpha };
        let viscosity = format!("bar.viscosity={alpha}");
        let load = format!("load.density=\"{}\"", exact.load_expression());
        let base = common::builtin("forced-mode", &[&viscosity, &load]);
        let found = closed_form::for_scene("forced-mode", &base).expect("closed form applies");
        let (h, e): (Vec<f64>, Vec<f64>) = (0..4)
            .map(|l| {
                let s = base.refined(l);
                (s.dx(), error_against(&s, found.as_ref()).unwrap().l2)
            })
            .unzip();
        let p = observed_order(&h, &e);
        assert!(
            (p - MODAL_ORDER).abs() <= MODAL_ORDER_TOL,
            "alpha = {alpha}: observed order {p:.3}, errors {e:?}"
        );
    }
}
