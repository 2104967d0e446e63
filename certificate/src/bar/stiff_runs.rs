//! Running the stiff and extreme case matrix of [`crate::bar::stiff`]: each case's solvers step in
//! lockstep with the exact one and are compared with it after every step, while each run's
//! identity residual, penetration, energy drift and (exact solver) KKT audit at round-off
//! floors are recorded into a [`CaseResult`]. A failing solver is stopped and its error kept;
//! the others go on.
//!
//! Apart from the case list, the tolerances and the table ([`crate::bar::stiff`]), which say what is
//! checked and why; this file only produces the numbers they are checked on.

use crate::bar::roundoff::rigid_drift;
use crate::bar::stiff::{
    COMBINATION_ROUNDINGS, Case, CaseResult, Family, GAP_ROUNDINGS, RESIDUAL_ROUNDINGS, Size,
    SolverRun, StepTerms, UNIT_ROUNDOFF, Worst, cases, sum_rounding, violation_law,
};
use rayon::prelude::*;
use std::cell::RefCell;
use std::rc::Rc;
use viscobar::bar::{Discretisation, Simulation};
use viscobar::internals::bar::body::make_solver;
use viscobar::internals::linalg::kernels::ldlt::Ldlt;
use viscobar::internals::linalg::norms::{max_abs, max_distance};
use viscobar::internals::linalg::spectrum::reference::STURM_ERROR_ULPS;
use viscobar::internals::linalg::system::TridiagSystem;
use viscobar::internals::linalg::tridiag::SymTridiag;
use viscobar::internals::step::block_pivot::TIE_ULPS;
use viscobar::output::Tracker;
use viscobar::scheme::RunError;
use viscobar::scheme::StepRecord;
use viscobar::step::Constraints;
use viscobar::step::audit::{KktAudit, Slack};
use viscobar::step::law::{Law, LawFamily};
use viscobar::step::{SolveInfo, SolverReport, StepFailure, StepSolver};

/// What the last solve formed, shared between a run's [`Traced`] solver and its [`Live`]
/// state: the right-hand side `b̂`, the answer `z`, the reactions `r` and the previous answer
/// `w` (the increment the scheme's `u^n − u^{n−1}` is, bit for bit: the simulation swaps its
/// `z` into `w` after each step, the start-up's included).
#[derive(Default)]
struct Trace {
    rhs: Vec<f64>,
    z: Vec<f64>,
    w: Vec<f64>,
    reactions: Vec<f64>,
    lower: Vec<f64>,
}

/// Every solver of the matrix, wrapped so that each solve's vectors are recorded for the
/// a-posteriori tolerances; the exact solver also runs the KKT audit at round-off floors
/// after every step (recorded, not enforced: a miss is reported in the table, the run goes
/// on).
struct Traced {
    inner: Box<dyn StepSolver>,
    /// The audit with `C`'s factorisation.
    audit: Option<(KktAudit, TridiagSystem)>,
    trace: Rc<RefCell<Trace>>,
}

impl StepSolver for Traced {
    fn name(&self) -> &'static str {
        self.inner.name()
    }

    fn solve(
        &mut self,
        rhs: &[f64],
        lower: &[f64],
        z: &mut [f64],
        reactions: &mut [f64],
    ) -> Result<SolveInfo, StepFailure> {
        let info = self.inner.solve(rhs, lower, z, reactions)?;
        {
            let mut t = self.trace.borrow_mut();
            let t = &mut *t;
            std::mem::swap(&mut t.w, &mut t.z);
            for (dst, src) in [
                (&mut t.rhs, rhs),
                (&mut t.z, &*z),
                (&mut t.reactions, &*reactions),
                (&mut t.lower, lower),
            ] {
                dst.clear();
                dst.extend_from_slice(src);
            }
        }
        let Some((audit, system)) = self.audit.as_mut() else {
            return Ok(info);
        };
        match audit.check(
            system,
            Law::Signorini,
            Slack::NONE,
            rhs,
            lower,
            z,
            reactions,
        ) {
            Err(StepFailure::NonFinite) => Err(StepFailure::NonFinite),
            _ => Ok(info),
        }
    }

    fn report(&self) -> Option<SolverReport> {
        self.audit.as_ref().map(|(a, _)| SolverReport {
            audit: a.report().clone(),
            inaccurate_steps: None,
        })
    }
}

