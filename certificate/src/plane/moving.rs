//! Moving obstacles (VERIFICATION.md, "Moving obstacles"): Galilean invariance of the scheme
//! with a moving obstacle, on both bodies. A body at rest under an obstacle approaching at the
//! speed `v` is, shifted by `v t`, the body moving at `−v` onto the fixed obstacle: the rigid
//! translation `v t` is in the kernel of `K` and of the second difference of the mass term,
//! and it moves every gap as the obstacle does. The identity holds in exact arithmetic; in
//! floating point the shift `v t_n` is rounded and `K` annihilates a translation to round-off,
//! so the two runs agree to round-off per step, not bitwise. The derivation of the obstacle's
//! work in the energy identity is docs/moving-obstacles.md. The same holds along a frictional
//! edge whose obstacle slides (a belt, docs/friction.md): the block at rest on a belt at `v` is
//! the block launched at `−v` on the fixed floor, shifted by `v t`.

use std::fmt::Write;
use viscobar::bar::Simulation;
use viscobar::plane::PlaneSimulation;
use viscobar::scene::plane::{PlaneScene, plane_builtin_text};
use viscobar::scene::{Scene, builtin_text};
use viscobar::scheme::{Body, RunError, Scheme};

/// The speed of the approaching obstacle in both cases (the built-in scenes' own speeds).
pub const PLANE_SPEED: f64 = 0.5;
pub const BAR_SPEED: f64 = 1.0;

/// Per step, in units of `ε max |u|`: how far the run with the moving obstacle may drift from
/// the shifted run with the fixed one. Each step rounds the shift `v t_n` once where it enters
/// the bounds (`u` is of the size of `v t`), and `K` applied to the translation in `w` is zero
/// to a few ulps of `‖K‖ |v Δt|`, which the step solve carries into `z` (κ(C) of a few at
/// `Δt ≈ h`); the differences of two steps add up at most linearly.
pub const GALILEAN_ULPS_PER_STEP: f64 = 16.0;

/// The two runs of one body compared at every step.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Galilean {
    pub steps: usize,
    /// Steps at which some constraint carries a reaction.
    pub steps_in_contact: usize,
    /// `max |u|` over both runs, and `max |u_moving − (u_fixed + v t)|`.
    pub max_u: f64,
    pub max_u_deviation: f64,
    /// `max |r|` and `max |r_moving − r_fixed|`.
    pub max_reaction: f64,
    pub max_reaction_deviation: f64,
    /// The force scale the reactions are rounded to when the body travels with the obstacle
    /// (the belt): `‖K‖∞ max |u|`, the size of `K u^n` in the step's right-hand side, whose
    /// rounding the reactions inherit; 0 for a body that stays near rest in one of the frames.
    pub force_scale: f64,
}

impl Galilean {
    /// `max(|Δu| / max|u|, |Δr| / max(max|r|, force_scale))` over
    /// `steps · GALILEAN_ULPS_PER_STEP · ε`.
    pub fn ratio(&self) -> f64 {
        let bound = self.steps as f64 * GALILEAN_ULPS_PER_STEP * f64::EPSILON;
        let rel = |d: f64, s: f64| if s > 0.0 { d / s } else { d };
        let reaction_scale = self.max_reaction.max(self.force_scale);
        rel(self.max_u_deviation, self.max_u).max(rel(self.max_reaction_deviation, reaction_scale))
            / bound
    }
}

/// Steps `fixed` and `moving` side by side; `shifted(unknown)` is whether an unknown moves
/// with the obstacle (the normal component), shifted by `speed · t`.
fn compare<B: Body>(
    mut fixed: Scheme<B>,
    mut moving: Scheme<B>,
    steps: usize,
    speed: f64,
    shifted: impl Fn(usize) -> bool,
) -> Result<Galilean, RunError> {
    let mut g = Galilean {
        steps,
        steps_in_contact: 0,
        max_u: 0.0,
        max_u_deviation: 0.0,
        max_reaction: 0.0,
        max_reaction_deviation: 0.0,
        force_scale: 0.0,
    };
    let dt = fixed.body().dt();
    loop {
        let n = fixed.step_index();
        let shift = speed * (n as f64 * dt);
        for (i, (a, b)) in moving
            .displacement()
            .iter()
            .zip(fixed.displacement())
            .enumerate()
        {
            let b = if shifted(i) { b + shift } else { *b };
            g.max_u = g.max_u.max(a.abs()).max(b.abs());
            g.max_u_deviation = g.max_u_deviation.max((a - b).abs());
        }
        let (ra, rb) = (moving.reactions(), fixed.reactions());
        if rb.iter().any(|&r| r > 0.0) {
            g.steps_in_contact += 1;
        }
        // The normal reactions, then the tangential ones (of either sign) of a frictional run.
        let tangential = (moving.tangential_reactions().iter())
            .zip(fixed.tangential_reactions())
            .map(|(a, b)| (a.abs(), b.abs(), a - b));
        for (a, b, d) in ra
            .iter()
            .zip(rb)
            .map(|(a, b)| (*a, *b, a - b))
            .chain(tangential)
        {
            g.max_reaction = g.max_reaction.max(a).max(b);
            g.max_reaction_deviation = g.max_reaction_deviation.max(d.abs());
        }
        if n == steps {
            return Ok(g);
        }
        fixed.step()?;
        moving.step()?;
    }
}

