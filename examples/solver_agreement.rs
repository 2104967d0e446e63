//! The figures of VERIFICATION.md, section "Step solvers", as markdown:
//!
//!     cargo run --release --example solver_agreement
//!
//! 1. OSQP and penalty against the exact solver on every built-in scene (whole runs, every
//!    node and step), with their audits;
//! 2. the penalty error against ε and its observed order;
//! 3. OSQP's failures on a stiff scene, with OSQP's own verdict next to viscobar's;
//! 4. a seeded sample of random step problems, OSQP against exact.
//!
//! Everything is deterministic: the same build prints the same numbers.

use osqp::Status;
use viscobar::compare::{StepProblem, compare, start_up_problem};
use viscobar::exact::ExactSolver;
use viscobar::osqp_solver::{OsqpSettings, OsqpSolver, raw_problem};
use viscobar::run::run_in_memory;
use viscobar::scene::{self, PENALTY_DEFAULT_EPSILON, Scene};
use viscobar::solver::StepSolver;
use viscobar::study::observed_order;
use viscobar::tridiag::{Ldlt, SymTridiag};

fn load(name: &str, overrides: &[String]) -> Scene {
    scene::load(name, overrides)
        .unwrap_or_else(|e| panic!("{name}: {e}"))
        .1
}

fn method(m: &str, extra: &[String]) -> Vec<String> {
    let mut o = vec![format!("solver.method=\"{m}\"")];
    o.extend(extra.iter().cloned());
    o
}

fn main() {
    agreement_tables();
    penalty_rate();
    failure_cases();
    random_problems();
}

