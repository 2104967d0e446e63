//! The plane body's figure: the deformed mesh (displacements magnified, the factor in the
//! title) coloured cell by cell by the von Mises stress at six times from `t = 0` to the end,
//! with a shared colour bar, as PNG and SVG (`viscobar run SCENE --figure`). Only with the
//! `plots` feature.
//!
//! Von Mises of plane strain at the cell centre, `σ = A ε(u) + α A ε(u_t)` (the velocity is
//! the scheme's `(u^n − u^{n−1})/Δt`), `σ_zz = λ tr ε(u + α u_t)`:
//! `σ_vM = sqrt(½((σxx − σyy)² + (σyy − σzz)² + (σzz − σxx)²) + 3σxy²)`.

#![cfg(feature = "plots")]

use crate::plane::PlaneSimulation;
use crate::plane::mesh::Grid;
use crate::scene::plane::PlaneScene;
use crate::scheme::RunError;
use crate::study::figure_writer::{
    DrawResult, Drawing, FigureError, colour_bar, register_font, write_figure,
};
use plotters::coord::Shift;
use plotters::prelude::*;
use plotters::style::colors::colormaps::ViridisRGB;
use std::path::{Path, PathBuf};

/// Snapshots drawn: `t = 0`, the end and four times evenly between.
pub const SNAPSHOTS: usize = 6;
/// The largest magnified displacement is this fraction of the larger side of the body.
const MAGNIFIED_SHARE: f64 = 0.1;
/// Width of the figure in pixels.
const WIDTH: u32 = 1000;
/// Bounds of a panel's height in pixels (its aspect follows the body's).
const PANEL_HEIGHT: (u32, u32) = (90, 300);
/// Height of the title and of the colour bar strips.
const TITLE_HEIGHT: u32 = 50;
const BAR_HEIGHT: u32 = 70;

