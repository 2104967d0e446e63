//! The plane body: the energy identity at every step, the bar as an exact special case, and the
//! observed order of the manufactured solution, on the computations of
//! `viscobar_certificate::plane` (which also writes VERIFICATION.md's "Plane body" tables).
//! Run in release (the sparse factorisation is ~150x slower in debug).

use viscobar::output::run_plane_in_memory;
use viscobar_certificate::plane::{
    MANUFACTURED_LEVELS, bar_case, bar_case_scenes, identity_scenes, manufactured_level,
    observed_order,
};

// The identity, energy-rise and bar-case tolerances: in the registry
// (viscobar_certificate::tolerances), which measures their worst values over these scenes
// (`viscobar-certificate verify --tolerances`).
use viscobar_certificate::tolerances::{
    PLANE_BAR_CASE_TOL as BAR_CASE_TOL, PLANE_ENERGY_RISE_TOL as ENERGY_RISE_TOL,
    PLANE_IDENTITY_TOL as IDENTITY_TOL,
};
/// The bars of the special case move by 0.1 or more: the check compares motion, not rest.
const BAR_CASE_MIN_MOTION: f64 = 0.05;
/// Observed order of the manufactured solution: 2 (Q1 in L2, the scheme in time) ± this.
const ORDER_TOL: f64 = 0.15;

#[test]
fn energy_identity_holds_at_every_step_of_every_builtin_plane_scene_and_the_manufactured_one() {
    for (name, scene) in identity_scenes() {
        let (records, summary, _) = run_plane_in_memory(&name, &scene).unwrap();
        assert_eq!(records.len(), scene.steps());
        for r in &records[1..] {
            assert!(
                r.identity_residual <= IDENTITY_TOL,
                "{name} step {}: {:e}",
                r.step,
                r.identity_residual
            );
        }
        assert!(summary.max_identity_residual <= IDENTITY_TOL);
        match summary.max_energy_rise {
            // Without load the energy never rises (the viscous term is ≥ 0).
            Some(rise) => assert!(rise <= ENERGY_RISE_TOL, "{name}: {rise:e}"),
            // With one the work is seen.
            None => assert!(records.iter().any(|r| r.work != 0.0), "{name}"),
        }
        if scene.plane.viscosity > 0.0 {
            assert!(
                records[1..].iter().all(|r| r.viscous_dissipation > 0.0),
                "{name}"
            );
        }
    }
}

#[test]
fn the_bar_is_an_exact_special_case_of_the_plane_body() {
    for (name, bar) in bar_case_scenes() {
        let c = bar_case(&bar).unwrap();
        assert!(
            c.max_u > BAR_CASE_MIN_MOTION,
            "{name}: the bar moves ({})",
            c.max_u
        );
        assert!(
            c.max_ux_deviation <= BAR_CASE_TOL * c.max_u,
            "{name}: ux off by {:e}",
            c.max_ux_deviation
        );
        assert!(
            c.max_uy <= BAR_CASE_TOL * c.max_u,
            "{name}: uy = {:e}",
            c.max_uy
        );
    }
}

#[test]
fn manufactured_solution_converges_at_order_two_with_dt_proportional_to_h() {
    let levels: Vec<_> = MANUFACTURED_LEVELS
        .iter()
        .map(|&nx| manufactured_level(nx).unwrap())
        .collect();
    let slope = observed_order(&levels);
    assert!(
        (slope - 2.0).abs() <= ORDER_TOL,
        "order {slope}: {levels:?}"
    );
}