fn agreement_tables() {
    println!("### OSQP against exact (default settings), whole runs\n");
    println!(
        "| scene | steps | max \\|u_osqp − u_exact\\| | max \\|u\\| | identity residual | \
         iterations mean / max | audit: stationarity / in displacement / complementarity \
         (worst ratio to tolerance) |"
    );
    println!("|---|---|---|---|---|---|---|");
    for name in scene::builtin_names() {
        let exact = load(name, &[]);
        let osqp = load(name, &method("osqp", &[]));
        let c = compare(name, &exact, &osqp).unwrap();
        let s = &c.summary;
        let a = s.audit.as_ref().unwrap();
        println!(
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
    println!();
    println!(
        "### Penalty (ε = {PENALTY_DEFAULT_EPSILON:e}) against exact, whole runs\n\n\
         | scene | max \\|u_pen − u_exact\\| | max penetration (u + a)⁻ | ratio | \
         identity residual | subsets tried mean / max | audit: law / stationarity / in displacement |"
    );
    println!("|---|---|---|---|---|---|---|");
    for name in scene::builtin_names() {
        let exact = load(name, &[]);
        if exact.obstacle.is_some() {
            continue; // normal compliance is implemented for the two ends only
        }
        let pen = load(name, &method("penalty", &[]));
        let c = compare(name, &exact, &pen).unwrap();
        let s = &c.summary;
        let a = s.audit.as_ref().unwrap();
        let ratio = if s.max_violation > 0.0 {
            format!("{:.2}", c.agreement.max_difference / s.max_violation)
        } else {
            "–".into()
        };
        println!(
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
    println!();
}

fn penalty_rate() {
    let epsilons = [1e-2, 1e-3, 1e-4, 1e-5, 1e-6];
    println!("### Penalty → exact as ε → 0 (max over nodes and steps of \\|u_pen − u_exact\\|)\n");
    print!("| scene |");
    for e in epsilons {
        print!(" ε = {e:.0e} |");
    }
    println!(" observed order |");
    println!("|---|{}---|", "---|".repeat(epsilons.len()));
    for name in ["impact", "clamped-impact", "both-ends", "one-end-forced"] {
        let exact = load(name, &[]);
        let errors: Vec<f64> = epsilons
            .iter()
            .map(|e| {
                let s = load(name, &method("penalty", &[format!("solver.epsilon={e:e}")]));
                compare(name, &exact, &s).unwrap().agreement.max_difference
            })
            .collect();
        print!("| {name} |");
        for e in &errors {
            print!(" {e:.3e} |");
        }
        println!(" {:.3} |", observed_order(&epsilons, &errors));
    }
    println!();
}

/// OSQP called directly (no audit) on the start-up step of `scene`: status, polish, OSQP's own
/// dual residual and tolerance, the reaction error, and the stationarity error mapped to
/// displacement, against the exact answer.
fn raw_first_step(scene: &Scene, s: OsqpSettings) -> String {
    let StepProblem {
        c,
        nodes,
        b,
        lo,
        z: z_exact,
        r: r_exact,
    } = start_up_problem(scene).unwrap();
    let n = c.dim();
    let mut prob = raw_problem(&c, &nodes, &b, &lo, s).unwrap();
    let status = prob.solve();
    let iterations = status.iter();
    let (name, sol) = match status {
        Status::Solved(sol) => ("solved", sol),
        Status::SolvedInaccurate(sol) => ("solved inaccurate", sol),
        Status::MaxIterationsReached(sol) => ("maximum iterations reached", sol),
        other => return format!("{other:?}"),
    };
    let norm = |v: &[f64]| v.iter().fold(0.0f64, |m, x| m.max(x.abs()));
    let x = sol.x();
    let r: Vec<f64> = sol.y().iter().map(|y| -y).collect();
    let mut res = c.mul(x);
    let scale = norm(&res).max(norm(&b)).max(norm(&r));
    for i in 0..n {
        res[i] -= b[i];
    }
    for (j, &node) in nodes.iter().enumerate() {
        res[node] -= r[j];
    }
    Ldlt::factor(&c).unwrap().solve_in_place(&mut res);
    let dz = x
        .iter()
        .zip(&z_exact)
        .fold(0.0f64, |m, (a, b)| m.max((a - b).abs()));
    format!(
        "OSQP alone: `{name}` after {iterations} iterations, polish {:?}; its dual residual \
         {:.2e} against its own tolerance {:.2e}; reaction {:.6e} (exact {:.6e}, relative error \
         {:.1e}); max \\|z − z_exact\\| = {dz:.2e}; \\|C⁻¹(Cz − b − r)\\|∞ = {:.2e}",
        sol.polish_status(),
        sol.dua_res(),
        s.eps_abs + s.eps_rel * scale,
        r[0],
        r_exact[0],
        (r[0] - r_exact[0]).abs() / r_exact[0].abs(),
        norm(&res),
    )
}

fn failure_cases() {
    println!(
        "### OSQP on a stiff scene: impact with α = 1e6, 64 elements, 20 steps of dt = ratio × dx\n"
    );
    let cases: [(f64, &[&str], OsqpSettings); 4] = [
        (100.0, &[], OsqpSettings::default()),
        (1000.0, &[], OsqpSettings::default()),
        (10000.0, &[], OsqpSettings::default()),
        (
            100.0,
            &[
                "solver.eps_abs=1e-3",
                "solver.eps_rel=1e-3",
                "solver.polish=false",
            ],
            OsqpSettings {
                eps_abs: 1e-3,
                eps_rel: 1e-3,
                polish: false,
                ..OsqpSettings::default()
            },
        ),
    ];
    for (ratio, extra, settings) in cases {
        let dt = ratio / 64.0;
        let base = vec![
            "bar.viscosity=1e6".to_string(),
            "mesh.elements=64".into(),
            format!("time.step={dt}"),
            format!("time.end={}", 20.0 * dt),
        ];
        let exact = load("impact", &base);
        let mut o = base.clone();
        o.push("solver.method=\"osqp\"".into());
        o.extend(extra.iter().map(|s| s.to_string()));
        let osqp = load("impact", &o);
        let outcome = match run_in_memory("impact", &osqp) {
            Ok(_) => "run succeeded".to_string(),
            Err(e) => format!("error: {e}"),
        };
        println!(
            "- dt = {ratio} dx{}:\n  - viscobar: {outcome}\n  - {}",
            if extra.is_empty() {
                String::from(" (default settings)")
            } else {
                format!(" ({})", extra.join(", "))
            },
            raw_first_step(&exact, settings)
        );
    }
    let inaccurate = [
        "solver.method=\"osqp\"",
        "solver.eps_abs=1e-8",
        "solver.eps_rel=1e-8",
        "solver.max_iter=75",
    ];
    let o: Vec<String> = inaccurate.iter().map(|s| s.to_string()).collect();
    let refused = match run_in_memory("impact", &load("impact", &o)) {
        Ok(_) => "run succeeded".to_string(),
        Err(e) => format!("error: {e}"),
    };
    let mut o2 = o.clone();
    o2.push("solver.accept_inaccurate=true".into());
    let accepted = match run_in_memory("impact", &load("impact", &o2)) {
        Ok((_, s, _)) => format!(
            "run succeeded, inaccurate_steps = {:?}, worst stationarity ratio {:.1e}",
            s.inaccurate_steps,
            s.audit.unwrap().stationarity.max_over_tolerance
        ),
        Err(e) => format!("error: {e}"),
    };
    println!(
        "- impact (unchanged) with {}:\n  - {refused}\n  - with accept_inaccurate = true: {accepted}\n",
        inaccurate[1..].join(", ")
    );
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

fn random_problems() {
    let mut g = Lcg(2009);
    let (count, mut worst_z, mut worst_r, mut failures) = (2000, 0.0f64, 0.0f64, 0);
    for case in 0..count {
        let n = 2 + (g.uniform(0.0, 22.0) as usize);
        let off: Vec<f64> = (0..n - 1).map(|_| g.uniform(-1.0, 1.0)).collect();
        let diag: Vec<f64> = (0..n)
            .map(|i| {
                let l = if i > 0 { off[i - 1].abs() } else { 0.0 };
                let r = if i + 1 < n { off[i].abs() } else { 0.0 };
                l + r + g.uniform(0.05, 3.0)
            })
            .collect();
        let c = SymTridiag::new(diag, off);
        let b: Vec<f64> = (0..n).map(|_| g.uniform(-5.0, 5.0)).collect();
        let nodes = match case % 3 {
            0 => vec![0],
            1 => vec![n - 1],
            _ => vec![0, n - 1],
        };
        let lo: Vec<f64> = nodes.iter().map(|_| g.uniform(-2.0, 2.0)).collect();
        let k = nodes.len();
        let (mut ze, mut re) = (vec![0.0; n], vec![0.0; k]);
        ExactSolver::new(&c, &nodes)
            .unwrap()
            .solve(&b, &lo, &mut ze, &mut re)
            .unwrap();
        let (mut zo, mut ro) = (vec![0.0; n], vec![0.0; k]);
        let mut osqp = OsqpSolver::new(&c, &nodes, OsqpSettings::default()).unwrap();
        if osqp.solve(&b, &lo, &mut zo, &mut ro).is_err() {
            failures += 1;
            continue;
        }
        let norm = |v: &[f64]| v.iter().fold(0.0f64, |m, x| m.max(x.abs()));
        let dz = ze
            .iter()
            .zip(&zo)
            .fold(0.0f64, |m, (a, b)| m.max((a - b).abs()));
        let dr = re
            .iter()
            .zip(&ro)
            .fold(0.0f64, |m, (a, b)| m.max((a - b).abs()));
        worst_z = worst_z.max(dz / (1.0 + norm(&ze)));
        worst_r = worst_r.max(dr / (1.0 + norm(&b)));
    }
    println!(
        "### Random step problems (tests/osqp_qp.rs's distribution, fixed seed)\n\n\
         {count} problems, 1 or 2 bounds, n = 2…23: OSQP errors {failures}; \
         max \\|z_osqp − z_exact\\|∞ / (1 + \\|z_exact\\|∞) = {worst_z:.1e}; \
         max \\|r_osqp − r_exact\\| / (1 + \\|b\\|∞) = {worst_r:.1e}\n"
    );
}
