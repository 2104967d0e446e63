//! The talk's figures: each talk scene is run once, `u` and the contact history are sampled on
//! a bounded grid while stepping, and the samples are drawn with plotters as PNG and SVG.
//!
//! Per scene (`<scene>.png`, `<scene>.svg`): the displacement `u(x, t)` as a colour map with a
//! colour bar, beside the contact history. Per talk figure (`figure-<k>.png/.svg`): the `l = 0`
//! scene beside the forced one, as the talk lays them out.
//!
//! Text is laid out with the embedded DejaVu Sans font through plotters' `ab_glyph` feature, so
//! no system font library is needed. Every file is written to a temporary name in the output
//! folder and renamed into place, so it is whole or absent.
//!
//! The work-precision diagram of `viscobar converge` is drawn here too
//! ([`write_work_precision`]).
//!
//! Only with the `plots` feature (on by default), which brings plotters and the font.

#![cfg(feature = "plots")]

use crate::scene::{self, Scene};
use crate::time::RunError;
use crate::time::run::{Summary, Tracker};
use crate::time::simulation::CONTACT_GAP_TOL;
use crate::time::simulation::{Simulation, StepRecord};
use plotters::coord::Shift;
use plotters::coord::types::RangedCoordf64;
use plotters::element::Polygon;
use plotters::prelude::*;
use plotters::style::colors::colormaps::ViridisRGB;
use std::path::{Path, PathBuf};

/// The talk's figures, in order: file stem, caption, and the scenes of its two panels
/// (`l = 0`, then forced). Adding a figure is adding one line here.
pub const TALK_FIGURES: &[(&str, &str, [&str; 2])] = &[
    (
        "figure-1",
        "Signorini at both ends",
        ["both-ends", "both-ends-forced"],
    ),
    (
        "figure-2",
        "Signorini at x = 0, Neumann at x = L",
        ["one-end", "one-end-forced"],
    ),
    (
        "figure-3",
        "Distributed Signorini (obstacle under every node)",
        ["distributed", "distributed-forced"],
    ),
];

/// The talk scenes, figure by figure.
pub fn talk_scenes() -> impl Iterator<Item = &'static str> {
    TALK_FIGURES
        .iter()
        .flat_map(|(_, _, scenes)| scenes.iter().copied())
}

/// Default output folder of `viscobar figures`.
pub const DEFAULT_OUT: &str = "out/figures";

/// At most this many x-intervals of `u` are kept (a 400-element mesh is kept node for node;
/// more nodes than plot pixels would add memory, not detail).
pub const MAX_X_INTERVALS: usize = 400;
/// At most this many t-intervals are kept: about one per pixel row of the colour map.
pub const MAX_T_INTERVALS: usize = 600;
/// One line per constraint is legible up to this many constraints (the two ends); beyond it the
/// contact panel draws the contact set over `(x, t)` instead.
pub const MAX_REACTION_LINES: usize = 2;

/// Size of a one-scene figure (pixels; kept small for the README).
pub const SCENE_SIZE: (u32, u32) = (1200, 500);
/// Size of a two-panel talk figure.
pub const PAIR_SIZE: (u32, u32) = (1200, 900);

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

/// What the second panel shows.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum ContactPanel {
    /// The reaction at each Signorini end against `t`.
    Reactions,
    /// The contact set `{x : u(x) + a(x) = 0}` over `(x, t)` (distributed obstacles).
    ContactSet,
}

impl ContactPanel {
    pub fn for_history(h: &ContactHistory) -> Self {
        if h.constraints() <= MAX_REACTION_LINES {
            Self::Reactions
        } else {
            Self::ContactSet
        }
    }
}

/// A run reduced to what the figures and the snapshots need.
#[derive(Clone, Debug)]
pub struct SampledRun {
    pub name: String,
    pub solver: String,
    pub alpha: f64,
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

    /// `l = 0` or `l = <expression>`.
    pub fn load_label(&self) -> String {
        format!("l = {}", self.load.as_deref().unwrap_or("0"))
    }

