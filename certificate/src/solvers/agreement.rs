//! The measured figures of VERIFICATION.md, section "Step solvers" (generated block
//! `solver-agreement`, `verify --update VERIFICATION.md`; alone: `solver-agreement`):
//!
//! 1. OSQP and penalty against the exact solver on every built-in scene (whole runs, every
//!    node and step), with their audits;
//! 2. the penalty error against ε and its observed order;
//! 3. OSQP's failures on a stiff scene, with OSQP's own verdict next to viscobar's;
//! 4. a seeded sample of random step problems, OSQP against exact.
//!
//! Everything is deterministic (no timings): the same build prints the same numbers. The
//! start-up step problem of a scene ([`start_up_problem`]) lets a solver be probed alone.

use osqp::Status;
use std::fmt::Write;
use viscobar::internals::linalg::kernels::ldlt::Ldlt;
use viscobar::internals::linalg::norms::{max_abs, max_distance};
use viscobar::internals::linalg::tridiag::SymTridiag;
use viscobar::internals::step::end_enumeration::EndEnumeration;
use viscobar::internals::step::end_penalty::PENALTY_DEFAULT_EPSILON;
use viscobar::internals::step::osqp::{Osqp, OsqpSettings, raw_problem};
use viscobar::output::run_in_memory;
use viscobar::scene::{self, Scene};
use viscobar::scheme::RunError;
use viscobar::step::StepSolver;
use viscobar::step::audit::dual_tolerance;
use viscobar::study::accuracy::observed_order;
use viscobar::study::compare::compare;

/// The four parts above, as Markdown.
pub fn markdown() -> Result<String, RunError> {
    let mut md = String::new();
    agreement_tables(&mut md)?;
    penalty_rate(&mut md)?;
    failure_cases(&mut md)?;
    random_problems(&mut md)?;
    Ok(md)
}

fn load(name: &str, overrides: &[String]) -> Result<Scene, RunError> {
    Ok(scene::load(name, overrides)?.1)
}

fn with_method(m: &str, extra: &[String]) -> Vec<String> {
    let mut o = vec![format!("solver.method=\"{m}\"")];
    o.extend(extra.iter().cloned());
    o
}

/// The audit report of an OSQP or penalty run (both always audit).
fn audit_of<'a>(
    name: &str,
    s: &'a viscobar::Summary,
) -> Result<&'a viscobar::step::AuditReport, RunError> {
    s.audit.as_ref().ok_or_else(|| RunError::SolverSetup {
        solver: s.solver.clone(),
        reason: format!("{name}: the run kept no audit report"),
    })
}

fn agreement_tables(md: &mut String) -> Result<(), RunError> {
    let _ = writeln!(
        md,
        "#### OSQP against exact (default settings), whole runs\n\n\
         | scene | steps | max \\|u_osqp − u_exact\\| | max \\|u\\| | identity residual | \
         iterations mean / max | audit: stationarity / in displacement / complementarity \
         (worst ratio to tolerance) |\n|---|---|---|---|---|---|---|"
    );
    for name in scene::builtin_names() {
        let exact = load(name, &[])?;
        let osqp = load(name, &with_method("osqp", &[]))?;
        let c = compare(name, &exact, &osqp)?;
        let s = &c.summary;
        let a = audit_of(name, s)?;
        let _ = writeln!(
            md,
            "| {name} | {} | {:.2e} | {:.3} | {:.1e} | {:.1} / {} | {:.1e} / {:.1e} / {:.1e} |",
            c.agreement.steps,
            c.agreement.max_difference,
            c.agreement.max_displacement,
            s.max_identity_residual,
            s.solver_iterations.mean,
            s.solver_iterations.max,
            a.stationarity.max_over_tolerance,
            a.stationarity_displacement.max_over_tolerance,
            a.complementarity.map_or(0.0, |w| w.max_over_tolerance),
        );
    }
    let _ = writeln!(
        md,
        "\n#### Penalty (ε = {PENALTY_DEFAULT_EPSILON:e}) against exact, whole runs\n\n\
         | scene | max \\|u_pen − u_exact\\| | max penetration (u + a)⁻ | ratio | \
         identity residual | subsets tried mean / max | audit: law / stationarity / in displacement |\n\
         |---|---|---|---|---|---|---|"
    );
    for name in scene::builtin_names() {
        let exact = load(name, &[])?;
        if exact.obstacle.is_some() {
            continue; // normal compliance is implemented for the two ends only
        }
        let pen = load(name, &with_method("penalty", &[]))?;
        let c = compare(name, &exact, &pen)?;
        let s = &c.summary;
        let a = audit_of(name, s)?;
        let ratio = if s.max_violation > 0.0 {
            format!("{:.2}", c.agreement.max_difference / s.max_violation)
        } else {
            "–".into()
        };
        let _ = writeln!(
            md,
            "| {name} | {:.3e} | {:.3e} | {ratio} | {:.1e} | {:.2} / {} | {:.1e} / {:.1e} / {:.1e} |",
            c.agreement.max_difference,
            s.max_violation,
            s.max_identity_residual,
            s.solver_iterations.mean,
            s.solver_iterations.max,
            a.penalty_law.map_or(0.0, |w| w.max_over_tolerance),
            a.stationarity.max_over_tolerance,
            a.stationarity_displacement.max_over_tolerance,
        );
    }
    let _ = writeln!(md);
    Ok(())
}

