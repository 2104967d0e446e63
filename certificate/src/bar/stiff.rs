//! The stiff and extreme case matrix (`verify --stiff`, `tests/stiff.rs`): the scheme at the
//! corners of its parameter space, every step solver that applies, and for each run either a
//! result checked against round-off tolerances or an error that names the step. Never a
//! silent wrong answer.
//!
//! Axes: `α ∈ {0, 1e-8, 1e3, 1e6}`, `Δt/Δx ∈ {1e-3, 1, 100, 1e4}`, meshes from 1 element to
//! 999 999 (1e6 nodes), two Signorini ends at gap 0 with initial contact, a bar lying on a
//! distributed obstacle, forcing 1e6, overflowing forcing, and 1e6-step runs for drift.
//!
//! Per run (solver): the energy-identity residual, the penetration, the distance to the exact
//! solver, the energy balance's drift and (exact solver) the KKT audit at round-off floors,
//! each against a tolerance computed a posteriori from what the step formed ([`StepTerms`],
//! [`Worst`]), derived in `docs/stiff-tolerances.md`. This file holds what is checked: the
//! cases, the tolerances, the verdict and the table of VERIFICATION.md; running the cases is
//! [`crate::bar::stiff_runs`].

use std::fmt::Write;
use viscobar::internals::step::end_penalty::PENALTY_DEFAULT_EPSILON;
use viscobar::internals::step::osqp::OSQP_DEFAULT_EPS;
use viscobar::scene::Scene;
use viscobar::scheme::RunError;
use viscobar::step::audit::{AUDIT_MARGIN, ROUNDOFF_ULPS};

/// Full size (`verify --stiff`) or the reduced size of `tests/stiff.rs`.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Size {
    Full,
    Reduced,
}

/// Largest mesh of the reduced matrix (the full one goes to 999 999 elements, 1e6 nodes).
pub const REDUCED_MAX_ELEMENTS: u64 = 100_000;
/// Steps of the long drift runs: full and reduced.
pub const LONG_STEPS: usize = 1_000_000;
pub const REDUCED_LONG_STEPS: usize = 100_000;
/// OSQP runs only up to this many nodes: its ADMM iterations (up to 100 000 per step at the
/// default settings) make larger stiff meshes a matter of hours, not of verification.
pub const OSQP_MAX_NODES: usize = 1001;

/// OSQP against exact, relative to the largest displacement: the requirement of
/// `tests/solvers.rs` (`1e-7` on displacements of order 1), made relative so that the
/// forcing-1e6 cases are held to the same standard.
pub const OSQP_AGREEMENT_REL: f64 = 1e-7;
/// Penalty against exact: (PP) converges to the exact scheme at first order in ε, with a
/// constant that depends on the regime (at `Δt ≪ Δx` the penalty contact is a resolved spring
/// bounce, tens of penetrations away from the exact impact), so no a-priori bound at one ε is
/// honest. The matrix runs ε and ε/10 and requires the distance to shrink by at least this
/// factor: first order predicts 10; 5 accepts an observed order down to 0.7 (the talk scenes
/// measure 0.93–1.0 over ε = 1e-2 … 1e-6, VERIFICATION.md, section "Step solvers").
pub const PENALTY_CONVERGENCE_FACTOR: f64 = 5.0;
/// The convergence check applies where (PP) is in its asymptotic regime, `ε <= this · S_jj`
/// at every constrained node (`S = C⁻¹` there): the penalty reaction is the exact one times
/// `S_jj/(S_jj + ε)`, linear in ε to within 10 % only then. Elsewhere (`Δt ≪ Δx`, where
/// `C ≈ M/Δt²` is stiffer than the penalty spring `1/ε`) the distances are reported as
/// pre-asymptotic, and the penalty answer is still audited against (PP)'s own law.
pub const PENALTY_ASYMPTOTIC: f64 = 0.1;
/// The second penalty run of each case: ε/10.
pub const PENALTY_SMALL_EPSILON: f64 = PENALTY_DEFAULT_EPSILON / 10.0;
/// OSQP's audit allows, per step, an error in `z` of `AUDIT_MARGIN (eps_abs + eps_rel ‖z‖)`;
/// its absolute part, carried forward over `N` steps by the stable scheme, is what the relative
/// requirement above cannot express when `|u| ≪ 1` (gap-0 cases).
pub const OSQP_STEP_ABS: f64 = AUDIT_MARGIN * OSQP_DEFAULT_EPS;

/// The geometry and data of a case.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Family {
    /// The `impact` scene: elastic/viscous bar at velocity −1, obstacle 0.1 below the left end,
    /// right end free.
    Impact,
    /// Both ends Signorini at gap 0, bar at rest on them and moving down (velocity −1): contact
    /// at both ends from the first step.
    GapZero,
    /// A distributed obstacle `g(x) = 0.2 + 0.1 cos 2x` with the bar lying on it (`u⁰ = −g`),
    /// pushed down by gravity `l = −1`: every node in contact (block pivoting).
    Resting,
    /// `impact` under the load `l = −1e6` pushing it into the obstacle.
    Forced,
    /// `impact` under `l = −1e300`: the displacement overflows; the run must stop with an error.
    Overflow,
    /// Free-free bar translating at unit velocity: `u = t` exactly (rigid-mode drift).
    Rigid,
    /// Both ends Signorini at gap 0.1, gravity `l = −1`: the bar bounces on the ends forever.
    Bounce,
}

