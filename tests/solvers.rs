//! Every (shape, method) cell of the algorithm table (`step::algorithm::ALGORITHMS`) under one
//! checker: the bar, the plane body with and without friction, the thermal bar; then OSQP's
//! failures surfaced as errors, bit-identical runs, and the bar's penalty solution converging
//! to the exact one as ε → 0.

mod common;
use common::{COMPLEMENTARITY_TOL, GAP_TOL, REACTION_TOL, viscobar};

use std::path::Path;

use osqp::Status;
use viscobar::RunError;
use viscobar::Simulation;
use viscobar::SolverMethod as Method;
use viscobar::internals::linalg::norms::max_abs;
use viscobar::internals::linalg::tridiag::SymTridiag;
use viscobar::internals::step::end_penalty::PENALTY_DEFAULT_EPSILON;
use viscobar::internals::step::end_penalty::PenaltySettings;
use viscobar::internals::step::osqp::{OSQP_INFTY, Osqp, OsqpSettings, raw_problem};
use viscobar::output::run_in_memory;
use viscobar::output::{run_plane_in_memory, run_thermal_in_memory};
use viscobar::scene::plane::{PENALTY_CONDENSED_MAX_NORMALS, PlaneScene, plane_builtin_text};
use viscobar::scene::{MassVariant, Scene};
use viscobar::step::algorithm::{ALGORITHMS, Shape, algorithm_for};
use viscobar::step::audit::dual_tolerance;
use viscobar::step::{StepFailure, StepSolver};
use viscobar::study::accuracy::observed_order;
use viscobar::study::compare::compare;
use viscobar_certificate::friction;
use viscobar_certificate::plane::contact::Method as PlaneMethod;
use viscobar_certificate::plane::contact::{
    CONTACT_SCENES, PENALTY_EPSILONS, agreement, checked_run, osqp_method, plane_scene,
};
use viscobar_certificate::solvers::agreement::start_up_problem;
use viscobar_certificate::solvers::agreement::stiff_impact_overrides;

// ---- tolerances -------------------------------------------------------------------------

// The solver tolerances, defined beside their measurement in the tolerance registry
// (`viscobar-certificate verify --tolerances`, `tolerances::solver_worst`).
use viscobar_certificate::tolerances::{
    FRICTION_DISSIPATION_TOL, MOMENTUM_TOL, OSQP_AGREEMENT_TOL, OSQP_GAP_TOL, OSQP_REACTION_TOL,
    PENALTY_LAW_TOL, PLANE_GAP_TOL, PLANE_IDENTITY_TOL, PLANE_OSQP_AGREEMENT_TOL, SMALL_TOL,
    THERMAL_IDENTITY_TOL, friction_osqp_agreement_ratio, osqp_small_problems,
    plane_osqp_agreement_ratio, plane_penalty_ratio, solver_cases, solver_worst,
};
/// Penalty against exact, in units of the penalty run's largest penetration `ε r`: the penalty
/// run is the exact scheme with each obstacle moved by its penetration; a boundary displacement
/// perturbs the wave by up to twice itself where it reflects at a free end, and the release
/// from contact is delayed by O(ε), which can double that again. Per contact episode: between
/// episodes the runs are linear, so the perturbations of successive episodes add (falling-bar,
/// two episodes, measured 2.0 after the first and 5.0 after the second).
const PENALTY_AGREEMENT_FACTOR: f64 = 4.0;

// ---- the generic checker ----------------------------------------------------------------

fn with_method(name: &str, method: Method, extra: &[&str]) -> Scene {
    let mut o = vec![format!("solver.method=\"{}\"", method.name())];
    o.extend(extra.iter().map(|s| s.to_string()));
    let o: Vec<&str> = o.iter().map(String::as_str).collect();
    common::builtin(name, &o)
}

