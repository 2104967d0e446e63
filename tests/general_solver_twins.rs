//! The bar's specialised exact step solvers against their general twin: a run with
//! `Kernels::general_solver` (every step by `CondensedLcp` on the bar's step matrix) keeps the
//! trajectory of the default run (`EndEnumeration` on the two-end scene, `BlockPivoting`
//! under an obstacle), step for step. `benches/twins.rs` times the two.

use viscobar_certificate::solvers::general_twins::general_twins;
use viscobar_certificate::tolerances::GENERAL_TWIN_TOL;

#[test]
fn the_general_solver_keeps_the_specialised_solvers_trajectories() {
    for twin in general_twins().unwrap() {
        let name = twin.name;
        assert!(twin.contact_steps > 0, "{name}: no contact");
        assert!(twin.same_contact_sets, "{name}: the contact sets differ");
        // Two algorithms, not one twice: their round-off differs.
        assert!(
            twin.deviation > 0.0,
            "{name}: the general solver did not run"
        );
        assert!(
            twin.deviation <= GENERAL_TWIN_TOL,
            "{name}: the runs differ by {:e} of max |u|",
            twin.deviation
        );
    }
}