impl Family {
    fn name(self) -> &'static str {
        match self {
            Family::Impact => "impact",
            Family::GapZero => "gap0",
            Family::Resting => "resting",
            Family::Forced => "force1e6",
            Family::Overflow => "overflow",
            Family::Rigid => "rigid",
            Family::Bounce => "bounce",
        }
    }

    /// The scene's TOML without `[mesh]` and `[time]`.
    fn toml(self, alpha: f64) -> String {
        let ends = |l: &str, r: &str| format!("[left]\n{l}\n[right]\n{r}\n");
        let sig = |a: f64| format!("condition = \"signorini\"\ngap = {a:?}");
        let free = "condition = \"free\"";
        let (ends, initial, load, obstacle) = match self {
            Family::Impact => (ends(&sig(0.1), free), ("0", "-1"), None, None),
            Family::GapZero => (ends(&sig(0.0), &sig(0.0)), ("0", "-1"), None, None),
            Family::Resting => (
                ends(free, free),
                ("-(0.2 + 0.1*cos(2*x))", "0"),
                Some("-1"),
                Some("0.2 + 0.1*cos(2*x)"),
            ),
            Family::Forced => (ends(&sig(0.1), free), ("0", "-1"), Some("-1e6"), None),
            Family::Overflow => (ends(&sig(0.1), free), ("0", "-1"), Some("-1e300"), None),
            Family::Rigid => (ends(free, free), ("0", "1"), None, None),
            Family::Bounce => (ends(&sig(0.1), &sig(0.1)), ("0", "0"), Some("-1"), None),
        };
        let mut t = format!("[bar]\nlength = 1.0\nviscosity = {alpha:?}\n{ends}");
        let _ = write!(
            t,
            "[initial]\ndisplacement = \"{}\"\nvelocity = \"{}\"\n",
            initial.0, initial.1
        );
        if let Some(l) = load {
            let _ = write!(t, "[load]\ndensity = \"{l}\"\n");
        }
        if let Some(g) = obstacle {
            let _ = write!(t, "[obstacle]\ngap = \"{g}\"\n");
        }
        t
    }
}

/// One case of the matrix.
#[derive(Clone, Debug)]
pub struct Case {
    pub family: Family,
    pub alpha: f64,
    /// `Δt / Δx`.
    pub ratio: f64,
    pub elements: u64,
    pub steps: usize,
    /// Whether the exact solver must fail (overflow): any other exact failure is a defect.
    pub exact_must_fail: bool,
}

impl Case {
    fn new(family: Family, alpha: f64, ratio: f64, elements: u64, steps: usize) -> Self {
        Self {
            family,
            alpha,
            ratio,
            elements,
            steps,
            exact_must_fail: family == Family::Overflow,
        }
    }

    /// A short identifier, unique in the matrix.
    pub fn id(&self) -> String {
        format!(
            "{}-a{}-r{}-e{}",
            self.family.name(),
            short(self.alpha),
            short(self.ratio),
            self.elements
        )
    }

    pub fn dx(&self) -> f64 {
        1.0 / self.elements as f64
    }

    pub fn dt(&self) -> f64 {
        self.ratio * self.dx()
    }

    /// The scene with step solver `solver` (a name of [`Case::solvers`]).
    pub fn scene(&self, solver: &str) -> Result<Scene, RunError> {
        let method = match solver {
            PENALTY_SMALL => format!("method = \"penalty\"\nepsilon = {PENALTY_SMALL_EPSILON:?}"),
            other => format!("method = \"{other}\""),
        };
        let text = format!(
            "{}[mesh]\nelements = {}\n[time]\nstep = {:?}\nend = {:?}\n[solver]\n{method}\n",
            self.family.toml(self.alpha),
            self.elements,
            self.dt(),
            self.steps as f64 * self.dt()
        );
        Ok(Scene::from_toml(&text, &[])?)
    }

    /// The solvers run on this case: exact always; OSQP on meshes up to [`OSQP_MAX_NODES`] and
    /// short runs; penalty wherever OSQP runs and on the large meshes with ends only (it
    /// refuses obstacles by design; the refusal is part of the table).
    pub fn solvers(&self) -> Vec<&'static str> {
        let long = matches!(self.family, Family::Rigid | Family::Bounce);
        let small = (self.elements as usize) < OSQP_MAX_NODES;
        let mut v = vec!["exact"];
        if !long && small {
            v.push("osqp");
        }
        if !long {
            v.push("penalty");
            v.push(PENALTY_SMALL);
        }
        v
    }
}

/// The name of the penalty run at [`PENALTY_SMALL_EPSILON`].
pub const PENALTY_SMALL: &str = "penalty ε/10";

/// ε of a penalty run.
fn epsilon_of(solver: &str) -> f64 {
    if solver == PENALTY_SMALL {
        PENALTY_SMALL_EPSILON
    } else {
        PENALTY_DEFAULT_EPSILON
    }
}

