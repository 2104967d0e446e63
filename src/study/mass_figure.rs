//! The figure of the mass variants on `impact` (`viscobar mass`): one row per variant
//! (consistent, redistributed, lumped), the energy `E^{n+1/2}` on the left and the reaction at
//! the left (contact) end on the right, with the closed-form reaction `v0` on `[t1, t1 + 2L]`
//! behind it; the same axes in every row. Only with the `plots` feature.

#![cfg(feature = "plots")]

use crate::scene::{self, MassVariant};
use crate::scheme::RunError;
use crate::study::figure_writer::{DrawResult, Drawing, FigureError, register_font, write_figure};
use crate::study::mass_variants::run_with_mass;
use plotters::coord::Shift;
use plotters::prelude::*;
use std::path::{Path, PathBuf};

/// Default output folder of `viscobar mass` (the committed copy is in `docs/figures`).
pub const DEFAULT_OUT: &str = "out/mass";
/// The figure's file stem.
pub const STEM: &str = "mass-variants-impact";
/// The scene drawn.
pub const SCENE: &str = "impact";
/// Size in pixels: three rows of two panels.
pub const SIZE: (u32, u32) = (1200, 900);

const TITLE_FONT: u32 = 24;
const PANEL_FONT: u32 = 18;
const AXIS_FONT: u32 = 16;
const TICK_FONT: u32 = 14;
/// Line colours, one per variant (consistent, redistributed, lumped).
const COLOURS: [RGBColor; 3] = [
    RGBColor(31, 119, 180),
    RGBColor(214, 39, 40),
    RGBColor(44, 160, 44),
];
/// Grey of the closed-form reaction.
const EXACT_GREY: RGBColor = RGBColor(150, 150, 150);
/// Margin around the data of each axis, as a share of its range.
const AXIS_MARGIN: f64 = 0.05;

/// One variant's run: `t`, `E^{n+1/2}` and the left end's reaction per step.
struct Series {
    mass: MassVariant,
    t: Vec<f64>,
    energy: Vec<f64>,
    reaction: Vec<f64>,
}

struct MassFigure {
    title: String,
    series: Vec<Series>,
    /// The closed-form contact interval and reaction, when the scene has one.
    exact: Option<([f64; 2], f64)>,
}

/// Runs `impact` (with `overrides`) once per variant and writes `mass-variants-impact.png` and
/// `.svg` into `out`; every run is done before a file is written. Returns the files written.
pub fn write_mass_figure(out: &Path, overrides: &[String]) -> Result<Vec<PathBuf>, FigureError> {
    let run_err = |source: RunError| FigureError::Run {
        scene: SCENE.to_string(),
        source,
    };
    let (_, scene) = scene::load(SCENE, overrides)
        .map_err(RunError::from)
        .map_err(run_err)?;
    let mut series = Vec::new();
    for mass in MassVariant::ALL {
        let (records, ..) = run_with_mass(SCENE, &scene, mass).map_err(run_err)?;
        series.push(Series {
            mass,
            t: records.iter().map(|r| r.time).collect(),
            energy: records.iter().map(|r| r.energy).collect(),
            reaction: records
                .iter()
                .map(|r| r.contact.groups[0].reaction)
                .collect(),
        });
    }
    let exact = crate::bar::closed_form::for_scene(SCENE, &scene)
        .and_then(|c| c.contact_intervals(scene.time.end))
        .and_then(|iv| iv.first().copied())
        .and_then(|iv| {
            let v0 = -crate::scene::Expression::parse("v", &scene.initial.velocity, false)
                .ok()?
                .eval(0.0, 0.0)
                .ok()?;
            Some((iv, v0))
        });
    let fig = MassFigure {
        title: format!(
            "{SCENE}: mass variants (α = {}, {} elements, Δt = {})",
            scene.bar.viscosity, scene.mesh.elements, scene.time.step
        ),
        series,
        exact,
    };
    register_font()?;
    std::fs::create_dir_all(out).map_err(|source| FigureError::Write {
        path: out.to_path_buf(),
        source,
    })?;
    let mut written = Vec::new();
    for ext in ["png", "svg"] {
        let path = out.join(format!("{STEM}.{ext}"));
        write_figure(&path, &fig)?;
        written.push(path);
    }
    Ok(written)
}

/// `[lo, hi]` of every value, widened by [`AXIS_MARGIN`] (and made non-empty).
fn range<'a>(values: impl Iterator<Item = &'a f64>) -> (f64, f64) {
    let (lo, hi) = values.fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), &v| {
        (a.min(v), b.max(v))
    });
    let span = if hi > lo { hi - lo } else { 1.0 };
    (lo - AXIS_MARGIN * span, hi + AXIS_MARGIN * span)
}

impl Drawing for MassFigure {
    fn size(&self) -> (u32, u32) {
        SIZE
    }

    fn draw_on<DB: DrawingBackend>(&self, root: &DrawingArea<DB, Shift>) -> DrawResult
    where
        DB::ErrorType: 'static,
    {
        let body = root.titled(&self.title, ("sans-serif", TITLE_FONT))?;
        let t_end = self.series[0].t.last().copied().unwrap_or(1.0);
        let e_range = range(self.series.iter().flat_map(|s| s.energy.iter()));
        let mut reactions: Vec<f64> = self
            .series
            .iter()
            .flat_map(|s| s.reaction.iter().copied())
            .collect();
        reactions.push(0.0);
        let r_range = range(reactions.iter());
        let rows = body.split_evenly((self.series.len(), 2));
        for (k, s) in self.series.iter().enumerate() {
            let colour = COLOURS[k % COLOURS.len()];
            let name = s.mass.name();
            let panels = [
                (
                    &rows[2 * k],
                    format!("{name}: energy E^(n+1/2)"),
                    e_range,
                    &s.energy,
                ),
                (
                    &rows[2 * k + 1],
                    format!("{name}: reaction at x = 0"),
                    r_range,
                    &s.reaction,
                ),
            ];
            for (p, (area, caption, (lo, hi), values)) in panels.into_iter().enumerate() {
                let mut chart = ChartBuilder::on(area)
                    .caption(caption, ("sans-serif", PANEL_FONT))
                    .margin(8)
                    .x_label_area_size(36)
                    .y_label_area_size(78)
                    .build_cartesian_2d(0.0..t_end, lo..hi)?;
                chart
                    .configure_mesh()
                    .x_desc("t")
                    .axis_desc_style(("sans-serif", AXIS_FONT))
                    .label_style(("sans-serif", TICK_FONT))
                    .y_label_formatter(&|v| {
                        if p == 0 {
                            format!("{v:.4}")
                        } else {
                            format!("{v:.2}")
                        }
                    })
                    .draw()?;
                if p == 1
                    && let Some(([a, b], v0)) = self.exact
                {
                    chart.draw_series(LineSeries::new(
                        [
                            (0.0, 0.0),
                            (a, 0.0),
                            (a, v0),
                            (b, v0),
                            (b, 0.0),
                            (t_end, 0.0),
                        ],
                        EXACT_GREY.stroke_width(2),
                    ))?;
                }
                chart.draw_series(LineSeries::new(
                    s.t.iter().copied().zip(values.iter().copied()),
                    colour.stroke_width(2),
                ))?;
            }
        }
        Ok(())
    }
}
