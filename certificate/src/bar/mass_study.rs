//! The mass variants side by side (VERIFICATION.md, "Mass variants"): for `impact` and
//! `falling-bar` at α = 0 and α = 0.1, per variant and mesh level, the energy the contact term
//! takes over the first contact episode, the L2 and contact-time errors, and the total
//! variation of the contact reaction over the episode (chatter), with observed orders. Against
//! the closed form at α = 0, against a fine run of the same variant at α = 0.1. Then the
//! certificate of every solver on the redistributed and lumped mass. The derivation of the
//! variants is in `docs/mass-variants.md`.

use std::fmt::Write;
use viscobar::Summary;
use viscobar::bar::Simulation;
use viscobar::bar::closed_form;
use viscobar::output::Tracker;
use viscobar::scene::{self, MassVariant, Scene, SceneError};
use viscobar::scheme::RunError;
use viscobar::study::accuracy::observed_order;
use viscobar::study::converge::contact_time_error;
use viscobar::study::mass_variants::with_mass;

/// The two scenes of the study, each run to this time: `impact` through its one contact
/// episode and release, `falling-bar` through its first episode `[3, 5]` and one unit of flight.
pub const MASS_STUDY_SCENES: [(&str, f64); 2] = [("impact", 3.0), ("falling-bar", 6.0)];
/// The viscosities of the study.
pub const MASS_STUDY_ALPHAS: [f64; 2] = [0.0, 0.1];
/// Mesh levels (Δx and Δt halved together from the scene's 100 elements, Δt = Δx).
pub const MASS_STUDY_LEVELS: u32 = 4;
/// Level of the reference run at α = 0.1 (the same variant): two levels above the finest, so
/// the reference's own error is about a quarter (L2 order ~0.7: a third) of the finest level's
/// and flattens the last observed order somewhat.
pub const MASS_STUDY_REFERENCE_LEVEL: u32 = 5;

/// One run of the study.
#[derive(Clone, Debug, PartialEq)]
pub struct MassRow {
    pub scene: &'static str,
    pub alpha: f64,
    pub mass: MassVariant,
    pub elements: u64,
    pub dx: f64,
    /// `Σ −½ r·(u^{n+1} − u^{n−1})` over the steps of the first contact episode (all the
    /// discrete episodes inside the run: the scenes have one exact episode there).
    pub contact_dissipation: f64,
    /// `E` before the episode minus `E` after it (with α or a load this holds more than the
    /// contact term).
    pub energy_drop: f64,
    /// `max_k ‖u_h(t_k) − u(t_k)‖` on the coarsest level's nodes and times (trapezoidal L2).
    pub l2_error: f64,
    /// [`contact_time_error`] of the run's contact intervals at the Signorini end.
    pub contact_time_error: f64,
    /// `Σ |r^{n+1} − r^n|` from the step before the episode to the step after it: `2 r_max` for
    /// a reaction that rises and falls once; more is oscillation.
    pub reaction_variation: f64,
    pub peak_reaction: f64,
}

/// A run sampled on the coarsest level's grid: `u` at its nodes (row per coarse time), the
/// reaction at the left end per step (index `n`, 0 at `n = 0`), and the summary.
struct Sampled {
    u: Vec<Vec<f64>>,
    reaction: Vec<f64>,
    summary: Summary,
}