/// Runs `method` on every built-in bar scene with an obstacle (`obstacle`) or without (and
/// every mass variant of `solver_cases`) side by side with the exact solver and checks the
/// energy identity, the contact law to the method's tolerance, and the agreement.
fn check_solver(method: Method, obstacle: bool) {
    for (scene_name, mass) in solver_cases() {
        let mass_key = format!("bar.mass=\"{}\"", mass.name());
        if let Err(err) = viscobar::scene::load(scene_name, std::slice::from_ref(&mass_key)) {
            // Redistribution with an obstacle is refused, naming both keys.
            assert_eq!(mass, MassVariant::Redistributed, "{scene_name}: {err}");
            let err = err.to_string();
            assert!(
                err.contains("bar.mass") && err.contains("obstacle.gap"),
                "{err}"
            );
            continue;
        }
        let label = format!("{scene_name} [mass {}]", mass.name());
        let name = label.as_str();
        let exact = with_method(scene_name, Method::Exact, &[&mass_key]);
        let scene = with_method(scene_name, method, &[&mass_key]);
        if scene.obstacle.is_some() != obstacle {
            continue;
        }
        if matches!(method, Method::Penalty) && scene.obstacle.is_some() {
            // Normal compliance is implemented for the two ends only: refused, not run.
            let err = compare(name, &exact, &scene).expect_err("penalty refuses an obstacle");
            assert!(err.to_string().contains("penalty"), "{err}");
            continue;
        }
        let cmp =
            compare(name, &exact, &scene).unwrap_or_else(|e| panic!("{method:?} on {name}: {e}"));
        let (records, summary, agreement) = (&cmp.records, &cmp.summary, cmp.agreement);
        assert_eq!(records.len(), scene.steps(), "{name}");
        let k = scene.signorini_ends().len();

        // The tolerances of the registry, through its measurement (`solver_worst`): the
        // identity against IDENTITY_TOL, or for OSQP against the run's a-posteriori bound.
        let w = solver_worst(&scene, &cmp);
        assert!(
            w.identity_ratio <= 1.0,
            "{method:?} {name}: identity residual over its tolerance {:e}",
            w.identity_ratio
        );
        let mut max_reaction = 0.0f64;
        for r in records {
            // Every constrained node (the obstacle's too), through the record's aggregates.
            if scene.obstacle.is_some() && matches!(method, Method::Exact) {
                assert!(
                    r.contact.min_gap >= -GAP_TOL && r.contact.min_reaction >= -REACTION_TOL,
                    "{name}: step {}",
                    r.step
                );
                assert!(
                    r.contact.max_complementarity <= COMPLEMENTARITY_TOL,
                    "{name}: step {}",
                    r.step
                );
            }
            for j in 0..k {
                let (g, l) = (r.contact.groups[j].min_gap, r.contact.groups[j].reaction);
                max_reaction = max_reaction.max(l);
                let at = format!(
                    "{method:?} {name}: step {} end {j}: gap {g:e} r {l:e}",
                    r.step
                );
                match method {
                    Method::Exact => {
                        assert!(g >= -GAP_TOL && l >= -REACTION_TOL, "{at}");
                        assert!((g * l).abs() <= COMPLEMENTARITY_TOL, "{at}");
                    }
                    // No complementarity: the gap is −ε r in contact.
                    Method::Penalty => assert!(l >= -REACTION_TOL, "{at}"),
                    Method::Osqp => {}
                }
            }
        }
        match method {
            Method::Osqp => assert!(
                w.negative_gap <= OSQP_GAP_TOL
                    && w.negative_reaction <= OSQP_REACTION_TOL
                    && w.complementarity_ratio <= 1.0,
                "{name}: {w:?}"
            ),
            Method::Penalty => assert!(w.law <= PENALTY_LAW_TOL, "{name}: law residual {w:?}"),
            Method::Exact => {}
        }

        // The solvers that audit themselves report it, consistently with the records.
        match method {
            Method::Exact => assert!(summary.audit.is_none() && summary.inaccurate_steps.is_none()),
            Method::Osqp | Method::Penalty => {
                let audit = summary.audit.as_ref().expect("audited solver reports");
                assert_eq!(audit.steps as usize, scene.steps(), "{name}");
                assert!(audit.stationarity.max_over_tolerance <= 1.0);
                assert!(audit.stationarity_displacement.max_over_tolerance <= 1.0);
                assert_eq!(
                    summary.inaccurate_steps,
                    (method == Method::Osqp).then_some(0)
                );
            }
        }

        match method {
            Method::Exact => assert_eq!(agreement.max_difference, 0.0, "{name}"),
            // The 1e-7 and the run's own a-posteriori bound (`osqp_agreement_bound`).
            Method::Osqp => assert!(
                w.agreement <= OSQP_AGREEMENT_TOL && w.agreement_ratio <= 1.0,
                "{name}: OSQP differs from exact by {:e} at step {} ({:e} of its bound)",
                agreement.max_difference,
                agreement.worst_step,
                w.agreement_ratio
            ),
            Method::Penalty => {
                // Penetration is ε × reaction (to round-off, `w.law` above), and the
                // displacement follows it.
                let penetration = summary.max_violation;
                // Episodes of the exact run: the penalty run's own count could grow with brief
                // spurious contacts and loosen its own bound.
                let (_, exact_summary, _) = run_in_memory(name, &exact).unwrap();
                let episodes = exact_summary.contact_intervals.values().map(Vec::len).max();
                let episodes = episodes.unwrap_or(0).max(1) as f64;
                assert!(
                    agreement.max_difference <= PENALTY_AGREEMENT_FACTOR * episodes * penetration,
                    "{name}: penalty differs from exact by {:e}, penetration {penetration:e}, {episodes} episodes",
                    agreement.max_difference
                );
            }
        }
        // Every scene with a Signorini end makes contact (energy_and_contact.rs), so the
        // penalty solver must penetrate there: the bound above is not vacuous.
        if method == Method::Penalty && k > 0 {
            assert!(summary.max_violation > 0.0, "{name}: no penetration");
        }
    }
}

// ---- the checker over the algorithm table ------------------------------------------------