/// The worst audit ratio of the exact solver, force stationarity `‖Cz − b − r‖` left out: the
/// end enumeration puts an active node on its bound exactly, moving `z_j` by its forward error
/// (up to `κ ε |z|`), which leaves a force residual `C_jj` times that by design. Its image in
/// displacement, `‖C⁻¹(Cz − b − r)‖`, is checked: that is the error of the answer.
fn worst_ratio(r: &viscobar::step::AuditReport) -> (f64, &'static str) {
    [
        (
            r.primal_violation.map_or(0.0, |w| w.max_over_tolerance),
            "primal violation",
        ),
        (r.negative_reaction.max_over_tolerance, "negative reaction"),
        (
            r.complementarity.map_or(0.0, |w| w.max_over_tolerance),
            "complementarity",
        ),
        (
            r.stationarity_displacement.max_over_tolerance,
            "stationarity in displacement",
        ),
    ]
    .into_iter()
    .fold((0.0, "none"), |a, b| if b.0 > a.0 { b } else { a })
}

fn build(case: &Case, method: &str, trace: Rc<RefCell<Trace>>) -> Result<Simulation, RunError> {
    let scene = case.scene(method)?;
    let disc = Discretisation::new(&scene)?;
    let inner = make_solver(&scene, &disc)?;
    let audit = match method {
        "exact" => {
            let mut system = TridiagSystem::new(&disc.step_matrix)?;
            let constraints = Constraints::lower_bounds(&disc.constrained_locals());
            let audit = KktAudit::new(&mut system, &constraints, LawFamily::Signorini);
            Some((audit, system))
        }
        _ => None,
    };
    Simulation::with_solver(
        &scene,
        disc,
        Box::new(Traced {
            inner,
            audit,
            trace,
        }),
    )
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

/// `|A|x` in difference form: `|s_i||x_i| + |e_{i−1}||x_{i−1} − x_i| + |e_i||x_{i+1} − x_i|`,
/// the absolute size of what `A x` forms row by row (no rigid offset, as in `mul_into`).
fn abs_rows(a: &SymTridiag, x: &[f64], out: &mut [f64]) {
    let n = x.len();
    let (s, e) = (a.row_sums(), &a.off);
    for i in 0..n {
        let mut v = (s[i] * x[i]).abs();
        if i > 0 {
            v += (e[i - 1] * (x[i - 1] - x[i])).abs();
        }
        if i + 1 < n {
            v += (e[i] * (x[i + 1] - x[i])).abs();
        }
        out[i] = v;
    }
}

/// `Σ |s_i| x_i² + Σ |e_i| (Δx_i)²`: the absolute terms of `xᵀAx` in difference form.
fn abs_quad(a: &SymTridiag, x: &[f64]) -> f64 {
    let (s, e) = (a.row_sums(), &a.off);
    let mut q = 0.0;
    for i in 0..x.len() {
        q += s[i].abs() * x[i] * x[i];
        if i + 1 < x.len() {
            let d = x[i + 1] - x[i];
            q += e[i].abs() * d * d;
        }
    }
    q
}

/// `P(v) = Σ |s_i| v_i² + Σ |e_i| |Δv_i| (|v_i| + |v_{i+1}|)`: `|vᵀA e|` for `|e_i| <= |v_i|`.
fn stored_form(a: &SymTridiag, v: &[f64]) -> f64 {
    let (s, e) = (a.row_sums(), &a.off);
    let mut q = 0.0;
    for i in 0..v.len() {
        q += s[i].abs() * v[i] * v[i];
        if i + 1 < v.len() {
            q += e[i].abs() * (v[i + 1] - v[i]).abs() * (v[i].abs() + v[i + 1].abs());
        }
    }
    q
}

/// What a run's penetration tolerance needs besides the step's vectors.
struct Penetration<'a> {
    solver: &'static str,
    /// The run's largest displacement so far (OSQP's relative primal tolerance).
    scale: f64,
    /// `max_j (C⁻¹)_jj` over the constrained ends (0 with an obstacle): the penalty law.
    schur_max: f64,
    /// A lower bound on `λ_min(C)` (the norm bound where `C` is not a Stieltjes matrix).
    lambda_min: f64,
    /// The factors of `C` with the rows and columns of an active set of ends replaced by
    /// identity ones, by mask (at most three per run: computed when first needed).
    pinned: &'a mut Vec<(u8, Ldlt)>,
}

