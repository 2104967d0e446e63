//! The frictional contact of a plane run over `(s, t)`: for each edge with friction, the state
//! of each node (open, sticking, slipping towards `+s` or `−s`, [`crate::scheme::is_slipping`]),
//! its normal pressure `r_N/ω` and its tangential traction `r_T/ω` (`ω` its trapezoid share of
//! the edge) as colour maps, `s` along the edge, `t` upwards (`friction-state.png`/`.svg`,
//! written beside the deformed mesh by `viscobar run SCENE --figure`; `viscobar figures` draws
//! it of the stick–slip scene). The slip is relative to a sliding obstacle. Only with `plots`.

#![cfg(feature = "plots")]

use crate::plane::PlaneSimulation;
use crate::scene::plane::{EDGE_NAMES, PlaneScene};
use crate::scheme::{RunError, in_contact, is_slipping};
use crate::study::figure_writer::{DrawResult, Drawing, FigureError, colour_bar, write_figure};
use plotters::coord::Shift;
use plotters::prelude::*;
use plotters::style::colors::colormaps::ViridisRGB;
use std::path::{Path, PathBuf};

/// Largest number of time rows kept (every k-th step beyond).
const MAX_ROWS: usize = 400;
const WIDTH: u32 = 900;
const PANEL_HEIGHT: u32 = 260;
const TITLE_HEIGHT: u32 = 40;
const BAR_HEIGHT: u32 = 70;

/// A node's state: open, sticking, slipping towards `+s`, towards `−s`.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum State {
    Open,
    Stick,
    SlipUp,
    SlipDown,
}

/// One time row of an edge: per frictional node its state, pressure and traction.
type NodeRow = Vec<(State, f64, f64)>;

/// One frictional edge's maps.
struct EdgeMaps {
    edge: usize,
    /// The frictional nodes of the edge: their index `j`, and their cell `[s − , s + ]`.
    nodes: Vec<usize>,
    cells: Vec<(f64, f64)>,
    /// Rows: `t` and, per node, its state, pressure and traction.
    rows: Vec<(f64, NodeRow)>,
}

/// The figure's data.
pub struct FrictionFigure {
    title: String,
    edges: Vec<EdgeMaps>,
    dt_row: f64,
    max_pressure: f64,
    max_traction: f64,
}

impl FrictionFigure {
    /// Runs `scene` and keeps its frictional nodes' states and forces; `None` without
    /// frictional nodes.
    pub fn run(name: &str, scene: &PlaneScene) -> Result<Option<Self>, RunError> {
        let mut sim = PlaneSimulation::new(scene)?;
        let friction = sim.contact().friction().clone();
        if friction.is_empty() {
            return Ok(None);
        }
        let normals = sim.body().normals().to_vec();
        let mut edges: Vec<EdgeMaps> = Vec::new();
        for edge in 0..4 {
            let nodes: Vec<usize> = (0..friction.len())
                .filter(|&j| normals[friction.normals[j]].edge == edge)
                .collect();
            if nodes.is_empty() {
                continue;
            }
            let s = |i: usize| normals[friction.normals[nodes[i]]].s;
            let cells = (0..nodes.len())
                .map(|i| {
                    let lo = if i > 0 { s(i - 1) } else { s(i) };
                    let hi = if i + 1 < nodes.len() { s(i + 1) } else { s(i) };
                    (0.5 * (s(i) + lo), 0.5 * (s(i) + hi))
                })
                .collect();
            edges.push(EdgeMaps {
                edge,
                nodes,
                cells,
                rows: Vec::new(),
            });
        }
        let steps = scene.steps();
        let every = steps.div_ceil(MAX_ROWS).max(1);
        let (mut max_pressure, mut max_traction) = (0.0f64, 0.0f64);
        let mut gaps = vec![0.0; sim.contact().len()];
        let mut previous: Vec<f64> = friction.tangents.iter().map(|_| 0.0).collect();
        let mut obstacle = previous.clone();
        for n in 1..steps {
            for (p, &t) in previous.iter_mut().zip(&friction.tangents) {
                *p = sim.state().w[t];
            }
            sim.step()?;
            if let Some(slide) = sim.contact().slide() {
                obstacle.copy_from_slice(slide.displacement());
            }
            if !(n + 1).is_multiple_of(every) {
                continue;
            }
            sim.gaps_into(&mut gaps);
            let (w, r, rt) = (sim.state().w, sim.reactions(), sim.tangential_reactions());
            for e in &mut edges {
                let row: NodeRow = (e.nodes.iter())
                    .map(|&j| {
                        let k = friction.normals[j];
                        // Relative to a sliding obstacle (`crate::scheme::friction`).
                        let delta = w[friction.tangents[j]] + previous[j] - obstacle[j];
                        let state = match (in_contact(gaps[k]), is_slipping(delta)) {
                            (false, _) => State::Open,
                            (true, false) => State::Stick,
                            (true, true) if delta > 0.0 => State::SlipUp,
                            (true, true) => State::SlipDown,
                        };
                        let weight = normals[k].weight;
                        let (p, tr) = if weight > 0.0 {
                            (r[k] / weight, rt[j] / weight)
                        } else {
                            (0.0, 0.0)
                        };
                        max_pressure = max_pressure.max(p);
                        max_traction = max_traction.max(tr.abs());
                        (state, p, tr)
                    })
                    .collect();
                e.rows.push((sim.time(), row));
            }
        }
        Ok(Some(Self {
            title: format!(
                "{name}: frictional contact over (s, t), one row per {every} step(s) \
                 (max pressure {max_pressure:.3e}, max traction {max_traction:.3e})"
            ),
            edges,
            dt_row: every as f64 * scene.time.step,
            max_pressure,
            max_traction,
        }))
    }

