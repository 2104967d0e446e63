//! The bar's specialised exact step solvers against their general twin: each built-in scene of
//! [`GENERAL_TWIN_SCENES`] run by default (`EndEnumeration` on the ends, `BlockPivoting` under
//! an obstacle) and with `Kernels::general_solver` (every step by `CondensedLcp` on the bar's
//! step matrix), step for step (`tests/general_solver_twins.rs`, `benches/twins.rs`).

use viscobar::Simulation;
use viscobar::bar::Kernels;
use viscobar::internals::linalg::norms::max_abs;
use viscobar::scene;
use viscobar::scheme::RunError;

/// The scenes compared: two-end contact and the obstacle under every node.
pub const GENERAL_TWIN_SCENES: [&str; 3] = ["both-ends", "one-end", "distributed"];

/// One scene's comparison.
#[derive(Clone, Debug)]
pub struct GeneralTwin {
    pub name: &'static str,
    /// The largest difference of the displacements over the run, over the run's largest `|u|`.
    pub deviation: f64,
    /// Steps with contact, and whether every step's contact set agreed.
    pub contact_steps: usize,
    pub same_contact_sets: bool,
}

/// [`GeneralTwin`] of each of [`GENERAL_TWIN_SCENES`].
pub fn general_twins() -> Result<Vec<GeneralTwin>, RunError> {
    let general = Kernels {
        general_solver: true,
        ..Kernels::TWINS
    };
    let mut out = Vec::new();
    for name in GENERAL_TWIN_SCENES {
        let (_, scene) = scene::load(name, &[])?;
        let mut a = Simulation::new(&scene)?;
        let mut b = Simulation::with_kernels(&scene, general)?;
        let (mut worst, mut scale, mut contact_steps) = (0.0f64, 0.0f64, 0);
        let mut same_contact_sets = true;
        for _ in 1..scene.steps() {
            let (ra, rb) = (a.step()?, b.step()?);
            contact_steps += usize::from(ra.contact.total_reaction > 0.0);
            same_contact_sets &= ra.contact.contact_nodes == rb.contact.contact_nodes;
            let (ua, ub) = (&a.state().u, &b.state().u);
            scale = scale.max(max_abs(ua.iter()));
            worst = (ua.iter().zip(ub.iter())).fold(worst, |m, (x, y)| m.max((x - y).abs()));
        }
        out.push(GeneralTwin {
            name,
            deviation: worst / scale,
            contact_steps,
            same_contact_sets,
        });
    }
    Ok(out)
}