/// Why the figure could not be made.
#[derive(Debug, thiserror::Error)]
pub enum PlaneFigureError {
    #[error(transparent)]
    Run(#[from] RunError),
    #[error(transparent)]
    Figure(#[from] FigureError),
}

impl PlaneFigureError {
    /// 2 for bad input, 1 otherwise.
    pub fn exit_code(&self) -> i32 {
        match self {
            PlaneFigureError::Run(e) => e.exit_code(),
            PlaneFigureError::Figure(e) => e.exit_code(),
        }
    }
}

/// One drawn time: the displacement and the von Mises stress of each cell.
struct Snapshot {
    t: f64,
    u: Vec<f64>,
    von_mises: Vec<f64>,
}

/// The figure's data.
pub struct PlaneFigure {
    title: String,
    grid: Grid,
    magnification: f64,
    snapshots: Vec<Snapshot>,
    max_stress: f64,
}

/// The von Mises stress of every cell (row by row) at its centre.
fn von_mises(grid: &Grid, scene: &PlaneScene, u: &[f64], v: &[f64]) -> Vec<f64> {
    let (lam, mu, alpha) = (scene.plane.lambda, scene.plane.mu, scene.plane.viscosity);
    let mut out = Vec::with_capacity(grid.cells());
    for j in 0..grid.ny {
        let (hx, hy) = (grid.hx, grid.hy(j));
        for i in 0..grid.nx {
            let [a, b, c, d] = grid.cell_nodes(i, j);
            // At the centre: ∂x = (right − left)/hx averaged over the rows, ∂y likewise.
            let grad = |f: &dyn Fn(usize) -> f64| {
                (
                    0.5 * ((f(b) - f(a)) + (f(c) - f(d))) / hx,
                    0.5 * ((f(d) - f(a)) + (f(c) - f(b))) / hy,
                )
            };
            let w = |n: usize, k: usize| u[2 * n + k] + alpha * v[2 * n + k];
            let (xx, xy) = grad(&|n| w(n, 0));
            let (yx, yy) = grad(&|n| w(n, 1));
            let tr = xx + yy;
            let (sxx, syy, szz) = (lam * tr + 2.0 * mu * xx, lam * tr + 2.0 * mu * yy, lam * tr);
            let sxy = mu * (xy + yx);
            let s = 0.5 * ((sxx - syy).powi(2) + (syy - szz).powi(2) + (szz - sxx).powi(2))
                + 3.0 * sxy * sxy;
            out.push(s.sqrt());
        }
    }
    out
}

impl PlaneFigure {
    /// Runs `scene` and keeps [`SNAPSHOTS`] times.
    pub fn run(name: &str, scene: &PlaneScene) -> Result<Self, RunError> {
        let steps = scene.steps();
        let wanted: Vec<usize> = (0..SNAPSHOTS)
            .map(|k| (k * steps + (SNAPSHOTS - 1) / 2) / (SNAPSHOTS - 1))
            .collect();
        let prepared = PlaneSimulation::prepare(scene)?;
        let grid = prepared.body().discretisation().grid.clone();
        let mut snapshots = Vec::new();
        let (mut u0, mut v0) = (vec![0.0; grid.dofs()], vec![0.0; grid.dofs()]);
        let state = prepared.state();
        prepared.body().scatter_into(state.u, 1.0, &mut u0);
        prepared.body().scatter_into(state.w, state.scale, &mut v0);
        snapshots.push(Snapshot {
            t: 0.0,
            von_mises: von_mises(&grid, scene, &u0, &v0),
            u: u0,
        });
        let mut sim = prepared.start()?;
        let mut v = vec![0.0; grid.dofs()];
        let mut keep = |sim: &PlaneSimulation, snapshots: &mut Vec<Snapshot>| {
            if wanted[1..].contains(&sim.step_index()) {
                let u = sim.displacement_dofs();
                sim.velocity_into(&mut v);
                snapshots.push(Snapshot {
                    t: sim.time(),
                    von_mises: von_mises(&grid, scene, &u, &v),
                    u,
                });
            }
        };
        keep(&sim, &mut snapshots);
        for _ in 1..steps {
            sim.step()?;
            keep(&sim, &mut snapshots);
        }
        let max_u = snapshots
            .iter()
            .flat_map(|s| s.u.iter())
            .fold(0.0f64, |a, v| a.max(v.abs()));
        let side = scene.plane.width.max(scene.plane.height);
        let magnification = if max_u > 0.0 {
            round_to_125(MAGNIFIED_SHARE * side / max_u)
        } else {
            1.0
        };
        let max_stress = snapshots
            .iter()
            .flat_map(|s| s.von_mises.iter())
            .fold(0.0f64, |a, v| a.max(*v));
        let title = format!(
            "{name}: deformed mesh (displacement x {magnification}), colour: von Mises stress \
             (max {max_stress:.3e}); {} x {} cells, lambda = {}, mu = {}, alpha = {}",
            grid.nx, grid.ny, scene.plane.lambda, scene.plane.mu, scene.plane.viscosity
        );
        Ok(Self {
            title,
            grid,
            magnification,
            snapshots,
            max_stress,
        })
    }

    /// The magnification of the displacements.
    pub fn magnification(&self) -> f64 {
        self.magnification
    }

    /// The deformed position of a node.
    fn position(&self, s: &Snapshot, node: usize) -> (f64, f64) {
        let (x, y) = self.grid.point(node);
        (
            x + self.magnification * s.u[2 * node],
            y + self.magnification * s.u[2 * node + 1],
        )
    }

    /// The box holding every deformed node of every snapshot, with a margin.
    fn bounds(&self) -> ((f64, f64), (f64, f64)) {
        let (mut x0, mut x1, mut y0, mut y1) = (0.0f64, self.grid.width, 0.0f64, self.grid.height);
        for s in &self.snapshots {
            for node in 0..self.grid.nodes() {
                let (x, y) = self.position(s, node);
                (x0, x1, y0, y1) = (x0.min(x), x1.max(x), y0.min(y), y1.max(y));
            }
        }
        let m = 0.03 * (x1 - x0).max(y1 - y0);
        ((x0 - m, x1 + m), (y0 - m, y1 + m))
    }

    fn panel_height(&self) -> u32 {
        let ((x0, x1), (y0, y1)) = self.bounds();
        let h = (f64::from(WIDTH) * (y1 - y0) / (x1 - x0)) as u32 + 30;
        h.clamp(PANEL_HEIGHT.0, PANEL_HEIGHT.1)
    }
}

/// `v` rounded down to 1, 2 or 5 times a power of ten (a factor a reader can state).
fn round_to_125(v: f64) -> f64 {
    let p = 10f64.powf(v.log10().floor());
    let m = v / p;
    let d = if m >= 5.0 {
        5.0
    } else if m >= 2.0 {
        2.0
    } else {
        1.0
    };
    // Parsed from text so that `2e-3` prints as such.
    format!("{:e}", d * p).parse().unwrap_or(d * p)
}

fn colour(value: f64, max: f64) -> RGBColor {
    let s = if max > 0.0 { value / max } else { 0.0 };
    ViridisRGB::get_color_normalized(s, 0.0, 1.0)
}

impl Drawing for PlaneFigure {
    fn size(&self) -> (u32, u32) {
        let n = self.snapshots.len() as u32;
        (WIDTH, TITLE_HEIGHT + n * self.panel_height() + BAR_HEIGHT)
    }

    fn draw_on<DB: DrawingBackend>(&self, root: &DrawingArea<DB, Shift>) -> DrawResult
    where
        DB::ErrorType: 'static,
    {
        let (title, rest) = root.split_vertically(TITLE_HEIGHT);
        title.titled(&self.title, ("sans-serif", 15))?;
        let n = self.snapshots.len() as u32;
        let (panels, bar) = rest.split_vertically(n * self.panel_height());
        let ((x0, x1), (y0, y1)) = self.bounds();
        for (s, area) in self
            .snapshots
            .iter()
            .zip(panels.split_evenly((self.snapshots.len(), 1)))
        {
            let mut chart = ChartBuilder::on(&area)
                .caption(
                    format!("t = {}", crate::output::text::output_time(s.t)),
                    ("sans-serif", 13),
                )
                .margin(4)
                .build_cartesian_2d(x0..x1, y0..y1)?;
            chart.plotting_area().fill(&WHITE)?;
            for j in 0..self.grid.ny {
                for i in 0..self.grid.nx {
                    let corners: Vec<(f64, f64)> = self
                        .grid
                        .cell_nodes(i, j)
                        .iter()
                        .map(|&node| self.position(s, node))
                        .collect();
                    let c = colour(s.von_mises[j * self.grid.nx + i], self.max_stress);
                    chart.draw_series(std::iter::once(Polygon::new(corners, c.filled())))?;
                }
            }
            // The undeformed outline, for reference.
            let (w, h) = (self.grid.width, self.grid.height);
            chart.draw_series(std::iter::once(PathElement::new(
                vec![(0.0, 0.0), (w, 0.0), (w, h), (0.0, h), (0.0, 0.0)],
                BLACK.mix(0.4),
            )))?;
        }
        // Colour bar: 0 … max von Mises stress.
        let top = self.max_stress.max(f64::MIN_POSITIVE);
        colour_bar(&bar, top, "von Mises stress", |v| colour(v, top))
    }
}

/// Runs `scene` and writes `deformed.png` and `deformed.svg` into `out`, with Signorini
/// edges `contact-pressure.png`/`.svg` (`crate::study::plane_contact_figure`), with
/// friction `friction-state.png`/`.svg` (`crate::study::friction_figure`) and with `[heat]`
/// `temperature.png`/`.svg` (`crate::study::temperature_figure`); returns their paths.
pub fn write(name: &str, scene: &PlaneScene, out: &Path) -> Result<Vec<PathBuf>, PlaneFigureError> {
    register_font()?;
    let figure = PlaneFigure::run(name, scene)?;
    std::fs::create_dir_all(out).map_err(|source| FigureError::Write {
        path: out.to_path_buf(),
        source,
    })?;
    let mut files = Vec::new();
    for ext in ["png", "svg"] {
        let path = out.join(format!("deformed.{ext}"));
        write_figure(&path, &figure)?;
        files.push(path);
    }
    if let Some(contact) =
        crate::study::plane_contact_figure::ContactPressureFigure::run(name, scene)?
    {
        files.extend(contact.write(out)?);
    }
    if let Some(friction) = crate::study::friction_figure::FrictionFigure::run(name, scene)? {
        files.extend(friction.write(out)?);
    }
    if let Some(heat) = crate::study::temperature_figure::TemperatureFigure::run(name, scene)? {
        files.extend(heat.write(out)?);
    }
    Ok(files)
}