/// `1e6`, `0.001` → `1e-3`, `0` → `0`, `1` → `1`.
fn short(v: f64) -> String {
    if v == 0.0 {
        "0".into()
    } else if v == 1.0 {
        "1".into()
    } else {
        let s = format!("{v:e}");
        s.replace("e0", "").replace(".0e", "e")
    }
}

/// Steps of a short case: the impact's first contact and release (`t ≤ 2.5`), at least 10
/// steps and at most 2400 (at `Δt = 1e-3 Δx` that still reaches the first contact at t = 0.1).
fn steps_for(dt: f64) -> usize {
    ((2.5 / dt).round() as usize).clamp(10, 2400)
}

/// The case list. The grid `α × Δt/Δx` runs on 20 elements, the mesh of the independent
/// figure `κ(C) ≈ 4.1e9` at `α = 1e6`, `Δt = 100 Δx` (see VERIFICATION.md).
pub fn cases(size: Size) -> Vec<Case> {
    const ALPHAS: [f64; 4] = [0.0, 1e-8, 1e3, 1e6];
    const RATIOS: [f64; 4] = [1e-3, 1.0, 100.0, 1e4];
    const GRID_ELEMENTS: u64 = 20;
    let dx = 1.0 / GRID_ELEMENTS as f64;
    let mut v = Vec::new();
    for family in [Family::Impact] {
        for alpha in ALPHAS {
            for ratio in RATIOS {
                v.push(Case::new(
                    family,
                    alpha,
                    ratio,
                    GRID_ELEMENTS,
                    steps_for(ratio * dx),
                ));
            }
        }
    }
    // α = 0.1 beside the grid: the independent probe's "κ ≈ 3.3 at Δt = Δx" matches α ≤ 1e-8
    // in the grid, not this case.
    v.push(Case::new(Family::Impact, 0.1, 1.0, GRID_ELEMENTS, 50));
    for family in [Family::GapZero, Family::Resting] {
        for alpha in [0.0, 1e6] {
            for ratio in RATIOS {
                v.push(Case::new(family, alpha, ratio, GRID_ELEMENTS, 20));
            }
        }
    }
    for ratio in RATIOS {
        v.push(Case::new(Family::Forced, 0.0, ratio, GRID_ELEMENTS, 20));
    }
    for ratio in [1.0, 1e4] {
        v.push(Case::new(Family::Overflow, 0.0, ratio, GRID_ELEMENTS, 20));
    }
    let max_elements = match size {
        Size::Full => 999_999,
        Size::Reduced => REDUCED_MAX_ELEMENTS,
    };
    for elements in [1u64, 2, 1000, 100_000, 999_999] {
        if elements <= max_elements {
            let steps = if elements > 1000 { 5 } else { 20 };
            v.push(Case::new(Family::GapZero, 0.0, 1.0, elements, steps));
        }
    }
    for elements in [100_000u64, 999_999] {
        if elements <= max_elements {
            v.push(Case::new(Family::Resting, 0.0, 100.0, elements, 3));
        }
    }
    let long = match size {
        Size::Full => LONG_STEPS,
        Size::Reduced => REDUCED_LONG_STEPS,
    };
    v.push(Case::new(Family::Rigid, 0.0, 1.0, 10, long));
    v.push(Case::new(Family::Bounce, 0.0, 1.0, 10, long));
    v.push(Case::new(Family::Bounce, 1e-8, 1.0, 10, long));
    v
}

/// Two round-off-exact solvers apart after `steps` steps, displacement scale `scale`.
pub fn roundoff_distance(kappa: f64, steps: usize, scale: f64) -> f64 {
    ROUNDOFF_ULPS * f64::EPSILON * kappa * steps as f64 * scale
}

/// What happened to one solver on one case.
#[derive(Clone, Debug, PartialEq)]
pub struct SolverRun {
    pub solver: &'static str,
    /// `None`: the run completed; `Some`: the error, shortened for the table.
    pub error: Option<String>,
    /// Whether the error names the step it occurred at (or came before the first step, from
    /// the set-up).
    pub error_located: bool,
    pub steps_done: usize,
    pub max_identity_residual: f64,
    /// `max(0, −(u_j + a_j))` over steps and constrained nodes.
    pub max_violation: f64,
    pub max_reaction: f64,
    /// `max_{n,i} |u − u_exact|` over the steps both completed (`None` for exact itself).
    pub distance: Option<f64>,
    /// Largest displacement of this run.
    pub max_displacement: f64,
    /// `|E^{N−1/2} − E^{1/2} − Σ (work − viscous − contact)|` over the largest of `E` and the
    /// summed magnitudes of the terms.
    pub energy_drift: f64,
    /// Exact solver: worst ratio of its KKT audit at round-off floors to its tolerance.
    pub audit_ratio: Option<f64>,
    /// Rigid case, exact solver: `max_i |u_i − t|` at the end.
    pub rigid_drift: Option<f64>,
    pub all_finite: bool,
    /// The identity residual and the penetration at the step where each is largest relative
    /// to its a-posteriori tolerance ([`StepTerms`]).
    pub identity: Worst,
    pub violation: Worst,
    /// The drift's tolerance, over the same scale as `energy_drift`: the per-step identity
    /// tolerances summed in units of energy ([`StepTerms::identity_bound`]), plus the rounding
    /// between the drift and the steps' residuals (each residual's four, the balance's terms
    /// and running sum, the final difference's two).
    ///
    /// Derivation: on the recorded numbers, in exact arithmetic, the residuals
    /// `E^{n+1/2} − E^{n−1/2} − work + viscous + contact` telescope to the drift
    /// `E^{N−1/2} − E^{1/2} − Σ (work − viscous − contact)`. Each computed residual is within
    /// its step's identity tolerance when that check holds and the energy the step carried is
    /// the recorded one. Not the former bound `|Σ_n signed residuals|`, which is the drift
    /// itself by the same telescoping (ratio 1, a check that could not fail): an energy held
    /// in single precision passed it on every run.
    pub drift_tolerance: f64,
    /// For the notes of the table: `Σ|residual_n| / Σ allowance_n` (how much of the summed
    /// identity tolerance the residuals use) and `|Σ residual_n| / Σ|residual_n|` (how much of
    /// that survives their cancellation); the drift's ratio is about their product.
    pub drift_used: f64,
    pub drift_cancellation: f64,
    /// The largest term of the identity tolerance at the run's worst identity step
    /// ([`StepTerms::dominant_term`]).
    pub identity_dominant: &'static str,
    /// Exact solver: the KKT audit's check with the worst ratio.
    pub audit_worst: &'static str,
}

