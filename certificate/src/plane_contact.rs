//! The plane contact certificate (VERIFICATION.md, "Plane contact"): the bar with contact as
//! an exact special case ([`crate::plane_checks::bar_case`]), the contact conditions and
//! the energy identity on the built-in contact scenes, the exact solver against OSQP and the
//! penalty, and the observed convergence of the tilted drop. The tests
//! (`tests/plane_contact.rs`) assert on the same computations.

use viscobar::plane::PlaneError;
use viscobar::plane::contact::ContactMethod;
use viscobar::plane::simulation::PlaneSimulation;
use viscobar::scene::plane::{AnyScene, PlaneScene, load_any};
use viscobar::step::osqp::OsqpSettings;
use viscobar::study::converge::ConvergeError;
use viscobar::time::RunError;

/// The built-in scenes of the solver comparison.
pub const CONTACT_SCENES: [&str; 2] = ["plane-tilted-drop", "plane-curved-obstacle"];

/// A built-in plane scene with overrides.
pub fn plane_scene(name: &str, set: &[String]) -> Result<PlaneScene, ConvergeError> {
    match load_any(name, set)?.1 {
        AnyScene::Plane(s) => Ok(*s),
        AnyScene::Bar(_) => Err(ConvergeError::BadInput(format!("{name} is a bar scene"))),
    }
}

/// A plane failure in a study: bad input or a failed run.
pub fn plane_error(e: PlaneError) -> ConvergeError {
    match e {
        PlaneError::Scene(s) => ConvergeError::Scene(s),
        other => ConvergeError::Run(RunError::SolverSetup {
            solver: viscobar::plane::run::SOLVER_NAME.into(),
            reason: other.to_string(),
        }),
    }
}

/// One method against the exact solver over a whole run: the largest differences of `u` (at
/// every degree of freedom) and of the reactions, over every step, with the exact run's
/// `max |u|` and `max r`.
#[derive(Clone, Debug)]
pub struct Agreement {
    pub method: &'static str,
    pub steps: usize,
    pub max_u_deviation: f64,
    pub max_u: f64,
    pub max_reaction_deviation: f64,
    pub max_reaction: f64,
    /// Largest contact set of the exact run, and the steps with contact.
    pub max_active: usize,
    pub contact_steps: usize,
    /// OSQP: the audit's worst ratio to its tolerance over all checks.
    pub audit_worst_ratio: Option<f64>,
    /// Mean iterations per step of the method.
    pub mean_iterations: f64,
}

/// OSQP's settings in the comparison: the bar's defaults (`eps = 1e-10`, polished).
pub fn osqp_method() -> ContactMethod {
    ContactMethod::Osqp(OsqpSettings::default())
}

/// Runs `scene` with the exact solver (whatever its `[solver]` table names) and with `method`
/// side by side.
pub fn agreement(scene: &PlaneScene, method: ContactMethod) -> Result<Agreement, ConvergeError> {
    let mut e = PlaneSimulation::with_method(scene, ContactMethod::Exact).map_err(plane_error)?;
    let mut o = PlaneSimulation::with_method(scene, method).map_err(plane_error)?;
    let mut a = Agreement {
        method: method.name(),
        steps: scene.steps(),
        max_u_deviation: 0.0,
        max_u: 0.0,
        max_reaction_deviation: 0.0,
        max_reaction: 0.0,
        max_active: 0,
        contact_steps: 0,
        audit_worst_ratio: None,
        mean_iterations: 0.0,
    };
    let mut iterations = 0u64;
    let compare = |e: &PlaneSimulation, o: &PlaneSimulation, a: &mut Agreement| {
        for (x, y) in e.unknowns().iter().zip(o.unknowns()) {
            a.max_u_deviation = a.max_u_deviation.max((x - y).abs());
            a.max_u = a.max_u.max(x.abs());
        }
        let (re, ro) = (
            e.contact().expect("a contact scene").reactions(),
            o.contact().expect("a contact scene").reactions(),
        );
        for (x, y) in re.iter().zip(ro) {
            a.max_reaction_deviation = a.max_reaction_deviation.max((x - y).abs());
            a.max_reaction = a.max_reaction.max(*x);
        }
    };
    compare(&e, &o, &mut a);
    for _ in 1..scene.steps() {
        let re = e.step().map_err(plane_error)?;
        let ro = o.step().map_err(plane_error)?;
        iterations += u64::from(ro.contact.iterations);
        a.max_active = a.max_active.max(re.contact.active);
        a.contact_steps += usize::from(re.contact.active > 0);
        compare(&e, &o, &mut a);
    }
    a.mean_iterations = iterations as f64 / (scene.steps().max(2) - 1) as f64;
    a.audit_worst_ratio = o.contact().and_then(|c| c.audit()).map(|r| {
        [
            r.primal_violation.unwrap_or_default().max_over_tolerance,
            r.negative_reaction.max_over_tolerance,
            r.complementarity.unwrap_or_default().max_over_tolerance,
            r.stationarity.max_over_tolerance,
            r.stationarity_displacement.max_over_tolerance,
        ]
        .into_iter()
        .fold(0.0, f64::max)
    });
    Ok(a)
}

