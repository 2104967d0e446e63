//! The built-in `plane-block-drop` (a 30 × 15 block falling onto a floor for 200 steps,
//! undamped as a Newmark run of a general-purpose code would be, and with the talk's α = 0.1)
//! never gains energy: at every step `E^{n+1/2} − E^{n−1/2} − work = −viscous − contact <= 0`
//! to round-off, with the contact term dissipative. Its cost is the criterion bench
//! `plane-contact/kratos-block-30x15-200-steps` (benches/plane.rs), not timed here.

use viscobar::output::run_plane_in_memory;
use viscobar::scene::{AnyScene, load_any};
use viscobar_certificate::tolerances::IDENTITY_TOL;

/// The talk's α (the bar's talk scenes).
const TALK_ALPHA: &str = "0.1";

fn block(set: &[String]) -> viscobar::PlaneScene {
    match load_any("plane-block-drop", set).unwrap().1 {
        AnyScene::Plane(s) => *s,
        AnyScene::Bar(_) => panic!("plane-block-drop is a plane scene"),
    }
}

#[test]
fn the_falling_block_never_gains_energy_undamped_or_viscous() {
    for set in [vec![], vec![format!("plane.viscosity={TALK_ALPHA}")]] {
        let scene = block(&set);
        assert_eq!((scene.mesh.nx, scene.mesh.ny, scene.steps()), (30, 15, 200));
        let (records, summary, sim) = run_plane_in_memory("plane-block-drop", &scene).unwrap();
        let alpha = scene.plane.viscosity;
        assert_eq!(records.len(), 200);
        assert_eq!(sim.contact().len(), 31, "the bottom's 31 nodes");
        let mut total_gain = 0.0;
        let mut contact = 0.0;
        for w in records.windows(2) {
            let (before, r) = (&w[0], &w[1]);
            let gain = r.energy - before.energy - r.work;
            let d = r.contact_dissipation;
            let scale = [
                r.energy,
                before.energy,
                r.work.abs(),
                r.viscous_dissipation,
                d.abs(),
            ]
            .into_iter()
            .fold(0.0, f64::max);
            assert!(
                gain <= IDENTITY_TOL * scale,
                "alpha {alpha}, step {}: energy gained {gain:e} beyond the load's work",
                r.step
            );
            assert!(
                d >= -IDENTITY_TOL * scale,
                "alpha {alpha}, step {}: contact term {d:e} < 0",
                r.step
            );
            assert!(r.identity_residual <= IDENTITY_TOL, "step {}", r.step);
            total_gain += gain;
            contact += d;
        }
        // It lands (the whole bottom); undamped, it leaves the floor and lands again (the
        // viscous block stays down).
        let touching: Vec<bool> = (records.iter())
            .map(|r| r.contact.contact_nodes > 0)
            .collect();
        let landings = touching.windows(2).filter(|w| !w[0] && w[1]).count();
        let releases = touching.windows(2).filter(|w| w[0] && !w[1]).count();
        let expected = if alpha == 0.0 { (2, 1) } else { (1, 0) };
        assert_eq!(
            (landings, releases),
            expected,
            "alpha {alpha}: {touching:?}"
        );
        let most = records.iter().map(|r| r.contact.contact_nodes).max();
        assert_eq!(most, Some(31));
        assert_eq!(
            summary.contact_intervals["bottom"].len(),
            expected.0,
            "one episode a landing"
        );
        // The landings take energy (the scheme's contact term), none is made.
        assert!(
            contact > 0.0,
            "alpha {alpha}: contact dissipated {contact:e}"
        );
        assert!(total_gain < 0.0, "alpha {alpha}: {total_gain:e}");
    }
}