/// The check of `method` on `shape`: the algorithm `ALGORITHMS` gives it, or its refusal;
/// `None` where the checker has no case (a failure for a cell the table fills).
fn case(shape: Shape, method: Method) -> Option<fn()> {
    use Shape::*;
    let check: fn() = match (shape, method) {
        (BarEnds, Method::Exact) => || check_solver(Method::Exact, false),
        (BarEnds, Method::Osqp) => || check_solver(Method::Osqp, false),
        (BarEnds, Method::Penalty) => || check_solver(Method::Penalty, false),
        (BarObstacle, Method::Exact) => || check_solver(Method::Exact, true),
        (BarObstacle, Method::Osqp) => || check_solver(Method::Osqp, true),
        // The refusal, on every obstacle scene.
        (BarObstacle, Method::Penalty) => || check_solver(Method::Penalty, true),
        (ThermalEnds, Method::Exact) => thermal_identity,
        (PlaneNormals, Method::Exact) => plane_contact_conditions,
        (PlaneNormals, Method::Osqp) => plane_osqp_agreement,
        (PlaneNormals, Method::Penalty) => plane_penalty_tends_to_exact,
        // Its run takes two minutes (the dense `S` of 4401 normals): the ignored test below.
        (ManyPlaneNormals, Method::Exact) => many_normals_accepted_by_the_exact_step,
        (ManyPlaneNormals, Method::Osqp) => || many_normals(Method::Osqp),
        (ManyPlaneNormals, Method::Penalty) => || many_normals(Method::Penalty),
        (PlaneFriction, Method::Exact) => friction_scene_checks,
        (PlaneFriction, Method::Osqp) => friction_osqp_agreement,
        _ => return None,
    };
    Some(check)
}

/// Every cell of `ALGORITHMS` that names an algorithm has its case.
#[test]
fn every_algorithm_of_the_table_has_a_case_in_the_checker() {
    for (shape, row) in ALGORITHMS {
        for (method, algorithm) in Method::ALL.into_iter().zip(row) {
            if let Some(a) = algorithm {
                assert!(
                    case(shape, method).is_some(),
                    "{a:?} ({shape:?}, {method:?})"
                );
            }
        }
    }
}

/// Every case of the table, each on its own thread; fails naming the cases that failed.
#[test]
fn every_algorithm_of_the_table_passes_the_checker() {
    let cells = ALGORITHMS.iter().flat_map(|&(shape, _)| {
        Method::ALL
            .into_iter()
            .filter_map(move |m| case(shape, m).map(|c| ((shape, m), c)))
    });
    let failed: Vec<_> = std::thread::scope(|s| {
        let runs: Vec<_> = cells.map(|(cell, c)| (cell, s.spawn(c))).collect();
        runs.into_iter()
            .filter_map(|(cell, run)| run.join().is_err().then_some(cell))
            .collect()
    });
    assert!(failed.is_empty(), "failed: {failed:?}");
}

/// The thermal bar: the total-energy identity to round-off at every step of every thermal scene
/// (built-ins and the variants exercising every term), with contact at many steps; thermal
/// dissipation is never negative.
fn thermal_identity() {
    let mut contact = 0;
    for (name, scene) in viscobar_certificate::thermal::identity_scenes().unwrap() {
        let (records, _, _) = run_thermal_in_memory(&name, &scene).unwrap();
        for r in &records {
            assert!(r.identity_residual <= THERMAL_IDENTITY_TOL, "{name}: {r:?}");
            let heat = r.heat.unwrap_or_default();
            assert!(heat.dissipation >= 0.0, "{name}: {r:?}");
            contact += usize::from(r.contact.contact_nodes > 0);
        }
    }
    assert!(contact > 100, "contact at {contact} steps");
}

/// The plane's exact step: the contact conditions and the energy identity at every node and
/// step of every frictionless built-in plane scene with a Signorini edge.
fn plane_contact_conditions() {
    let mut with_contact = 0;
    for (name, scene) in viscobar_certificate::plane::identity_scenes() {
        if scene.edges.gaps().unwrap().iter().all(Option::is_none) {
            continue;
        }
        // The friction scenes (a stiff block resting on its floor at gap 0) are held by their
        // solver's audit, whose floors follow the stiffness (`friction_scene_checks`).
        if scene.edges.frictions().unwrap().iter().any(Option::is_some) {
            continue;
        }
        let (records, summary, checks) = checked_run(&name, &scene).unwrap();
        with_contact += 1;
        let in_contact = |r: &viscobar::StepRecord| r.contact.contact_nodes;
        assert!(
            records.iter().any(|r| in_contact(r) > 0),
            "{name}: no contact"
        );
        assert!(
            in_contact(records.last().unwrap()) < records.iter().map(in_contact).max().unwrap(),
            "{name}: the contact set never shrinks"
        );
        for (r, c) in records.iter().zip(&checks) {
            let (gap, energy) = (PLANE_GAP_TOL * c.scale, PLANE_GAP_TOL * r.energy);
            assert!(c.penetration <= gap, "{name} {}: {c:?}", r.step);
            let complementarity = c.complementarity <= gap * r.contact.total_reaction;
            assert!(complementarity, "{name} {}: {c:?}", r.step);
            assert!(r.contact_dissipation >= -energy, "{name}: {r:?}");
        }
        for r in &records[1..] {
            assert!(r.identity_residual <= PLANE_IDENTITY_TOL, "{name}: {r:?}");
        }
        assert!(summary.max_identity_residual <= PLANE_IDENTITY_TOL);
        // The contact term is part of the balance: dropping it breaks the identity.
        let big = records
            .iter()
            .map(|r| r.contact_dissipation)
            .fold(0.0, f64::max);
        assert!(
            big > 1e3 * PLANE_IDENTITY_TOL * records[0].energy,
            "{name}: contact dissipates nothing"
        );
    }
    assert!(with_contact >= 2);
}

