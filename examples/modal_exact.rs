//! The `modal` scene against its closed form: a free-free Kelvin–Voigt bar (`α = 0.01`) started
//! at rest in its second mode, `u = A(t) cos(2πx)` with `A'' + α ω² A' + ω² A = 0`, `ω = 2π`.
//! No contact: the smooth case, where the scheme is second order in `Δx` and `Δt` together. The
//! example runs the built-in scene and the scene refined once (`Δx`, `Δt` halved) through the
//! library and measures each against the closed form (`study::accuracy::error_against`).
//!
//!     cargo run --release --example modal_exact

use viscobar::bar::closed_form;
use viscobar::study::accuracy::error_against;
use viscobar::{RunError, scene};

fn main() -> Result<(), RunError> {
    let (name, scene) = scene::load("modal", &[])?;
    let exact = closed_form::for_scene(&name, &scene).expect("`modal` has a closed form");
    let mut previous: Option<f64> = None;
    for level in 0..2 {
        let scene = scene.refined(level);
        let errors = error_against(&scene, exact.as_ref())?;
        println!(
            "modal: {:4} elements, dt = {:.3e}: L2 error {:.3e}, max error {:.3e}",
            scene.mesh.elements, scene.time.step, errors.l2, errors.max
        );
        if let Some(coarse) = previous {
            println!("  L2 error ratio coarse/fine: {:.2}", coarse / errors.l2);
        }
        previous = Some(errors.l2);
    }
    println!(
        "What to see: errors below 1e-2 of the unit amplitude, divided by about 4 when Δx and\n\
         Δt are halved: second-order convergence (VERIFICATION.md, \"Convergence to closed forms\")."
    );
    Ok(())
}
