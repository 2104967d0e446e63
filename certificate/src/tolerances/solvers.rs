//! The step solvers' tolerances on the built-in scenes (`tests/solvers.rs`), the exact
//! solver's tie (`tests/exact_solver.rs`) and the equal-error check of `tests/converge.rs`,
//! each beside the measurement of what it guards.

use super::{GAP_TOL, IDENTITY_TOL, exact_sample_error};
use viscobar::internals::linalg::tridiag::SymTridiag;
use viscobar::internals::step::end_penalty::PENALTY_DEFAULT_EPSILON;
use viscobar::internals::step::osqp::OSQP_DEFAULT_EPS;
use viscobar::scene::{self, MassVariant, Scene, SolverMethod, builtin_names};
use viscobar::scheme::RunError;
use viscobar::step::audit::AUDIT_MARGIN;
use viscobar::study::compare::{Comparison, compare};

// ---- tests/general_solver_twins.rs: the bar's specialised solvers against the general one --

/// The two runs' displacements agree to this, relative to the run's largest `|u|`: each
/// step's answers agree to 64 ulps (`step::condensed_lcp`'s twin tests), and the scheme does
/// not amplify a perturbation, so the differences stay round-off over the run (measured
/// 2.1e-13 on `distributed`, 1.8e-15 on the end scenes; fifty times the largest).
pub const GENERAL_TWIN_TOL: f64 = 1e-11;

// ---- tests/solvers.rs: the three step solvers on every built-in scene ----------------------

/// Energy identity, OSQP, a priori: it holds up to `½ ρ·δ` with `ρ` the stationarity residual,
/// which the audit allows up to `AUDIT_MARGIN · eps_rel = 1e-9` relative to `‖Cz‖`.
pub const OSQP_IDENTITY_TOL: f64 = AUDIT_MARGIN * OSQP_DEFAULT_EPS;
/// OSQP: the audit's primal tolerance `AUDIT_MARGIN (eps_abs + eps_rel · s)` with the scale
/// `s = max(|z_j|, |lo_j|) <= 3` on the built-in scenes (|u| <= 2.7), plus the exact solver's
/// rounding of `u + a`.
pub const OSQP_GAP_TOL: f64 = AUDIT_MARGIN * OSQP_DEFAULT_EPS * 4.0 + GAP_TOL;
/// OSQP: the audit's dual tolerance `AUDIT_MARGIN (eps_abs + eps_rel · s_f)` with the force
/// scale `s_f = max(‖b‖, ‖Cz‖, r)`, of the size of `dx |v|/dt + |u_x| + r`, below 1e3 on the
/// built-in scenes (|v|, |u_x|, r of order 1, dx/dt <= 1).
pub const OSQP_REACTION_TOL: f64 = AUDIT_MARGIN * OSQP_DEFAULT_EPS * 1e3;
/// Penalty law `ε r = max(0, −gap)` in the recorded gap `u^{n+1} + a`: rounding of
/// `u^n + z + a` (each below 3 in magnitude) on top of the solver's own round-off.
pub const PENALTY_LAW_TOL: f64 = 1e-14;
/// OSQP against exact, max over nodes and steps of the displacement: the requirement,
/// kept as the outer contract; the check that can fail is [`osqp_agreement_bound`].
pub const OSQP_AGREEMENT_TOL: f64 = 1e-7;
/// Per step, in units of `ε max |u|`: how far two solves of one step's active-set system may
/// differ (exact's LDLᵀ and polished OSQP's KKT solve, both backward stable, κ(C) of a few at
/// Δt ≈ Δx; measured up to 2.5 on the built-in scenes).
pub const AGREEMENT_ULPS_PER_STEP: f64 = 16.0;

/// The agreement bound of one OSQP run, a posteriori: per step, the two solves' round-off
/// [`AGREEMENT_ULPS_PER_STEP`] `ε max |u|` plus OSQP's own audited stationarity residual in
/// displacement (`‖C⁻¹ρ‖∞`, the step's error for its active set), accumulated linearly over the
/// steps (the scheme is stable: it does not amplify a perturbation). 0 without an audit (an
/// OSQP run always audits: any difference then fails).
pub fn osqp_agreement_bound(cmp: &Comparison) -> f64 {
    let Some(audit) = cmp.summary.audit.as_ref() else {
        return 0.0;
    };
    let per_step = AGREEMENT_ULPS_PER_STEP * f64::EPSILON * cmp.agreement.max_displacement
        + audit.stationarity_displacement.max;
    cmp.agreement.steps as f64 * per_step
}