    /// The line naming the discretisation and the solver.
    pub fn parameters_label(&self) -> String {
        format!(
            "α = {}, J = {} ({} elements), Δt = {}, solver: {}",
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

/// Runs `scene`, keeping `u` at the sampled mesh points, the energy at the sampled steps and
/// the contact history binned between them. Memory is that of the samples, not of the run.
pub fn sample_run(name: &str, scene: &Scene, sampling: Sampling) -> Result<SampledRun, RunError> {
    let mut sim = Simulation::new(scene)?;
    let mut tracker = Tracker::new(&sim, scene.load.density.is_none());
    let disc = sim.discretisation();
    let nodes = strided(disc.nodes - 1, sampling.x_stride);
    let xs: Vec<f64> = nodes.iter().map(|&i| disc.x(i)).collect();
    let steps = scene.steps();
    let steps_sampled = strided(steps, sampling.t_stride);
    let ts: Vec<f64> = steps_sampled.iter().map(|&n| n as f64 * disc.dt).collect();
    let mut contact = ContactHistory::new(
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
    let mut full = vec![0.0; disc.nodes];
    let mut gaps = vec![0.0; disc.constraints.len()];
    let mut u = Vec::with_capacity(nodes.len() * steps_sampled.len());
    let mut energy = Vec::with_capacity(steps_sampled.len());
    let keep = |full: &[f64], u: &mut Vec<f64>| u.extend(nodes.iter().map(|&i| full[i]));
    keep(&sim.initial_state().0, &mut u);
    energy.push(None);
    let mut next = 1; // index into steps_sampled of the next step to keep
    let mut observe = |sim: &Simulation, r: &StepRecord, u: &mut Vec<f64>, energy: &mut Vec<_>| {
        let k = contact.constraints();
        let new_bin = r.step == steps_sampled[next - 1] + 1; // the previous bin closed
        // Per-constraint contact data come from the simulation (a step record keeps only the
        // ends and aggregates).
        sim.constraint_gaps_into(&mut gaps[..k]);
        contact.observe(r.time, &gaps[..k], &sim.reactions()[..k], new_bin);
        if steps_sampled.get(next) == Some(&r.step) {
            sim.displacement_into(&mut full);
            keep(&full, u);
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
        energy,
        contact,
        summary,
    })
}

/// Why `viscobar figures` failed.
#[derive(Debug, thiserror::Error)]
pub enum FigureError {
    #[error("scene `{scene}`: {source}")]
    Run { scene: String, source: RunError },
    #[error("cannot draw {path}: {message}")]
    Draw { path: PathBuf, message: String },
    #[error("cannot write {path}: {source}")]
    Write {
        path: PathBuf,
        source: std::io::Error,
    },
    #[error("cannot load the embedded font")]
    Font,
}

impl FigureError {
    /// Process exit code, as for `run`: 2 for bad input, 1 for a failure during the run.
    pub fn exit_code(&self) -> i32 {
        match self {
            FigureError::Run { source, .. } => source.exit_code(),
            _ => 1,
        }
    }
}

/// Registers DejaVu Sans as plotters' "sans-serif"; without it every text fails with
/// `FontUnavailable`.
pub fn register_font() -> Result<(), FigureError> {
    static REGISTERED: std::sync::OnceLock<bool> = std::sync::OnceLock::new();
    let ok = *REGISTERED.get_or_init(|| {
        plotters::style::register_font("sans-serif", FontStyle::Normal, dejavu::sans::regular())
            .is_ok()
    });
    ok.then_some(()).ok_or(FigureError::Font)
}

/// Runs the talk scenes (with `overrides`, e.g. the solver) and writes every figure into `out`.
/// All scenes are loaded and run before the first file is written, so bad input or a failed run
/// leaves `out` untouched. Returns the files written, in order.
pub fn write_talk_figures(out: &Path, overrides: &[String]) -> Result<Vec<PathBuf>, FigureError> {
    let run_err = |scene: &str| {
        let scene = scene.to_string();
        move |source: RunError| FigureError::Run { scene, source }
    };
    let mut scenes = Vec::new();
    for name in talk_scenes() {
        let (name, scene) = scene::load(name, overrides)
            .map_err(RunError::from)
            .map_err(run_err(name))?;
        scenes.push((name, scene));
    }
    let mut runs = Vec::new();
    for (name, scene) in &scenes {
        let sampling = Sampling::for_figure(scene);
        runs.push(sample_run(name, scene, sampling).map_err(run_err(name))?);
    }
    register_font()?;
    std::fs::create_dir_all(out).map_err(|source| FigureError::Write {
        path: out.to_path_buf(),
        source,
    })?;
    let mut written = Vec::new();
    for run in &runs {
        for ext in ["png", "svg"] {
            let path = out.join(format!("{}.{ext}", run.name));
            write_figure(&path, Figure::Scene(run))?;
            written.push(path);
        }
    }
    for (k, (stem, caption, _)) in TALK_FIGURES.iter().enumerate() {
        let pair = [&runs[2 * k], &runs[2 * k + 1]];
        let title = format!("Figure {}: {caption}", k + 1);
        for ext in ["png", "svg"] {
            let path = out.join(format!("{stem}.{ext}"));
            write_figure(&path, Figure::Pair(&title, pair))?;
            written.push(path);
        }
    }
    Ok(written)
}

type DrawResult = Result<(), Box<dyn std::error::Error>>;

/// A figure to draw: one scene, or a talk figure (its title and its two scenes).
#[derive(Clone, Copy)]
enum Figure<'a> {
    Scene(&'a SampledRun),
    Pair(&'a str, [&'a SampledRun; 2]),
    /// A log-log work-precision diagram: its title and one line per solver setting.
    WorkPrecision(&'a str, &'a [WorkPrecisionLine]),
}

impl Figure<'_> {
    fn size(&self) -> (u32, u32) {
        match self {
            Figure::Scene(_) => SCENE_SIZE,
            Figure::Pair(..) => PAIR_SIZE,
            Figure::WorkPrecision(..) => WORK_PRECISION_SIZE,
        }
    }

    fn draw<DB: DrawingBackend>(&self, root: &DrawingArea<DB, Shift>) -> DrawResult
    where
        DB::ErrorType: 'static,
    {
        root.fill(&WHITE)?;
        match *self {
            Figure::Scene(run) => draw_scene(root, run)?,
            Figure::Pair(title, runs) => draw_pair(root, title, runs)?,
            Figure::WorkPrecision(title, lines) => draw_work_precision(root, title, lines)?,
        }
        Ok(root.present()?)
    }
}

/// Draws `fig` as PNG or SVG (by the extension of `path`) and writes it via a temporary file in
/// the same folder, renamed into place only when complete.
fn write_figure(path: &Path, fig: Figure) -> Result<(), FigureError> {
    let file = path
        .file_name()
        .map_or_else(String::new, |f| f.to_string_lossy().into_owned());
    // The bitmap backend picks the encoder from the extension, so the temporary name keeps it.
    let tmp = path.with_file_name(format!(".partial-{}-{file}", std::process::id()));
    let draw_err = |e: Box<dyn std::error::Error>| FigureError::Draw {
        path: path.to_path_buf(),
        message: e.to_string(),
    };
    let write_err = |source| FigureError::Write {
        path: path.to_path_buf(),
        source,
    };
    let result = if path.extension().is_some_and(|e| e == "svg") {
        let mut svg = String::new();
        let drawn = {
            let root = SVGBackend::with_string(&mut svg, fig.size()).into_drawing_area();
            fig.draw(&root)
        };
        // plotters-svg 0.3.7 writes the invalid MIME type `data:png` for embedded bitmaps.
        drawn.map_err(draw_err).and_then(|()| {
            let svg = svg.replace("\"data:png;base64,", "\"data:image/png;base64,");
            std::fs::write(&tmp, svg).map_err(write_err)
        })
    } else {
        let root = BitMapBackend::new(&tmp, fig.size()).into_drawing_area();
        fig.draw(&root).map_err(draw_err)
    };
    let result = result.and_then(|()| std::fs::rename(&tmp, path).map_err(write_err));
    if result.is_err() {
        let _ = std::fs::remove_file(&tmp);
    }
    result
}

/// Font sizes (pixels): figure title, panel title, axis names, tick labels, legend.
const TITLE_FONT: u32 = 26;
const SUBTITLE_FONT: u32 = 18;
const PANEL_FONT: u32 = 20;
const AXIS_FONT: u32 = 20;
const TICK_FONT: u32 = 16;
/// Colour levels of the displacement map: bands read like contour lines against the colour
/// bar, and flat bands keep the PNG small.
const COLOUR_LEVELS: usize = 24;
/// Width of the colour bar column, labels included.
const COLOUR_BAR_WIDTH: u32 = 115;
/// Width of the colour-map-and-bar column of a one-scene figure.
const MAP_COLUMN_WIDTH: u32 = 680;
/// Share of a talk figure's column height given to the colour map (the rest: contact panel).
const MAP_HEIGHT_PERCENT: u32 = 62;
/// Line colours of the contact panel, one per constraint.
const LINE_COLOURS: [RGBColor; 2] = [RGBColor(31, 119, 180), RGBColor(214, 39, 40)];

fn sans(size: u32) -> (&'static str, u32) {
    ("sans-serif", size)
}

fn draw_scene<DB: DrawingBackend>(root: &DrawingArea<DB, Shift>, run: &SampledRun) -> DrawResult
where
    DB::ErrorType: 'static,
{
    let body = root.titled(
        &format!("{}  ({})", run.name, run.load_label()),
        sans(TITLE_FONT),
    )?;
    let body = body.titled(&run.parameters_label(), sans(SUBTITLE_FONT))?;
    let (left, right) = body.split_horizontally(MAP_COLUMN_WIDTH);
    draw_u_map(&left, run)?;
    draw_contact(&right, run)
}

fn draw_pair<DB: DrawingBackend>(
    root: &DrawingArea<DB, Shift>,
    title: &str,
    runs: [&SampledRun; 2],
) -> DrawResult
where
    DB::ErrorType: 'static,
{
    let body = root.titled(title, sans(TITLE_FONT + 2))?;
    for (column, run) in body.split_evenly((1, 2)).iter().zip(runs) {
        let column = column.titled(
            &format!("{}  ({})", run.name, run.load_label()),
            sans(PANEL_FONT + 2),
        )?;
        let column = column.titled(&run.parameters_label(), sans(SUBTITLE_FONT - 2))?;
        let (_, h) = column.dim_in_pixel();
        let (top, bottom) = column.split_vertically(h * MAP_HEIGHT_PERCENT / 100);
        draw_u_map(&top, run)?;
        draw_contact(&bottom, run)?;
    }
    Ok(())
}

/// Smallest and largest value, widened when they coincide so the colour scale is defined.
fn value_range(values: &[f64]) -> (f64, f64) {
    let (lo, hi) = values
        .iter()
        .fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), &v| {
            (a.min(v), b.max(v))
        });
    if !(lo.is_finite() && hi.is_finite()) {
        (0.0, 1.0)
    } else if lo == hi {
        (lo - 0.5, hi + 0.5)
    } else {
        (lo, hi)
    }
}