/// The plane's OSQP step against the exact one on the contact scenes.
fn plane_osqp_agreement() {
    for name in CONTACT_SCENES {
        let scene = plane_scene(name, &[]).unwrap();
        let a = agreement(&scene, osqp_method()).unwrap();
        assert!(
            a.max_active > 1 && a.contact_steps > 0,
            "{name}: contact {a:?}"
        );
        let (u, r) = (a.max_u_deviation, a.max_reaction_deviation);
        assert!(u <= PLANE_OSQP_AGREEMENT_TOL * a.max_u, "{name}: u {u:e}");
        assert!(
            r <= PLANE_OSQP_AGREEMENT_TOL * a.max_reaction,
            "{name}: r {r:e}"
        );
        assert!(a.audit_worst_ratio.unwrap() <= 1.0);
        // The run's own bound: two solves' round-off per step (the registry's).
        let ratio = plane_osqp_agreement_ratio(&a);
        assert!(ratio <= 1.0, "{name}: {ratio:e} of the bound");
    }
}

/// Normal compliance tends to Signorini as ε → 0: its gap is `−ε r`, so the deviation from
/// the exact run is O(ε) (measured ratio between ε = 1e-4 and 1e-6 in VERIFICATION.md); at
/// least a factor 10 of the 100 must show, and ε = 1e-6 must be within the registry's bound
/// `PLANE_PENALTY_FACTOR ε r_max`.
const PENALTY_MIN_RATIO: f64 = 10.0;

/// The plane's condensed penalty against the exact step on the tilted drop.
fn plane_penalty_tends_to_exact() {
    let scene = plane_scene("plane-tilted-drop", &[]).unwrap();
    let [a, b] = PENALTY_EPSILONS
        .map(|epsilon| agreement(&scene, PlaneMethod::Penalty { epsilon }).unwrap());
    let (ea, eb) = (a.max_u_deviation / a.max_u, b.max_u_deviation / b.max_u);
    assert!(ea >= PENALTY_MIN_RATIO * eb, "{ea:e} {eb:e}");
    let ratio = plane_penalty_ratio(&b, PENALTY_EPSILONS[1]);
    assert!(ratio <= 1.0, "{eb:e}: {ratio:e} of the bound");
}

/// [`many_normals_scene`] with the exact step is accepted, and its algorithm is the one that
/// [`plane_contact_conditions`] checks on fewer normals.
fn many_normals_accepted_by_the_exact_step() {
    let scene = many_normals_scene(Method::Exact);
    assert!(scene.contact_normals() > PENALTY_CONDENSED_MAX_NORMALS);
    let exact = |shape| algorithm_for(Method::Exact, shape);
    assert_eq!(exact(Shape::ManyPlaneNormals), exact(Shape::PlaneNormals));
}

/// The exact step's run of [`many_normals`], about two minutes on one core.
#[test]
#[ignore = "about 2 min: cargo test --release --test solvers -- --ignored"]
fn the_exact_step_runs_beyond_the_condensed_switch() {
    many_normals(Method::Exact);
}

/// A strip on 4400 × 1 cells pushed into a floor (4401 normals, beyond the penalty's condensed
/// switch), with `method`.
fn many_normals_scene(method: Method) -> PlaneScene {
    let m = format!("solver.method=\"{}\"", method.name());
    let set = [
        "mesh.nx=4400",
        "mesh.ny=1",
        "plane.width=44.0",
        "time.end=0.03",
        "initial.displacement=[\"0\", \"0\"]",
        "initial.velocity=[\"0\", \"-1\"]",
        "edges.bottom={condition=\"signorini\", gap=0.005}",
        &m,
    ];
    let set: Vec<String> = set.iter().map(|s| s.to_string()).collect();
    PlaneScene::from_toml(plane_builtin_text("plane-strip").unwrap(), &set).unwrap()
}

/// [`many_normals_scene`] runs: the contact is real and the energy identity closes.
fn many_normals(method: Method) {
    let scene = many_normals_scene(method);
    assert!(scene.contact_normals() > PENALTY_CONDENSED_MAX_NORMALS);
    let (records, summary, _) = run_plane_in_memory("wide", &scene).unwrap();
    assert_eq!(summary.solver, method.name());
    let last = records.last().unwrap();
    assert!(last.contact.total_reaction > 0.0, "{method:?}: {last:?}");
    for r in records.iter().skip(1) {
        assert!(
            r.identity_residual <= PLANE_IDENTITY_TOL,
            "{method:?}: {r:?}"
        );
    }
}