/// The OSQP identity tolerance of one run, a posteriori: the run's own worst stationarity
/// residual over the audit's tolerance scales the a-priori [`OSQP_IDENTITY_TOL`] (the identity
/// error `½ ρ·δ` is linear in `ρ`), on top of the round-off [`IDENTITY_TOL`] of every solver.
pub fn osqp_identity_tol(stationarity_over_tolerance: f64) -> f64 {
    IDENTITY_TOL + stationarity_over_tolerance * OSQP_IDENTITY_TOL
}

/// The scenes the mass variants other than consistent are checked on (consistent: every
/// built-in scene): one and two Signorini ends, a clamped far end, a load, an obstacle (which
/// refuses redistribution); the two 2400-step talk scenes with one end are left out to keep the
/// test short (both-ends has the same ends with more of them).
pub const MASS_VARIANT_SCENES: [&str; 5] = [
    "impact",
    "falling-bar",
    "clamped-impact",
    "both-ends",
    "distributed",
];

/// (scene, mass variant) pairs of the solvers' generic checker (`tests/solvers.rs`).
pub fn solver_cases() -> Vec<(&'static str, MassVariant)> {
    let mut v: Vec<_> = builtin_names()
        .into_iter()
        .map(|n| (n, MassVariant::Consistent))
        .collect();
    for mass in [MassVariant::Redistributed, MassVariant::Lumped] {
        v.extend(MASS_VARIANT_SCENES.iter().map(|n| (*n, mass)));
    }
    v
}

/// Worst values over one compared run (`scene` run side by side with the exact solver) of what
/// the solver tolerances of `tests/solvers.rs` guard.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct SolverWorst {
    /// Identity residual over its tolerance: [`IDENTITY_TOL`] (exact, penalty) or
    /// [`osqp_identity_tol`] of the run's audit (OSQP).
    pub identity_ratio: f64,
    /// `max (−gap)⁺` over the Signorini ends and the obstacle's nodes.
    pub negative_gap: f64,
    /// `max (−r)⁺` over the same.
    pub negative_reaction: f64,
    /// OSQP: `max |gap · r| / (OSQP_GAP_TOL |r| + OSQP_REACTION_TOL |gap|)` at the ends.
    pub complementarity_ratio: f64,
    /// Penalty: `max |ε r − (−gap)⁺|` at the ends, and the penetration beyond `ε r_max`.
    pub law: f64,
    /// `max |u − u_exact|` over nodes and steps.
    pub agreement: f64,
    /// OSQP: that over the run's [`osqp_agreement_bound`].
    pub agreement_ratio: f64,
}

impl SolverWorst {
    pub fn max(self, o: SolverWorst) -> SolverWorst {
        SolverWorst {
            identity_ratio: self.identity_ratio.max(o.identity_ratio),
            negative_gap: self.negative_gap.max(o.negative_gap),
            negative_reaction: self.negative_reaction.max(o.negative_reaction),
            complementarity_ratio: self.complementarity_ratio.max(o.complementarity_ratio),
            law: self.law.max(o.law),
            agreement: self.agreement.max(o.agreement),
            agreement_ratio: self.agreement_ratio.max(o.agreement_ratio),
        }
    }
}