/// One case with its condition number and the runs of its solvers (exact first).
#[derive(Clone, Debug)]
pub struct CaseResult {
    pub case: Case,
    pub kappa: Option<f64>,
    pub nodes: usize,
    pub max_gap: f64,
    /// `min_j` and `max_j (C⁻¹)_jj` over the constrained nodes (ends only; `None` for an
    /// obstacle or when there is none).
    pub schur: Option<(f64, f64)>,
    pub runs: Vec<SolverRun>,
}

/// Whether the penalty runs of this case are in (PP)'s asymptotic regime.
pub fn penalty_asymptotic(result: &CaseResult) -> bool {
    result
        .schur
        .is_some_and(|(s, _)| PENALTY_DEFAULT_EPSILON <= PENALTY_ASYMPTOTIC * s)
}

/// The checks of one run, each as (what, value, tolerance); a run passes when every value is
/// within its tolerance (NaN fails).
pub fn checks(result: &CaseResult, run: &SolverRun) -> Vec<(&'static str, f64, f64)> {
    let kappa = result.kappa.unwrap_or(f64::INFINITY);
    let exact = &result.runs[0];
    let scale = run.max_displacement + result.max_gap;
    let steps = run.steps_done.max(1);
    let mut v = vec![
        // A-posteriori, from the run's own steps ([`StepTerms`]).
        (
            "identity residual",
            run.identity.value,
            run.identity.tolerance,
        ),
        ("energy drift", run.energy_drift, run.drift_tolerance),
        ("violation", run.violation.value, run.violation.tolerance),
    ];
    if let Some(d) = run.distance {
        let s = exact.max_displacement.max(run.max_displacement);
        let base = roundoff_distance(kappa, steps, s);
        let coarse = result
            .runs
            .iter()
            .find(|r| r.solver == "penalty" && r.error.is_none());
        let tol = match run.solver {
            "osqp" => OSQP_AGREEMENT_REL * s + steps as f64 * OSQP_STEP_ABS + base,
            PENALTY_SMALL if penalty_asymptotic(result) => coarse
                .and_then(|r| r.distance)
                .map_or(f64::INFINITY, |d| d / PENALTY_CONVERGENCE_FACTOR + base),
            // Penalty at ε: reported; its convergence is checked by the ε/10 run.
            _ => f64::INFINITY,
        };
        v.push(("distance to exact", d, tol));
    }
    if let Some(a) = run.audit_ratio {
        v.push(("KKT audit at round-off", a, 1.0));
    }
    if let Some(d) = run.rigid_drift {
        // Each step rounds u + z to an ulp of |u|: at most N ulps of the final |u| = t.
        v.push((
            "rigid drift |u - t|",
            d,
            rigid_drift_tolerance(steps, scale),
        ));
    }
    v
}

/// `u^{n+1} = u^n + z` rounds once per step to half an ulp of `|u| <= t_N`; `N` steps.
pub fn rigid_drift_tolerance(steps: usize, max_u: f64) -> f64 {
    steps as f64 * f64::EPSILON * max_u
}

/// Why a run does not pass, or `None`. A completed run passes when it is finite and every
/// check holds; a failed run passes when its error names the step (or is a set-up refusal)
/// and the case allows it: the exact solver must complete unless the case overflows, and then
/// it must fail.
pub fn verdict(result: &CaseResult, run: &SolverRun) -> Option<String> {
    let must_fail = result.case.exact_must_fail;
    match &run.error {
        Some(e) if !run.error_located => Some(format!("error without its step: {e}")),
        Some(e) if run.solver == "exact" && !must_fail => Some(format!("exact failed: {e}")),
        Some(_) => None,
        None if must_fail => Some("completed although the data overflow".into()),
        None if !run.all_finite => Some("non-finite displacement reported as success".into()),
        None => {
            let bad: Vec<String> = checks(result, run)
                .into_iter()
                // A NaN value or tolerance fails too.
                .filter(|(_, v, t)| {
                    matches!(v.partial_cmp(t), None | Some(std::cmp::Ordering::Greater))
                })
                .map(|(w, v, t)| format!("{w} {v:.1e} > {t:.1e}"))
                .collect();
            (!bad.is_empty()).then(|| bad.join("; "))
        }
    }
}

