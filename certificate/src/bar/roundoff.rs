//! The rigid-mode round-off study (VERIFICATION.md, "Round-off"): a free-free bar translating
//! rigidly, `u = t`, which the scheme reproduces exactly in exact arithmetic, so whatever
//! distance from `u = t` a run ends at is round-off; the increment form of viscobar's time loop
//! against the talk's form of the step.

use viscobar::bar::{Discretisation, Simulation};
use viscobar::internals::linalg::kernels::ldlt_fast::TwistedLdlt;
use viscobar::internals::linalg::tridiag::SymTridiag;
use viscobar::scene::Scene;
use viscobar::scheme::RunError;
use viscobar::study::accuracy::lockstep;

/// `max_i |u_i − t|`: the distance of a rigid translation's displacement from `u = t`.
pub fn rigid_drift(u: &[f64], t: f64) -> f64 {
    u.iter().fold(0.0f64, |m, v| m.max((v - t).abs()))
}

/// The rigid-mode round-off study: a free-free elastic bar of length 1 launched at unit
/// velocity (`u = t` exactly, and exactly reproduced by the scheme in exact arithmetic), run
/// `steps` steps with `dt = dx`. Returns `max_i |u_i^N − t_N|` for the increment form used by
/// [`Simulation`] and for the talk's form `C u^{n+1} = F̃^n`, which forms
/// `2M u^n/Δt² − (M/Δt² + R/2) u^{n−1}` (size `|u|/Δt²`) to produce an increment of size `Δt`.
pub fn rigid_mode_drift(elements: u64, steps: usize) -> Result<(f64, f64), RunError> {
    let text = format!(
        "[bar]\nlength = 1.0\n[left]\ncondition = \"free\"\n[right]\ncondition = \"free\"\n\
         [initial]\ndisplacement = \"0\"\nvelocity = \"1\"\n[mesh]\nelements = {elements}\n\
         [time]\nstep = {dt}\nend = {end}\n",
        dt = 1.0 / elements as f64,
        end = (steps + 1) as f64 / elements as f64
    );
    let scene = Scene::from_toml(&text, &[])?;
    let mut sim = Simulation::new(&scene)?;
    lockstep(std::slice::from_mut(&mut sim), steps, |_, _| {})?;
    let increment = rigid_drift(&sim.displacement_dofs(), sim.time());

    let disc = Discretisation::new(&scene)?;
    let dt = disc.dt;
    let n = disc.unknowns();
    // The factorisation the time loop solves with, so that only the form differs.
    let c = TwistedLdlt::factor(&disc.step_matrix)?;
    let b = SymTridiag::combine(1.0 / (dt * dt), &disc.mass, 0.5, &disc.stiffness);
    let (mut u_prev, mut u, mut next) = (vec![0.0; n], vec![dt; n], vec![0.0; n]);
    let (mut mu, mut bu) = (vec![0.0; n], vec![0.0; n]);
    for _ in 1..steps {
        disc.mass.mul_into(&u, &mut mu);
        b.mul_into(&u_prev, &mut bu);
        for i in 0..n {
            next[i] = 2.0 / (dt * dt) * mu[i] - bu[i];
        }
        c.solve_in_place(&mut next);
        std::mem::swap(&mut u_prev, &mut u);
        std::mem::swap(&mut u, &mut next);
    }
    let talk = rigid_drift(&u, steps as f64 * dt);
    Ok((increment, talk))
}