fn penalty_rate(md: &mut String) -> Result<(), RunError> {
    let epsilons = [1e-2, 1e-3, 1e-4, 1e-5, 1e-6];
    let _ = write!(
        md,
        "#### Penalty → exact as ε → 0 (max over nodes and steps of \\|u_pen − u_exact\\|)\n\n| scene |"
    );
    for e in epsilons {
        let _ = write!(md, " ε = {e:.0e} |");
    }
    let _ = writeln!(
        md,
        " observed order |\n|---|{}---|",
        "---|".repeat(epsilons.len())
    );
    for name in ["impact", "clamped-impact", "both-ends", "one-end-forced"] {
        let exact = load(name, &[])?;
        let mut errors = Vec::with_capacity(epsilons.len());
        for e in epsilons {
            let s = load(
                name,
                &with_method("penalty", &[format!("solver.epsilon={e:e}")]),
            )?;
            errors.push(compare(name, &exact, &s)?.agreement.max_difference);
        }
        let _ = write!(md, "| {name} |");
        for e in &errors {
            let _ = write!(md, " {e:.3e} |");
        }
        let _ = writeln!(md, " {:.3} |", observed_order(&epsilons, &errors));
    }
    let _ = writeln!(md);
    Ok(())
}

/// OSQP called directly (no audit) on the start-up step of `scene`: status, polish, OSQP's own
/// dual residual and tolerance, the reaction error, and the stationarity error mapped to
/// displacement, against the exact answer.
fn raw_first_step(scene: &Scene, s: OsqpSettings) -> Result<String, RunError> {
    let StepProblem {
        c,
        nodes,
        b,
        lo,
        z: z_exact,
        r: r_exact,
    } = start_up_problem(scene)?;
    let mut prob = raw_problem(&c, &nodes, &b, &lo, s)?;
    let status = prob.solve();
    let iterations = status.iter();
    let (name, sol) = match status {
        Status::Solved(sol) => ("solved", sol),
        Status::SolvedInaccurate(sol) => ("solved inaccurate", sol),
        Status::MaxIterationsReached(sol) => ("maximum iterations reached", sol),
        other => return Ok(format!("{other:?}")),
    };
    let x = sol.x();
    let r: Vec<f64> = sol.y().iter().map(|y| -y).collect();
    let mut res = c.mul(x);
    let osqp_dual_tolerance = dual_tolerance(
        s.eps_abs,
        s.eps_rel,
        max_abs(&res),
        max_abs(&b),
        max_abs(&r),
    );
    for (ri, bi) in res.iter_mut().zip(&b) {
        *ri -= bi;
    }
    for (j, &node) in nodes.iter().enumerate() {
        res[node] -= r[j];
    }
    Ldlt::factor(&c)?.solve_in_place(&mut res);
    Ok(format!(
        "OSQP alone: `{name}` after {iterations} iterations, polish {:?}; its dual residual \
         {:.2e} against its own tolerance {:.2e}; reaction {:.6e} (exact {:.6e}, relative error \
         {:.1e}); max \\|z − z_exact\\| = {:.2e}; \\|C⁻¹(Cz − b − r)\\|∞ = {:.2e}",
        sol.polish_status(),
        sol.dua_res(),
        osqp_dual_tolerance,
        r[0],
        r_exact[0],
        (r[0] - r_exact[0]).abs() / r_exact[0].abs(),
        max_distance(x, &z_exact),
        max_abs(&res),
    ))
}

fn outcome(name: &str, scene: &Scene) -> String {
    match run_in_memory(name, scene) {
        Ok(_) => "run succeeded".to_string(),
        Err(e) => format!("error: {e}"),
    }
}

/// The overrides that make the impact scene the stiff scene of the OSQP failure cases (here and
/// in tests/solvers.rs): α = 1e6, 64 elements, 20 steps of `dt = ratio · dx`.
pub fn stiff_impact_overrides(ratio: f64) -> Vec<String> {
    let dt = ratio / 64.0;
    vec![
        "bar.viscosity=1e6".to_string(),
        "mesh.elements=64".into(),
        format!("time.step={dt}"),
        format!("time.end={}", 20.0 * dt),
    ]
}

