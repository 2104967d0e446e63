//! The contact pressure of a plane run with Signorini edges over `(s, t)`: one panel per
//! Signorini edge, the pressure `p_k = r_k / ω_k` of each node (its reaction over its
//! trapezoid share of the edge) as a colour map, `s` along the edge, `t` upwards
//! (`contact-pressure.png`/`.svg`, written beside the deformed mesh by `viscobar run SCENE
//! --figure`). Only with the `plots` feature.

#![cfg(feature = "plots")]

use crate::plane::PlaneSimulation;
use crate::scene::plane::{EDGE_NAMES, PlaneScene};
use crate::scheme::RunError;
use crate::study::figure_writer::{DrawResult, Drawing, FigureError, colour_bar, write_figure};
use plotters::coord::Shift;
use plotters::prelude::*;
use plotters::style::colors::colormaps::ViridisRGB;
use std::path::{Path, PathBuf};

/// Largest number of time rows kept (every k-th step beyond).
const MAX_ROWS: usize = 400;
const WIDTH: u32 = 900;
const PANEL_HEIGHT: u32 = 320;
const TITLE_HEIGHT: u32 = 40;
const BAR_HEIGHT: u32 = 70;

/// One edge's pressure map.
struct Panel {
    edge: usize,
    /// `s` of each node and the half-widths of its cell `[s − left, s + right]`.
    cells: Vec<(f64, f64)>,
    /// Rows: `t` and the pressure of each node.
    rows: Vec<(f64, Vec<f64>)>,
}

/// The figure's data.
pub struct ContactPressureFigure {
    title: String,
    panels: Vec<Panel>,
    dt_row: f64,
    max_pressure: f64,
}

impl ContactPressureFigure {
    /// Runs `scene` (which must have a Signorini edge) and keeps the pressures; `None` without
    /// contact normals.
    pub fn run(name: &str, scene: &PlaneScene) -> Result<Option<Self>, RunError> {
        let mut sim = PlaneSimulation::new(scene)?;
        let normals = sim.body().normals().to_vec();
        if normals.is_empty() {
            return Ok(None);
        }
        let mut panels: Vec<Panel> = Vec::new();
        for edge in 0..4 {
            let ks: Vec<usize> = (0..normals.len())
                .filter(|&k| normals[k].edge == edge)
                .collect();
            if ks.is_empty() {
                continue;
            }
            let cells = ks
                .iter()
                .enumerate()
                .map(|(i, &k)| {
                    let s = normals[k].s;
                    let lo = if i > 0 { normals[ks[i - 1]].s } else { s };
                    let hi = ks.get(i + 1).map_or(s, |&j| normals[j].s);
                    (s - 0.5 * (s - lo), s + 0.5 * (hi - s))
                })
                .collect();
            panels.push(Panel {
                edge,
                cells,
                rows: Vec::new(),
            });
        }
        let steps = scene.steps();
        let every = steps.div_ceil(MAX_ROWS).max(1);
        let mut max_pressure = 0.0f64;
        let mut keep = |sim: &PlaneSimulation, panels: &mut Vec<Panel>| {
            for p in panels.iter_mut() {
                let row: Vec<f64> = normals
                    .iter()
                    .zip(sim.reactions())
                    .filter(|(n, _)| n.edge == p.edge)
                    .map(|(n, r)| if n.weight > 0.0 { r / n.weight } else { 0.0 })
                    .collect();
                max_pressure = row.iter().fold(max_pressure, |a, v| a.max(*v));
                p.rows.push((sim.time(), row));
            }
        };
        keep(&sim, &mut panels);
        for _ in 1..steps {
            sim.step()?;
            if sim.step_index().is_multiple_of(every) {
                keep(&sim, &mut panels);
            }
        }
        Ok(Some(Self {
            title: format!(
                "{name}: contact pressure r/w over (s, t) (max {max_pressure:.3e}), one row per {} step(s)",
                every
            ),
            panels,
            dt_row: every as f64 * scene.time.step,
            max_pressure,
        }))
    }
}

fn colour(value: f64, max: f64) -> RGBColor {
    if value <= 0.0 {
        return WHITE;
    }
    ViridisRGB::get_color_normalized(value / max, 0.0, 1.0)
}

impl Drawing for ContactPressureFigure {
    fn size(&self) -> (u32, u32) {
        (
            WIDTH,
            TITLE_HEIGHT + self.panels.len() as u32 * PANEL_HEIGHT + BAR_HEIGHT,
        )
    }

    fn draw_on<DB: DrawingBackend>(&self, root: &DrawingArea<DB, Shift>) -> DrawResult
    where
        DB::ErrorType: 'static,
    {
        let (title, rest) = root.split_vertically(TITLE_HEIGHT);
        title.titled(&self.title, ("sans-serif", 15))?;
        let (panels, bar) = rest.split_vertically(self.panels.len() as u32 * PANEL_HEIGHT);
        let top = self.max_pressure.max(f64::MIN_POSITIVE);
        for (p, area) in self
            .panels
            .iter()
            .zip(panels.split_evenly((self.panels.len(), 1)))
        {
            let s0 = p.cells.first().map_or(0.0, |c| c.0);
            let s1 = p.cells.last().map_or(1.0, |c| c.1);
            let t1 = p.rows.last().map_or(1.0, |r| r.0) + self.dt_row;
            let mut chart = ChartBuilder::on(&area)
                .caption(format!("{} edge", EDGE_NAMES[p.edge]), ("sans-serif", 13))
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
            for (t, row) in &p.rows {
                chart.draw_series(row.iter().zip(&p.cells).filter(|(v, _)| **v > 0.0).map(
                    |(v, (a, b))| {
                        Rectangle::new([(*a, *t), (*b, t + self.dt_row)], colour(*v, top).filled())
                    },
                ))?;
            }
        }
        colour_bar(&bar, top, "contact pressure (white: no contact)", |v| {
            colour(v, top)
        })
    }
}

impl ContactPressureFigure {
    /// Writes `contact-pressure.png`/`.svg` into `out`; returns their paths.
    pub fn write(&self, out: &Path) -> Result<Vec<PathBuf>, FigureError> {
        let mut files = Vec::new();
        for ext in ["png", "svg"] {
            let path = out.join(format!("contact-pressure.{ext}"));
            write_figure(&path, self)?;
            files.push(path);
        }
        Ok(files)
    }
}