/// Decimals that show a range of width `span` with about three significant digits.
fn tick_decimals(span: f64) -> usize {
    (2.0 - span.abs().log10().floor()).clamp(0.0, 8.0) as usize
}

/// Index of the entry of ascending `v` nearest to `x`.
fn nearest(v: &[f64], x: f64) -> usize {
    let k = v.partition_point(|&a| a < x);
    if k == 0 {
        0
    } else if k == v.len() || x - v[k - 1] <= v[k] - x {
        k - 1
    } else {
        k
    }
}

/// Fills the plotting area of a chart over `(x, t)` with one image: each pixel takes the colour
/// of the nearest sample `(xs[i], ts[k])`. One image (not one rectangle per sample) keeps the SVG
/// small.
fn draw_raster<DB: DrawingBackend>(
    chart: &mut ChartContext<'_, DB, Cartesian2d<RangedCoordf64, RangedCoordf64>>,
    (x_end, t_end): (f64, f64),
    xs: &[f64],
    ts: &[f64],
    colour: impl Fn(usize, usize) -> RGBColor,
) -> DrawResult
where
    DB::ErrorType: 'static,
{
    let (w, h) = chart.plotting_area().dim_in_pixel();
    if w == 0 || h == 0 || xs.is_empty() || ts.is_empty() {
        return Ok(());
    }
    let columns: Vec<usize> = (0..w)
        .map(|px| nearest(xs, (px as f64 + 0.5) / w as f64 * x_end))
        .collect();
    let mut buf = Vec::with_capacity((w * h * 3) as usize);
    for py in 0..h {
        let k = nearest(ts, t_end * (1.0 - (py as f64 + 0.5) / h as f64)); // row 0 is t_end
        for &i in &columns {
            let c = colour(i, k);
            buf.extend_from_slice(&[c.0, c.1, c.2]);
        }
    }
    let image = BitMapElement::with_owned_buffer((0.0, t_end), (w, h), buf)
        .ok_or("raster buffer of the wrong size")?;
    chart.draw_series(std::iter::once(image))?;
    chart
        .plotting_area()
        .draw(&Rectangle::new([(0.0, 0.0), (x_end, t_end)], BLACK))?;
    Ok(())
}