/// One level of the tilted drop's refinement study against a finer exact run.
#[derive(Clone, Copy, Debug)]
pub struct ContactLevel {
    pub level: u32,
    pub nx: u64,
    pub dt: f64,
    /// Over every step of this level, the largest nodal `|u − u_ref|` (the reference at the
    /// same node and time), over the reference's `max |u|`.
    pub max_error: f64,
}

/// The tilted drop's convergence study: its end time (the fall, the contact spreading and the
/// rocking; the runs at the reference level stay within seconds).
pub const CONVERGENCE_END: f64 = 0.6;
/// Levels compared and the reference level (2x finer in space and time than the finest: a
/// level-4 reference, 66k unknowns and 3840 steps, takes minutes, too long for the tests).
pub const CONVERGENCE_LEVELS: [u32; 3] = [0, 1, 2];
pub const CONVERGENCE_REFERENCE: u32 = 3;

/// Runs `scene` (exact solver) refined to each of `levels` and to `reference`, and measures each level at its
/// nodes and steps against the reference (whose grid holds every coarser node: uniform rows,
/// or the same grading, doubled).
pub fn convergence(
    scene: &PlaneScene,
    levels: &[u32],
    reference: u32,
) -> Result<Vec<ContactLevel>, ConvergeError> {
    // The reference's displacement at the steps that are multiples of 2^(reference − 0).
    let fine = scene.refined(reference);
    let mut sim = PlaneSimulation::with_method(&fine, ContactMethod::Exact).map_err(plane_error)?;
    let stride = 1usize << reference;
    let mut kept = vec![sim.displacement()];
    for n in 1..fine.steps() {
        sim.step().map_err(plane_error)?;
        if (n + 1).is_multiple_of(stride) {
            kept.push(sim.displacement());
        }
    }
    let fine_grid = sim.discretisation().grid.clone();
    let scale = kept
        .iter()
        .flat_map(|u| u.iter())
        .fold(0.0f64, |a, v| a.max(v.abs()));
    let mut out = Vec::new();
    for &level in levels {
        let s = scene.refined(level);
        let mut sim =
            PlaneSimulation::with_method(&s, ContactMethod::Exact).map_err(plane_error)?;
        let grid = sim.discretisation().grid.clone();
        let (f, every) = (1usize << (reference - level), 1usize << level);
        let mut max_error = 0.0f64;
        let mut measure = |sim: &PlaneSimulation, n: usize| {
            if !n.is_multiple_of(every) {
                return;
            }
            let u = sim.displacement();
            let r = &kept[n / every];
            for node in 0..grid.nodes() {
                let (i, j) = grid.position(node);
                let fnode = fine_grid.node(i * f, j * f);
                for c in 0..2 {
                    max_error = max_error.max((u[2 * node + c] - r[2 * fnode + c]).abs());
                }
            }
        };
        measure(&sim, 0);
        for n in 1..s.steps() {
            sim.step().map_err(plane_error)?;
            measure(&sim, n + 1);
        }
        out.push(ContactLevel {
            level,
            nx: s.mesh.nx,
            dt: s.time.step,
            max_error: max_error / scale,
        });
    }
    Ok(out)
}

/// The observed orders between consecutive levels, `log2(e_l / e_{l+1})`.
pub fn orders(levels: &[ContactLevel]) -> Vec<f64> {
    levels
        .windows(2)
        .map(|w| (w[0].max_error / w[1].max_error).log2())
        .collect()
}

/// The penalty parameters of the comparison with the exact solver.
pub const PENALTY_EPSILONS: [f64; 2] = [1e-4, 1e-6];

/// The figures of one contact scene's exact run.
#[derive(Clone, Debug)]
pub struct SceneCheck {
    pub name: String,
    pub summary: viscobar::plane::run::PlaneSummary,
}