/// The a-posteriori quantities of a step (see [`StepTerms`]): `t` the solve's vectors, `u1`,
/// `u0`, `um` the stored `û^{n+1}, û^n, û^{n−1}` on the unknowns, `force` the step's `F^n`,
/// `e_prev = E^{n−1/2}`.
#[allow(clippy::too_many_arguments)]
fn step_terms(
    d: &Discretisation,
    locals: &[usize],
    t: &Trace,
    force: &[f64],
    u1: &[f64],
    u0: &[f64],
    um: &[f64],
    rec: &StepRecord,
    e_prev: f64,
    penetration: &mut Penetration,
) -> StepTerms {
    let n = t.z.len();
    let u = UNIT_ROUNDOFF;
    let (z, w, b) = (&t.z[..], &t.w[..], &t.rhs[..]);
    let inv_dt2 = 1.0 / (d.dt * d.dt);
    let c_w = 0.5 - d.alpha / (2.0 * d.dt);
    let delta: Vec<f64> = z.iter().zip(w).map(|(a, b)| a + b).collect();
    let mut pr = vec![0.0; n];
    for (j, &l) in locals.iter().enumerate() {
        pr[l] += t.reactions[j];
    }
    let mut rho = vec![0.0; n];
    d.step_matrix.mul_into(z, &mut rho);
    for i in 0..n {
        rho[i] = rho[i] - b[i] - pr[i];
    }
    let y: Vec<f64> = (0..n).map(|i| c_w * w[i] - u0[i]).collect();
    let (mut cz, mut mw, mut ry) = (vec![0.0; n], vec![0.0; n], vec![0.0; n]);
    abs_rows(&d.step_matrix, z, &mut cz);
    abs_rows(&d.mass, w, &mut mw);
    abs_rows(&d.stiffness, &y, &mut ry);
    let (rs, re) = (d.stiffness.row_sums(), &d.stiffness.off);
    let mut f = vec![0.0; n];
    let mut force_dot = 0.0;
    for i in 0..n {
        let force_bound = force[i].abs();
        // `y_i` is rounded once (`u |y_i|`); R carries that into rows i and i ± 1.
        let mut y_round = (rs[i].abs()) * y[i].abs();
        if i > 0 {
            y_round += re[i - 1].abs() * (y[i].abs() + y[i - 1].abs());
        }
        if i + 1 < n {
            y_round += re[i].abs() * (y[i].abs() + y[i + 1].abs());
        }
        f[i] = RESIDUAL_ROUNDINGS
            * u
            * (cz[i] + 2.0 * b[i].abs() + pr[i].abs() + mw[i] * inv_dt2 + ry[i] + force_bound)
            + u * y_round;
        force_dot += force_bound * delta[i].abs();
    }
    let half = |v: f64| 0.5 * v;
    let rho_dot = half((0..n).map(|i| rho[i] * delta[i]).sum::<f64>()).abs();
    let floor_rho_abs = half((0..n).map(|i| (delta[i] * f[i]).abs()).sum::<f64>());
    let contact_dot: f64 = (0..n).map(|i| (pr[i] * delta[i]).abs()).sum();
    let sum_terms = 0.5 * inv_dt2 * (abs_quad(&d.mass, z) + abs_quad(&d.mass, w))
        // `|û^n|²_R` enters both energies as the same computed number: its rounding cancels.
        + 0.25 * (abs_quad(&d.stiffness, u1) + abs_quad(&d.stiffness, um))
        + d.alpha / (4.0 * d.dt) * abs_quad(&d.stiffness, &delta)
        + 0.5 * force_dot
        + 0.5 * contact_dot;
    let stored_rounding = 0.5 * u * (stored_form(&d.stiffness, u1) + stored_form(&d.stiffness, um));
    let scale = [
        rec.energy,
        e_prev,
        rec.work.abs(),
        rec.viscous_dissipation,
        rec.contact_dissipation.abs(),
    ]
    .into_iter()
    .fold(0.0, f64::max);
    let combination = rec.energy.abs()
        + e_prev.abs()
        + rec.work.abs()
        + rec.viscous_dissipation
        + rec.contact_dissipation.abs();
    let solver = penetration.solver;
    let mut max_reaction = 0.0f64;
    for &r in &t.reactions {
        max_reaction = max_reaction.max(r);
    }
    let law = violation_law(
        solver,
        max_reaction,
        penetration.scale,
        penetration.schur_max,
    );
    // The exact solvers' allowance at the constrained nodes without a reaction (see
    // [`StepTerms::violation_tolerance`]): the block-pivoting solver accepts the z it returns
    // with margins down to `−TIE_ULPS ε max(max|z|, max|lo|)`; the end enumeration decides on
    // its Schur candidate (or re-solves after it), so the z it returns is untested when an
    // end is active, and the forward error of that z on its own active set is allowed there.
    let ends = d.ends_only();
    let mut mask = 0u8;
    for (j, &r) in t.reactions.iter().enumerate() {
        if ends && r > 0.0 {
            mask |= 1 << j;
        }
    }
    let inactive = t.reactions.iter().filter(|&&r| r <= 0.0).count();
    let untested = solver == "exact" && ends && mask != 0 && inactive > 0;
    let forward = if untested {
        Some(forward_on_inactive(
            d,
            locals,
            mask,
            &rho,
            &cz,
            b,
            &pr,
            penetration,
        ))
    } else {
        None
    };
    let tie = if solver == "exact" && !ends {
        TIE_ULPS * f64::EPSILON * max_abs(z).max(max_abs(&t.lower))
    } else {
        0.0
    };
    let mut node = Worst::default();
    let (mut node_gap, mut node_allowance) = (0.0, 0.0);
    for (j, (&l, c)) in locals.iter().zip(&d.constraints).enumerate() {
        // The gap as the simulation forms it (`ContactSet::measure`): `û^{n+1}_j + a_j`.
        let violation = (-(u1[l] + c.gap)).max(0.0);
        let gap = sum_rounding(GAP_ROUNDINGS, t.lower[j].abs() + u1[l].abs());
        let allowance = match (&forward, t.reactions[j] > 0.0) {
            (_, true) => 0.0,
            (Some(f), false) => f[l],
            (None, false) => tie,
        };
        let before = node;
        node.update(violation, law + gap + allowance);
        if node != before {
            (node_gap, node_allowance) = (gap, allowance);
        }
    }
    StepTerms {
        residual: rec.identity_residual,
        scale,
        rho_dot,
        floor_rho_abs,
        sum_terms,
        sum_len: n,
        stored_rounding,
        combination,
        violation: node.value,
        gap_rounding: node_gap,
        allowance: node_allowance,
        law,
    }
}

