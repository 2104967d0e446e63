//! Signorini contact on the plane body's edges (issue 21): the bar with contact as an exact
//! special case, and the contact conditions and energy identity at every node and step of
//! every built-in plane scene. Run in release.

use viscobar::study::plane_checks::{bar_case, bar_contact_case_scenes};

/// The bar with contact as a special case: the same equations and the same complementarity
/// problem (the plane's LCP on the edge's `ny + 1` normals has the bar's solution times the
/// trapezoid shares), solved by different factorisations: round-off only.
const BAR_CASE_TOL: f64 = 1e-12;

#[test]
fn the_bar_with_contact_is_an_exact_special_case_of_the_plane_body() {
    for (name, bar) in bar_contact_case_scenes() {
        let c = bar_case(&bar).unwrap();
        eprintln!("{name}: {c:?}");
        assert!(c.contact_steps > 0, "{name}: no contact");
        assert!(
            c.max_ux_deviation <= BAR_CASE_TOL * c.max_u,
            "{name}: ux off by {:e}",
            c.max_ux_deviation
        );
        assert!(c.max_uy <= BAR_CASE_TOL * c.max_u, "{name}: uy {:e}", c.max_uy);
        assert!(
            c.max_reaction_deviation <= BAR_CASE_TOL * c.max_reaction,
            "{name}: reactions off by {:e}",
            c.max_reaction_deviation
        );
    }
}