/// An `(x, t)` chart with labelled axes on `area`, leaving `right` pixels on the right free.
fn space_time_chart<'a, DB: DrawingBackend>(
    area: &DrawingArea<DB, Shift>,
    (x_end, t_end): (f64, f64),
) -> Result<
    ChartContext<'a, DB, Cartesian2d<RangedCoordf64, RangedCoordf64>>,
    Box<dyn std::error::Error>,
>
where
    DB::ErrorType: 'static,
{
    let mut chart = ChartBuilder::on(area)
        .margin(10)
        .x_label_area_size(50)
        .y_label_area_size(60)
        .build_cartesian_2d(0.0..x_end, 0.0..t_end)?;
    chart
        .configure_mesh()
        .disable_mesh()
        .x_desc("x")
        .y_desc("t")
        .axis_desc_style(sans(AXIS_FONT))
        .label_style(sans(TICK_FONT))
        .draw()?;
    Ok(chart)
}

/// `u(x, t)` as a colour map, with its colour bar on the right.
fn draw_u_map<DB: DrawingBackend>(area: &DrawingArea<DB, Shift>, run: &SampledRun) -> DrawResult
where
    DB::ErrorType: 'static,
{
    let area = area.titled("displacement u(x, t)", sans(PANEL_FONT))?;
    let (w, _) = area.dim_in_pixel();
    let (map_area, bar_area) = area.split_horizontally(w.saturating_sub(COLOUR_BAR_WIDTH));
    let (lo, hi) = value_range(&run.u);
    let colour = |v: f64| {
        let level = ((v - lo) / (hi - lo) * COLOUR_LEVELS as f64).floor();
        let level = level.clamp(0.0, COLOUR_LEVELS as f64 - 1.0);
        ViridisRGB::get_color_normalized(level + 0.5, 0.0, COLOUR_LEVELS as f64)
    };
    let extent = (run.length, run.final_time());
    let mut chart = space_time_chart(&map_area, extent)?;
    let nx = run.xs.len();
    draw_raster(&mut chart, extent, &run.xs, &run.ts, |i, k| {
        colour(run.u[k * nx + i])
    })?;

    // Same top margin and x-label height as the map, so bar and map line up.
    let mut bar = ChartBuilder::on(&bar_area)
        .margin_top(10)
        .margin_bottom(10)
        .margin_right(10)
        .x_label_area_size(50)
        .right_y_label_area_size(75)
        .build_cartesian_2d(0.0..1.0, lo..hi)?;
    let decimals = tick_decimals(hi - lo);
    bar.configure_mesh()
        .disable_mesh()
        .y_labels(8)
        .y_label_formatter(&|v| tick(*v, decimals))
        .x_labels(0)
        .x_desc("u")
        .axis_desc_style(sans(AXIS_FONT))
        .label_style(sans(TICK_FONT))
        .draw()?;
    const SHADES: usize = 256; // the colour map's own resolution
    bar.draw_series((0..SHADES).map(|s| {
        let v0 = lo + (hi - lo) * s as f64 / SHADES as f64;
        let v1 = lo + (hi - lo) * (s + 1) as f64 / SHADES as f64;
        Rectangle::new([(0.0, v0), (1.0, v1)], colour(0.5 * (v0 + v1)).filled())
    }))?;
    bar.plotting_area()
        .draw(&Rectangle::new([(0.0, lo), (1.0, hi)], BLACK))?;
    Ok(())
}