/// The forward error of the end solver's answer on the unknowns off its active set: `z`
/// against the exact answer `z*` of the same `b̂` with `z*_A = lo_A` on the ends that carry a
/// reaction (`mask`). Both have `z_A = lo_A` (the solver writes `lower[j]` there on every
/// path), so `e = z − z*` has `e_A = 0` and `C_II e_I = ρ_I` with `ρ = C z − b̂ − r` (`r_I = 0`)
/// in exact arithmetic, and `|ρ_I| <= |ρ̂_I| + f_I`, `f` the rounding of `ρ̂` alone (the
/// solver answered `b̂`). `C_II` is `C` with its active ends removed: one O(n) solve with the
/// factor of `C` pinned there (at most three factors per run, against the previous full-`C`
/// bound, whose near-singular rigid mode made it 1e4 times too large at `Δt = 1e4 Δx`). Where
/// `C` is a Stieltjes matrix, `C_II⁻¹ >= 0` entrywise, so `|e_I| <= C_II⁻¹ (|ρ̂_I| + f_I)`
/// componentwise; that solve has no cancellation (pivots positive, multipliers `<= 0`, data
/// `>= 0`) and errs by at most `γ_{3n}` relative, covered by `1 + 2nε`. Else the norm bound
/// `‖|ρ̂_I| + f_I‖₂ / λ_min(C)` (`λ_min(C_II) >= λ_min(C)` by interlacing) at every node.
#[allow(clippy::too_many_arguments)]
fn forward_on_inactive(
    d: &Discretisation,
    locals: &[usize],
    mask: u8,
    rho: &[f64],
    cz: &[f64],
    b: &[f64],
    pr: &[f64],
    penetration: &mut Penetration,
) -> Vec<f64> {
    let n = rho.len();
    let u = UNIT_ROUNDOFF;
    let active: Vec<usize> = (locals.iter().enumerate())
        .filter(|&(j, _)| mask & (1 << j) != 0)
        .map(|(_, &l)| l)
        .collect();
    let mut v: Vec<f64> = (0..n)
        .map(|i| rho[i].abs() + RESIDUAL_ROUNDINGS * u * (cz[i] + b[i].abs() + pr[i].abs()))
        .collect();
    for &l in &active {
        v[l] = 0.0;
    }
    let stieltjes = d.step_matrix.off.iter().all(|&e| e <= 0.0);
    if !stieltjes {
        let norm = v.iter().map(|x| x * x).sum::<f64>().sqrt() / penetration.lambda_min;
        v.fill(norm);
        return v;
    }
    let pinned = &mut *penetration.pinned;
    let k = match pinned.iter().position(|(m, _)| *m == mask) {
        Some(k) => k,
        None => match Ldlt::factor_with_identity_rows(&d.step_matrix, &active) {
            Ok(f) => {
                pinned.push((mask, f));
                pinned.len() - 1
            }
            // Not expected (a principal submatrix of an SPD C): a NaN tolerance fails.
            Err(_) => {
                v.fill(f64::NAN);
                return v;
            }
        },
    };
    pinned[k].1.solve_in_place(&mut v);
    let grow = 1.0 + 2.0 * n as f64 * f64::EPSILON;
    for x in v.iter_mut() {
        *x = grow * x.max(0.0);
    }
    v
}