fn sampled(name: &str, scene: &Scene, level: u32) -> Result<Sampled, RunError> {
    let stride = 1usize << level;
    let mut sim = Simulation::new(scene)?;
    let mut tracker = Tracker::new(&sim, scene.load.density.is_none());
    let nodes = sim.discretisation().nodes;
    let coarse = |v: &[f64]| v.iter().step_by(stride).copied().collect::<Vec<_>>();
    let (u0, _) = sim.initial_state();
    let mut u = vec![coarse(&u0)];
    let mut reaction = vec![0.0, sim.first_record().contact.groups[0].reaction];
    let mut buf = vec![0.0; nodes];
    let mut keep = |sim: &Simulation, u: &mut Vec<Vec<f64>>| {
        if sim.step_index().is_multiple_of(stride) {
            sim.displacement_into(&mut buf);
            u.push(coarse(&buf));
        }
    };
    keep(&sim, &mut u);
    for _ in 1..scene.steps() {
        let r = sim.step()?;
        tracker.observe(&r);
        reaction.push(r.contact.groups[0].reaction);
        keep(&sim, &mut u);
    }
    let summary = tracker.finish(name, &sim, 0.0);
    Ok(Sampled {
        u,
        reaction,
        summary,
    })
}

/// Trapezoidal L2 norm of `a − b` on nodes spaced `dx`.
fn l2_difference(a: &[f64], b: &[f64], dx: f64) -> f64 {
    let n = a.len();
    let sum: f64 = (0..n)
        .map(|i| {
            let w = if i == 0 || i + 1 == n { 0.5 } else { 1.0 };
            w * (a[i] - b[i]).powi(2)
        })
        .sum();
    (sum * dx).sqrt()
}

/// The contact intervals at the left end, and the merged first episode's contact dissipation,
/// energy drop and peak reaction (`None` without contact or with an unmeasured energy).
fn first_episode(summary: &Summary) -> Option<(Vec<[f64; 2]>, f64, f64, f64)> {
    let episodes = summary.contact_episodes.get("left")?;
    let (first, last) = (episodes.first()?, episodes.last()?);
    let dissipation = episodes
        .iter()
        .map(|e| e.contact_dissipation)
        .sum::<Option<f64>>()?;
    let drop = first.energy_before? - last.energy_after?;
    let peak = episodes.iter().map(|e| e.peak_reaction).fold(0.0, f64::max);
    let intervals = episodes.iter().map(|e| [e.start, e.end]).collect();
    Some((intervals, dissipation, drop, peak))
}

/// The study's failures: a run, or a run without the contact episode the scenes must have.
#[derive(Debug, thiserror::Error)]
pub enum MassStudyError {
    #[error(transparent)]
    Run(#[from] RunError),
    #[error(
        "{scene} (mass {mass}, α = {alpha}, {elements} elements): no complete contact episode at the left end"
    )]
    NoEpisode {
        scene: &'static str,
        mass: &'static str,
        alpha: f64,
        elements: u64,
    },
}

impl From<SceneError> for MassStudyError {
    fn from(e: SceneError) -> Self {
        MassStudyError::Run(e.into())
    }
}

/// Runs the whole study: [`MASS_STUDY_SCENES`] × [`MASS_STUDY_ALPHAS`] × [`MassVariant::ALL`] ×
/// [`MASS_STUDY_LEVELS`], in that order.
pub fn mass_study() -> Result<Vec<MassRow>, MassStudyError> {
    let mut rows = Vec::new();
    for (name, end) in MASS_STUDY_SCENES {
        let (_, mut base) = scene::load(name, &[])?;
        base.time.end = end;
        for alpha in MASS_STUDY_ALPHAS {
            base.bar.viscosity = alpha;
            for mass in MassVariant::ALL {
                let variant = with_mass(&base, mass)?;
                rows.extend(study_one(name, &variant, alpha, mass)?);
            }
        }
    }
    Ok(rows)
}