/// The contact panel: reactions against `t` at the ends, or the contact set over `(x, t)`.
fn draw_contact<DB: DrawingBackend>(area: &DrawingArea<DB, Shift>, run: &SampledRun) -> DrawResult
where
    DB::ErrorType: 'static,
{
    match ContactPanel::for_history(&run.contact) {
        ContactPanel::Reactions => draw_reactions(area, &run.contact, run.final_time()),
        ContactPanel::ContactSet => {
            draw_contact_set(area, &run.contact, run.length, run.final_time())
        }
    }
}

/// One line per constraint: its largest reaction in each time bin, against `t`.
fn draw_reactions<DB: DrawingBackend>(
    area: &DrawingArea<DB, Shift>,
    h: &ContactHistory,
    t_end: f64,
) -> DrawResult
where
    DB::ErrorType: 'static,
{
    let k = h.constraints();
    let title = if k == 1 {
        "contact reaction r at the Signorini end"
    } else {
        "contact reaction r at the Signorini ends"
    };
    let area = area.titled(title, sans(PANEL_FONT))?;
    let r_max = h.reaction.iter().copied().fold(0.0, f64::max);
    let top = if r_max > 0.0 { 1.12 * r_max } else { 1.0 }; // headroom for the legend
    let mut chart = ChartBuilder::on(&area)
        .margin(10)
        .margin_right(25)
        .x_label_area_size(50)
        .y_label_area_size(70)
        .build_cartesian_2d(0.0..t_end, 0.0..top)?;
    let decimals = tick_decimals(top);
    chart
        .configure_mesh()
        .x_desc("t")
        .y_desc("r")
        .y_label_formatter(&|v| tick(*v, decimals))
        .axis_desc_style(sans(AXIS_FONT))
        .label_style(sans(TICK_FONT))
        .light_line_style(WHITE)
        .draw()?;
    if k == 0 {
        chart.draw_series(std::iter::once(Text::new(
            "no Signorini end",
            (0.05 * t_end, 0.5 * top),
            sans(AXIS_FONT),
        )))?;
        return Ok(());
    }
    // Filled under a 1-pixel line: thicker plotters lines are polygonised with mitre joins,
    // which break up at the sharp reaction peaks; the translucent fill keeps overlapping ends
    // visible (both-ends: the two reactions nearly coincide after the second impact).
    for j in 0..k {
        let colour = LINE_COLOURS[j % LINE_COLOURS.len()];
        let points: Vec<(f64, f64)> = h
            .times
            .iter()
            .enumerate()
            .map(|(b, &t)| (t, h.reaction[b * k + j]))
            .collect();
        let (t0, t1) = (points[0].0, points[points.len() - 1].0);
        let outline = std::iter::once((t0, 0.0))
            .chain(points.iter().copied())
            .chain(std::iter::once((t1, 0.0)));
        chart.draw_series(std::iter::once(Polygon::new(
            outline.collect::<Vec<_>>(),
            colour.mix(FILL_OPACITY).filled(),
        )))?;
        chart
            .draw_series(LineSeries::new(points, colour))?
            .label(format!("{} end (x = {})", h.names[j], short(h.xs[j])))
            .legend(move |(x, y)| {
                Rectangle::new([(x, y - 6), (x + 24, y + 6)], colour.mix(0.7).filled())
            });
    }
    chart
        .configure_series_labels()
        .position(SeriesLabelPosition::UpperRight)
        .background_style(WHITE.mix(0.85))
        .border_style(BLACK)
        .label_font(sans(TICK_FONT))
        .draw()?;
    Ok(())
}