fn sci(v: f64) -> String {
    format!("{v:.1e}")
}

/// The Markdown table: one row per case and solver; each checked figure as `value / tolerance`.
pub fn markdown(results: &[CaseResult]) -> String {
    let mut md = String::from(
        "| case | elements | α | Δt/Δx | steps | κ(C) | solver | outcome | identity residual / tol | \
         penetration / tol | distance to exact / tol | energy drift / tol | exact: KKT audit ratio |\n\
         |---|---|---|---|---|---|---|---|---|---|---|---|---|\n",
    );
    for r in results {
        let c = &r.case;
        for run in &r.runs {
            let outcome = match (&run.error, verdict(r, run)) {
                (_, Some(why)) => format!("**FAIL**: {why}"),
                (Some(e), None) => e.clone(),
                (None, None) => "ok".into(),
            };
            let checks = checks(r, run);
            let cell = |name: &str| {
                if run.error.is_some() {
                    return "–".to_string();
                }
                checks
                    .iter()
                    .find(|(w, _, _)| *w == name)
                    .map_or("–".into(), |(_, v, t)| match t.is_finite() {
                        true => format!("{} / {}", sci(*v), sci(*t)),
                        false => sci(*v),
                    })
            };
            let pre =
                run.solver.starts_with("penalty") && run.error.is_none() && !penalty_asymptotic(r);
            let distance = if pre {
                format!("{} (pre-asymptotic)", cell("distance to exact"))
            } else if run.solver == "exact" {
                run.rigid_drift.map_or("(reference)".into(), |_| {
                    format!("u = t: {}", cell("rigid drift |u - t|"))
                })
            } else {
                cell("distance to exact")
            };
            let _ = writeln!(
                md,
                "| {} | {} | {} | {} | {} | {} | {} | {} | {} | {} | {} | {} | {} |",
                c.id(),
                c.elements,
                short(c.alpha),
                short(c.ratio),
                c.steps,
                r.kappa.map_or("not SPD".into(), sci),
                run.solver,
                outcome.replace('|', "\\|"),
                cell("identity residual"),
                cell("violation"),
                distance,
                cell("energy drift"),
                run.audit_ratio.map_or("–".into(), sci),
            );
        }
    }
    md.push_str(&low_ratio_notes(results));
    md
}

/// Ratios below this are listed under the table with their reason (the registry's rule: a
/// tolerance at most 1000 times what it guards, unless the table says why).
pub const NOTE_RATIO_FLOOR: f64 = 1e-3;

/// Why a completed run's check has a nonzero ratio below [`NOTE_RATIO_FLOOR`], from what the
/// run measured.
fn low_ratio_reason(result: &CaseResult, run: &SolverRun, check: &str) -> String {
    match check {
        "identity residual" if result.nodes >= 10_000 => format!(
            "the worst step's tolerance is mostly {} over {} nodes: a worst-case bound grows \
             like the number of terms, the rounding it bounds about like its square root",
            run.identity_dominant, result.nodes
        ),
        "identity residual" => format!(
            "the worst step's residual is {} of its scale, and its tolerance mostly {}, which \
             does not vanish with it",
            sci(run.identity.value),
            run.identity_dominant
        ),
        "energy drift" => format!(
            "the residuals use {} of their summed per-step tolerances and keep {} of their \
             absolute sum after cancelling ({} steps)",
            sci(run.drift_used),
            sci(run.drift_cancellation),
            run.steps_done
        ),
        "violation" => "OSQP's own law, its audited primal tolerance \
             `AUDIT_MARGIN·eps·(1 + max|u|)`; its polished answer meets the bound to round-off"
            .into(),
        "distance to exact" => "a requirement, not a round-off bound (OSQP: `tests/solvers.rs`' \
             1e-7 relative plus the audit's per-step allowance; penalty ε/10: a fifth of the \
             distance at ε)"
            .into(),
        "KKT audit at round-off" => format!(
            "worst check {}, against the audit's a-priori round-off floors (`step::audit`, \
             `ROUNDOFF_ULPS` = {ROUNDOFF_ULPS} ulps of the sizes compared; the displacement \
             floor carries `‖C⁻¹‖`)",
            run.audit_worst
        ),
        _ => "–".into(),
    }
}

/// The notes under the table: every completed run's check with a nonzero ratio below
/// [`NOTE_RATIO_FLOOR`], with its reason.
pub fn low_ratio_notes(results: &[CaseResult]) -> String {
    let mut md = String::new();
    for r in results {
        for run in r.runs.iter().filter(|run| run.error.is_none()) {
            for (check, v, t) in checks(r, run) {
                let ratio = v / t;
                if v == 0.0 || !t.is_finite() || ratio >= NOTE_RATIO_FLOOR {
                    continue;
                }
                let _ = writeln!(
                    md,
                    "- `{}` / {}, {check}: ratio {}: {}",
                    r.case.id(),
                    run.solver,
                    sci(ratio),
                    low_ratio_reason(r, run, check)
                );
            }
        }
    }
    if md.is_empty() {
        return md;
    }
    format!(
        "\nNonzero ratios below {NOTE_RATIO_FLOOR:e}, and why (generated from each run's \
         measurements):\n\n{md}"
    )
}

