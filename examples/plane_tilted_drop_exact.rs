//! The `plane-tilted-drop` scene with the exact step: a Kelvin–Voigt block in plane strain,
//! tilted, dropped under gravity onto a rigid floor below its bottom edge. The example steps the
//! built-in scene through the library, checks the scheme's energy identity and the contact
//! conditions at every step, and prints the contact episodes of the bottom edge, the energy the
//! contact took, and the step solver's work.
//!
//!     cargo run --release --example plane_tilted_drop_exact

use viscobar::output::Tracker;
use viscobar::output::output_time;
use viscobar::plane::PlaneSimulation;
use viscobar::scene::{AnyScene, load_any};

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let AnyScene::Plane(scene) = load_any("plane-tilted-drop", &[])?.1 else {
        unreachable!("a built-in plane scene")
    };
    let mut sim = PlaneSimulation::new(&scene)?;
    let mut tracker = Tracker::new(&sim, !sim.is_forced());
    let (mut worst_residual, mut worst_penetration, mut dissipated) = (0.0f64, 0.0f64, 0.0);
    for _ in 1..scene.steps() {
        let r = sim.step()?;
        tracker.observe(&r);
        worst_residual = worst_residual.max(r.identity_residual);
        worst_penetration = worst_penetration.max(-r.contact.min_gap);
        dissipated += r.contact_dissipation;
    }
    let summary = tracker.finish("plane-tilted-drop", &sim, 0.0);
    println!(
        "plane-tilted-drop: {} unknowns, {} contact normals, {} steps of dt = {}",
        summary.unknowns,
        sim.contact().len(),
        summary.steps,
        summary.dt
    );
    println!("  energy identity, worst relative residual: {worst_residual:.1e}");
    println!("  worst penetration (gap < 0):              {worst_penetration:.1e}");
    println!("  energy taken by contact, Σ D:             {dissipated:.4e}");
    println!(
        "  active sets tried per step (mean, max):   {:.2}, {}",
        summary.solver_iterations.mean, summary.solver_iterations.max
    );
    for e in &summary.contact_episodes["bottom"] {
        println!(
            "  bottom edge in contact over [{}, {}]: impulse {:.4}, peak reaction {:.4}",
            output_time(e.start),
            output_time(e.end),
            e.impulse,
            e.peak_reaction
        );
    }
    println!(
        "What to see: the identity holds to round-off (about 1e-15) at every step while the\n\
         contact set grows from one corner to the whole edge; no node goes below the floor\n\
         beyond round-off; the contact term only takes energy (Σ D > 0)."
    );
    Ok(())
}