/// The contact set over `(x, t)`: dark where a constraint touched its obstacle in a time bin.
/// For distributed obstacles (more constraints than [`MAX_REACTION_LINES`]).
fn draw_contact_set<DB: DrawingBackend>(
    area: &DrawingArea<DB, Shift>,
    h: &ContactHistory,
    length: f64,
    t_end: f64,
) -> DrawResult
where
    DB::ErrorType: 'static,
{
    let area = area.titled("contact set (dark: u + a = 0)", sans(PANEL_FONT))?;
    let extent = (length, t_end);
    let mut chart = space_time_chart(&area, extent)?;
    draw_raster(&mut chart, extent, &h.xs, &h.times, |j, bin| {
        if h.in_contact(bin, j) {
            CONTACT_COLOUR
        } else {
            WHITE
        }
    })
}

/// Opacity of the fill under a reaction line.
const FILL_OPACITY: f64 = 0.35;

/// `x` with at most four decimals and no trailing zeros (`0`, `3.1416`).
fn short(x: f64) -> String {
    let s = format!("{x:.4}");
    let s = s.trim_end_matches('0').trim_end_matches('.');
    if s == "-0" { "0".into() } else { s.into() }
}

/// A tick label with `decimals` decimals, without a sign on zero (`-0.000` → `0.000`).
fn tick(v: f64, decimals: usize) -> String {
    let s = format!("{v:.decimals$}");
    match s.strip_prefix('-') {
        Some(rest) if rest.chars().all(|c| c == '0' || c == '.') => rest.to_string(),
        _ => s,
    }
}

