//! `[plane] integration`: selective reduced integration of the `λ` term does not lock, full
//! integration does; both pass the patch test; the bar is still an exact special case (`λ = 0`:
//! the rules give the same `K`, bit for bit); the energy identity keeps its form (the `K`-forms
//! follow the rule).

use viscobar::internals::plane::matrices::{Integration, Material, assemble_with};
use viscobar::internals::plane::mesh::Grid;
use viscobar_certificate::plane::locking::{
    LOCKED_BELOW, PATCH_TOL, SELECTIVE_BAND, cantilever_table, identity_ratio, patch_worst,
};

#[test]
fn both_rules_pass_the_patch_test() {
    let [full, selective] = patch_worst().unwrap();
    println!("patch: full {full:e}, selective {selective:e}");
    assert!(full <= PATCH_TOL, "{full}");
    assert!(selective <= PATCH_TOL, "{selective}");
}

/// Against Timoshenko beam theory: selective stays in its band at every ν up to 0.4999, full
/// falls below it from ν = 0.45 on and locks at 0.4999.
#[test]
fn selective_integration_does_not_lock_and_full_does() {
    let table = cantilever_table().unwrap();
    for r in &table {
        println!("{r:?}");
        assert!(
            (SELECTIVE_BAND.0..=SELECTIVE_BAND.1).contains(&r.selective),
            "{r:?}"
        );
        if r.nu >= 0.45 {
            assert!(r.full < SELECTIVE_BAND.0, "{r:?}");
        }
    }
    let last = table.last().unwrap();
    assert!(last.full < LOCKED_BELOW, "{last:?}");
}

/// With `λ = 0` the λ term vanishes: both rules assemble the same `K`, bit for bit (so the
/// bar's special case, certified for full integration, holds for selective too); with `λ ≠ 0`
/// they differ.
#[test]
fn the_rules_agree_bitwise_without_lambda() {
    let grid = Grid::new(2.0, 0.5, 7, 3, 2.0);
    let m = |lambda| Material {
        lambda,
        mu: 0.5,
        density: 1.0,
    };
    let full = assemble_with(&grid, m(0.0), Integration::Full);
    let sel = assemble_with(&grid, m(0.0), Integration::Selective);
    assert!(
        full.stiffness
            .iter()
            .zip(&sel.stiffness)
            .all(|(a, b)| a.to_bits() == b.to_bits())
    );
    let full = assemble_with(&grid, m(1.0), Integration::Full);
    let sel = assemble_with(&grid, m(1.0), Integration::Selective);
    assert!(full.stiffness != sel.stiffness);
}

/// The energy identity of a nearly incompressible cantilever with either rule: the `K`-forms
/// follow the rule, so the identity closes to its round-off, which grows with `λ/μ` (forms of
/// the other rule would leave a residual of the order of the λ term).
#[test]
fn the_energy_identity_holds_with_selective_integration() {
    for rule in [Integration::Full, Integration::Selective] {
        let ratio = identity_ratio(0.4999, rule).unwrap();
        println!("{rule:?}: identity residual / bound {ratio:.3}");
        assert!(ratio <= 1.0, "{rule:?}: {ratio}");
    }
}

/// The bar as a special case (`λ = 0`, certified to `PLANE_BAR_CASE_TOL` with full
/// integration in `tests/plane.rs`) runs bit for bit the same with selective integration: the
/// plane scenes of the bar cases, every displacement and energy of every step.
#[test]
fn the_bar_cases_run_bitwise_the_same_with_selective_integration() {
    use viscobar_certificate::plane::{BAR_CASE_BODY, bar_case_scenes, plane_of_bar};
    for (name, bar) in bar_case_scenes() {
        let (height, ny, grading) = BAR_CASE_BODY;
        let full = plane_of_bar(&bar, height, ny, grading).unwrap();
        let mut selective = full.clone();
        selective.plane.integration = Integration::Selective;
        let (a, _, sa) = viscobar::output::run_plane_in_memory(name, &full).unwrap();
        let (b, _, sb) = viscobar::output::run_plane_in_memory(name, &selective).unwrap();
        assert!(
            sa.displacement()
                .iter()
                .zip(sb.displacement())
                .all(|(x, y)| x.to_bits() == y.to_bits()),
            "{name}"
        );
        assert!(
            a.iter()
                .zip(&b)
                .all(|(x, y)| x.energy.to_bits() == y.energy.to_bits()),
            "{name}"
        );
    }
}
