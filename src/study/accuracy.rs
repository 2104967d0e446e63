//! Error measurement against closed forms, shared by the tests and the CLI studies.

use crate::bar::closed_form::ClosedForm;
use crate::bar::{Discretisation, Simulation};
use crate::linalg::ldlt::Ldlt;
use crate::linalg::tridiag::SymTridiag;
use crate::scene::Scene;
use crate::scheme::RunError;
use crate::scheme::{Body, Scheme, StepRecord};

/// Errors of a run against an exact solution, at the nodes and every time step.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct ErrorNorms {
    /// `max_n ‖u_h(t_n) − u(·, t_n)‖_{L2}` with the trapezoidal rule on the nodes.
    pub l2: f64,
    /// `max_n max_i |u_i^n − u(x_i, t_n)|`.
    pub max: f64,
}

/// `max_i |u_i − t|`: the distance of a rigid translation's displacement from `u = t`.
pub fn rigid_drift(u: &[f64], t: f64) -> f64 {
    u.iter().fold(0.0f64, |m, v| m.max((v - t).abs()))
}

/// Steps `sims` together from the start-up state to `steps` states, calling `observe` with the
/// simulations and the records of the step: once after the start-up (no records), then after
/// every step. They step in slice order, so a failure is the first failing simulation's.
pub fn lockstep<B: Body>(
    sims: &mut [Scheme<B>],
    steps: usize,
    mut observe: impl FnMut(&[Scheme<B>], Vec<StepRecord>),
) -> Result<(), RunError> {
    observe(sims, Vec::new());
    for _ in 1..steps {
        let records = sims
            .iter_mut()
            .map(Scheme::step)
            .collect::<Result<Vec<_>, _>>()?;
        observe(sims, records);
    }
    Ok(())
}

/// Runs `scene` with the exact solver and measures its error against `exact`.
pub fn error_against(scene: &Scene, exact: &dyn ClosedForm) -> Result<ErrorNorms, RunError> {
    let mut sim = Simulation::new(scene)?;
    let disc = sim.discretisation().clone();
    let xs: Vec<f64> = (0..disc.nodes).map(|i| disc.x(i)).collect();
    let weights: Vec<f64> = (0..disc.nodes)
        .map(|i| {
            if i == 0 || i + 1 == disc.nodes {
                0.5 * disc.dx
            } else {
                disc.dx
            }
        })
        .collect();
    let mut u = vec![0.0; disc.nodes];
    let mut norms = ErrorNorms::default();
    lockstep(std::slice::from_mut(&mut sim), scene.steps(), |sims, _| {
        let sim = &sims[0];
        sim.displacement_into(&mut u);
        let t = sim.time();
        let mut l2 = 0.0;
        for i in 0..u.len() {
            let e = u[i] - exact.displacement(xs[i], t);
            l2 += weights[i] * e * e;
            norms.max = norms.max.max(e.abs());
        }
        norms.l2 = norms.l2.max(l2.sqrt());
    })?;
    Ok(norms)
}

/// Least-squares slope of `log e` against `log h`: the observed order of convergence.
pub fn observed_order(h: &[f64], e: &[f64]) -> f64 {
    let n = h.len() as f64;
    let lx: Vec<f64> = h.iter().map(|v| v.ln()).collect();
    let ly: Vec<f64> = e.iter().map(|v| v.ln()).collect();
    let mx = lx.iter().sum::<f64>() / n;
    let my = ly.iter().sum::<f64>() / n;
    let sxy: f64 = lx.iter().zip(&ly).map(|(x, y)| (x - mx) * (y - my)).sum();
    let sxx: f64 = lx.iter().map(|x| (x - mx) * (x - mx)).sum();
    sxy / sxx
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
    let c = Ldlt::factor(&disc.step_matrix)?;
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
