//! The temperature of a plane run with `[heat]`: the field `θ` over the body at the end (each
//! cell coloured bilinearly from its nodes), and over `(s, t)` along one edge (the first with
//! friction, else the bottom) the state of its frictional nodes (open, sticking, slipping,
//! [`crate::scheme::NodeState`]) beside its temperature; one colour bar for both temperatures,
//! dark cold (`temperature.png`/`.svg`, written beside the deformed mesh by `viscobar run SCENE
//! --figure`; `viscobar figures` draws it of `plane-brake`). Only with `plots`.

#![cfg(feature = "plots")]

use crate::plane::PlaneSimulation;
use crate::plane::mesh::Grid;
use crate::scene::plane::{EDGE_NAMES, PlaneScene};
use crate::scheme::{Body, NodeState, RunError};
use crate::study::figure_writer::{
    DrawResult, Drawing, FigureError, colour_bar_between, write_figure,
};
use plotters::coord::Shift;
use plotters::prelude::*;
use plotters::style::colors::colormaps::Copper;
use std::path::{Path, PathBuf};

/// Largest number of time rows kept (every k-th step beyond).
const MAX_ROWS: usize = 400;
const WIDTH: u32 = 1000;
const TITLE_HEIGHT: u32 = 40;
const FIELD_HEIGHT: u32 = 300;
const MAP_HEIGHT: u32 = 320;
const BAR_HEIGHT: u32 = 70;
/// Sub-cells per cell side of the field's bilinear colouring.
const SUBDIVISION: usize = 4;
/// The field chart's caption and tick label strips, in pixels (for its aspect ratio).
const CAPTION: u32 = 24;
const X_LABELS: u32 = 30;
const Y_LABELS: u32 = 50;
const MARGIN: u32 = 6;

/// The figure's size in pixels.
pub const FIGURE_SIZE: (u32, u32) = (WIDTH, TITLE_HEIGHT + FIELD_HEIGHT + MAP_HEIGHT + BAR_HEIGHT);

/// One time row of the edge: `t_n`, per edge node its state (`None` without friction) and
/// `θ^{n−1/2}`.
type EdgeRow = (f64, Vec<Option<NodeState>>, Vec<f64>);

/// The figure's data.
pub struct TemperatureFigure {
    title: String,
    grid: Grid,
    /// `θ` at every node at the end.
    field: Vec<f64>,
    /// The edge drawn over `(s, t)` and its nodes' cells `[s−, s+]`.
    edge: usize,
    cells: Vec<(f64, f64)>,
    rows: Vec<EdgeRow>,
    dt_row: f64,
    t_end: f64,
    /// The colour range of both temperatures.
    range: (f64, f64),
}

/// The nodes of edge `edge` (0 left, 1 right, 2 bottom, 3 top), in the order of `s`.
fn edge_nodes(grid: &Grid, edge: usize) -> Vec<usize> {
    match edge {
        0 => (0..=grid.ny).map(|j| grid.node(0, j)).collect(),
        1 => (0..=grid.ny).map(|j| grid.node(grid.nx, j)).collect(),
        2 => (0..=grid.nx).map(|i| grid.node(i, 0)).collect(),
        _ => (0..=grid.nx).map(|i| grid.node(i, grid.ny)).collect(),
    }
}