/// The plane's exact step with Coulomb friction: the identity with `D_f`, `D_f >= 0`, the
/// momentum balance along the tangent and the audit at every step of the friction scenes.
fn friction_scene_checks() {
    let checks = friction::scene_checks().unwrap();
    for c in &checks {
        let name = &c.name;
        assert!(c.max_identity <= PLANE_IDENTITY_TOL, "{name}: {c:?}");
        let d = c.min_dissipation_ratio;
        assert!(d >= -FRICTION_DISSIPATION_TOL, "{name}: D_f / E = {d:e}");
        assert!(c.momentum <= MOMENTUM_TOL, "{name}: {:e}", c.momentum);
        assert!(c.audit_worst_ratio <= 1.0, "{name}: {c:?}");
        // Friction dissipates, and far beyond the identity's round-off: dropping D_f would
        // break the identity.
        assert!(c.total_dissipation > 1e6 * PLANE_IDENTITY_TOL, "{name}");
        assert!(c.steps_slipping > 0, "{name}: never slips");
    }
    // The drop both sticks and slips, and so does the launched block (it stops).
    for c in checks.iter().filter(|c| c.name != "plane-friction-slope") {
        assert!(c.steps_sticking > 10 && c.max_stick > 1, "{c:?}");
    }
}

/// The exact friction step against OSQP's Tresca fixed point on the friction scenes.
fn friction_osqp_agreement() {
    for a in friction::osqp_agreements().unwrap() {
        let ratio = friction_osqp_agreement_ratio(&a);
        assert!(ratio <= 1.0, "{}: {ratio:e} of the bound", a.name);
        assert!(a.audit_worst_ratio <= 1.0, "{}", a.name);
        // The fixed point iterates: Coulomb is more than one Tresca problem.
        assert!(a.max_iterations > 2 && a.mean_iterations > 1.0, "{a:?}");
    }
}

/// On the coarsest meshes `C_jj` (mass over Δt²) is large but still softer than the spring
/// `1/ε`, so the reaction is taken from stationarity, whose row `(Cz − b)_j` cancels: the law's
/// audit must weigh that row's rounding (`u ε (|C||z| + |b|)_j`), which it once did not (the
/// forced scenes failed it at J = 2 and 3, the falling bar at J = 2).
#[test]
fn penalty_passes_its_audit_on_the_coarsest_meshes() {
    for name in [
        "both-ends-forced",
        "one-end-forced",
        "falling-bar",
        "both-ends",
    ] {
        for elements in 1..=8 {
            let setting = format!("mesh.elements={elements}");
            let scene = with_method(name, Method::Penalty, &[&setting]);
            if let Err(e) = run_in_memory(name, &scene) {
                panic!("{name} with {elements} elements: {e}");
            }
        }
    }
}

// ---- penalty → exact as ε → 0 -----------------------------------------------------------

/// Observed order in ε of the penalty solution's distance to the exact one: first order in
/// theory (penetration ε r, the rest follows linearly); the least-squares slope over
/// ε = 1e-2 … 1e-6 may sit below 1 by a few percent because at ε = 1e-2 the penetration is
/// already a tenth of the gap (pre-asymptotic), so ±0.1 around 1.
const PENALTY_RATE_BAND: (f64, f64) = (0.9, 1.1);

#[test]
fn penalty_converges_to_exact_at_first_order_in_epsilon() {
    let epsilons = [1e-2, 1e-3, 1e-4, 1e-5, 1e-6];
    for name in ["impact", "both-ends"] {
        let exact = with_method(name, Method::Exact, &[]);
        let errors: Vec<f64> = epsilons
            .iter()
            .map(|eps| {
                let s = with_method(name, Method::Penalty, &[&format!("solver.epsilon={eps:e}")]);
                compare(name, &exact, &s).unwrap().agreement.max_difference
            })
            .collect();
        let rate = observed_order(&epsilons, &errors);
        assert!(
            rate >= PENALTY_RATE_BAND.0 && rate <= PENALTY_RATE_BAND.1,
            "{name}: observed order {rate} in ε (errors {errors:?})"
        );
        // And monotone: each decade of ε shrinks the error.
        assert!(errors.windows(2).all(|w| w[1] < w[0]), "{errors:?}");
    }
}

// ---- OSQP's failures are errors ---------------------------------------------------------

/// What OSQP itself says about one step problem, called through the `osqp` crate directly
/// (independently of `Osqp`): status, answer, its own dual residual and tolerance.
struct RawOsqp {
    solved: bool,
    reaction: Vec<f64>,
    dual_residual: f64,
    dual_tolerance: f64,
}

fn raw_osqp(c: &SymTridiag, nodes: &[usize], b: &[f64], lo: &[f64], s: OsqpSettings) -> RawOsqp {
    let mut prob = raw_problem(c, nodes, b, lo, s).unwrap();
    let status = prob.solve();
    let (solved, sol) = match status {
        Status::Solved(sol) => (true, sol),
        Status::SolvedInaccurate(sol) | Status::MaxIterationsReached(sol) => (false, sol),
        other => panic!("unexpected status {other:?}"),
    };
    let x = sol.x();
    let reaction: Vec<f64> = sol.y().iter().map(|y| -y).collect();
    // OSQP's own criterion (auxil.c), as the audit computes it.
    let cz_norm = max_abs(&c.mul(x));
    let tolerance = dual_tolerance(
        s.eps_abs,
        s.eps_rel,
        cz_norm,
        max_abs(b),
        max_abs(&reaction),
    );
    RawOsqp {
        solved,
        reaction,
        dual_residual: sol.dua_res(),
        dual_tolerance: tolerance,
    }
}

