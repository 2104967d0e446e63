//! The log-log work-precision diagram of `viscobar converge` and of VERIFICATION.md's "Error
//! against run time": one line per solver setting, labelled with the setting at its finest
//! point, the L2 error (max over t) against the wall time of the steps, with reference slopes,
//! as PNG or SVG.
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
const WORK_PRECISION_SIZE: (u32, u32) = (1000, 700);
/// Reference slopes drawn (dashed, grey): an order `p` in `dx` at a fixed `dt/dx` costs
/// `time ~ dx^(−2)` (nodes × steps), so its error falls like `time^(−p/2)`. Order 2 is the
/// scheme's for smooth solutions, 2/3 the kink rate of the impact solutions (VERIFICATION.md).
const REFERENCE_ORDERS: [(f64, &str); 2] = [
    (2.0, "order 2: slope -1"),
    (2.0 / 3.0, "order 2/3: slope -1/3"),
];
/// Factor widening the time axis to the right, so the labels beside the last points fit.
const LABEL_ROOM: f64 = 4.0;
/// Vertical pixels between the labels of consecutive lines at their finest points.
const LABEL_ROW: i32 = 14;
/// Grey of the reference slopes.
const SLOPE_COLOUR: RGBColor = RGBColor(130, 130, 130);

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
    // Room on the right for the settings' labels.
    let x1 = x1 * LABEL_ROOM;
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
    // Reference slopes through the first line's coarsest point, over the whole time axis.
    if let Some(&(t0, e0)) = lines.first().and_then(|l| l.1.first()) {
        for (p, label) in REFERENCE_ORDERS {
            let at = |t: f64| e0 * (t / t0).powf(-p / 2.0);
            let pts: Vec<(f64, f64)> = (0..=40)
                .map(|i| x0 * (x1 / x0).powf(f64::from(i) / 40.0))
                .map(|t| (t, at(t)))
                .filter(|&(_, e)| e >= y0 && e <= y1)
                .collect();
            // Dashes: every other segment of the sampled line.
            chart.draw_series(
                pts.windows(2)
                    .step_by(2)
                    .map(|w| PathElement::new(vec![w[0], w[1]], SLOPE_COLOUR.stroke_width(1))),
            )?;
            // Labelled a quarter of the way along, where it stays inside the plot.
            if let Some(&at) = pts.get(pts.len() / 4) {
                chart.draw_series(std::iter::once(
                    EmptyElement::at(at)
                        + Text::new(
                            label.to_string(),
                            (6, 4),
                            ("sans-serif", 13).into_font().color(&SLOPE_COLOUR),
                        ),
                ))?;
            }
        }
    }
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
        // The setting beside the line's finest (last) point; the lines often end at the same
        // error, so each label sits on its own row (LABEL_ROW pixels per line).
        if let Some(&last) = pts.last() {
            let row = (k as i32 - lines.len() as i32 / 2) * LABEL_ROW;
            chart.draw_series(std::iter::once(
                EmptyElement::at(last)
                    + Text::new(
                        label.clone(),
                        (8, row - 6),
                        ("sans-serif", 13).into_font().color(&colour),
                    ),
            ))?;
        }
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