/// `plane-tilted-drop` (falling at 0.5 onto its floor, gravity, viscous) against the block at
/// rest under a floor rising at 0.5: `edges.bottom.gap = 0.05 − 0.5 t`.
pub fn galilean_plane() -> Result<Galilean, RunError> {
    let text = plane_builtin_text("plane-tilted-drop").expect("a built-in scene");
    let fixed = PlaneScene::from_toml(text, &[])?;
    let moving = PlaneScene::from_toml(
        text,
        &[
            "initial.velocity=[\"0\", \"0\"]".into(),
            format!("edges.bottom.gap=\"0.05 - {PLANE_SPEED}*t\""),
        ],
    )?;
    let sim = PlaneSimulation::new(&moving)?;
    let y: Vec<bool> = sim
        .discretisation()
        .free
        .iter()
        .map(|d| d % 2 == 1)
        .collect();
    compare(
        PlaneSimulation::new(&fixed)?,
        sim,
        fixed.steps(),
        PLANE_SPEED,
        |i| y[i],
    )
}

/// The belt's speed: `plane-friction-launch`'s block is launched at `−BELT_SPEED`.
pub const BELT_SPEED: f64 = -1.0;

/// `plane-friction-launch` (launched at 1 along its frictional floor, stopped by friction)
/// against the block at rest on the floor sliding at −1 (`edges.bottom.velocity = −1`): the
/// shift `v t` is along `x`, and the normal and tangential reactions agree. Both blocks travel
/// (up to `|v| t_end` on the belt), so each step's `K u^n` is rounded to `ε ‖K‖∞ max|u|`, far
/// above the reactions' own size: the reactions are measured against that force scale.
pub fn galilean_belt() -> Result<Galilean, RunError> {
    let text = plane_builtin_text("plane-friction-launch").expect("a built-in scene");
    let fixed = PlaneScene::from_toml(text, &[])?;
    let belt = PlaneScene::from_toml(
        text,
        &[
            "initial.velocity=[\"0\", \"0\"]".into(),
            format!("edges.bottom.velocity=\"{BELT_SPEED}\""),
        ],
    )?;
    let sim = PlaneSimulation::new(&belt)?;
    let disc = sim.discretisation();
    let x: Vec<bool> = disc.free.iter().map(|d| d % 2 == 0).collect();
    let stiffness_norm = (0..disc.pattern.n)
        .map(|i| {
            let row = disc.pattern.row_ptr[i]..disc.pattern.row_ptr[i + 1];
            disc.stiffness[row].iter().map(|k| k.abs()).sum::<f64>()
        })
        .fold(0.0, f64::max);
    let mut g = compare(
        PlaneSimulation::new(&fixed)?,
        sim,
        fixed.steps(),
        BELT_SPEED,
        |i| x[i],
    )?;
    g.force_scale = stiffness_norm * g.max_u;
    Ok(g)
}

/// `impact` (moving at −1 onto its left obstacle) against the bar at rest with its left
/// obstacle approaching at 1: `left.gap = 0.1 − t`.
pub fn galilean_bar() -> Result<Galilean, RunError> {
    let text = builtin_text("impact").expect("a built-in scene");
    let fixed = Scene::from_toml(text, &[])?;
    let moving = Scene::from_toml(
        text,
        &[
            "initial.velocity=0".into(),
            format!("left.gap=\"0.1 - {BAR_SPEED}*t\""),
        ],
    )?;
    compare(
        Simulation::new(&fixed)?,
        Simulation::new(&moving)?,
        fixed.steps(),
        BAR_SPEED,
        |_| true,
    )
}

/// The generated block `moving`: the Galilean comparison of both bodies.
pub fn markdown() -> Result<String, RunError> {
    let mut md = String::from(
        "| body | fixed run | moving obstacle | steps | steps in contact | max abs(u − (u_fixed + v t)) / max abs(u) | max abs(r − r_fixed) / max abs(r) | over steps · 16 ε |\n|---|---|---|---|---|---|---|---|\n",
    );
    for (body, fixed, moving, g) in [
        (
            "plane",
            "plane-tilted-drop (falling at 0.5)",
            "at rest, `edges.bottom.gap = 0.05 − 0.5 t`",
            galilean_plane()?,
        ),
        (
            "plane, friction",
            "plane-friction-launch (launched at 1)",
            "at rest, `edges.bottom.velocity = −1` (a belt)",
            galilean_belt()?,
        ),
        (
            "bar",
            "impact (moving at −1)",
            "at rest, `left.gap = 0.1 − t`",
            galilean_bar()?,
        ),
    ] {
        let _ = writeln!(
            md,
            "| {body} | {fixed} | {moving} | {} | {} | {:.1e} | {:.1e} | {:.2} |",
            g.steps,
            g.steps_in_contact,
            g.max_u_deviation / g.max_u,
            g.max_reaction_deviation / g.max_reaction,
            g.ratio()
        );
    }
    Ok(md)
}