/// The stiff scene of the failure cases: the impact scene with α = 1e6 on 64 elements, time
/// step `ratio · dx`, 20 steps.
fn stiff_impact(ratio: f64, extra: &[&str]) -> Scene {
    let mut o = stiff_impact_overrides(ratio);
    o.extend(extra.iter().map(|s| s.to_string()));
    let o: Vec<&str> = o.iter().map(String::as_str).collect();
    common::builtin("impact", &o)
}

fn step_failure<T>(result: Result<T, RunError>) -> (usize, StepFailure) {
    match result {
        Err(RunError::Step { step, failure, .. }) => (step, failure),
        Err(e) => panic!("expected a step failure, got {e}"),
        Ok(_) => panic!("expected a step failure, the run succeeded"),
    }
}

/// OSQP alone on the start-up step of [`stiff_impact`] at `ratio` with `settings`, and the
/// relative error of its reaction against the exact solver's.
fn raw_start_up(ratio: f64, settings: OsqpSettings) -> (RawOsqp, f64) {
    let f = start_up_problem(&stiff_impact(ratio, &[])).unwrap();
    let raw = raw_osqp(&f.c, &f.nodes, &f.b, &f.lo, settings);
    let reaction_error = (raw.reaction[0] - f.r[0]).abs() / f.r[0];
    (raw, reaction_error)
}

/// The audit failure that must stop the OSQP run of [`stiff_impact`] at `ratio` (with
/// `overrides`) at step 1: what failed, its value and its tolerance.
fn first_step_audit_failure(ratio: f64, overrides: &[&str]) -> (&'static str, f64, f64) {
    let mut o = vec!["solver.method=\"osqp\""];
    o.extend(overrides);
    let scene = stiff_impact(ratio, &o);
    let (step, failure) = step_failure(run_in_memory("impact", &scene));
    assert_eq!(step, 1);
    match failure {
        StepFailure::AuditFailed {
            what,
            value,
            tolerance,
        } => (what, value, tolerance),
        f => panic!("expected an audit failure, got {f}"),
    }
}

/// With default (tight) settings at dt = 1000 dx OSQP reports "solved" for the first step
/// although its polished answer's dual residual is far above its own stopping tolerance (0.6's
/// polish is accepted when the primal residual improves and the ADMM dual residual was below
/// 1e-10, whatever the polished dual residual); the reaction is then off in the fifth digit.
/// The audit's stationarity check refuses it.
#[test]
fn osqp_success_that_misses_its_own_tolerance_is_an_error() {
    let (raw, reaction_error) = raw_start_up(1000.0, OsqpSettings::default());
    assert!(raw.solved, "OSQP reports solved");
    assert!(
        raw.dual_residual > 10.0 * raw.dual_tolerance,
        "OSQP's dual residual {:e} vs its tolerance {:e}",
        raw.dual_residual,
        raw.dual_tolerance
    );
    assert!(reaction_error > 1e-6, "reaction error {reaction_error:e}");

    let (what, value, tolerance) = first_step_audit_failure(1000.0, &[]);
    assert!(what.starts_with("stationarity |Cz"), "{what}");
    assert!(value > tolerance);
}

/// The independent test's case (α = 1e6, dt = 100 dx, 64 elements) with OSQP's tolerances
/// loosened to 1e-3 and polishing off: OSQP reports "solved" with a reaction several percent
/// off (the stationarity residual, mapped to displacement, is about 0.1 against a gap of 0.1);
/// within OSQP's own residual test, refused by the audit's displacement check.
#[test]
fn osqp_loose_answer_far_from_exact_is_an_error() {
    let loose = [
        "solver.eps_abs=1e-3",
        "solver.eps_rel=1e-3",
        "solver.polish=false",
    ];
    let settings = OsqpSettings {
        eps_abs: 1e-3,
        eps_rel: 1e-3,
        polish: false,
        ..OsqpSettings::default()
    };
    let (raw, reaction_error) = raw_start_up(100.0, settings);
    assert!(raw.solved && raw.dual_residual <= raw.dual_tolerance);
    assert!(reaction_error > 1e-2, "reaction error {reaction_error:e}");

    let (what, value, tolerance) = first_step_audit_failure(100.0, &loose);
    assert!(what.starts_with("stationarity in displacement"), "{what}");
    assert!(value > 5.0 * tolerance, "{value:e} vs {tolerance:e}");
}

/// With default settings at dt = 100 dx OSQP does not converge within max_iter: a status
/// error naming step, time and status.
#[test]
fn osqp_non_convergence_is_an_error_naming_step_time_and_status() {
    let scene = stiff_impact(100.0, &["solver.method=\"osqp\""]);
    let err = run_in_memory("impact", &scene).err().expect("run fails");
    let text = err.to_string();
    assert!(text.contains("step 1 (t = 1.5625)"), "{text}");
    assert!(text.contains("maximum iterations reached"), "{text}");
    assert_eq!(err.exit_code(), 1);
}

