//! Writing a figure as PNG or SVG, whole or absent: every file is drawn to a temporary name in
//! the output folder and renamed into place, and the SVG backend's embedded-bitmap MIME type is
//! corrected. Text is laid out with the embedded DejaVu Sans font through plotters' `ab_glyph`
//! feature, so no system font library is needed.
//!
//! Shared by the talk's figures (`study::figures`) and the work-precision diagram
//! (`study::work_precision`). Only with the `plots` feature.

#![cfg(feature = "plots")]

use crate::scheme::RunError;
use plotters::coord::Shift;
use plotters::prelude::*;
use std::path::{Path, PathBuf};

/// Why a figure could not be made: a scene of `viscobar figures` failed, or drawing, writing or
/// the font did.
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

pub(crate) type DrawResult = Result<(), Box<dyn std::error::Error>>;

/// A figure to draw: its size in pixels and its drawing on a white page.
pub(crate) trait Drawing {
    fn size(&self) -> (u32, u32);

    fn draw_on<DB: DrawingBackend>(&self, root: &DrawingArea<DB, Shift>) -> DrawResult
    where
        DB::ErrorType: 'static;
}

/// Fills `root` white, draws `fig` on it and presents it.
fn render<DB: DrawingBackend>(fig: &impl Drawing, root: &DrawingArea<DB, Shift>) -> DrawResult
where
    DB::ErrorType: 'static,
{
    root.fill(&WHITE)?;
    fig.draw_on(root)?;
    Ok(root.present()?)
}

/// Draws `fig` as PNG or SVG (by the extension of `path`) and writes it via a temporary file in
/// the same folder, renamed into place only when complete.
pub(crate) fn write_figure(path: &Path, fig: &impl Drawing) -> Result<(), FigureError> {
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
            render(fig, &root)
        };
        // plotters-svg 0.3.7 writes the invalid MIME type `data:png` for embedded bitmaps.
        drawn.map_err(draw_err).and_then(|()| {
            let svg = svg.replace("\"data:png;base64,", "\"data:image/png;base64,");
            std::fs::write(&tmp, svg).map_err(write_err)
        })
    } else {
        let root = BitMapBackend::new(&tmp, fig.size()).into_drawing_area();
        render(fig, &root).map_err(draw_err)
    };
    let result = result.and_then(|()| std::fs::rename(&tmp, path).map_err(write_err));
    if result.is_err() {
        let _ = std::fs::remove_file(&tmp);
    }
    result
}

/// A horizontal colour bar over `0 … top` on `area`, labelled `label`: 200 cells, each
/// coloured by `colour` at its right end (so a map that is white at 0 shows no white cell).
pub(crate) fn colour_bar<DB: DrawingBackend>(
    area: &DrawingArea<DB, Shift>,
    top: f64,
    label: &str,
    colour: impl Fn(f64) -> RGBColor,
) -> DrawResult
where
    DB::ErrorType: 'static,
{
    colour_bar_between(area, (0.0, top), label, colour)
}

/// [`colour_bar`] over `lo … top`.
pub(crate) fn colour_bar_between<DB: DrawingBackend>(
    area: &DrawingArea<DB, Shift>,
    (lo, top): (f64, f64),
    label: &str,
    colour: impl Fn(f64) -> RGBColor,
) -> DrawResult
where
    DB::ErrorType: 'static,
{
    let mut chart = ChartBuilder::on(area)
        .margin_left(40)
        .margin_right(40)
        .margin_bottom(8)
        .x_label_area_size(30)
        .build_cartesian_2d(lo..top, 0.0..1.0)?;
    chart
        .configure_mesh()
        .disable_y_axis()
        .disable_mesh()
        .x_labels(6)
        .x_label_formatter(&|v| format!("{v:.2e}"))
        .x_label_style(("sans-serif", 12))
        .axis_desc_style(("sans-serif", 13))
        .x_desc(label)
        .draw()?;
    let cells = 200;
    chart.draw_series((0..cells).map(|k| {
        let (a, b) = (
            lo + (top - lo) * k as f64 / cells as f64,
            lo + (top - lo) * (k + 1) as f64 / cells as f64,
        );
        Rectangle::new([(a, 0.0), (b, 1.0)], colour(b).filled())
    }))?;
    Ok(())
}