/// One solver's run state while stepping in lockstep with the others.
struct Live {
    sim: Option<Simulation>,
    /// The run's summary statistics (identity residual, penetration, first and last energy),
    /// taken into `out` by [`Live::settle`] when the run ends.
    tracker: Option<Tracker>,
    trace: Rc<RefCell<Trace>>,
    out: SolverRun,
    u: Vec<f64>,
    /// `û^n` and `û^{n−1}` on the unknowns (before the step observed).
    u_now: Vec<f64>,
    u_before: Vec<f64>,
    energy_prev: f64,
    /// A lower bound on `λ_min(C)` of the case.
    lambda_min: f64,
    /// `max_j (C⁻¹)_jj` over the constrained ends (0 with an obstacle).
    schur_max: f64,
    energy_max: f64,
    balance: f64,
    magnitude: f64,
    /// `Σ_n` of the steps' absolute identity tolerances ([`StepTerms::identity_bound`]) and
    /// of the drift's per-step rounding bounds.
    allowance_sum: f64,
    drift_rounding: f64,
    /// `Σ_n` of the steps' residuals on the recorded numbers, signed and absolute (the
    /// drift's notes: how much of the allowance is used, how much cancels).
    residual_sum: f64,
    residual_abs_sum: f64,
    dump: Option<StepTerms>,
    /// The factors of `C` pinned on an active set of ends ([`Penetration::pinned`]).
    pinned: Vec<(u8, Ldlt)>,
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
        let d = sim.discretisation();
        let unknowns = d.first..d.first + d.unknowns();
        let (u0, _) = sim.initial_state();
        self.u_before = u0[unknowns.clone()].to_vec();
        sim.displacement_into(&mut self.u);
        self.u_now = self.u[unknowns].to_vec();
        self.energy_prev = first.energy;
        self.sim = Some(sim);
        self.observe(&first, true);
    }

    fn observe(&mut self, r: &StepRecord, first: bool) {
        self.out.steps_done = r.step;
        if let Some(sim) = &self.sim {
            sim.displacement_into(&mut self.u);
        }
        if !first {
            if let Some(t) = self.tracker.as_mut() {
                t.observe(r);
            }
            let u = UNIT_ROUNDOFF;
            let term = r.work - r.viscous_dissipation - r.contact_dissipation;
            let size = r.work.abs() + r.viscous_dissipation + r.contact_dissipation.abs();
            self.balance += term;
            self.magnitude += size;
            // This step's rounding between the drift and the steps' computed residuals: the
            // residual's own roundings (its exact value on the recorded numbers telescopes),
            // two of the balance's term and one of its running sum.
            let residual = r.energy - self.energy_prev - r.work
                + r.viscous_dissipation
                + r.contact_dissipation;
            self.residual_sum += residual;
            self.residual_abs_sum += residual.abs();
            let combination = r.energy.abs() + self.energy_prev.abs() + size;
            let c = u * (COMBINATION_ROUNDINGS * combination + 2.0 * size + self.balance.abs());
            self.drift_rounding += c;
            if let Some(sim) = self.sim.as_mut() {
                // F^n as the step used it, evaluated again (deterministic).
                let force = match sim.load_vector(r.step - 1) {
                    Ok(f) => f.to_vec(),
                    Err(_) => vec![f64::NAN; self.u_now.len()],
                };
                let d = sim.discretisation();
                let unknowns = d.first..d.first + d.unknowns();
                let terms = step_terms(
                    d,
                    &d.constrained_locals(),
                    &self.trace.borrow(),
                    &force,
                    &self.u[unknowns.clone()],
                    &self.u_now,
                    &self.u_before,
                    r,
                    self.energy_prev,
                    &mut Penetration {
                        solver: self.out.solver,
                        scale: self.out.max_displacement.max(max_abs(&self.u)),
                        schur_max: self.schur_max,
                        lambda_min: self.lambda_min,
                        pinned: &mut self.pinned,
                    },
                );
                let id_tol = terms.identity_tolerance();
                self.allowance_sum += terms.identity_bound();
                if terms.residual / id_tol >= self.out.identity.ratio() {
                    self.dump = Some(terms);
                }
                self.out.identity.update(terms.residual, id_tol);
                self.out
                    .violation
                    .update(terms.violation, terms.violation_tolerance());
                self.u_before.clone_from(&self.u_now);
                self.u_now.copy_from_slice(&self.u[unknowns]);
            }
            self.energy_prev = r.energy;
        }
        self.energy_max = self.energy_max.max(r.energy.abs());
        let o = &mut self.out;
        if let Some(sim) = &self.sim {
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
        // The drift is the sum of the steps' residuals on the recorded numbers (telescoping),
        // each within its step's identity tolerance when that check holds and the energy each
        // step carries is the one recorded: their sum, the per-step roundings and the final
        // difference's two (`SolverRun::drift_tolerance`).
        let bound = self.allowance_sum
            + self.drift_rounding
            + 2.0
                * UNIT_ROUNDOFF
                * (s.energy_final.abs() + s.energy_initial.abs() + self.balance.abs());
        if self.allowance_sum > 0.0 {
            o.drift_used = self.residual_abs_sum / self.allowance_sum;
        }
        if self.residual_abs_sum > 0.0 {
            o.drift_cancellation = self.residual_sum.abs() / self.residual_abs_sum;
        }
        if let Some(t) = &self.dump {
            o.identity_dominant = t.dominant_term();
        }
        (o.energy_drift, o.drift_tolerance) = if scale > 0.0 {
            (drift / scale, bound / scale)
        } else {
            (0.0, 0.0)
        };
        if let (Some(t), true) = (self.dump, std::env::var_os("VISCOBAR_STIFF_DUMP").is_some()) {
            let id_tol = t.identity_tolerance();
            eprintln!(
                "DUMP {} id {:.2e}/{:.2e}={:.1e} | sc {:.1e} rhodot {:.1e} fl1 {:.1e} sums {:.1e} m {} st {:.1e} comb {:.1e} | viol {:.1e}/{:.1e} drift {:.1e}/{:.1e}",
                o.solver,
                t.residual,
                id_tol,
                t.residual / id_tol,
                t.scale,
                t.rho_dot,
                t.floor_rho_abs,
                t.sum_terms,
                t.sum_len,
                t.stored_rounding,
                t.combination,
                o.violation.value,
                o.violation.tolerance,
                o.energy_drift,
                o.drift_tolerance
            );
        }
    }
}

