//! Error measurement against closed forms, shared by the tests and the CLI studies.

use crate::bar::Simulation;
use crate::bar::closed_form::ClosedForm;
use crate::scene::Scene;
use crate::scheme::{Body, RunError, Scheme, StepRecord};

/// Errors of a run against an exact solution, at the nodes and every time step.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct ErrorNorms {
    /// `max_n ‖u_h(t_n) − u(·, t_n)‖_{L2}` with the trapezoidal rule on the nodes.
    pub l2: f64,
    /// `max_n max_i |u_i^n − u(x_i, t_n)|`.
    pub max: f64,
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
