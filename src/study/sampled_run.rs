//! A run reduced to what the talk's figures and the snapshots need: `u` (and, for a bar with a
//! temperature, `θ`) on a bounded grid of mesh points, the energy at the sampled steps, and the
//! contact history binned between them, all kept while stepping (memory is that of the samples,
//! not of the run).
//!
//! Apart from the drawing (`study::figures`) because `tests/snapshots.rs` pins these samples
//! without drawing them. Only with the `plots` feature, like the figures it feeds.

#![cfg(feature = "plots")]

use crate::bar::{Discretisation, Simulation};
use crate::output::summary::{Summary, Tracker};
use crate::scene::Scene;
use crate::scheme::CONTACT_GAP_TOL;
use crate::scheme::StepRecord;
use crate::scheme::{Body, RunError, Scheme, Unstarted};
use crate::thermal::ThermalSimulation;

/// At most this many x-intervals of `u` are kept (a 400-element mesh is kept node for node;
/// more nodes than plot pixels would add memory, not detail).
pub const MAX_X_INTERVALS: usize = 400;
/// At most this many t-intervals are kept: about one per pixel row of the colour map.
pub const MAX_T_INTERVALS: usize = 600;

/// Which mesh points are kept: every `x_stride`-th node and every `t_stride`-th step, plus the
/// last node and the last step.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Sampling {
    pub x_stride: usize,
    pub t_stride: usize,
}

impl Sampling {
    /// The figures' sampling: the finest with at most [`MAX_X_INTERVALS`] by
    /// [`MAX_T_INTERVALS`] intervals.
    pub fn for_figure(scene: &Scene) -> Self {
        Self {
            x_stride: scene.elements().div_ceil(MAX_X_INTERVALS).max(1),
            t_stride: scene.steps().div_ceil(MAX_T_INTERVALS).max(1),
        }
    }

    /// Exactly `x_points` nodes by `t_points` steps, all of them mesh points (so no
    /// interpolation), or `None` when the mesh does not contain such a grid.
    pub fn exact(scene: &Scene, x_points: usize, t_points: usize) -> Option<Self> {
        let (elements, steps) = (scene.elements(), scene.steps());
        let (xi, ti) = (x_points.checked_sub(1)?, t_points.checked_sub(1)?);
        (xi > 0 && ti > 0 && elements % xi == 0 && steps % ti == 0).then(|| Self {
            x_stride: elements / xi,
            t_stride: steps / ti,
        })
    }
}

/// Indices `0, stride, 2·stride, …` up to `last`, with `last` always included.
fn strided(last: usize, stride: usize) -> Vec<usize> {
    let mut v: Vec<usize> = (0..=last).step_by(stride.max(1)).collect();
    if v.last() != Some(&last) {
        v.push(last);
    }
    v
}

/// The contact history of a run, per time bin and per constraint, in a form that does not
/// depend on how many constraints there are (two ends, or one per node for a distributed
/// obstacle). Bin `k` covers the steps after the previous sampled step up to its own.
#[derive(Clone, Debug, Default)]
pub struct ContactHistory {
    /// One per constraint: a name (`left`, `right`, ...) and the node's `x`.
    pub names: Vec<String>,
    pub xs: Vec<f64>,
    /// The time of the last step of each bin.
    pub times: Vec<f64>,
    /// Largest reaction in each bin, `reaction[bin * constraints + j]` (peaks of short impacts
    /// are kept, not sampled away).
    pub reaction: Vec<f64>,
    /// Smallest gap `u + a` in each bin, same layout.
    pub gap: Vec<f64>,
}

impl ContactHistory {
    pub fn new(names: Vec<String>, xs: Vec<f64>) -> Self {
        Self {
            names,
            xs,
            ..Default::default()
        }
    }

    pub fn constraints(&self) -> usize {
        self.names.len()
    }

    /// Takes one step's contact data (`gaps[j]`, `reactions[j]` per constraint); `new_bin`
    /// starts the next bin.
    pub fn observe(&mut self, t: f64, gaps: &[f64], reactions: &[f64], new_bin: bool) {
        let k = self.constraints();
        if new_bin || self.times.is_empty() {
            self.times.push(t);
            self.reaction.extend_from_slice(&reactions[..k]);
            self.gap.extend_from_slice(&gaps[..k]);
            return;
        }
        *self.times.last_mut().expect("a bin is open") = t;
        let start = self.reaction.len() - k;
        for j in 0..k {
            self.reaction[start + j] = self.reaction[start + j].max(reactions[j]);
            self.gap[start + j] = self.gap[start + j].min(gaps[j]);
        }
    }

