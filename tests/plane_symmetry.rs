//! Mirror and turn symmetry of the plane body with Signorini edges. A scene reflected
//! (x → W − x, y → H − y) or turned by ±90° or 180° (edges, gaps, initial data and load carried
//! along) is the same continuous problem, and its Q1 grid is the image of the original grid, so
//! its run must be the image of the original run, node by node and step by step, up to the
//! round-off of a different elimination order. The gaps vary along their edges and contact
//! reaches both end nodes of every Signorini edge (checked), so the tests guard, with no
//! reference value: the outward normal and the unknown of each edge (contact on the bottom,
//! top, left and right edges), the edge coordinate `s` at every node of an edge, its end nodes
//! included, and the corner normals of two Signorini edges; for the exact method (α > 0 and
//! α = 0), the penalty and OSQP.

use viscobar_certificate::plane::symmetry::{
    Case, Runs, Suite, between_walls_suite, check, corner_suite, end_contact, falling_block_suite,
    solver_suites,
};

// ---- tolerances ----------------------------------------------------------------------------

// The tolerances of this file: in the registry (viscobar_certificate::tolerances), which measures
// their worst values over these checks (`viscobar-certificate verify --tolerances`). The
// deviations of each check are printed by `cargo test --release --test plane_symmetry --
// --nocapture`.
use viscobar_certificate::tolerances::{
    PLANE_SYMMETRY_DISPLACEMENT_TOL as SYMMETRY_DISPLACEMENT_TOL,
    PLANE_SYMMETRY_REACTION_TOL as SYMMETRY_REACTION_TOL,
};
/// Least share of the run's largest reaction that each end node of a Signorini edge must carry
/// at some step: real contact, far above round-off (the least share is printed).
const END_REACTION_SHARE: f64 = 0.01;

// ---- the checks -------------------------------------------------------------------------------

/// Checks that contact occurs at both end nodes of every Signorini edge of `case` at some step,
/// with a reaction of at least [`END_REACTION_SHARE`] of the run's largest, and that the contact
/// set changes at least twice (lands, and changes again): the comparison then runs the gap at
/// the ends and the contact solver's choices.
fn assert_contact_reaches_the_ends(case: &Case, runs: &mut Runs) {
    let run = runs.of(case).unwrap_or_else(|e| panic!("{e}"));
    let found = end_contact(case, &run);
    let largest = found.largest;
    for end in &found.ends {
        let (p, most) = (end.node, end.most);
        assert!(
            most >= END_REACTION_SHARE * largest,
            "{}: no contact at its end node {p:?} (largest reaction there {most:e}, in the \
             run {largest:e})",
            end.edge
        );
    }
    let changes = found.contact_set_changes;
    eprintln!(
        "end nodes' reaction share at least {:.3}, contact set changes {changes} times",
        found.least_share()
    );
    assert!(changes >= 2, "the contact set changes {changes} times");
}

/// The checks of `suite`: contact reaches the ends of its base case's edges, and every image
/// run is the image of the run, within the tolerances.
fn assert_symmetric(suite: &Suite) {
    let mut runs = Runs::default();
    assert_contact_reaches_the_ends(&suite.base, &mut runs);
    for (case, sym) in &suite.checks {
        let c = check(&mut runs, case, *sym).unwrap_or_else(|e| panic!("{e}"));
        let (what, d) = (c.what, c.deviation);
        eprintln!("{what}: {d:?}");
        assert!(
            d.u <= SYMMETRY_DISPLACEMENT_TOL,
            "{what}: displacements deviate by {:e} of the largest, beyond {SYMMETRY_DISPLACEMENT_TOL:e}",
            d.u
        );
        assert!(
            d.r <= SYMMETRY_REACTION_TOL,
            "{what}: reactions deviate by {:e} of the largest, beyond {SYMMETRY_REACTION_TOL:e}",
            d.r
        );
    }
}

// ---- the tests ---------------------------------------------------------------------------------

#[test]
fn a_viscous_block_falling_on_a_sloped_floor_runs_the_same_mirrored_and_turned() {
    // Mirrored and turned; then contact on the top, and that run reflected.
    assert_symmetric(&falling_block_suite());
}

#[test]
fn an_undamped_block_between_two_walls_runs_the_same_mirrored_and_turned() {
    assert_symmetric(&between_walls_suite());
}

#[test]
fn a_block_pushed_into_a_corner_runs_the_same_mirrored_and_turned() {
    assert_symmetric(&corner_suite());
}

#[test]
fn penalty_and_osqp_runs_are_mirrored_too() {
    for suite in solver_suites() {
        assert_symmetric(&suite);
    }
}