/// [`SolverWorst`] of one comparison of `scene` (its own solver) against the exact solver.
pub fn solver_worst(scene: &Scene, cmp: &Comparison) -> SolverWorst {
    let method = scene.solver.method;
    let identity_tol = match (method, cmp.summary.audit.as_ref()) {
        (SolverMethod::Osqp, Some(a)) => osqp_identity_tol(a.stationarity.max_over_tolerance),
        (SolverMethod::Osqp, None) => 0.0, // an OSQP run always audits: any residual fails
        _ => IDENTITY_TOL,
    };
    let k = scene.signorini_ends().len();
    let mut w = SolverWorst {
        agreement: cmp.agreement.max_difference,
        ..SolverWorst::default()
    };
    if method == SolverMethod::Osqp {
        let bound = osqp_agreement_bound(cmp);
        let difference = cmp.agreement.max_difference;
        w.agreement_ratio = if bound > 0.0 {
            difference / bound
        } else if difference > 0.0 {
            f64::INFINITY
        } else {
            0.0
        };
    }
    let mut max_reaction = 0.0f64;
    for r in &cmp.records {
        w.identity_ratio = w.identity_ratio.max(r.identity_residual / identity_tol);
        if scene.obstacle.is_some() {
            w.negative_gap = w.negative_gap.max(-r.contact.min_gap);
            w.negative_reaction = w.negative_reaction.max(-r.contact.min_reaction);
        }
        for j in 0..k {
            let (g, l) = (r.contact.groups[j].min_gap, r.contact.groups[j].reaction);
            max_reaction = max_reaction.max(l);
            w.negative_gap = w.negative_gap.max(-g);
            w.negative_reaction = w.negative_reaction.max(-l);
            match method {
                SolverMethod::Osqp => {
                    let tol = OSQP_GAP_TOL * l.abs() + OSQP_REACTION_TOL * g.abs();
                    let ratio = if tol > 0.0 { (g * l).abs() / tol } else { 0.0 };
                    w.complementarity_ratio = w.complementarity_ratio.max(ratio);
                }
                SolverMethod::Penalty => {
                    let law = (PENALTY_DEFAULT_EPSILON * l - (-g).max(0.0)).abs();
                    w.law = w.law.max(law);
                }
                SolverMethod::Exact => {}
            }
        }
    }
    if method == SolverMethod::Penalty {
        // Penetration is ε × reaction, to round-off.
        let beyond = cmp.summary.max_violation - PENALTY_DEFAULT_EPSILON * max_reaction;
        w.law = w.law.max(beyond);
    }
    w
}

/// The scene `name` with mass variant `mass` and step solver `method`, or `None` where the
/// combination is refused (redistribution with an obstacle; the penalty solver with one).
pub fn solver_case(
    name: &str,
    mass: MassVariant,
    method: &str,
) -> Result<Option<(Scene, Scene)>, RunError> {
    let mass_key = format!("bar.mass=\"{}\"", mass.name());
    if scene::load(name, std::slice::from_ref(&mass_key)).is_err() {
        return Ok(None);
    }
    let load = |m: &str| -> Result<Scene, RunError> {
        Ok(scene::load(name, &[mass_key.clone(), format!("solver.method=\"{m}\"")])?.1)
    };
    let (exact, scene) = (load("exact")?, load(method)?);
    if method == "penalty" && scene.obstacle.is_some() {
        return Ok(None);
    }
    Ok(Some((exact, scene)))
}

/// [`SolverWorst`] of `method` ("osqp" or "penalty") over every case of [`solver_cases`].
pub fn solver_worst_all(method: &str) -> Result<SolverWorst, RunError> {
    let mut w = SolverWorst::default();
    for (name, mass) in solver_cases() {
        if let Some((exact, scene)) = solver_case(name, mass, method)? {
            w = w.max(solver_worst(&scene, &compare(name, &exact, &scene)?));
        }
    }
    Ok(w)
}

/// The small hand-made OSQP problems: polished, the answer is the active set's solve, so
/// `κ(C) = 5.8` times a few roundings of `|z| <= 7/3` (1e-12 was below the registry's floor).
pub const SMALL_TOL: f64 = 64.0 * f64::EPSILON;

/// OSQP (default settings) on two hand-made problems with `C = tridiag(−1, 2, −1)` of size 3,
/// `b = 1`: no constraint (`z = (3/2, 2, 3/2)`), and `z_0 >= 2` active
/// (`z = (2, 7/3, 5/3)`, reaction `2/3`): the worst error of `z` and `r` against these closed
/// forms, and the number of steps the second solver audited.
pub fn osqp_small_problems() -> Result<(f64, u64), RunError> {
    use viscobar::internals::step::osqp::{Osqp, OsqpSettings};
    use viscobar::step::StepSolver;
    let c = SymTridiag::new(vec![2.0, 2.0, 2.0], vec![-1.0, -1.0]);
    let b = [1.0, 1.0, 1.0];
    let mut worst = 0.0f64;
    let failed = |step: usize, failure| RunError::Step {
        step,
        time: 0.0,
        solver: "osqp".into(),
        failure,
    };
    let mut free = Osqp::new(&c, &[], OsqpSettings::default())?;
    let mut z = [0.0; 3];
    free.solve(&b, &[], &mut z, &mut [])
        .map_err(|f| failed(0, f))?;
    for (zi, want) in z.iter().zip([1.5, 2.0, 1.5]) {
        worst = worst.max((zi - want).abs());
    }
    let mut one = Osqp::new(&c, &[0], OsqpSettings::default())?;
    let mut r = [0.0];
    one.solve(&b, &[2.0], &mut z, &mut r)
        .map_err(|f| failed(1, f))?;
    for (zi, want) in z.iter().zip([2.0, 7.0 / 3.0, 5.0 / 3.0]) {
        worst = worst.max((zi - want).abs());
    }
    worst = worst.max((r[0] - 2.0 / 3.0).abs());
    let steps = one.report().map_or(0, |rep| rep.audit.steps);
    Ok((worst, steps))
}