/// Unit round-off `u = ε/2`: a correctly rounded operation errs by at most `u` times its
/// result.
pub const UNIT_ROUNDOFF: f64 = 0.5 * f64::EPSILON;
/// Rounding depth of one entry of the computed solve residual `ρ̂ = C z − b̂ − r` and of the
/// right-hand side `b̂` (`src/bar/kernels/rhs.rs`): a difference-form row is two differences,
/// three products and two sums (5 roundings in sequence), then two subtractions; `b̂`'s rows
/// are the same depth (the `R y` and `M w` rows, the scaling by `1/Δt²`, two sums, the load).
/// `γ_8 = 8u/(1 − 8u)`, 8.0000001u here; the margin to 9 covers the `O(u²)`.
pub const RESIDUAL_ROUNDINGS: f64 = 9.0;
/// Rounding depth of one term of the energy sums (`src/bar/kernels/energy.rs`): a difference,
/// two products and the accumulation into its lane, plus the combination of the sums into the
/// energy (scaling, two sums) and of the energies into the residual (four sums).
pub const SUM_TERM_ROUNDINGS: f64 = 10.0;
/// Roundings in forming the residual from the sums: three in each energy
/// (`½K/Δt² + ¼(P + P')`, all terms nonnegative, so each at most `u E`) and four in
/// `E − E' − work + viscous + contact`, each at most `u` times the sum of the magnitudes.
pub const COMBINATION_ROUNDINGS: f64 = 7.0;
/// The worst-case bound `γ_k Σ|t|` on the rounding of a sum of `k` rounded terms
/// (Higham, *Accuracy and Stability of Numerical Algorithms*, 2nd ed., Lemma 3.1 and §3.1):
/// whatever the order and the grouping of the additions, `γ_k = ku/(1 − ku)`.
///
/// Not the probabilistic `λ√k u Σ|t|` (Higham and Mary 2019): its independence model fails
/// on this scheme's data. A bar in uniform motion sums `10⁵` equal kinetic terms, whose
/// rounding errors are alike, and the `gap0` case on 1e5 elements measured 1.2 times that
/// bound at λ = 11.
pub fn sum_rounding(k: f64, abs_sum: f64) -> f64 {
    let ku = k * UNIT_ROUNDOFF;
    if ku < 1.0 {
        ku / (1.0 - ku) * abs_sum
    } else {
        f64::INFINITY
    }
}

/// The a-posteriori quantities of one step of one run, all computed by
/// [`crate::bar::stiff_runs`] from the vectors the step formed (the solver's `b̂`, `z`, `r`, the
/// previous increment `w`, the stored `û^{n−1}, û^n, û^{n+1}`), with `δ = z + w`, `ρ̂` the
/// computed `C z − b̂ − Σ r_j e_j` and `f_i` the entrywise bound on its rounding and on the
/// rounding of `b̂` (see [`StepTerms::identity_tolerance`]).
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct StepTerms {
    /// The step record's relative identity residual and its scale (the largest of
    /// `E^{n+1/2}, E^{n−1/2}, |work|, viscous, |contact|`).
    pub residual: f64,
    pub scale: f64,
    /// `|½ δ·ρ̂|`: the identity residual exact arithmetic would leave on the computed vectors.
    pub rho_dot: f64,
    /// `½ Σ |δ_i| f_i`, `f_i = γ_9 (|C|z_i + 2|b̂_i| + |r_i| + |M|w_i/Δt² + |R|y_i + |F_i|)
    /// + u·(the rounding of y = c_w w − û^n carried by R)`, with `|A|x` the difference-form
    /// absolute row (no rigid offset): the bound on `½|δ·(ρ − ρ̂)|`.
    pub floor_rho_abs: f64,
    /// `Σ |t|` over the terms of every sum the identity is made of: `½|z|²_M/Δt²`,
    /// `½|w|²_M/Δt²`, `¼|û^{n+1}|²_R`, `¼|û^{n−1}|²_R`, `α/(4Δt)|δ|²_R`, `½|F·δ|`, `½|r·δ|`,
    /// in absolute values term by term (`¼|û^n|²_R` enters both energies as the same computed
    /// number, so its rounding cancels).
    pub sum_terms: f64,
    /// The largest number of terms in one of those sums (the unknowns).
    pub sum_len: usize,
    /// The potentials take the stored `û^{n±1}`, rounded from `û^n ± z` (`±w`):
    /// `½u (P(û^{n+1}) + P(û^{n−1}))`, `P(v) = Σ|s_i|v_i² + Σ|e_i||Δv_i|(|v_i| + |v_{i+1}|)`.
    pub stored_rounding: f64,
    /// `|E^{n+1/2}| + |E^{n−1/2}| + |work| + viscous + |contact|`: the final four sums.
    pub combination: f64,
    /// The penetration `max(0, −(û^{n+1}_j + a_j))` at the constrained node whose ratio to its
    /// own tolerance is the largest (the three terms below are that node's).
    pub violation: f64,
    /// `γ_2 (|lo_j| + |û^{n+1}_j|)`: the rounding of the bound and of the stored displacement
    /// ([`GAP_ROUNDINGS`]).
    pub gap_rounding: f64,
    /// What the solver's acceptance test lets the `z` it returns fall below `lo_j` at a node
    /// without a reaction (0 at nodes with one, where `z_j = lo_j` exactly): the block-pivoting
    /// solver's tie threshold, or the end enumeration's forward error on its active set.
    pub allowance: f64,
    /// The solver's own law ([`violation_law`]): 0 for the exact solvers.
    pub law: f64,
}