fn study_one(
    name: &'static str,
    base: &Scene,
    alpha: f64,
    mass: MassVariant,
) -> Result<Vec<MassRow>, MassStudyError> {
    let no_episode = |s: &Scene| MassStudyError::NoEpisode {
        scene: name,
        mass: mass.name(),
        alpha,
        elements: s.mesh.elements,
    };
    // The reference on the coarsest grid: the closed form, or a fine run of the same variant.
    let coarse_dx = base.dx();
    let closed = closed_form::for_scene(name, base);
    let (reference, exact_intervals): (Vec<Vec<f64>>, Vec<[f64; 2]>) = match &closed {
        Some(exact) => {
            let u = (0..=base.steps())
                .map(|k| {
                    let t = k as f64 * base.time.step;
                    (0..=base.elements())
                        .map(|i| exact.displacement(i as f64 * coarse_dx, t))
                        .collect()
                })
                .collect();
            let intervals = exact
                .contact_intervals(base.time.end)
                .ok_or_else(|| no_episode(base))?;
            (u, intervals)
        }
        None => {
            let fine = base.refined(MASS_STUDY_REFERENCE_LEVEL);
            let run = sampled(name, &fine, MASS_STUDY_REFERENCE_LEVEL)?;
            let (intervals, ..) = first_episode(&run.summary).ok_or_else(|| no_episode(&fine))?;
            // One exact-like interval: the span of the reference's episodes.
            let span = [intervals[0][0], intervals[intervals.len() - 1][1]];
            (run.u, vec![span])
        }
    };
    let mut rows = Vec::new();
    for level in 0..MASS_STUDY_LEVELS {
        let s = base.refined(level);
        let run = sampled(name, &s, level)?;
        let (intervals, contact_dissipation, energy_drop, peak_reaction) =
            first_episode(&run.summary).ok_or_else(|| no_episode(&s))?;
        let l2_error = run
            .u
            .iter()
            .zip(&reference)
            .map(|(a, b)| l2_difference(a, b, coarse_dx))
            .fold(0.0, f64::max);
        let contact_time_error =
            contact_time_error(&exact_intervals, &intervals).ok_or_else(|| no_episode(&s))?;
        // From the step before the first contact to the step after the last.
        let dt = s.time.step;
        let step_of = |t: f64| (t / dt).round() as usize;
        let (a, b) = (
            step_of(intervals[0][0]) - 1,
            (step_of(intervals[intervals.len() - 1][1]) + 1).min(run.reaction.len() - 1),
        );
        let reaction_variation = run.reaction[a..=b]
            .windows(2)
            .map(|w| (w[1] - w[0]).abs())
            .sum();
        rows.push(MassRow {
            scene: name,
            alpha,
            mass,
            elements: s.mesh.elements,
            dx: s.dx(),
            contact_dissipation,
            energy_drop,
            l2_error,
            contact_time_error,
            reaction_variation,
            peak_reaction,
        });
    }
    Ok(rows)
}

/// Observed order of `f` over one (scene, α, variant) group of rows; `None` when a value is 0
/// (a contact time on the reference's step, no log) or negative.
pub fn group_order(group: &[MassRow], f: impl Fn(&MassRow) -> f64) -> Option<f64> {
    let h: Vec<f64> = group.iter().map(|r| r.dx).collect();
    let e: Vec<f64> = group.iter().map(f).collect();
    e.iter().all(|v| *v > 0.0).then(|| observed_order(&h, &e))
}

/// The rows grouped by (scene, α, variant), each group the levels in order.
pub fn groups(rows: &[MassRow]) -> impl Iterator<Item = &[MassRow]> {
    rows.chunks(MASS_STUDY_LEVELS as usize)
}