/// "Solved inaccurate" is refused unless `accept_inaccurate`; accepted steps are counted.
/// (eps = 1e-8 with max_iter = 75 on the impact scene gives exactly one such step.)
#[test]
fn solved_inaccurate_is_refused_unless_accepted_and_then_counted() {
    let base = [
        "solver.method=\"osqp\"",
        "solver.eps_abs=1e-8",
        "solver.eps_rel=1e-8",
        "solver.max_iter=75",
    ];
    let refused = common::builtin("impact", &base);
    let err = run_in_memory("impact", &refused).err().expect("refused");
    assert!(err.to_string().contains("solved inaccurate"), "{err}");
    assert!(err.to_string().contains("accept_inaccurate"), "{err}");

    let mut o = base.to_vec();
    o.push("solver.accept_inaccurate=true");
    let accepted = common::builtin("impact", &o);
    let (_, summary, _) = run_in_memory("impact", &accepted).unwrap();
    assert_eq!(summary.inaccurate_steps, Some(1));
    let audit = summary.audit.unwrap();
    assert!(audit.stationarity.max_over_tolerance <= 1.0);
}

// ---- determinism ------------------------------------------------------------------------

#[test]
fn osqp_runs_are_bit_identical_in_process() {
    runs_are_bit_identical_in_process(Method::Osqp);
}

/// The exact end solver, whose superposition and `u += z` share one pass when they may.
#[test]
fn exact_runs_are_bit_identical_in_process() {
    runs_are_bit_identical_in_process(Method::Exact);
}

fn runs_are_bit_identical_in_process(method: Method) {
    // Up to t = 4: both ends in contact from t ≈ 3.03.
    let scene = with_method("both-ends-forced", method, &["time.end=4"]);
    let mut a = Simulation::new(&scene).unwrap();
    let mut b = Simulation::new(&scene).unwrap();
    let bits = |s: &Simulation| {
        s.displacement()
            .iter()
            .map(|v| v.to_bits())
            .collect::<Vec<_>>()
    };
    assert_eq!(bits(&a), bits(&b));
    let mut contact = false;
    for _ in 1..scene.steps() {
        let ra = a.step().unwrap();
        let rb = b.step().unwrap();
        assert_eq!(bits(&a), bits(&b), "step {}", ra.step);
        let reactions = |r: &viscobar::StepRecord| r.contact.groups.map(|g| g.reaction.to_bits());
        assert_eq!(reactions(&ra), reactions(&rb));
        contact |= ra.contact.total_reaction > 0.0;
    }
    assert!(contact, "the comparison covers steps in contact");
}

/// `viscobar run SCENE --solver SOLVER [--set SETTING]... --out OUT`, which must succeed.
fn run_cli(scene: &str, solver: &str, settings: &[&str], out: &Path) -> std::process::Output {
    let mut args = vec!["run", scene, "--solver", solver];
    for s in settings {
        args.extend(["--set", s]);
    }
    args.extend(["--out", out.to_str().unwrap()]);
    let o = viscobar(&args);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    o
}