/// Colour of the contact set: the dark end of viridis (not a grey, so never text).
const CONTACT_COLOUR: RGBColor = RGBColor(68, 1, 84);

/// One line of a work-precision diagram: its legend label and its `(wall time, error)` points.
pub type WorkPrecisionLine = (String, Vec<(f64, f64)>);

/// Line colours of the work-precision diagram, one per setting (exact, then OSQP shades, then
/// penalty shades).
const WORK_PRECISION_COLOURS: [(u8, u8, u8); 7] = [
    (0, 0, 0),
    (8, 81, 156),
    (49, 130, 189),
    (107, 174, 214),
    (165, 15, 21),
    (222, 45, 38),
    (251, 106, 74),
];
/// Size of the work-precision figure (pixels).
const WORK_PRECISION_SIZE: (u32, u32) = (900, 640);

/// Draws the log-log work-precision diagram of `lines` (`viscobar converge`) and writes it as
/// PNG or SVG (by the extension of `path`), whole or not at all.
pub fn write_work_precision(
    path: &Path,
    title: &str,
    lines: &[WorkPrecisionLine],
) -> Result<(), FigureError> {
    register_font()?;
    write_figure(path, Figure::WorkPrecision(title, lines))
}

fn draw_work_precision<DB: DrawingBackend>(
    root: &DrawingArea<DB, Shift>,
    title: &str,
    lines: &[WorkPrecisionLine],
) -> DrawResult
where
    DB::ErrorType: 'static,
{
    let bounds = |f: fn(&(f64, f64)) -> f64| {
        let vals = lines.iter().flat_map(|l| l.1.iter().map(f));
        let (lo, hi) = vals.fold((f64::INFINITY, 0.0f64), |(a, b), v| (a.min(v), b.max(v)));
        (lo / 1.5, hi * 1.5)
    };
    let (x0, x1) = bounds(|p| p.0);
    let (y0, y1) = bounds(|p| p.1);
    let mut chart = ChartBuilder::on(root)
        .caption(title, ("sans-serif", 20))
        .margin(15)
        .x_label_area_size(45)
        .y_label_area_size(75)
        .build_cartesian_2d((x0..x1).log_scale(), (y0..y1).log_scale())?;
    chart
        .configure_mesh()
        .x_desc("wall time of the steps (s)")
        .y_desc("L2 error (max over t)")
        .label_style(("sans-serif", 15))
        .axis_desc_style(("sans-serif", 17))
        .x_label_formatter(&|v| format!("{v:.0e}"))
        .y_label_formatter(&|v| format!("{v:.0e}"))
        .draw()?;
    for (k, (label, pts)) in lines.iter().enumerate() {
        let (r, g, b) = WORK_PRECISION_COLOURS[k % WORK_PRECISION_COLOURS.len()];
        let colour = RGBColor(r, g, b);
        chart
            .draw_series(LineSeries::new(pts.iter().copied(), colour.stroke_width(2)))?
            .label(label.clone())
            .legend(move |(x, y)| {
                PathElement::new(vec![(x, y), (x + 20, y)], colour.stroke_width(2))
            });
        chart.draw_series(pts.iter().map(|p| Circle::new(*p, 4, colour.filled())))?;
    }
    chart
        .configure_series_labels()
        .background_style(WHITE.mix(0.85))
        .border_style(BLACK)
        .label_font(("sans-serif", 15))
        .position(SeriesLabelPosition::UpperRight)
        .draw()?;
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Pixels of `colour` in a drawing of the contact set of `h`.
    fn contact_pixels(h: &ContactHistory) -> usize {
        const SIZE: (u32, u32) = (400, 300);
        let mut buf = vec![0u8; (SIZE.0 * SIZE.1 * 3) as usize];
        {
            let root = BitMapBackend::with_buffer(&mut buf, SIZE).into_drawing_area();
            root.fill(&WHITE).unwrap();
            draw_contact_set(&root, h, 1.0, 1.0).unwrap();
            root.present().unwrap();
        }
        let c = CONTACT_COLOUR;
        buf.chunks(3).filter(|p| *p == [c.0, c.1, c.2]).count()
    }

    /// The hook for distributed obstacles: with more constraints than the reaction panel can
    /// show, the contact set is drawn, and it is coloured exactly where a node touched.
    #[test]
    fn many_constraints_draw_the_contact_set_where_nodes_touch() {
        register_font().unwrap();
        let names = (0..5).map(|i| format!("node {i}")).collect();
        let xs = (0..5).map(|i| f64::from(i) * 0.25).collect();
        let mut touching = ContactHistory::new(names, xs);
        let mut apart = touching.clone();
        for (bin, t) in [0.25, 0.5, 0.75, 1.0].into_iter().enumerate() {
            let mut gaps = [1.0; 5];
            apart.observe(t, &gaps, &[0.0; 5], true);
            if bin == 2 {
                gaps[3] = 0.0; // node 3 (x = 0.75) touches in the third bin
            }
            touching.observe(t, &gaps, &[0.0; 5], true);
        }
        assert_eq!(
            ContactPanel::for_history(&touching),
            ContactPanel::ContactSet
        );
        assert!(touching.in_contact(2, 3) && !touching.in_contact(1, 3));
        assert_eq!(contact_pixels(&apart), 0);
        // One of 5 columns by one of 4 rows of the plot area (about 320 x 220 pixels).
        let n = contact_pixels(&touching);
        assert!((2000..6000).contains(&n), "{n} contact pixels");
    }
}
