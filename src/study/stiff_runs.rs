//! Running the stiff and extreme case matrix of `study::stiff`: each case's solvers step in
//! lockstep with the exact one and are compared with it after every step, while each run's
//! identity residual, penetration, energy drift and (exact solver) KKT audit at round-off
//! floors are recorded into a [`CaseResult`]. A failing solver is stopped and its error kept;
//! the others go on.
//!
//! Apart from the case list, the tolerances and the table (`study::stiff`), which say what is
//! checked and why; this file only produces the numbers they are checked on.

use crate::linalg::norms::{max_abs, max_distance};
use crate::step::audit::{KktAudit, Law};
use crate::step::{SolveInfo, SolverReport, StepFailure, StepSolver};
use crate::study::accuracy::rigid_drift;
use crate::study::stiff::{Case, CaseResult, Family, Size, SolverRun, cases};
use crate::time::RunError;
use crate::time::simulation::{Discretisation, Simulation, make_solver};
use crate::time::summary::Tracker;
use rayon::prelude::*;

/// The exact solver with the KKT audit at round-off floors recorded after every step (not
/// enforced: a miss is reported in the table, the run goes on).
struct Audited {
    inner: Box<dyn StepSolver>,
    audit: KktAudit,
}

impl StepSolver for Audited {
    fn name(&self) -> &'static str {
        self.inner.name()
    }

    // Forwarded, so that the matrix audits the solver as runs use it.
    fn set_state_scale(&mut self, max_abs_u: f64) {
        self.inner.set_state_scale(max_abs_u);
    }

    fn solve(
        &mut self,
        rhs: &[f64],
        lower: &[f64],
        z: &mut [f64],
        reactions: &mut [f64],
    ) -> Result<SolveInfo, StepFailure> {
        let info = self.inner.solve(rhs, lower, z, reactions)?;
        let law = Law::Signorini {
            eps_abs: 0.0,
            eps_rel: 0.0,
        };
        match self.audit.check(law, rhs, lower, z, reactions) {
            Err(StepFailure::NonFinite) => Err(StepFailure::NonFinite),
            _ => Ok(info),
        }
    }

    fn report(&self) -> Option<SolverReport> {
        Some(SolverReport {
            audit: self.audit.report().clone(),
            inaccurate_steps: None,
        })
    }
}

/// The worst audit ratio of the exact solver, force stationarity `‖Cz − b − r‖` left out: the
/// end enumeration puts an active node on its bound exactly, moving `z_j` by its forward error
/// (up to `κ ε |z|`), which leaves a force residual `C_jj` times that by design. Its image in
/// displacement, `‖C⁻¹(Cz − b − r)‖`, is checked: that is the error of the answer.
fn worst_ratio(r: &crate::step::AuditReport) -> f64 {
    [
        r.primal_violation.map_or(0.0, |w| w.max_over_tolerance),
        r.negative_reaction.max_over_tolerance,
        r.complementarity.map_or(0.0, |w| w.max_over_tolerance),
        r.stationarity_displacement.max_over_tolerance,
    ]
    .into_iter()
    .fold(0.0, f64::max)
}

fn build(case: &Case, method: &str) -> Result<Simulation, RunError> {
    let scene = case.scene(method)?;
    if method != "exact" {
        return Simulation::new(&scene);
    }
    let disc = Discretisation::new(&scene)?;
    let inner = make_solver(&scene, &disc)?;
    let audit = KktAudit::new(&disc.step_matrix, &disc.constrained_locals(), false)?;
    Simulation::with_solver(&scene, disc, Box::new(Audited { inner, audit }))
}

/// The table's short form of an error.
fn short_error(e: &RunError) -> (String, bool) {
    match e {
        RunError::Step { step, failure, .. } => {
            let what = match failure {
                StepFailure::AuditFailed { what, .. } => format!("audit: {what}"),
                other => other.to_string(),
            };
            (format!("error at step {step}: {what}"), true)
        }
        // Set-up errors come before the first step (a refused solver, a singular C).
        other => (format!("refused: {other}"), true),
    }
}

/// One solver's run state while stepping in lockstep with the others.
struct Live {
    sim: Option<Simulation>,
    /// The run's summary statistics (identity residual, penetration, first and last energy),
    /// taken into `out` by [`Live::settle`] when the run ends.
    tracker: Option<Tracker>,
    out: SolverRun,
    u: Vec<f64>,
    energy_max: f64,
    balance: f64,
    magnitude: f64,
}

impl Live {
    fn fail(&mut self, e: &RunError) {
        let (msg, located) = short_error(e);
        self.out.error = Some(msg);
        self.out.error_located = located;
        self.settle();
        self.sim = None;
    }

    /// A run just built: the tracker takes its start-up record.
    fn start(&mut self, sim: Simulation) {
        // Unforced or not: the energy rise is not read here.
        self.tracker = Some(Tracker::new(&sim, false));
        let first = sim.first_record();
        self.sim = Some(sim);
        self.observe(&first, true);
    }