#[test]
fn osqp_runs_write_byte_identical_files() {
    let base = std::env::temp_dir().join(format!("viscobar-osqp-bits-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&base);
    let dirs = [base.join("a"), base.join("b")];
    for d in &dirs {
        run_cli("both-ends-forced", "osqp", &["time.end=4"], d);
    }
    let read = |d: &Path, f: &str| std::fs::read(d.join(f)).unwrap();
    for f in ["history.csv", "displacement.csv"] {
        let (a, b) = (read(&dirs[0], f), read(&dirs[1], f));
        assert!(!a.is_empty());
        assert!(a == b, "{f} differs between two identical runs");
    }
    let _ = std::fs::remove_dir_all(&base);
}

// ---- the OSQP solver on its own -----------------------------------------------------------

#[test]
fn osqp_handles_no_constraints_and_reports_reactions_with_the_right_sign() {
    // No constrained node (A is 0 × 3, OSQP still solves C z = b), then one active bound with
    // reaction (C z − b)_0 = 2/3 > 0: closed forms in `osqp_small_problems`.
    let (worst, audited) = osqp_small_problems().unwrap();
    assert!(worst <= SMALL_TOL, "worst error {worst:e}");
    assert_eq!(audited, 1);
}

#[test]
fn osqp_refuses_non_finite_data_without_panicking() {
    let c = SymTridiag::new(vec![2.0, 2.0], vec![-1.0]);
    let mut s = Osqp::new(&c, &[0], OsqpSettings::default()).unwrap();
    let (mut z, mut r) = ([0.0; 2], [0.0]);
    for (b, lo) in [
        ([f64::NAN, 0.0], 0.0),
        ([0.0, f64::INFINITY], 0.0),
        ([0.0, 0.0], f64::NAN),
        ([0.0, 0.0], 2.0 * OSQP_INFTY),
    ] {
        assert_eq!(
            s.solve(&b, &[lo], &mut z, &mut r),
            Err(StepFailure::NonFinite),
            "b = {b:?}, lo = {lo}"
        );
    }
    // And it still works afterwards.
    s.solve(&[1.0, 1.0], &[0.0], &mut z, &mut r).unwrap();
}

// ---- scene settings ---------------------------------------------------------------------

#[test]
fn solver_settings_of_another_method_or_out_of_range_are_refused() {
    // Each case: its overrides, separated by spaces, and what the error must name.
    let refused = [
        ("solver.eps_abs=1e-6", "solver.eps_abs"),
        (
            "solver.method=\"penalty\" solver.polish=false",
            "solver.polish",
        ),
        (
            "solver.method=\"osqp\" solver.epsilon=1e-3",
            "solver.epsilon",
        ),
        (
            "solver.method=\"penalty\" solver.epsilon=0",
            "solver.epsilon",
        ),
        (
            "solver.method=\"penalty\" solver.epsilon=-1",
            "solver.epsilon",
        ),
        (
            "solver.method=\"osqp\" solver.adaptive_rho_interval=0",
            "adaptive_rho_interval",
        ),
        (
            "solver.method=\"osqp\" solver.max_iter=0",
            "solver.max_iter",
        ),
        (
            "solver.method=\"osqp\" solver.eps_rel=-1e-3",
            "solver.eps_rel",
        ),
        (
            "solver.method=\"osqp\" solver.eps_abs=0 solver.eps_rel=0",
            "both be 0",
        ),
        ("solver.method=\"gurobi\"", "method"),
        ("solver.method=\"osqp\" solver.rho=0.1", "rho"),
    ];
    let load_impact = |overrides: &str| {
        let o: Vec<String> = overrides.split(' ').map(str::to_string).collect();
        viscobar::scene::load("impact", &o)
    };
    for (overrides, needle) in refused {
        let err = load_impact(overrides).expect_err("refused");
        assert!(err.to_string().contains(needle), "{overrides}: {err}");
    }
    for ok in [
        "solver.method=\"osqp\" solver.eps_abs=1e-8 solver.polish=false",
        "solver.method=\"penalty\" solver.epsilon=1e-4",
    ] {
        load_impact(ok).unwrap();
    }
}

#[test]
fn cli_runs_osqp_and_penalty_and_reports_their_audit() {
    let base = std::env::temp_dir().join(format!("viscobar-cli-solvers-{}", std::process::id()));
    for solver in ["osqp", "penalty"] {
        let out = base.join(solver);
        run_cli("impact", solver, &[], &out);
        let summary: serde_json::Value =
            serde_json::from_str(&std::fs::read_to_string(out.join("summary.json")).unwrap())
                .unwrap();
        assert_eq!(summary["solver"], solver);
        let audit = &summary["audit"];
        assert_eq!(audit["steps"], 300);
        for key in [
            "stationarity",
            "stationarity_displacement",
            "negative_reaction",
        ] {
            assert!(
                audit[key]["max_over_tolerance"].as_f64().unwrap() <= 1.0,
                "{key}"
            );
        }
        match solver {
            "osqp" => {
                assert_eq!(summary["inaccurate_steps"], 0);
                assert!(audit.get("complementarity").is_some());
                assert!(summary["max_violation"].as_f64().unwrap() <= OSQP_GAP_TOL);
            }
            _ => {
                assert!(audit.get("penalty_law").is_some());
                assert!(summary.get("inaccurate_steps").is_none());
                // The impact's reaction is about 1: penetration about ε.
                let p = summary["max_violation"].as_f64().unwrap();
                assert!(p > 0.5 * PENALTY_DEFAULT_EPSILON && p < 2.0 * PENALTY_DEFAULT_EPSILON);
            }
        }
    }
    let o = viscobar(&["run", "impact", "--solver", "simplex"]);
    assert_eq!(o.status.code(), Some(2));
    let _ = std::fs::remove_dir_all(&base);
}

#[test]
fn cli_warns_about_accepted_inaccurate_steps() {
    let out = std::env::temp_dir().join(format!("viscobar-cli-inacc-{}", std::process::id()));
    let settings = [
        "solver.eps_abs=1e-8",
        "solver.eps_rel=1e-8",
        "solver.max_iter=75",
        "solver.accept_inaccurate=true",
    ];
    let o = run_cli("impact", "osqp", &settings, &out);
    let stderr = String::from_utf8_lossy(&o.stderr);
    assert!(stderr.contains("warning: 1 steps accepted"), "{stderr}");
    let _ = std::fs::remove_dir_all(&out);
}

#[test]
fn penalty_solver_refuses_a_bad_epsilon_without_panicking() {
    let c = SymTridiag::new(vec![2.0, 2.0], vec![-1.0]);
    for eps in [0.0, -1.0, f64::NAN, f64::INFINITY] {
        assert!(
            viscobar::internals::step::end_penalty::EndPenalty::new(
                &c,
                &[0],
                PenaltySettings { epsilon: eps }
            )
            .is_err()
        );
    }
    // A scene built in code, never validated, gets an error naming the field.
    let mut scene = common::builtin("impact", &["solver.method=\"penalty\""]);
    scene.solver.epsilon = Some(-1.0);
    let err = Simulation::new(&scene).err().expect("refused");
    assert!(err.to_string().contains("solver.epsilon"), "{err}");
    assert_eq!(err.exit_code(), 2);
}