impl TemperatureFigure {
    /// Runs `scene` and keeps its temperature; `None` without `[heat]`.
    pub fn run(name: &str, scene: &PlaneScene) -> Result<Option<Self>, RunError> {
        if scene.heat.is_none() {
            return Ok(None);
        }
        let mut sim = PlaneSimulation::new(scene)?;
        let grid = sim.discretisation().grid.clone();
        let friction = sim.contact().friction().clone();
        let normals = sim.body().normals().to_vec();
        let edge = (0..4)
            .find(|&e| friction.normals.iter().any(|&k| normals[k].edge == e))
            .unwrap_or(2);
        let nodes = edge_nodes(&grid, edge);
        // The frictional node `j` of each edge node, if any.
        let frictional: Vec<Option<usize>> = (nodes.iter())
            .map(|&node| {
                (0..friction.len()).find(|&j| {
                    let k = friction.normals[j];
                    normals[k].edge == edge && normals[k].node == node
                })
            })
            .collect();
        let s: Vec<f64> = (nodes.iter())
            .map(|&node| {
                let (x, y) = grid.point(node);
                if edge < 2 { y } else { x }
            })
            .collect();
        let last = s.len() - 1;
        let cells = (0..s.len())
            .map(|i| {
                let lo = s[i.saturating_sub(1)];
                let hi = s[(i + 1).min(last)];
                (0.5 * (s[i] + lo), 0.5 * (s[i] + hi))
            })
            .collect();
        let theta = |sim: &PlaneSimulation, node: usize| {
            sim.body()
                .temperature(sim.displacement(), node)
                .expect("a scene with [heat]")
        };
        let steps = scene.steps();
        let every = steps.div_ceil(MAX_ROWS).max(1);
        let mut rows: Vec<EdgeRow> = Vec::new();
        // From the first full step on: the start-up's increments classify no slip.
        for n in 1..steps {
            sim.step()?;
            if !(n + 1).is_multiple_of(every) {
                continue;
            }
            let [z, w] = sim.increments();
            let states = (frictional.iter())
                .map(|j| j.map(|j| sim.contact().node_state(j, (sim.state().u, z, w))))
                .collect();
            let temperatures = nodes.iter().map(|&node| theta(&sim, node)).collect();
            rows.push((sim.time(), states, temperatures));
        }
        let field: Vec<f64> = (0..grid.nodes()).map(|node| theta(&sim, node)).collect();
        let values = || field.iter().chain(rows.iter().flat_map(|r| r.2.iter()));
        let lo = values().fold(0.0f64, |a, &v| a.min(v));
        let mut hi = values().fold(f64::NEG_INFINITY, |a, &v| a.max(v));
        if hi <= lo {
            hi = lo + 1.0;
        }
        let dt = scene.time.step;
        let t_end = sim.time();
        let title = format!(
            "{name}: temperature θ at t = {}; along the {} edge over (s, t): state and θ",
            crate::output::text::output_time(t_end - 0.5 * dt),
            EDGE_NAMES[edge]
        );
        Ok(Some(Self {
            title,
            grid,
            field,
            edge,
            cells,
            rows,
            dt_row: every as f64 * dt,
            t_end,
            range: (lo, hi),
        }))
    }