/// The study as VERIFICATION.md's tables: one row per run, the observed orders on the first
/// row of each group; then, per scene and α, the dissipation and variation of each variant
/// relative to consistent at the finest level.
pub fn markdown(rows: &[MassRow]) -> String {
    let mut md = String::from(
        "| scene | α | mass | elements | contact dissipation (order) | E before − E after | L2 error (order) | contact-time error (order) | TV of the reaction (order) | peak reaction |\n\
         |---|---|---|---|---|---|---|---|---|---|\n",
    );
    for group in groups(rows) {
        let orders = [
            group_order(group, |r| r.contact_dissipation),
            group_order(group, |r| r.l2_error),
            group_order(group, |r| r.contact_time_error),
            group_order(group, |r| r.reaction_variation),
        ];
        for (i, r) in group.iter().enumerate() {
            let cell = |v: f64, k: usize| {
                if i == 0 {
                    let order = orders[k].map_or("-".to_string(), |o| format!("{o:.2}"));
                    format!("{v:.3e} ({order})")
                } else {
                    format!("{v:.3e}")
                }
            };
            let _ = writeln!(
                md,
                "| {} | {} | {} | {} | {} | {:.3e} | {} | {} | {} | {:.4} |",
                r.scene,
                r.alpha,
                r.mass.name(),
                r.elements,
                cell(r.contact_dissipation, 0),
                r.energy_drop,
                cell(r.l2_error, 1),
                cell(r.contact_time_error, 2),
                cell(r.reaction_variation, 3),
                r.peak_reaction
            );
        }
    }
    md.push_str(
        "\nAt the finest level, relative to consistent:\n\n\
         | scene | α | mass | contact dissipation | L2 error | TV of the reaction |\n|---|---|---|---|---|---|\n",
    );
    let finest: Vec<&MassRow> = groups(rows).filter_map(|g| g.last()).collect();
    for r in &finest {
        let Some(c) = finest.iter().find(|c| {
            c.scene == r.scene && c.alpha == r.alpha && c.mass == MassVariant::Consistent
        }) else {
            continue;
        };
        let _ = writeln!(
            md,
            "| {} | {} | {} | {:.3} | {:.3} | {:.3} |",
            r.scene,
            r.alpha,
            r.mass.name(),
            r.contact_dissipation / c.contact_dissipation,
            r.l2_error / c.l2_error,
            r.reaction_variation / c.reaction_variation
        );
    }
    md
}

/// The scenes of the certificate table (those of the generic checker's mass variants in
/// `tests/solvers.rs`): one and two Signorini ends, a clamped far end, a load, an obstacle.
pub const CERTIFICATE_SCENES: [&str; 5] = [
    "impact",
    "falling-bar",
    "clamped-impact",
    "both-ends",
    "distributed",
];

/// The certificate of every (scene, variant, solver) for the redistributed and lumped mass
/// (consistent: VERIFICATION.md's "Scenes" and "Step solvers" sections): each solver run side
/// by side with the exact solver on the same variant, as Markdown: the largest identity
/// residual, `|gap·r|`, penetration and distance to exact, or why the combination is refused.
pub fn certificate_markdown() -> Result<String, RunError> {
    use viscobar::scene::SolverMethod;
    let mut md = String::from(
        "| scene | mass | solver | max identity residual | max abs(gap·reaction) | max penetration | max abs(u − u_exact) |\n\
         |---|---|---|---|---|---|---|\n",
    );
    for name in CERTIFICATE_SCENES {
        let (_, base) = scene::load(name, &[])?;
        for mass in [MassVariant::Redistributed, MassVariant::Lumped] {
            let exact = match with_mass(&base, mass) {
                Ok(s) => s,
                Err(e) => {
                    let _ = writeln!(
                        md,
                        "| {name} | {} | all | refused: {e} | | | |",
                        mass.name()
                    );
                    continue;
                }
            };
            for method in [
                SolverMethod::Exact,
                SolverMethod::Osqp,
                SolverMethod::Penalty,
            ] {
                let mut s = exact.clone();
                s.solver.method = method;
                let row = match viscobar::study::compare::compare(name, &exact, &s) {
                    Ok(c) => format!(
                        "{:.1e} | {:.1e} | {:.1e} | {:.1e}",
                        c.summary.max_identity_residual,
                        c.summary.max_complementarity,
                        c.summary.max_violation,
                        c.agreement.max_difference
                    ),
                    Err(RunError::Scene(e)) => format!("refused: {e} | | |"),
                    Err(e) => return Err(e),
                };
                let _ = writeln!(
                    md,
                    "| {name} | {} | {} | {row} |",
                    mass.name(),
                    method.name()
                );
            }
        }
    }
    Ok(md)
}