    /// Whether constraint `j` touched its obstacle during bin `bin`.
    pub fn in_contact(&self, bin: usize, j: usize) -> bool {
        self.gap[bin * self.constraints() + j] <= CONTACT_GAP_TOL
    }
}

/// A run reduced to what the figures and the snapshots need.
#[derive(Clone, Debug)]
pub struct SampledRun {
    pub name: String,
    pub solver: String,
    pub alpha: f64,
    /// The diffusivity `κ` and the coupling `γ` of a bar with a temperature (`[heat]`).
    pub heat: Option<(f64, f64)>,
    pub length: f64,
    pub elements: usize,
    pub dt: f64,
    pub steps: usize,
    /// The load density as written in the scene, `None` for `l = 0`.
    pub load: Option<String>,
    /// Sampled nodes and their `x`.
    pub nodes: Vec<usize>,
    pub xs: Vec<f64>,
    /// Sampled steps and their `t`.
    pub steps_sampled: Vec<usize>,
    pub ts: Vec<f64>,
    /// `u[k * xs.len() + i]` = `u` at node `nodes[i]` after step `steps_sampled[k]`.
    pub u: Vec<f64>,
    /// `θ` in the layout of `u` (the profile file's `theta`), for a bar with a temperature.
    pub theta: Option<Vec<f64>>,
    /// `E^{n−1/2}` recorded by sampled step `n` (`None` for `n = 0`, which has no record).
    pub energy: Vec<Option<f64>>,
    /// Binned like `steps_sampled` (bin `k` ends at sampled step `k + 1`).
    pub contact: ContactHistory,
    pub summary: Summary,
}

impl SampledRun {
    /// Row `k` of the sampled displacement.
    pub fn u_row(&self, k: usize) -> &[f64] {
        &self.u[k * self.xs.len()..(k + 1) * self.xs.len()]
    }

    /// Row `k` of the sampled temperature (`None` without one).
    pub fn theta_row(&self, k: usize) -> Option<&[f64]> {
        let n = self.xs.len();
        self.theta.as_deref().map(|t| &t[k * n..(k + 1) * n])
    }

    /// `l = 0` or `l = <expression>`.
    pub fn load_label(&self) -> String {
        format!("l = {}", self.load.as_deref().unwrap_or("0"))
    }

    /// The line naming the discretisation and the solver (and `κ`, `γ` with a temperature).
    pub fn parameters_label(&self) -> String {
        let heat = self
            .heat
            .map_or_else(String::new, |(k, g)| format!(", κ = {k}, γ = {g}"));
        format!(
            "α = {}{heat}, J = {} ({} elements), Δt = {}, solver: {}",
            self.alpha,
            self.elements.saturating_sub(1),
            self.elements,
            self.dt,
            self.solver
        )
    }

    pub fn final_time(&self) -> f64 {
        self.ts.last().copied().unwrap_or(0.0)
    }
}

/// Runs `scene` (as the thermal bar when it has `[heat]`), keeping `u` (and `θ`) at the sampled
/// mesh points, the energy at the sampled steps and the contact history binned between them.
/// Memory is that of the samples, not of the run.
pub fn sample_run(name: &str, scene: &Scene, sampling: Sampling) -> Result<SampledRun, RunError> {
    if scene.heat.is_some() {
        let prepared = ThermalSimulation::prepare(scene)?;
        let grid = Grid::new(prepared.body().bar().discretisation(), scene, sampling);
        sample_scheme(name, scene, prepared, grid)
    } else {
        let prepared = Simulation::prepare(scene)?;
        let grid = Grid::new(prepared.body().discretisation(), scene, sampling);
        sample_scheme(name, scene, prepared, grid)
    }
}

/// The sampled nodes and steps of a bar run, and its empty contact history.
struct Grid {
    nodes: Vec<usize>,
    xs: Vec<f64>,
    steps_sampled: Vec<usize>,
    ts: Vec<f64>,
    contact: ContactHistory,
}