impl StepTerms {
    /// The relative identity tolerance of this step.
    ///
    /// Derivation. On the computed vectors, with `u^{n+1} = û^n + z` and `u^{n−1} = û^n − w`
    /// exactly, the identity is the scheme multiplied by `δ/2`, so exact arithmetic leaves
    /// exactly `½ δ·ρ`, `ρ = C z − b − r` the scheme's residual for the exact `b(û^n, w, F)`.
    /// `ρ − ρ̂` is the rounding of `ρ̂` and of `b̂`, at most `f_i` entrywise (`γ_8` of the
    /// absolute rows formed). What the computation adds: the rounding of the energy sums
    /// ([`sum_rounding`], the worst case `γ_k Σ|t|`), of the stored displacements
    /// (`stored_rounding`) and of the final combination (`7u Σ`, [`COMBINATION_ROUNDINGS`]).
    /// The `½ Σ δ_i (ρ_i − ρ̂_i)` part is at most `½ Σ |δ_i| f_i`. All worst-case bounds,
    /// to first order in `u`; everything in them is measured in this step: no κ, no a-priori
    /// size. The triangle inequality then gives the tolerance.
    pub fn identity_tolerance(&self) -> f64 {
        if self.scale <= 0.0 {
            return 0.0;
        }
        self.identity_bound() / self.scale
    }

    /// The largest of the identity tolerance's terms, for the notes of the table.
    pub fn dominant_term(&self) -> &'static str {
        let k = self.sum_len.max(1) as f64 + SUM_TERM_ROUNDINGS;
        [
            (self.rho_dot, "the solve's residual |½δ·ρ̂|"),
            (self.floor_rho_abs, "the rounding of ρ̂ and b̂ (½Σ|δ_i| f_i)"),
            (
                sum_rounding(k, self.sum_terms),
                "the energy sums' worst-case rounding γ_k Σ|t|",
            ),
            (self.stored_rounding, "the stored displacements' rounding"),
            (
                COMBINATION_ROUNDINGS * UNIT_ROUNDOFF * self.combination,
                "the final combination's rounding",
            ),
        ]
        .into_iter()
        .fold((0.0, "none"), |a, b| if b.0 > a.0 { b } else { a })
        .1
    }

    /// The identity tolerance in units of energy (`identity_tolerance · scale`, formed before
    /// the division): what the energy drift sums ([`SolverRun::drift_tolerance`]).
    pub fn identity_bound(&self) -> f64 {
        if self.scale <= 0.0 {
            return 0.0;
        }
        let k = self.sum_len.max(1) as f64 + SUM_TERM_ROUNDINGS;
        self.rho_dot
            + self.floor_rho_abs
            + sum_rounding(k, self.sum_terms)
            + self.stored_rounding
            + COMBINATION_ROUNDINGS * UNIT_ROUNDOFF * self.combination
    }

    /// The penetration tolerance of this step at its worst node: the gap's rounding, the
    /// solver's allowance and its law, `gap_rounding + allowance + law`, each derived from
    /// what the solver tests on the `z` it returns.
    ///
    /// *The gap's rounding.* The simulation forms `lo_j = fl(−a_j − û^n_j)`, stores
    /// `û^{n+1}_j = fl(û^n_j + z_j)` and measures `fl(û^{n+1}_j + a_j)`
    /// (`ContactSet::lower_bounds_into`, `ContactSet::measure`). If `z_j >= lo_j`, then
    /// `û^n_j + z_j + a_j >= (−a_j − û^n_j) δ_1` and
    /// `û^{n+1}_j + a_j >= −u (|lo_j| + |û^{n+1}_j|)/(1 − u)`; the last rounding keeps the sign
    /// and adds a factor `1 + u`, so the computed gap is at least
    /// `−γ_2 (|lo_j| + |û^{n+1}_j|)` (Higham, Lemma 3.1). No forward error of the solve enters
    /// it: only whether the returned `z_j >= lo_j` holds.
    ///
    /// *The exact solvers' allowance* (`src/step/end_enumeration.rs`, `src/step/block_pivot.rs`). At a
    /// node with a reaction every path writes `z_j = lo_j` bit for bit (`superpose`,
    /// `superpose_and_add`, `solve_on_active_set`; block pivoting copies `lo` into the active
    /// runs in `solve_all`): allowance 0. At a node without one:
    /// - block pivoting accepts an iteration only when no free node has
    ///   `z_i − lo_i < −TIE_ULPS ε max(max|z|, max|lo|)` (`margin_at`, `select_infeasible`),
    ///   on the `z` it returns: that threshold is the allowance;
    /// - the end enumeration with no active end returns `z⁰`, which its candidate `∅` tested
    ///   as is (`candidate` adds `Σ 0·S_ji` to `z⁰_j`): allowance 0. The warm start also
    ///   tests the `z` it returns (`solve_on_active_set`'s flag), but with an active end the
    ///   enumeration tests the Schur value `z⁰_j + Σ r_i S_ji`, not the superposed or
    ///   re-solved `z` it returns (`resolve` ignores the flag), and the run cannot tell the
    ///   paths apart: the allowance is then the forward error of `z` against the exact answer
    ///   on the same active set, `(C_II⁻¹ (|ρ̂_I| + f_I))_j`, a solve with `C` pinned on the
    ///   active ends (`stiff_runs::forward_on_inactive`). It assumes the chosen set is the
    ///   exact one: a set chosen wrongly beyond round-off is what this check is there to
    ///   report.
    ///
    /// *The law*: penalty `ε r` (its rounding included), OSQP its audited primal tolerance
    /// ([`violation_law`]); those solvers' `z` is checked against their law by the audit.
    pub fn violation_tolerance(&self) -> f64 {
        self.law + self.allowance + self.gap_rounding
    }
}