fn failure_cases(md: &mut String) -> Result<(), RunError> {
    let _ = writeln!(
        md,
        "#### OSQP on a stiff scene: impact with α = 1e6, 64 elements, 20 steps of dt = ratio × dx\n"
    );
    let loose = OsqpSettings {
        eps_abs: 1e-3,
        eps_rel: 1e-3,
        polish: false,
        ..OsqpSettings::default()
    };
    let loose_overrides: &[&str] = &[
        "solver.eps_abs=1e-3",
        "solver.eps_rel=1e-3",
        "solver.polish=false",
    ];
    let cases: [(f64, &[&str], OsqpSettings); 4] = [
        (100.0, &[], OsqpSettings::default()),
        (1000.0, &[], OsqpSettings::default()),
        (10000.0, &[], OsqpSettings::default()),
        (100.0, loose_overrides, loose),
    ];
    for (ratio, extra, settings) in cases {
        let base = stiff_impact_overrides(ratio);
        let exact = load("impact", &base)?;
        let mut o = base.clone();
        o.push("solver.method=\"osqp\"".into());
        o.extend(extra.iter().map(|s| s.to_string()));
        let osqp = load("impact", &o)?;
        let label = if extra.is_empty() {
            String::from(" (default settings)")
        } else {
            format!(" ({})", extra.join(", "))
        };
        let _ = writeln!(
            md,
            "- dt = {ratio} dx{label}:\n  - viscobar: {}\n  - {}",
            outcome("impact", &osqp),
            raw_first_step(&exact, settings)?
        );
    }
    let inaccurate = [
        "solver.method=\"osqp\"",
        "solver.eps_abs=1e-8",
        "solver.eps_rel=1e-8",
        "solver.max_iter=75",
    ];
    let o: Vec<String> = inaccurate.iter().map(|s| s.to_string()).collect();
    let refused = outcome("impact", &load("impact", &o)?);
    let mut o2 = o.clone();
    o2.push("solver.accept_inaccurate=true".into());
    let accepted = match run_in_memory("impact", &load("impact", &o2)?) {
        Ok((_, s, _)) => format!(
            "run succeeded, inaccurate_steps = {:?}, worst stationarity ratio {:.1e}",
            s.inaccurate_steps,
            s.audit
                .map_or(f64::NAN, |a| a.stationarity.max_over_tolerance)
        ),
        Err(e) => format!("error: {e}"),
    };
    let _ = writeln!(
        md,
        "- impact (unchanged) with {}:\n  - {refused}\n  - with accept_inaccurate = true: {accepted}\n",
        inaccurate[1..].join(", ")
    );
    Ok(())
}

/// Smallest diagonal-dominance margin of the random step matrices (here and in the tests'
/// `spd_tridiag`): keeps the condition number below about 1e4 for the sizes drawn.
pub const MIN_MARGIN: f64 = 0.05;
/// Largest diagonal-dominance margin of the random step matrices.
pub const MAX_MARGIN: f64 = 3.0;

/// The SPD tridiagonal matrix with off-diagonal `off` whose diagonal exceeds each row's
/// off-diagonal magnitudes by `margin[i]` (off-diagonals of either sign: the step matrix C is
/// not an M-matrix when the mass term dominates).
pub fn diagonally_dominant(off: Vec<f64>, margin: &[f64]) -> SymTridiag {
    let n = margin.len();
    let diag = (0..n)
        .map(|i| {
            let l = if i > 0 { off[i - 1].abs() } else { 0.0 };
            let r = if i + 1 < n { off[i].abs() } else { 0.0 };
            l + r + margin[i]
        })
        .collect();
    SymTridiag::new(diag, off)
}

/// A 64-bit linear congruential generator (Knuth's MMIX constants): a fixed, dependency-free
/// sample.
struct Lcg(u64);
impl Lcg {
    fn uniform(&mut self, lo: f64, hi: f64) -> f64 {
        self.0 = self
            .0
            .wrapping_mul(6364136223846793005)
            .wrapping_add(1442695040888963407);
        lo + (hi - lo) * ((self.0 >> 11) as f64 / (1u64 << 53) as f64)
    }
}