impl Grid {
    fn new(disc: &Discretisation, scene: &Scene, sampling: Sampling) -> Self {
        let nodes = strided(disc.nodes - 1, sampling.x_stride);
        let xs: Vec<f64> = nodes.iter().map(|&i| disc.x(i)).collect();
        let steps_sampled = strided(scene.steps(), sampling.t_stride);
        let ts: Vec<f64> = steps_sampled.iter().map(|&n| n as f64 * disc.dt).collect();
        let contact = ContactHistory::new(
            disc.constraints
                .iter()
                .map(|c| {
                    c.side.map_or_else(
                        || format!("x = {:.3}", disc.x(c.node)),
                        |s| s.name().to_string(),
                    )
                })
                .collect(),
            disc.constraints.iter().map(|c| disc.x(c.node)).collect(),
        );
        Self {
            nodes,
            xs,
            steps_sampled,
            ts,
            contact,
        }
    }
}

/// [`sample_run`] of a bar set up (`prepared`, short of its start-up step) on `grid`: the
/// start-up step, then every step; `θ` where the body has a temperature.
fn sample_scheme<B: Body>(
    name: &str,
    scene: &Scene,
    prepared: Unstarted<B>,
    grid: Grid,
) -> Result<SampledRun, RunError> {
    let Grid {
        nodes,
        xs,
        steps_sampled,
        ts,
        mut contact,
    } = grid;
    let steps = scene.steps();
    let rows = nodes.len() * steps_sampled.len();
    let mut u = Vec::with_capacity(rows);
    let mut theta = prepared
        .body()
        .has_temperature()
        .then(|| Vec::with_capacity(rows));
    let mut energy = Vec::with_capacity(steps_sampled.len());
    // `u` at every mesh node from the unknowns `state` (clamped nodes 0), and `θ` beside it.
    let mut full = vec![0.0; prepared.body().nodes()];
    let mut keep = |body: &B, state: &[f64], u: &mut Vec<f64>, theta: &mut Option<Vec<f64>>| {
        for (dof, f) in full.iter_mut().enumerate() {
            *f = body.unknown_of(dof).map_or(0.0, |i| state[i]);
        }
        u.extend(nodes.iter().map(|&i| full[i]));
        if let Some(theta) = theta {
            theta.extend(
                nodes
                    .iter()
                    .map(|&i| body.temperature(state, i).unwrap_or(0.0)),
            );
        }
    };
    // `u^0` (and `θ^0`) before the start-up step moves it on, as the profile file writes it.
    keep(prepared.body(), prepared.state().u, &mut u, &mut theta);
    energy.push(None);
    let mut sim = prepared.start()?;
    let mut tracker = Tracker::new(&sim, !sim.is_forced());
    let mut gaps = vec![0.0; contact.constraints()];
    let mut next = 1; // index into steps_sampled of the next step to keep
    let mut observe = |sim: &Scheme<B>, r: &StepRecord, u: &mut Vec<f64>, energy: &mut Vec<_>| {
        let k = contact.constraints();
        let new_bin = r.step == steps_sampled[next - 1] + 1; // the previous bin closed
        // Per-constraint contact data come from the simulation (a step record keeps only the
        // ends and aggregates).
        sim.gaps_into(&mut gaps[..k]);
        contact.observe(r.time, &gaps[..k], &sim.reactions()[..k], new_bin);
        if steps_sampled.get(next) == Some(&r.step) {
            keep(sim.body(), sim.displacement(), u, &mut theta);
            energy.push(Some(r.energy));
            next += 1;
        }
    };
    let first = sim.first_record();
    observe(&sim, &first, &mut u, &mut energy);
    let start = std::time::Instant::now();
    for _ in 1..steps {
        let r = sim.step()?;
        tracker.observe(&r);
        observe(&sim, &r, &mut u, &mut energy);
    }
    let summary = tracker.finish(name, &sim, start.elapsed().as_secs_f64());
    Ok(SampledRun {
        name: name.to_string(),
        solver: sim.solver_name().to_string(),
        alpha: scene.bar.viscosity,
        heat: (scene.heat.as_ref()).map(|h| (h.diffusivity, h.coupling)),
        length: scene.bar.length,
        elements: scene.elements(),
        dt: scene.time.step,
        steps,
        load: scene.load.density.clone(),
        nodes,
        xs,
        steps_sampled,
        ts,
        u,
        theta,
        energy,
        contact,
        summary,
    })
}