    fn observe(&mut self, r: &crate::time::simulation::StepRecord, first: bool) {
        let o = &mut self.out;
        o.steps_done = r.step;
        if !first {
            if let Some(t) = self.tracker.as_mut() {
                t.observe(r);
            }
            self.balance += r.work - r.viscous_dissipation - r.contact_dissipation;
            self.magnitude += r.work.abs() + r.viscous_dissipation + r.contact_dissipation.abs();
        }
        self.energy_max = self.energy_max.max(r.energy.abs());
        if let Some(sim) = &self.sim {
            sim.displacement_into(&mut self.u);
            o.all_finite &= self.u.iter().all(|v| v.is_finite());
            o.max_displacement = o.max_displacement.max(max_abs(&self.u));
            o.max_reaction = o.max_reaction.max(max_abs(sim.reactions()));
        }
    }

    /// The run has ended (completed or failed): the tracker's statistics and the energy drift
    /// into `out`.
    fn settle(&mut self) {
        let (Some(tracker), Some(sim)) = (self.tracker.take(), &self.sim) else {
            return;
        };
        let s = tracker.finish("", sim, 0.0);
        let o = &mut self.out;
        o.max_identity_residual = s.max_identity_residual;
        o.max_violation = s.max_violation;
        let scale = self.energy_max.max(self.magnitude);
        let drift = (s.energy_final - s.energy_initial - self.balance).abs();
        o.energy_drift = if scale > 0.0 { drift / scale } else { 0.0 };
    }
}

/// Runs one case: every solver in lockstep with the exact one, compared after every step.
pub fn run_case(case: &Case) -> CaseResult {
    let nodes = case.elements as usize + 1;
    let mut kappa = None;
    let mut max_gap = 0.0f64;
    let mut schur = None;
    let mut live: Vec<Live> = case
        .solvers()
        .into_iter()
        .map(|solver| {
            let mut l = Live {
                sim: None,
                out: SolverRun {
                    solver,
                    error: None,
                    error_located: false,
                    steps_done: 0,
                    max_identity_residual: 0.0,
                    max_violation: 0.0,
                    max_reaction: 0.0,
                    distance: (solver != "exact").then_some(0.0),
                    max_displacement: 0.0,
                    energy_drift: 0.0,
                    audit_ratio: None,
                    rigid_drift: None,
                    all_finite: true,
                },
                tracker: None,
                u: vec![0.0; nodes],
                energy_max: 0.0,
                balance: 0.0,
                magnitude: 0.0,
            };
            match build(case, solver) {
                Ok(sim) => {
                    if kappa.is_none() {
                        let d = sim.discretisation();
                        kappa = crate::linalg::spectrum::condition_number(&d.step_matrix);
                        max_gap = d.constraints.iter().fold(0.0, |m, c| m.max(c.gap));
                        schur = d.ends_only().then(|| inverse_diagonal_range(d)).flatten();
                    }
                    l.start(sim);
                }
                Err(e) => l.fail(&e),
            }
            l
        })
        .collect();
    compare_with_exact(&mut live);
    for _ in 1..case.steps {
        if live.iter().all(|l| l.sim.is_none()) {
            break;
        }
        for l in live.iter_mut() {
            let Some(sim) = l.sim.as_mut() else { continue };
            match sim.step() {
                Ok(r) => l.observe(&r, false),
                Err(e) => l.fail(&e),
            }
        }
        compare_with_exact(&mut live);
    }
    let runs = live
        .into_iter()
        .map(|mut l| {
            l.settle();
            if let Some(sim) = &l.sim {
                l.out.audit_ratio = (l.out.solver == "exact")
                    .then(|| sim.solver_report().map_or(0.0, |r| worst_ratio(&r.audit)));
                if case.family == Family::Rigid {
                    let t = sim.time();
                    l.out.rigid_drift = Some(rigid_drift(&l.u, t));
                }
            }
            l.out
        })
        .collect();
    CaseResult {
        case: case.clone(),
        kappa,
        nodes,
        max_gap,
        schur,
        runs,
    }
}

/// `(min_j, max_j) (C⁻¹)_jj` over the constrained nodes, one O(n) solve each (at most two).
fn inverse_diagonal_range(d: &Discretisation) -> Option<(f64, f64)> {
    let factor = crate::linalg::ldlt::Ldlt::factor(&d.step_matrix).ok()?;
    d.constrained_locals()
        .iter()
        .map(|&j| factor.column_of_inverse(j)[j])
        .fold(None, |acc, v| match acc {
            None => Some((v, v)),
            Some((lo, hi)) => Some((v.min(lo), v.max(hi))),
        })
}

/// After a step of every live run: the distance of each to the exact run (index 0), while
/// both are alive (`observe` has just copied each run's `u^n` into `l.u`).
fn compare_with_exact(live: &mut [Live]) {
    let (exact, others) = live.split_first_mut().expect("exact first");
    if exact.sim.is_none() {
        return;
    }
    for l in others.iter_mut().filter(|l| l.sim.is_some()) {
        let d = max_distance(&l.u, &exact.u);
        if let Some(dist) = l.out.distance.as_mut() {
            *dist = dist.max(d);
        }
    }
}

/// Runs every case, in parallel on rayon's pool, results in case order (deterministic).
pub fn run_all(size: Size) -> Vec<CaseResult> {
    cases(size).par_iter().map(run_case).collect()
}
