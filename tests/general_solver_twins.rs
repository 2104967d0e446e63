//! The bar's specialised exact step solvers against their general twin: a run with
//! `Kernels::general_solver` (every step by `CondensedLcp` on the bar's step matrix) keeps the
//! trajectory of the default run (`EndEnumeration` on the two-end scene, `BlockPivoting`
//! under an obstacle), step for step. `benches/twins.rs` times the two.

mod common;

use viscobar::Simulation;
use viscobar::bar::Kernels;
use viscobar::internals::linalg::norms::max_abs;

/// The two runs' displacements agree to this, relative to the run's largest `|u|`: each
/// step's answers agree to 64 ulps (`step::condensed_lcp`'s twin tests), and the scheme does
/// not amplify a perturbation, so the differences stay round-off over the run (measured
/// 2.1e-13 on `distributed`, 1.8e-15 on the end scenes; fifty times the largest).
const GENERAL_TWIN_TOL: f64 = 1e-11;

#[test]
fn the_general_solver_keeps_the_specialised_solvers_trajectories() {
    let general = Kernels {
        general_solver: true,
        ..Kernels::TWINS
    };
    for name in ["both-ends", "one-end", "distributed"] {
        let scene = common::builtin(name, &[]);
        let mut a = Simulation::new(&scene).unwrap();
        let mut b = Simulation::with_kernels(&scene, general).unwrap();
        let (mut worst, mut scale, mut contact_steps) = (0.0f64, 0.0f64, 0);
        for _ in 1..scene.steps() {
            let (ra, rb) = (a.step().unwrap(), b.step().unwrap());
            contact_steps += usize::from(ra.contact.total_reaction > 0.0);
            assert_eq!(
                ra.contact.contact_nodes, rb.contact.contact_nodes,
                "{name}, step {}: contact sets differ",
                ra.step
            );
            let (ua, ub) = (&a.state().u, &b.state().u);
            scale = scale.max(max_abs(ua.iter()));
            worst = (ua.iter().zip(ub.iter())).fold(worst, |m, (x, y)| m.max((x - y).abs()));
        }
        assert!(contact_steps > 0, "{name}: no contact");
        // Two algorithms, not one twice: their round-off differs.
        assert!(worst > 0.0, "{name}: the general solver did not run");
        assert!(
            worst <= GENERAL_TWIN_TOL * scale,
            "{name}: the runs differ by {:e} of max |u|",
            worst / scale
        );
    }
}