// ---- tests/exact_solver.rs ----------------------------------------------------------------------

/// Round-off level of the exact solver's tie (entries of size 1, condition number 12).
pub const TIE_TOL: f64 = 1e-14;

/// The exact solver on a tie: `C = tridiag(−1, 2, −1)` of size 3, `b = C·1`, bounds `z_0, z_2 >=
/// 1`, so every active set gives `z = 1` with zero reactions in exact arithmetic. Three calls:
/// the worst `|z − 1|` and `r` (`r` must be `>= 0`), whether the bounds held exactly and the
/// reactions were not negative, and whether every call gave the first call's bits.
pub fn exact_tie() -> Result<(f64, bool, bool), RunError> {
    use viscobar::internals::step::end_enumeration::EndEnumeration;
    use viscobar::step::StepSolver;
    let c = SymTridiag::new(vec![2.0, 2.0, 2.0], vec![-1.0, -1.0]);
    let z_free = [1.0, 1.0, 1.0];
    let b = c.mul(&z_free);
    let mut solver = EndEnumeration::new(&c, &[0, 2])?;
    let (mut worst, mut signs, mut same) = (0.0f64, true, true);
    let mut first: Option<(Vec<f64>, Vec<f64>)> = None;
    for call in 0..3 {
        let (mut z, mut r) = (vec![0.0; 3], vec![0.0; 2]);
        solver
            .solve(&b, &[1.0, 1.0], &mut z, &mut r)
            .map_err(exact_sample_error(call))?;
        for i in 0..3 {
            worst = worst.max((z[i] - z_free[i]).abs());
        }
        for v in &r {
            worst = worst.max(v.abs());
        }
        signs &= z[0] >= 1.0 && z[2] >= 1.0 && r.iter().all(|v| *v >= 0.0);
        match &first {
            None => first = Some((z, r)),
            Some((z1, r1)) => same &= z1 == &z && r1 == &r,
        }
    }
    Ok((worst, signs, same))
}

// ---- tests/converge.rs ------------------------------------------------------------------------

/// "Equal or better error": the exact solver's L2 error may exceed tight OSQP's (eps 1e-10) by
/// this relative amount. The two answers differ by OSQP's audited residual, about 1e-10 of a
/// displacement of size 1 against L2 errors of about 1e-2 (see the measured row).
pub const EQUAL_ERROR_RTOL: f64 = 1e-6;

/// The study of `tests/converge.rs`'s `exact_solver_beats_tight_osqp_at_equal_error_on_a_talk_scene`:
/// one-end at 100 elements and Δt = 0.02, exact and OSQP (eps 1e-10), two levels; rows
/// `0..2` exact, `2..4` OSQP.
pub fn equal_error_study() -> Result<viscobar::study::converge::Study, RunError> {
    use viscobar::study::converge::{self, ConvergeError, SolverSetting};
    let overrides = [
        "mesh.elements=100".to_string(),
        "time.step=0.02".to_string(),
    ];
    let (_, base) = scene::load("one-end", &overrides)?;
    let settings = [SolverSetting::Exact, SolverSetting::Osqp(1e-10)];
    converge::study("one-end", &base, &settings, 2, None).map_err(|e| match e {
        ConvergeError::Run(r) => r,
        ConvergeError::Scene(s) => RunError::Scene(s),
        other => RunError::SolverSetup {
            solver: "converge".into(),
            reason: other.to_string(),
        },
    })
}

/// What [`EQUAL_ERROR_RTOL`] guards on [`equal_error_study`]: the largest
/// `l2_exact / l2_osqp − 1` over its levels (negative: exact is strictly better).
pub fn equal_error_excess(study: &viscobar::study::converge::Study) -> f64 {
    let levels = study.rows.len() / 2;
    (0..levels)
        .map(|l| study.rows[l].l2_error / study.rows[levels + l].l2_error - 1.0)
        .fold(f64::NEG_INFINITY, f64::max)
}