    /// Writes `temperature.png`/`.svg` into `out`; returns their paths.
    pub fn write(&self, out: &Path) -> Result<Vec<PathBuf>, FigureError> {
        self.write_as(out, "temperature")
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

    fn colour(&self, v: f64) -> RGBColor {
        Copper::get_color_normalized(v, self.range.0, self.range.1)
    }

    /// The field at the end, each cell split into [`SUBDIVISION`]² rectangles coloured by the
    /// bilinear interpolant at their centres, on axes of the body's aspect ratio.
    fn draw_field<DB: DrawingBackend>(&self, area: &DrawingArea<DB, Shift>) -> DrawResult
    where
        DB::ErrorType: 'static,
    {
        let (w, h) = (self.grid.width, self.grid.height);
        let (pw, ph) = area.dim_in_pixel();
        let free_w = f64::from(pw - 2 * MARGIN - Y_LABELS);
        let free_h = f64::from(ph - 2 * MARGIN - X_LABELS - CAPTION);
        let (mut side, mut top) = (MARGIN, MARGIN);
        if free_w / free_h > w / h {
            side += ((free_w - free_h * w / h) / 2.0) as u32;
        } else {
            top += ((free_h - free_w * h / w) / 2.0) as u32;
        }
        let mut chart = ChartBuilder::on(area)
            .caption("temperature θ over the body", ("sans-serif", 13))
            .margin_left(side)
            .margin_right(side)
            .margin_top(top)
            .margin_bottom(top)
            .x_label_area_size(X_LABELS)
            .y_label_area_size(Y_LABELS)
            .build_cartesian_2d(0.0..w, 0.0..h)?;
        chart
            .configure_mesh()
            .disable_mesh()
            .x_label_style(("sans-serif", 12))
            .y_label_style(("sans-serif", 12))
            .axis_desc_style(("sans-serif", 13))
            .x_desc("x")
            .y_desc("y")
            .draw()?;
        let k = SUBDIVISION as f64;
        for j in 0..self.grid.ny {
            for i in 0..self.grid.nx {
                let [a, b, c, d] = self.grid.cell_nodes(i, j);
                let ((x0, y0), (x1, y1)) = (self.grid.point(a), self.grid.point(c));
                let [ta, tb, tc, td] = [a, b, c, d].map(|n| self.field[n]);
                chart.draw_series((0..SUBDIVISION * SUBDIVISION).map(|m| {
                    let (p, q) = ((m % SUBDIVISION) as f64, (m / SUBDIVISION) as f64);
                    let (xi, eta) = ((p + 0.5) / k, (q + 0.5) / k);
                    let v = (1.0 - eta) * ((1.0 - xi) * ta + xi * tb)
                        + eta * ((1.0 - xi) * td + xi * tc);
                    let corner = |r: f64, s: f64| (x0 + (x1 - x0) * r / k, y0 + (y1 - y0) * s / k);
                    Rectangle::new(
                        [corner(p, q), corner(p + 1.0, q + 1.0)],
                        self.colour(v).filled(),
                    )
                }))?;
            }
        }
        Ok(())
    }

    /// The edge over `(s, t)`: its nodes' states (`temperature = false`) or `θ`.
    fn draw_edge<DB: DrawingBackend>(
        &self,
        area: &DrawingArea<DB, Shift>,
        temperature: bool,
    ) -> DrawResult
    where
        DB::ErrorType: 'static,
    {
        let name = EDGE_NAMES[self.edge];
        let caption = if temperature {
            format!("{name} edge: temperature θ")
        } else {
            format!("{name} edge: state (white open, blue stick, red slip, grey no friction)")
        };
        let s0 = self.cells.first().map_or(0.0, |c| c.0);
        let s1 = self.cells.last().map_or(1.0, |c| c.1);
        let mut chart = ChartBuilder::on(area)
            .caption(caption, ("sans-serif", 13))
            .margin(6)
            .x_label_area_size(30)
            .y_label_area_size(50)
            .build_cartesian_2d(s0..s1, 0.0..self.t_end)?;
        chart
            .configure_mesh()
            .disable_mesh()
            .x_label_style(("sans-serif", 12))
            .y_label_style(("sans-serif", 12))
            .axis_desc_style(("sans-serif", 13))
            .x_desc("s")
            .y_desc("t")
            .draw()?;
        for (t, states, thetas) in &self.rows {
            let cells = self.cells.iter().zip(states.iter().zip(thetas));
            chart.draw_series(cells.filter_map(|(&(a, b), (state, &theta))| {
                let colour = match (temperature, state) {
                    (true, _) => self.colour(theta),
                    (false, None) => RGBColor(215, 215, 215),
                    (false, Some(NodeState::Open)) => return None,
                    (false, Some(NodeState::Stick)) => RGBColor(31, 119, 180),
                    (false, Some(NodeState::Slip)) => RGBColor(214, 39, 40),
                };
                Some(Rectangle::new(
                    [(a, t - self.dt_row), (b, *t)],
                    colour.filled(),
                ))
            }))?;
        }
        Ok(())
    }
}

impl Drawing for TemperatureFigure {
    fn size(&self) -> (u32, u32) {
        FIGURE_SIZE
    }

    fn draw_on<DB: DrawingBackend>(&self, root: &DrawingArea<DB, Shift>) -> DrawResult
    where
        DB::ErrorType: 'static,
    {
        let (title, rest) = root.split_vertically(TITLE_HEIGHT);
        title.titled(&self.title, ("sans-serif", 15))?;
        let (field, rest) = rest.split_vertically(FIELD_HEIGHT);
        self.draw_field(&field)?;
        let (maps, bar) = rest.split_vertically(MAP_HEIGHT);
        let (states, temperatures) = maps.split_horizontally(WIDTH / 2);
        self.draw_edge(&states, false)?;
        self.draw_edge(&temperatures, true)?;
        colour_bar_between(&bar, self.range, "temperature θ (dark: cold)", |v| {
            self.colour(v)
        })
    }
}