/// Runs one case: every solver in lockstep with the exact one, compared after every step.
pub fn run_case(case: &Case) -> CaseResult {
    let nodes = case.elements as usize + 1;
    let mut kappa = None;
    let mut max_gap = 0.0f64;
    let mut schur = None;
    let mut lambda_min = f64::NAN;
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
                    identity: Worst::default(),
                    violation: Worst::default(),
                    drift_tolerance: 0.0,
                    drift_used: 0.0,
                    drift_cancellation: 0.0,
                    identity_dominant: "none",
                    audit_worst: "none",
                },
                tracker: None,
                trace: Rc::new(RefCell::new(Trace::default())),
                u: vec![0.0; nodes],
                u_now: Vec::new(),
                u_before: Vec::new(),
                energy_prev: 0.0,
                lambda_min: f64::NAN,
                schur_max: 0.0,
                energy_max: 0.0,
                balance: 0.0,
                magnitude: 0.0,
                allowance_sum: 0.0,
                residual_sum: 0.0,
                residual_abs_sum: 0.0,
                drift_rounding: 0.0,
                dump: None,
                pinned: Vec::new(),
            };
            match build(case, solver, l.trace.clone()) {
                Ok(sim) => {
                    if kappa.is_none() {
                        let d = sim.discretisation();
                        let c = &d.step_matrix;
                        kappa = viscobar::internals::linalg::spectrum::condition_number(c);
                        // The bisection's error bound, tested against the double-double
                        // reference in `linalg::spectrum`.
                        lambda_min =
                            (viscobar::internals::linalg::spectrum::smallest_eigenvalue_spd(c)
                                - STURM_ERROR_ULPS * f64::EPSILON * c.inf_norm())
                            .max(0.0);
                        max_gap = d.constraints.iter().fold(0.0, |m, c| m.max(c.gap));
                        schur = d.ends_only().then(|| inverse_diagonal_range(d)).flatten();
                    }
                    l.lambda_min = lambda_min;
                    l.schur_max = schur.map_or(0.0, |(_, hi): (f64, f64)| hi);
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
                if l.out.solver == "exact" {
                    let (ratio, what) = sim
                        .solver_report()
                        .map_or((0.0, "none"), |r| worst_ratio(&r.audit));
                    l.out.audit_ratio = Some(ratio);
                    l.out.audit_worst = what;
                }
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
    let factor = Ldlt::factor(&d.step_matrix).ok()?;
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
