//! The talk's figures: each talk scene is run once and sampled while stepping
//! (`study::sampled_run`), and the samples are drawn with plotters as PNG and SVG
//! (`study::figure_writer` writes each file whole or not at all).
//!
//! Per scene (`<scene>.png`, `<scene>.svg`): the displacement `u(x, t)` as a colour map with a
//! colour bar (for a bar with a temperature, `θ(x, t)` beside it on its own scale), beside the
//! contact history. Per talk figure (`figure-<k>.png/.svg`): the `l = 0`
//! scene beside the forced one, as the talk lays them out. Per friction figure
//! (`<scene>.png/.svg`): the stick/slip state and forces over `(s, t)`; per temperature
//! figure, the plane body's `θ` at the end and along its frictional edge over `(s, t)`.
//!
//! Only with the `plots` feature (on by default), which brings plotters and the font.

#![cfg(feature = "plots")]

use crate::scene;
use crate::scene::plane::{PlaneScene, plane_builtin_text};
use crate::scheme::RunError;
use crate::study::figure_writer::{DrawResult, Drawing, FigureError, register_font, write_figure};
use crate::study::friction_figure::{self, FrictionFigure};
use crate::study::sampled_run::{ContactHistory, SampledRun, Sampling, sample_run};
use crate::study::temperature_figure::{self, TemperatureFigure};
use plotters::coord::Shift;
use plotters::coord::types::RangedCoordf64;
use plotters::element::Polygon;
use plotters::prelude::*;
use plotters::style::colors::colormaps::{Copper, ViridisRGB};
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

/// The frictional scenes whose contact over `(s, t)` `viscobar figures` also draws
/// (`<scene>.png`/`.svg`, the figure of `run SCENE --figure`'s `friction-state`), each of one
/// frictional edge ([`FRICTION_FIGURE_SIZE`]).
pub const FRICTION_FIGURES: &[&str] = &["plane-friction-stick-slip"];

/// Size of a friction figure of one frictional edge.
pub const FRICTION_FIGURE_SIZE: (u32, u32) = friction_figure::figure_size(1);

/// The plane scenes with a temperature whose `θ` `viscobar figures` also draws
/// (`<scene>.png`/`.svg`, the figure of `run SCENE --figure`'s `temperature`).
pub const HEAT_FIGURES: &[&str] = &["plane-brake"];

/// Size of a temperature figure.
pub const HEAT_FIGURE_SIZE: (u32, u32) = temperature_figure::FIGURE_SIZE;

/// The talk scenes, figure by figure.
pub fn talk_scenes() -> impl Iterator<Item = &'static str> {
    TALK_FIGURES
        .iter()
        .flat_map(|(_, _, scenes)| scenes.iter().copied())
}

/// Default output folder of `viscobar figures`.
pub const DEFAULT_OUT: &str = "out/figures";

/// One line per constraint is legible up to this many constraints (the two ends); beyond it the
/// contact panel draws the contact set over `(x, t)` instead.
pub const MAX_REACTION_LINES: usize = 2;