    /// Writes `friction-state.png`/`.svg` into `out`; returns their paths.
    pub fn write(&self, out: &Path) -> Result<Vec<PathBuf>, FigureError> {
        self.write_as(out, "friction-state")
    }

    /// Writes `<stem>.png`/`.svg` into `out`; returns their paths.
    pub fn write_as(&self, out: &Path, stem: &str) -> Result<Vec<PathBuf>, FigureError> {
        let mut files = Vec::new();
        for ext in ["png", "svg"] {
            let path = out.join(format!("{stem}.{ext}"));
            write_figure(&path, self)?;
            files.push(path);
        }
        Ok(files)
    }
}

/// The figure's size in pixels with `edges` frictional edges (three maps each).
pub const fn figure_size(edges: usize) -> (u32, u32) {
    let panels = 3 * edges as u32;
    (WIDTH, TITLE_HEIGHT + panels * PANEL_HEIGHT + 2 * BAR_HEIGHT)
}

fn state_colour(s: State) -> RGBColor {
    match s {
        State::Open => WHITE,
        State::Stick => RGBColor(31, 119, 180),
        State::SlipUp => RGBColor(214, 39, 40),
        State::SlipDown => RGBColor(255, 160, 40),
    }
}

/// Blue (negative) through white to red (positive), `v` in `[−top, top]`.
fn diverging(v: f64, top: f64) -> RGBColor {
    let x = (v / top).clamp(-1.0, 1.0);
    let fade = |c: u8, a: f64| (255.0 - (255.0 - f64::from(c)) * a) as u8;
    if x >= 0.0 {
        RGBColor(fade(214, x), fade(39, x), fade(40, x))
    } else {
        RGBColor(fade(31, -x), fade(119, -x), fade(180, -x))
    }
}

impl Drawing for FrictionFigure {
    fn size(&self) -> (u32, u32) {
        figure_size(self.edges.len())
    }

    fn draw_on<DB: DrawingBackend>(&self, root: &DrawingArea<DB, Shift>) -> DrawResult
    where
        DB::ErrorType: 'static,
    {
        let (title, rest) = root.split_vertically(TITLE_HEIGHT);
        title.titled(&self.title, ("sans-serif", 15))?;
        let panels = 3 * self.edges.len();
        let (maps, bars) = rest.split_vertically(panels as u32 * PANEL_HEIGHT);
        let areas = maps.split_evenly((panels, 1));
        let (pressure_top, traction_top) = (
            self.max_pressure.max(f64::MIN_POSITIVE),
            self.max_traction.max(f64::MIN_POSITIVE),
        );
        for (e, areas) in self.edges.iter().zip(areas.chunks(3)) {
            let name = EDGE_NAMES[e.edge];
            let captions = [
                format!(
                    "{name} edge: state (white open, blue stick, red slip towards +s, orange towards −s)"
                ),
                format!("{name} edge: normal pressure r_N/w"),
                format!("{name} edge: tangential traction r_T/w (red along +s)"),
            ];
            for (panel, (area, caption)) in areas.iter().zip(captions).enumerate() {
                let s0 = e.cells.first().map_or(0.0, |c| c.0);
                let s1 = e.cells.last().map_or(1.0, |c| c.1);
                let t1 = e.rows.last().map_or(1.0, |r| r.0) + self.dt_row;
                let mut chart = ChartBuilder::on(area)
                    .caption(caption, ("sans-serif", 13))
                    .margin(6)
                    .x_label_area_size(30)
                    .y_label_area_size(50)
                    .build_cartesian_2d(s0..s1, 0.0..t1)?;
                chart
                    .configure_mesh()
                    .disable_mesh()
                    .x_label_style(("sans-serif", 12))
                    .y_label_style(("sans-serif", 12))
                    .axis_desc_style(("sans-serif", 13))
                    .x_desc("s")
                    .y_desc("t")
                    .draw()?;
                for (t, row) in &e.rows {
                    chart.draw_series(row.iter().zip(&e.cells).filter_map(
                        |(&(state, p, tr), &(a, b))| {
                            let colour = match panel {
                                0 if state != State::Open => state_colour(state),
                                1 if p > 0.0 => {
                                    ViridisRGB::get_color_normalized(p / pressure_top, 0.0, 1.0)
                                }
                                2 if tr != 0.0 => diverging(tr, traction_top),
                                _ => return None,
                            };
                            Some(Rectangle::new(
                                [(a, *t), (b, t + self.dt_row)],
                                colour.filled(),
                            ))
                        },
                    ))?;
                }
            }
        }
        let (pressure_bar, traction_bar) = bars.split_vertically(BAR_HEIGHT);
        colour_bar(
            &pressure_bar,
            pressure_top,
            "normal pressure (white: none)",
            |v| ViridisRGB::get_color_normalized(v / pressure_top, 0.0, 1.0),
        )?;
        colour_bar(
            &traction_bar,
            traction_top,
            "tangential traction magnitude (red along +s, blue along −s)",
            |v| diverging(v, traction_top),
        )
    }
}
