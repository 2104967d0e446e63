//! The period-2 mode of sticking nodes (docs/friction.md, "The period-2 mode"): a sticking node
//! obeys `u^{n+1} = u^{n−1}`, so an offset between odd and even steps left by a slip stays. Measured
//! here on the block resting on its floor ([`resting_scene`]) and on `plane-friction-launch`
//! after it stops, over a window after the transients, at several `Δt`: the step-to-step
//! alternation of the floor's total reaction and the odd-step amplitude of the mean `u_x`.

use crate::plane::contact::{plane_error, plane_scene};
use std::fmt::Write;
use viscobar::plane::PlaneSimulation;
use viscobar::scene::plane::PlaneScene;
use viscobar::study::converge::ConvergeError;

/// The resting block's end time and the start of its window: the elastic transient (slowest
/// mode damped at `α ω²/2`, about 20/s) has decayed below round-off well before.
pub const RESTING_END: f64 = 2.0;
pub const RESTING_WINDOW: f64 = 1.0;
/// The launched block stops at about `t = 2` (rigid limit `v0/(μg)`); the window starts after.
pub const LAUNCH_END: f64 = 3.0;
pub const LAUNCH_WINDOW: f64 = 2.5;
/// The time steps of the table: the scenes' `Δt = 0.01` halved and doubled.
pub const TABLE_STEPS: [f64; 4] = [0.02, 0.01, 0.005, 0.0025];

/// A block 1 × 0.5 at rest on a floor with friction 0.5 under gravity 1, `λ = μ = 100`,
/// `α = 0.05`, 16 × 8 cells, time step `dt` to `end`: `plane-friction-launch` with `v0 = 0`.
pub fn resting_scene(dt: f64, end: f64) -> Result<PlaneScene, ConvergeError> {
    let set = [
        "initial.velocity=[\"0\", \"0\"]".to_string(),
        "mesh.nx=16".to_string(),
        "mesh.ny=8".to_string(),
        format!("time.step={dt}"),
        format!("time.end={end}"),
    ];
    plane_scene("plane-friction-launch", &set)
}

/// `plane-friction-launch` at time step `dt` to [`LAUNCH_END`].
pub fn launch_scene(dt: f64) -> Result<PlaneScene, ConvergeError> {
    let set = [format!("time.step={dt}"), format!("time.end={LAUNCH_END}")];
    plane_scene("plane-friction-launch", &set)
}

/// The period-2 content of a run over its window `t_n >= window`.
#[derive(Clone, Copy, Debug, Default)]
pub struct PeriodTwo {
    pub dt: f64,
    /// `max |R^{n+1} − R^n| / mean R` of the floor's total reaction `R^n = Σ_k r_N,k`.
    pub reaction: f64,
    /// `max |ū^{n+1} − 2ū^n + ū^{n−1}| / 4` of the mean `u_x` `ū^n` of the nodes (the amplitude
    /// of an alternation `±a` about a smooth motion).
    pub displacement: f64,
}

/// Runs `scene` and measures [`PeriodTwo`] over `t_n >= window`.
pub fn period_two(scene: &PlaneScene, window: f64) -> Result<PeriodTwo, ConvergeError> {
    let mut sim = PlaneSimulation::new(scene).map_err(plane_error)?;
    let dt = scene.time.step;
    let mean_ux = |sim: &PlaneSimulation| {
        let u = sim.displacement_dofs();
        u.iter().step_by(2).sum::<f64>() / (u.len() / 2) as f64
    };
    let (mut totals, mut means) = (Vec::new(), Vec::new());
    for _ in 1..scene.steps() {
        sim.step().map_err(plane_error)?;
        if sim.time() >= window - 0.5 * dt {
            totals.push(sim.reactions().iter().sum::<f64>());
            means.push(mean_ux(&sim));
        }
    }
    if totals.len() < 3 {
        return Err(ConvergeError::BadInput(
            "period-2 window under 3 steps".into(),
        ));
    }
    let mean = totals.iter().sum::<f64>() / totals.len() as f64;
    let reaction = (totals.windows(2)).fold(0.0f64, |a, p| a.max((p[1] - p[0]).abs())) / mean;
    let displacement =
        (means.windows(3)).fold(0.0f64, |a, p| a.max((p[2] - 2.0 * p[1] + p[0]).abs() / 4.0));
    Ok(PeriodTwo {
        dt,
        reaction,
        displacement,
    })
}

/// [`period_two`] of the resting block at `dt`.
pub fn resting(dt: f64) -> Result<PeriodTwo, ConvergeError> {
    period_two(&resting_scene(dt, RESTING_END)?, RESTING_WINDOW)
}

/// [`period_two`] of the launched block at `dt`.
pub fn launch(dt: f64) -> Result<PeriodTwo, ConvergeError> {
    period_two(&launch_scene(dt)?, LAUNCH_WINDOW)
}

/// Both scenes at every `Δt` of [`TABLE_STEPS`]: `(resting, launch)` rows.
pub fn table() -> Result<Vec<(PeriodTwo, PeriodTwo)>, ConvergeError> {
    TABLE_STEPS
        .iter()
        .map(|&dt| Ok((resting(dt)?, launch(dt)?)))
        .collect()
}

/// The observed order `log2(a(2Δt) / a(Δt))` between consecutive rows (`None` at a zero).
pub fn order(coarse: f64, fine: f64, ratio: f64) -> Option<f64> {
    (coarse > 0.0 && fine > 0.0).then(|| (coarse / fine).ln() / ratio.ln())
}

/// The table's Markdown.
pub fn markdown(rows: &[(PeriodTwo, PeriodTwo)]) -> String {
    let mut md = String::from(
        "| Δt | resting: reaction alternation / R | resting: mean u_x amplitude | launch: reaction alternation / R | launch: mean u_x amplitude | launch: order |\n|---|---|---|---|---|---|\n",
    );
    let sci = |v: f64| format!("{v:.2e}");
    let ord = |v: Option<f64>| v.map_or("–".to_string(), |o| format!("{o:.2}"));
    for (i, (r, l)) in rows.iter().enumerate() {
        // The resting block's amplitude is round-off at every Δt: only the launch's has an order.
        let lo = i.checked_sub(1).and_then(|j| {
            let pl = rows[j].1;
            order(pl.displacement, l.displacement, pl.dt / l.dt)
        });
        let _ = writeln!(
            md,
            "| {} | {} | {} | {} | {} | {} |",
            r.dt,
            sci(r.reaction),
            sci(r.displacement),
            sci(l.reaction),
            sci(l.displacement),
            ord(lo)
        );
    }
    md
}