/// Size of a one-scene figure (pixels; kept small for the README).
pub const SCENE_SIZE: (u32, u32) = (1200, 500);
/// Size of a one-scene figure of a bar with a temperature: a second colour-map column, `θ`.
pub const THERMAL_SCENE_SIZE: (u32, u32) = (SCENE_SIZE.0 + MAP_COLUMN_WIDTH, SCENE_SIZE.1);
/// Size of a two-panel talk figure.
pub const PAIR_SIZE: (u32, u32) = (1200, 900);

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
    let mut friction = Vec::new();
    for &name in FRICTION_FIGURES {
        let text = plane_builtin_text(name).expect("a built-in plane scene");
        // The scene's own solver: `--solver penalty` has no friction law.
        let scene = PlaneScene::from_toml(text, &[])
            .map_err(RunError::from)
            .map_err(run_err(name))?;
        let figure = FrictionFigure::run(name, &scene).map_err(run_err(name))?;
        friction.push((name, figure.expect("a frictional scene")));
    }
    let mut heat = Vec::new();
    for &name in HEAT_FIGURES {
        let text = plane_builtin_text(name).expect("a built-in plane scene");
        let scene = PlaneScene::from_toml(text, &[])
            .map_err(RunError::from)
            .map_err(run_err(name))?;
        let figure = TemperatureFigure::run(name, &scene).map_err(run_err(name))?;
        heat.push((name, figure.expect("a scene with [heat]")));
    }
    register_font()?;
    create_folder(out)?;
    let mut written = Vec::new();
    for run in &runs {
        written.extend(write_both(out, &run.name, &TalkFigure::Scene(run))?);
    }
    for (k, (stem, caption, _)) in TALK_FIGURES.iter().enumerate() {
        let pair = [&runs[2 * k], &runs[2 * k + 1]];
        let title = format!("Figure {}: {caption}", k + 1);
        written.extend(write_both(out, stem, &TalkFigure::Pair(&title, pair))?);
    }
    for (name, figure) in &friction {
        written.extend(figure.write_as(out, name)?);
    }
    for (name, figure) in &heat {
        written.extend(figure.write_as(out, name)?);
    }
    Ok(written)
}

/// Runs one bar scene and writes its figure (the colour map of u(x, t) beside its contact
/// panel, as [`write_talk_figures`] draws each talk scene; with `[heat]`, the colour map of
/// θ(x, t) between them) as `<name>.png` and `<name>.svg` into `out`; returns the files
/// written (`viscobar run SCENE --figure`).
pub fn write_scene_figure(
    name: &str,
    scene: &scene::Scene,
    out: &Path,
) -> Result<Vec<PathBuf>, FigureError> {
    let run = sample_run(name, scene, Sampling::for_figure(scene)).map_err(|source| {
        FigureError::Run {
            scene: name.to_string(),
            source,
        }
    })?;
    register_font()?;
    create_folder(out)?;
    write_both(out, name, &TalkFigure::Scene(&run))
}

/// `out` and its parents, made if missing.
fn create_folder(out: &Path) -> Result<(), FigureError> {
    std::fs::create_dir_all(out).map_err(|source| FigureError::Write {
        path: out.to_path_buf(),
        source,
    })
}

/// `<stem>.png` and `<stem>.svg` of `figure` in `out`; returns their paths.
fn write_both(out: &Path, stem: &str, figure: &TalkFigure) -> Result<Vec<PathBuf>, FigureError> {
    let mut written = Vec::new();
    for ext in ["png", "svg"] {
        let path = out.join(format!("{stem}.{ext}"));
        write_figure(&path, figure)?;
        written.push(path);
    }
    Ok(written)
}

/// A figure to draw: one scene, or a talk figure (its title and its two scenes).
#[derive(Clone, Copy)]
enum TalkFigure<'a> {
    Scene(&'a SampledRun),
    Pair(&'a str, [&'a SampledRun; 2]),
}

impl Drawing for TalkFigure<'_> {
    fn size(&self) -> (u32, u32) {
        match self {
            TalkFigure::Scene(run) if run.theta.is_some() => THERMAL_SCENE_SIZE,
            TalkFigure::Scene(_) => SCENE_SIZE,
            TalkFigure::Pair(..) => PAIR_SIZE,
        }
    }

    fn draw_on<DB: DrawingBackend>(&self, root: &DrawingArea<DB, Shift>) -> DrawResult
    where
        DB::ErrorType: 'static,
    {
        match *self {
            TalkFigure::Scene(run) => draw_scene(root, run),
            TalkFigure::Pair(title, runs) => draw_pair(root, title, runs),
        }
    }
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
/// Opacity of the contact episodes' shading behind the reactions: light enough that the
/// reaction fills and lines stay readable over it.
const EPISODE_OPACITY: f64 = 0.12;
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
    draw_map(&left, run, &Field::displacement(run))?;
    let right = match Field::temperature(run) {
        Some(theta) => {
            let (middle, right) = right.split_horizontally(MAP_COLUMN_WIDTH);
            draw_map(&middle, run, &theta)?;
            right
        }
        None => right,
    };
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
        match Field::temperature(run) {
            Some(theta) => {
                let maps = top.split_evenly((1, 2));
                draw_map(&maps[0], run, &Field::displacement(run))?;
                draw_map(&maps[1], run, &theta)?;
            }
            None => draw_map(&top, run, &Field::displacement(run))?,
        }
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