/// Roundings between the bound and the measured gap: `lo_j = −a_j − û^n_j` and
/// `û^{n+1}_j = û^n_j + z_j`, each at most `u` times its result (the gap's own rounding keeps
/// its sign): `γ_2 (|lo_j| + |û^{n+1}_j|)` ([`StepTerms::violation_tolerance`]).
pub const GAP_ROUNDINGS: f64 = 2.0;

/// The penetration a solver's law allows at step size `max_reaction` (the step's largest
/// reaction), `scale` the run's largest displacement and `s_max` the largest `(C⁻¹)_jj` at
/// the ends: 0 for the exact solvers; OSQP its audited primal tolerance; penalty `ε r`, its
/// `z_j = z⁰_j + Σ S_jk r_k` rounded to ulps of `|z⁰_j| <= |z_j| + S_jj r` (as in the audit's
/// penalty-law floor).
pub fn violation_law(solver: &str, max_reaction: f64, scale: f64, s_max: f64) -> f64 {
    match solver {
        "exact" => 0.0,
        "osqp" => AUDIT_MARGIN * OSQP_DEFAULT_EPS * (1.0 + scale),
        _ => {
            let eps_r = epsilon_of(solver) * max_reaction;
            eps_r + ROUNDOFF_ULPS * f64::EPSILON * (eps_r + s_max * max_reaction)
        }
    }
}

/// The worst step of a run for one check: the value and the tolerance of the step with the
/// largest ratio.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Worst {
    pub value: f64,
    pub tolerance: f64,
}

impl Worst {
    /// Keeps the step with the larger ratio (a NaN ratio is kept: it fails).
    pub fn update(&mut self, value: f64, tolerance: f64) {
        let ratio = |v: f64, t: f64| if v == 0.0 { 0.0 } else { v / t };
        let (new, old) = (ratio(value, tolerance), ratio(self.value, self.tolerance));
        if old.is_nan() {
            return;
        }
        if new.is_nan() || new > old || (old == 0.0 && self.tolerance == 0.0) {
            *self = Worst { value, tolerance };
        }
    }

    pub fn ratio(&self) -> f64 {
        if self.value == 0.0 {
            0.0
        } else {
            self.value / self.tolerance
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use proptest::prelude::*;

    /// The gap as the simulation forms it from `z`: `lo = −a − û^n`, `û^{n+1} = û^n + z`,
    /// `gap = û^{n+1} + a`; returns `(gap, lo, û^{n+1})`.
    fn gap_of(a: f64, u: f64, z: f64) -> (f64, f64, f64) {
        let lo = -a - u;
        let u1 = u + z;
        (u1 + a, lo, u1)
    }

    proptest! {
        /// [`StepTerms::violation_tolerance`]'s gap rounding: any `z >= lo` leaves a computed
        /// gap of at least `−γ_2 (|lo| + |û^{n+1}|)`, whatever the sizes of `a`, `û^n` and the
        /// margin.
        #[test]
        fn a_feasible_z_leaves_a_gap_within_its_rounding(
            a in -1e3f64..1e3,
            u in -1e6f64..1e6,
            margin in prop_oneof![Just(0.0), 0.0f64..1e-12, 0.0f64..1.0],
        ) {
            let lo = -a - u;
            let (gap, lo, u1) = gap_of(a, u, lo + margin * lo.abs().max(1.0));
            let tol = sum_rounding(GAP_ROUNDINGS, lo.abs() + u1.abs());
            prop_assert!(-gap <= tol, "gap {gap:e}, tolerance {tol:e}");
        }
    }

    /// And it is tight enough to see a `z` put 16 ulps of `|lo|` below its bound where `|lo|`
    /// dominates (the block-pivoting mutation of the stiff matrix).
    #[test]
    fn a_z_sixteen_ulps_below_its_bound_exceeds_it() {
        let (a, u) = (0.3, 212.1);
        let lo = -a - u;
        let (gap, lo, u1) = gap_of(a, u, lo - 16.0 * f64::EPSILON * lo.abs());
        let tol = sum_rounding(GAP_ROUNDINGS, lo.abs() + u1.abs());
        assert!(-gap > tol, "gap {gap:e}, tolerance {tol:e}");
    }
}