/// The exact runs of the built-in contact scenes.
pub fn scene_checks() -> Result<Vec<SceneCheck>, ConvergeError> {
    CONTACT_SCENES
        .iter()
        .map(|name| {
            let scene = plane_scene(name, &[])?;
            let (_, summary, _) =
                viscobar::plane::run::run_plane_in_memory(name, &scene).map_err(plane_error)?;
            Ok(SceneCheck {
                name: name.to_string(),
                summary,
            })
        })
        .collect()
}

/// The generated block of VERIFICATION.md's "Plane contact" section (id `plane-contact`).
pub fn markdown() -> Result<String, ConvergeError> {
    use crate::plane_checks::{BAR_CASE_BODY, bar_case, bar_contact_case_scenes};
    use std::fmt::Write;
    let mut md = String::from(
        "| bar scene | steps | steps in contact | plane rows (y_grading) | max abs(ux − u) / max abs(u) | max abs(uy) / max abs(u) | max abs(r_k − ω_k r) / max r |\n|---|---|---|---|---|---|---|\n",
    );
    for (name, bar) in bar_contact_case_scenes() {
        let c = bar_case(&bar)?;
        let _ = writeln!(
            md,
            "| {name} | {} | {} | {} ({}) | {:.1e} | {:.1e} | {:.1e} |",
            c.steps,
            c.contact_steps,
            BAR_CASE_BODY.1,
            BAR_CASE_BODY.2,
            c.max_ux_deviation / c.max_u,
            c.max_uy / c.max_u,
            c.max_reaction_deviation / c.max_reaction
        );
    }
    md.push_str(
        "\n| scene | unknowns | normals m | steps | steps in contact | max in contact | max identity residual | max penetration / scale | max abs(r·gap) / scale | contact dissipation | LCP sets tried (mean, max) |\n|---|---|---|---|---|---|---|---|---|---|---|\n",
    );
    for s in scene_checks()? {
        let (p, c) = (&s.summary, s.summary.contact.clone().unwrap_or_default());
        let _ = writeln!(
            md,
            "| {} | {} | {} | {} | {} | {} | {:.1e} | {:.1e} | {:.1e} | {:.4e} | {:.2}, {} |",
            s.name,
            p.unknowns,
            c.normals,
            p.steps,
            c.contact_steps,
            c.max_active,
            p.max_identity_residual,
            c.max_penetration,
            c.max_complementarity,
            c.dissipation,
            c.iterations_mean,
            c.iterations_max
        );
    }
    md.push_str(
        "\n| scene | method | max abs(u − u_exact) / max abs(u) | max abs(r − r_exact) / max r | iterations per step (mean) | audit: worst residual / tolerance |\n|---|---|---|---|---|---|\n",
    );
    for name in CONTACT_SCENES {
        let scene = plane_scene(name, &[])?;
        let mut methods = vec![(osqp_method(), "osqp, eps = 1e-10".to_string())];
        for e in PENALTY_EPSILONS {
            methods.push((
                ContactMethod::Penalty { epsilon: e },
                format!("penalty, ε = {e:e}"),
            ));
        }
        for (method, label) in methods {
            let a = agreement(&scene, method)?;
            let audit = a
                .audit_worst_ratio
                .map_or_else(|| "–".to_string(), |r| format!("{r:.1e}"));
            let _ = writeln!(
                md,
                "| {name} | {label} | {:.1e} | {:.1e} | {:.1} | {audit} |",
                a.max_u_deviation / a.max_u,
                a.max_reaction_deviation / a.max_reaction,
                a.mean_iterations
            );
        }
    }
    let scene = plane_scene(
        "plane-tilted-drop",
        &[format!("time.end={CONVERGENCE_END}")],
    )?;
    let levels = convergence(&scene, &CONVERGENCE_LEVELS, CONVERGENCE_REFERENCE)?;
    let orders = orders(&levels);
    md.push_str("\n| level | nx × ny | Δt | max nodal error / max abs(u_ref) | order |\n|---|---|---|---|---|\n");
    for (k, l) in levels.iter().enumerate() {
        let order = if k == 0 {
            "–".to_string()
        } else {
            format!("{:.2}", orders[k - 1])
        };
        let _ = writeln!(
            md,
            "| {} | {} × {} | {} | {:.3e} | {order} |",
            l.level,
            l.nx,
            l.nx / 2,
            l.dt,
            l.max_error
        );
    }
    let _ = writeln!(
        md,
        "\nReference: level {CONVERGENCE_REFERENCE} (exact solver), T = {CONVERGENCE_END}."
    );
    Ok(md)
}