/// A sampled field over `(x, t)` drawn as a colour map: its values (in the layout of
/// [`SampledRun::u`]), the panel's title, the colour bar's label and the colour map.
struct Field<'a> {
    values: &'a [f64],
    title: &'static str,
    label: &'static str,
    palette: fn(f64, f64, f64) -> RGBColor,
}

impl<'a> Field<'a> {
    fn displacement(run: &'a SampledRun) -> Self {
        Self {
            values: &run.u,
            title: "displacement u(x, t)",
            label: "u",
            palette: ViridisRGB::get_color_normalized::<f64>,
        }
    }

    /// `θ(x, t)` of a bar with a temperature, in a colour map of its own (dark is cold).
    fn temperature(run: &'a SampledRun) -> Option<Self> {
        Some(Self {
            values: run.theta.as_deref()?,
            title: "temperature θ(x, t)",
            label: "θ",
            palette: Copper::get_color_normalized::<f64>,
        })
    }
}

/// `field` as a colour map on its own scale, with its colour bar on the right.
fn draw_map<DB: DrawingBackend>(
    area: &DrawingArea<DB, Shift>,
    run: &SampledRun,
    field: &Field,
) -> DrawResult
where
    DB::ErrorType: 'static,
{
    let area = area.titled(field.title, sans(PANEL_FONT))?;
    let (w, _) = area.dim_in_pixel();
    let (map_area, bar_area) = area.split_horizontally(w.saturating_sub(COLOUR_BAR_WIDTH));
    let (lo, hi) = value_range(field.values);
    let colour = |v: f64| {
        let level = ((v - lo) / (hi - lo) * COLOUR_LEVELS as f64).floor();
        let level = level.clamp(0.0, COLOUR_LEVELS as f64 - 1.0);
        (field.palette)(level + 0.5, 0.0, COLOUR_LEVELS as f64)
    };
    let extent = (run.length, run.final_time());
    let mut chart = space_time_chart(&map_area, extent)?;
    let nx = run.xs.len();
    draw_raster(&mut chart, extent, &run.xs, &run.ts, |i, k| {
        colour(field.values[k * nx + i])
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
        .x_desc(field.label)
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
        ContactPanel::Reactions => draw_reactions(area, run, run.final_time()),
        ContactPanel::ContactSet => {
            let episodes = run.summary.contact_episodes.get(OBSTACLE_EPISODES);
            let spans: Vec<[f64; 2]> = episodes
                .into_iter()
                .flatten()
                .map(|e| [e.start, e.end])
                .collect();
            draw_contact_set(area, &run.contact, &spans, run.length, run.final_time())
        }
    }
}

/// One line per constraint: its largest reaction in each time bin, against `t`, over the
/// contact episodes of `summary.json` shaded in the end's colour (the same episodes).
fn draw_reactions<DB: DrawingBackend>(
    area: &DrawingArea<DB, Shift>,
    run: &SampledRun,
    t_end: f64,
) -> DrawResult
where
    DB::ErrorType: 'static,
{
    let h = &run.contact;
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
    for j in 0..k {
        let colour = LINE_COLOURS[j % LINE_COLOURS.len()];
        let episodes = run.summary.contact_episodes.get(&h.names[j]);
        chart.draw_series(episodes.into_iter().flatten().map(|e| {
            Rectangle::new(
                [(e.start, 0.0), (e.end, top)],
                colour.mix(EPISODE_OPACITY).filled(),
            )
        }))?;
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

/// The key of the whole obstacle's contact episodes in `summary.json` (one list for the whole
/// contact set: an episode lasts while any node is in contact).
const OBSTACLE_EPISODES: &str = "obstacle";

/// The contact set over `(x, t)`: dark where a constraint touched its obstacle in a time bin,
/// over the contact episodes of the whole set (`summary.json`, `obstacle`) shaded as bands
/// across the bar, in the contact colour at the reaction panels' [`EPISODE_OPACITY`]. For
/// distributed obstacles (more constraints than [`MAX_REACTION_LINES`]).
fn draw_contact_set<DB: DrawingBackend>(
    area: &DrawingArea<DB, Shift>,
    h: &ContactHistory,
    episodes: &[[f64; 2]],
    length: f64,
    t_end: f64,
) -> DrawResult
where
    DB::ErrorType: 'static,
{
    let area = area.titled(
        "contact set (dark: u + a = 0; shaded: contact episodes)",
        sans(PANEL_FONT),
    )?;
    let extent = (length, t_end);
    let mut chart = space_time_chart(&area, extent)?;
    let shade = over_white(CONTACT_COLOUR, EPISODE_OPACITY);
    draw_raster(&mut chart, extent, &h.xs, &h.times, |j, bin| {
        let t = h.times[bin];
        if h.in_contact(bin, j) {
            CONTACT_COLOUR
        } else if episodes.iter().any(|e| e[0] <= t && t <= e[1]) {
            shade
        } else {
            WHITE
        }
    })
}

/// `colour` at `opacity` over white, as one opaque colour (the raster has no alpha).
fn over_white(colour: RGBColor, opacity: f64) -> RGBColor {
    let mix = |c: u8| (opacity * f64::from(c) + (1.0 - opacity) * 255.0).round() as u8;
    RGBColor(mix(colour.0), mix(colour.1), mix(colour.2))
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

#[cfg(test)]
mod tests {
    use super::*;

    /// Pixels of `colour` in a drawing of the contact set of `h` over `episodes`.
    fn pixels(h: &ContactHistory, episodes: &[[f64; 2]], colour: RGBColor) -> usize {
        const SIZE: (u32, u32) = (400, 300);
        let mut buf = vec![0u8; (SIZE.0 * SIZE.1 * 3) as usize];
        {
            let root = BitMapBackend::with_buffer(&mut buf, SIZE).into_drawing_area();
            root.fill(&WHITE).unwrap();
            draw_contact_set(&root, h, episodes, 1.0, 1.0).unwrap();
            root.present().unwrap();
        }
        let c = colour;
        buf.chunks(3).filter(|p| *p == [c.0, c.1, c.2]).count()
    }

    fn contact_pixels(h: &ContactHistory) -> usize {
        pixels(h, &[], CONTACT_COLOUR)
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

    /// The obstacle's contact episodes are shaded as bands across the bar, behind the contact
    /// set (which keeps its colour): none without episodes, the whole time bin of an episode
    /// across the bar but the touching cell.
    #[test]
    fn the_obstacle_episodes_are_shaded_behind_the_contact_set() {
        register_font().unwrap();
        let names = (0..5).map(|i| format!("node {i}")).collect();
        let xs = (0..5).map(|i| f64::from(i) * 0.25).collect();
        let mut h = ContactHistory::new(names, xs);
        for (bin, t) in [0.25, 0.5, 0.75, 1.0].into_iter().enumerate() {
            let mut gaps = [1.0; 5];
            if bin == 2 {
                gaps[3] = 0.0;
            }
            h.observe(t, &gaps, &[0.0; 5], true);
        }
        let shade = over_white(CONTACT_COLOUR, EPISODE_OPACITY);
        assert_eq!(pixels(&h, &[], shade), 0);
        let episode = [[0.7, 0.8]]; // the third bin's time, 0.75
        let (shaded, dark) = (
            pixels(&h, &episode, shade),
            pixels(&h, &episode, CONTACT_COLOUR),
        );
        assert_eq!(dark, contact_pixels(&h), "the contact set keeps its colour");
        // The band: the third of 4 time bins across the whole bar; node 3's column (a quarter
        // of the width: nodes 0 and 4 own half columns) stays dark, so 3x its pixels are shaded
        // (±10% for the pixel rounding of the bin edges).
        assert!(
            (27 * dark / 10..33 * dark / 10).contains(&shaded),
            "{shaded} shaded pixels, {dark} dark"
        );
    }
}
