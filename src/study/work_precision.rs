//! The log-log work-precision diagram of `viscobar converge`: one line per solver setting,
//! the L2 error (max over t) against the wall time of the steps, as PNG or SVG.
//!
//! Apart from the talk's figures (`study::figures`): it shares only the file writing
//! (`study::figure_writer`). Only with the `plots` feature.

#![cfg(feature = "plots")]

use crate::study::figure_writer::{DrawResult, Drawing, FigureError, register_font, write_figure};
use plotters::coord::Shift;
use plotters::prelude::*;
use std::path::Path;

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
    write_figure(path, &WorkPrecision { title, lines })
}

/// A work-precision diagram to draw: its title and one line per solver setting.
struct WorkPrecision<'a> {
    title: &'a str,
    lines: &'a [WorkPrecisionLine],
}

impl Drawing for WorkPrecision<'_> {
    fn size(&self) -> (u32, u32) {
        WORK_PRECISION_SIZE
    }

    fn draw_on<DB: DrawingBackend>(&self, root: &DrawingArea<DB, Shift>) -> DrawResult
    where
        DB::ErrorType: 'static,
    {
        draw_work_precision(root, self.title, self.lines)
    }
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