fn random_problems(md: &mut String) -> Result<(), RunError> {
    let mut g = Lcg(2009);
    let (count, mut worst_z, mut worst_r, mut failures) = (2000, 0.0f64, 0.0f64, 0);
    for case in 0..count {
        let n = 2 + (g.uniform(0.0, 22.0) as usize);
        let off: Vec<f64> = (0..n - 1).map(|_| g.uniform(-1.0, 1.0)).collect();
        let margin: Vec<f64> = (0..n).map(|_| g.uniform(MIN_MARGIN, MAX_MARGIN)).collect();
        let c = diagonally_dominant(off, &margin);
        let b: Vec<f64> = (0..n).map(|_| g.uniform(-5.0, 5.0)).collect();
        let nodes = match case % 3 {
            0 => vec![0],
            1 => vec![n - 1],
            _ => vec![0, n - 1],
        };
        let lo: Vec<f64> = nodes.iter().map(|_| g.uniform(-2.0, 2.0)).collect();
        let k = nodes.len();
        let (mut ze, mut re) = (vec![0.0; n], vec![0.0; k]);
        EndEnumeration::new(&c, &nodes)?
            .solve(&b, &lo, &mut ze, &mut re)
            .map_err(|failure| RunError::Step {
                step: case,
                time: 0.0,
                solver: "exact".into(),
                failure,
            })?;
        let (mut zo, mut ro) = (vec![0.0; n], vec![0.0; k]);
        let mut osqp = Osqp::new(&c, &nodes, OsqpSettings::default())?;
        if osqp.solve(&b, &lo, &mut zo, &mut ro).is_err() {
            failures += 1;
            continue;
        }
        worst_z = worst_z.max(max_distance(&ze, &zo) / (1.0 + max_abs(&ze)));
        worst_r = worst_r.max(max_distance(&re, &ro) / (1.0 + max_abs(&b)));
    }
    let _ = writeln!(
        md,
        "#### Random step problems (tests/osqp_qp.rs's distribution, fixed seed)\n\n\
         {count} problems, 1 or 2 bounds, n = 2…23: OSQP errors {failures}; \
         max \\|z_osqp − z_exact\\|∞ / (1 + \\|z_exact\\|∞) = {worst_z:.1e}; \
         max \\|r_osqp − r_exact\\| / (1 + \\|b\\|∞) = {worst_r:.1e}"
    );
    Ok(())
}

/// One step problem `min ½zᵀCz − bᵀz, z_j >= lo_j` with the exact solver's answer `(z, r)`.
#[derive(Clone, Debug)]
pub struct StepProblem {
    pub c: viscobar::internals::linalg::tridiag::SymTridiag,
    /// Local indices of the constrained nodes.
    pub nodes: Vec<usize>,
    pub b: Vec<f64>,
    pub lo: Vec<f64>,
    pub z: Vec<f64>,
    pub r: Vec<f64>,
}

/// The start-up step problem of `scene` (the step `u^0 → u^1`) as the exact solver of the scene's
/// constraints sees it, and its answer: the data on which other solvers are probed in isolation.
pub fn start_up_problem(scene: &Scene) -> Result<StepProblem, RunError> {
    use std::cell::RefCell;
    use std::rc::Rc;
    use viscobar::bar::{Discretisation, Simulation};
    use viscobar::internals::bar::body::make_solver;
    use viscobar::step::{SolveInfo, StepFailure};

    /// Wraps the exact solver and keeps the first problem it is given, with its answer.
    struct Recorder {
        inner: Box<dyn StepSolver>,
        first: Rc<RefCell<Option<[Vec<f64>; 4]>>>,
    }
    impl StepSolver for Recorder {
        fn name(&self) -> &'static str {
            "recorder"
        }
        fn solve(
            &mut self,
            b: &[f64],
            lo: &[f64],
            z: &mut [f64],
            r: &mut [f64],
        ) -> Result<SolveInfo, StepFailure> {
            let info = self.inner.solve(b, lo, z, r)?;
            self.first
                .borrow_mut()
                .get_or_insert_with(|| [b.to_vec(), lo.to_vec(), z.to_vec(), r.to_vec()]);
            Ok(info)
        }
    }

    let mut exact = scene.clone();
    exact.solver.method = viscobar::scene::SolverMethod::Exact;
    let disc = Discretisation::new(&exact)?;
    let c = disc.step_matrix.clone();
    let nodes = disc.constrained_locals();
    let first = Rc::default();
    let recorder = Recorder {
        inner: make_solver(&exact, &disc)?,
        first: Rc::clone(&first),
    };
    // Setting the simulation up solves the start-up step.
    Simulation::with_solver(&exact, disc, Box::new(recorder))?;
    let [b, lo, z, r] = first.take().ok_or_else(|| RunError::SolverSetup {
        solver: "exact".into(),
        reason: "the start-up step was not solved".into(),
    })?;
    Ok(StepProblem {
        c,
        nodes,
        b,
        lo,
        z,
        r,
    })
}
