//! The plane contact certificate (VERIFICATION.md, "Plane contact"): the bar with contact as
//! an exact special case ([`crate::plane::bar_case`]), the contact conditions and
//! the energy identity on the built-in contact scenes, the exact solver against OSQP and the
//! penalty, and the observed convergence of the tilted drop. The tests
//! (`tests/plane_contact.rs`) assert on the same computations.

use viscobar::plane::PlaneSimulation;
use viscobar::scene::plane::{AnyScene, PlaneScene, load_any};
use viscobar::scene::{SolverMethod, SolverSpec};
use viscobar::scheme::{RunError, StepRecord};
use viscobar::study::converge::ConvergeError;

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
pub fn plane_error(e: RunError) -> ConvergeError {
    match e {
        RunError::Scene(s) => ConvergeError::Scene(s),
        other => ConvergeError::Run(other),
    }
}

/// A step solver of the comparison: its method and, for the penalty, its ε (the scene's
/// other settings are the defaults: OSQP at `eps = 1e-10`, polished).
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Method {
    Exact,
    Osqp,
    Penalty { epsilon: f64 },
}

impl Method {
    pub fn name(self) -> &'static str {
        match self {
            Method::Exact => "exact",
            Method::Osqp => "osqp",
            Method::Penalty { .. } => "penalty",
        }
    }

    /// `scene` with its `[solver]` table set to this method.
    pub fn apply(self, scene: &PlaneScene) -> PlaneScene {
        let mut s = scene.clone();
        s.solver = match self {
            Method::Exact => SolverSpec::default(),
            Method::Osqp => SolverSpec {
                method: SolverMethod::Osqp,
                ..SolverSpec::default()
            },
            Method::Penalty { epsilon } => SolverSpec {
                method: SolverMethod::Penalty,
                epsilon: Some(epsilon),
                ..SolverSpec::default()
            },
        };
        s
    }

    /// The run of `scene` with this method.
    pub fn simulation(self, scene: &PlaneScene) -> Result<PlaneSimulation, ConvergeError> {
        PlaneSimulation::new(&self.apply(scene)).map_err(plane_error)
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
pub fn osqp_method() -> Method {
    Method::Osqp
}

/// Runs `scene` with the exact solver (whatever its `[solver]` table names) and with `method`
/// side by side.
pub fn agreement(scene: &PlaneScene, method: Method) -> Result<Agreement, ConvergeError> {
    let mut e = Method::Exact.simulation(scene)?;
    let mut o = method.simulation(scene)?;
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
        for (x, y) in e.displacement().iter().zip(o.displacement()) {
            a.max_u_deviation = a.max_u_deviation.max((x - y).abs());
            a.max_u = a.max_u.max(x.abs());
        }
        for (x, y) in e.reactions().iter().zip(o.reactions()) {
            a.max_reaction_deviation = a.max_reaction_deviation.max((x - y).abs());
            a.max_reaction = a.max_reaction.max(*x);
        }
    };
    compare(&e, &o, &mut a);
    for _ in 1..scene.steps() {
        let re = e.step().map_err(plane_error)?;
        let ro = o.step().map_err(plane_error)?;
        iterations += u64::from(ro.iterations);
        a.max_active = a.max_active.max(re.contact.contact_nodes);
        a.contact_steps += usize::from(re.contact.contact_nodes > 0);
        compare(&e, &o, &mut a);
    }
    a.mean_iterations = iterations as f64 / (scene.steps().max(2) - 1) as f64;
    a.audit_worst_ratio = o.solver_report().map(|r| r.audit).map(|r| {
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
    let prepared = PlaneSimulation::prepare(&Method::Exact.apply(&fine)).map_err(plane_error)?;
    let mut u0 = vec![0.0; 2 * prepared.body().discretisation().grid.nodes()];
    prepared
        .body()
        .scatter_into(prepared.state().u, 1.0, &mut u0);
    let mut sim = prepared.start().map_err(plane_error)?;
    let stride = 1usize << reference;
    let mut kept = vec![u0];
    for n in 1..fine.steps() {
        sim.step().map_err(plane_error)?;
        if (n + 1).is_multiple_of(stride) {
            kept.push(sim.displacement_dofs());
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
        let prepared = PlaneSimulation::prepare(&Method::Exact.apply(&s)).map_err(plane_error)?;
        let grid = prepared.body().discretisation().grid.clone();
        let mut u0 = vec![0.0; 2 * grid.nodes()];
        prepared
            .body()
            .scatter_into(prepared.state().u, 1.0, &mut u0);
        let mut sim = prepared.start().map_err(plane_error)?;
        let (f, every) = (1usize << (reference - level), 1usize << level);
        let mut max_error = 0.0f64;
        let mut measure = |u: &[f64], n: usize| {
            if !n.is_multiple_of(every) {
                return;
            }
            let r = &kept[n / every];
            for node in 0..grid.nodes() {
                let (i, j) = grid.position(node);
                let fnode = fine_grid.node(i * f, j * f);
                for c in 0..2 {
                    max_error = max_error.max((u[2 * node + c] - r[2 * fnode + c]).abs());
                }
            }
        };
        measure(&u0, 0);
        for n in 1..s.steps() {
            sim.step().map_err(plane_error)?;
            measure(&sim.displacement_dofs(), n + 1);
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

/// The contact conditions of a plane run's state at one step: the largest penetration
/// `max(0, −gap_k)` and `|r_k gap_k|`, and the scale of the gaps' round-off,
/// `max_k max(|g_k|, |u·n_k|)`.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct GapCheck {
    pub penetration: f64,
    pub complementarity: f64,
    pub scale: f64,
}

impl GapCheck {
    /// The check of `sim`'s current state and reactions.
    pub fn of(sim: &PlaneSimulation) -> Self {
        let contact = sim.contact();
        let mut gaps = vec![0.0; contact.len()];
        sim.gaps_into(&mut gaps);
        let mut c = Self::default();
        for ((gap, g), r) in gaps.iter().zip(contact.gaps()).zip(sim.reactions()) {
            c.penetration = c.penetration.max(-gap);
            c.complementarity = c.complementarity.max((r * gap).abs());
            c.scale = c.scale.max(g.abs()).max((gap - g).abs());
        }
        c
    }
}

/// Runs a plane scene in memory as `viscobar::output::run_plane_in_memory` does, with the
/// [`GapCheck`] of every step (the start-up step first).
pub fn checked_run(
    name: &str,
    scene: &PlaneScene,
) -> Result<(Vec<StepRecord>, viscobar::Summary, Vec<GapCheck>), ConvergeError> {
    let mut sim = PlaneSimulation::new(scene).map_err(plane_error)?;
    let mut tracker = viscobar::output::Tracker::new(&sim, !sim.is_forced());
    let (mut records, mut checks) = (vec![sim.first_record()], vec![GapCheck::of(&sim)]);
    for _ in 1..scene.steps() {
        let r = sim.step().map_err(plane_error)?;
        tracker.observe(&r);
        records.push(r);
        checks.push(GapCheck::of(&sim));
    }
    let summary = tracker.finish(name, &sim, 0.0);
    Ok((records, summary, checks))
}

/// The penalty parameters of the comparison with the exact solver.
pub const PENALTY_EPSILONS: [f64; 2] = [1e-4, 1e-6];

/// The figures of one contact scene's exact run.
#[derive(Clone, Debug)]
pub struct SceneCheck {
    pub name: String,
    pub summary: viscobar::Summary,
    /// Contact normals, the most in contact at one step, the steps with some in contact, and
    /// the contact dissipation summed over the run.
    pub normals: usize,
    pub max_in_contact: usize,
    pub contact_steps: usize,
    pub dissipation: f64,
}

/// The exact runs of the built-in contact scenes.
pub fn scene_checks() -> Result<Vec<SceneCheck>, ConvergeError> {
    CONTACT_SCENES
        .iter()
        .map(|name| {
            let scene = plane_scene(name, &[])?;
            let (records, summary, sim) =
                viscobar::output::run_plane_in_memory(name, &scene).map_err(plane_error)?;
            let in_contact = |r: &StepRecord| r.contact.contact_nodes;
            Ok(SceneCheck {
                name: name.to_string(),
                summary,
                normals: sim.contact().len(),
                max_in_contact: records.iter().map(in_contact).max().unwrap_or(0),
                contact_steps: records.iter().filter(|r| in_contact(r) > 0).count(),
                dissipation: records.iter().map(|r| r.contact_dissipation).sum(),
            })
        })
        .collect()
}

/// The generated block of VERIFICATION.md's "Plane contact" section (id `plane-contact`).
pub fn markdown() -> Result<String, ConvergeError> {
    use crate::plane::{BAR_CASE_BODY, bar_case, bar_contact_case_scenes};
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
        "\n| scene | unknowns | normals m | steps | steps in contact | max in contact | max identity residual | max penetration | max abs(r·gap) | contact dissipation | LCP sets tried (mean, max) |\n|---|---|---|---|---|---|---|---|---|---|---|\n",
    );
    for s in scene_checks()? {
        let p = &s.summary;
        let _ = writeln!(
            md,
            "| {} | {} | {} | {} | {} | {} | {:.1e} | {:.1e} | {:.1e} | {:.4e} | {:.2}, {} |",
            s.name,
            p.unknowns,
            s.normals,
            p.steps,
            s.contact_steps,
            s.max_in_contact,
            p.max_identity_residual,
            p.max_violation,
            p.max_complementarity,
            s.dissipation,
            p.solver_iterations.mean,
            p.solver_iterations.max
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
                Method::Penalty { epsilon: e },
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
    md.push_str(&convergence_markdown(
        &levels,
        CONVERGENCE_REFERENCE,
        CONVERGENCE_END,
    ));
    Ok(md)
}

/// A refinement study's table (level, mesh, `Δt`, error against the reference, observed
/// order) and its reference line: level `reference`, compared up to `end`.
pub fn convergence_markdown(levels: &[ContactLevel], reference: u32, end: f64) -> String {
    use std::fmt::Write;
    let orders = orders(levels);
    let mut md = String::from(
        "\n| level | nx × ny | Δt | max nodal error / max abs(u_ref) | order |\n|---|---|---|---|---|\n",
    );
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
        "\nReference: level {reference} (exact solver), T = {end}."
    );
    md
}
