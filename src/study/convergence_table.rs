//! The report of a refinement study ([`Study`]): `convergence.csv`, the Markdown table of the
//! runs with the observed orders, and the work-precision diagram's data.

use crate::output::files::write_atomically;
use crate::study::accuracy::observed_order;
use crate::study::converge::{ConvergeError, Row, SolverSetting, Study};
use std::fmt::Write as _;
use std::path::{Path, PathBuf};

/// The columns of `convergence.csv` (README, "Refinement study").
pub const CSV_HEADER: [&str; 14] = [
    "solver",
    "setting",
    "level",
    "elements",
    "dt",
    "steps",
    "l2_error",
    "h1_error",
    "energy_error",
    "contact_time_error",
    "wall_time_s",
    "time_relative_to_exact",
    "reference",
    "reference_l2_error_estimate",
];

/// One CSV cell per RFC 4180: quoted (its quotes doubled) when it holds a comma, a double
/// quote, a carriage return or a line feed; as is otherwise.
pub fn csv_cell(text: &str) -> String {
    if text.contains([',', '"', '\r', '\n']) {
        format!("\"{}\"", text.replace('"', "\"\""))
    } else {
        text.to_string()
    }
}

/// The settings in the order they first appear.
fn settings_of(rows: &[Row]) -> Vec<SolverSetting> {
    let mut out: Vec<SolverSetting> = Vec::new();
    for r in rows {
        if !out.contains(&r.setting) {
            out.push(r.setting);
        }
    }
    out
}

/// A column of [`Study::table`]: its header and the cell of a row.
pub type Column = (&'static str, fn(&Row) -> String);

impl Study {
    /// Observed orders (L2, H1) per setting: least-squares slopes of log error against log dx.
    pub fn orders(&self) -> Vec<(SolverSetting, f64, f64)> {
        settings_of(&self.rows)
            .into_iter()
            .map(|s| {
                let rs: Vec<&Row> = self.rows.iter().filter(|r| r.setting == s).collect();
                let h: Vec<f64> = rs.iter().map(|r| r.dx).collect();
                let l2: Vec<f64> = rs.iter().map(|r| r.l2_error).collect();
                let h1: Vec<f64> = rs.iter().map(|r| r.h1_error).collect();
                (s, observed_order(&h, &l2), observed_order(&h, &h1))
            })
            .collect()
    }

    /// `convergence.csv`: RFC 4180 (comma-separated, a cell with a comma, a double quote or a
    /// line break quoted, its quotes doubled; CRLF-free, one header line). One row per run; the
    /// reference and its estimated error repeated on every row so each row stands alone.
    pub fn csv(&self) -> String {
        let mut out = CSV_HEADER.join(",");
        out.push('\n');
        let opt = |v: Option<f64>| v.map_or(String::new(), |v| format!("{v:e}"));
        let relative = self.time_relative_to_exact();
        for (r, rel) in self.rows.iter().zip(relative) {
            let cells = [
                r.setting.solver().to_string(),
                r.setting.setting(),
                r.level.to_string(),
                r.elements.to_string(),
                format!("{:e}", r.dt),
                r.steps.to_string(),
                format!("{:e}", r.l2_error),
                format!("{:e}", r.h1_error),
                opt(r.energy_error),
                opt(r.contact_time_error),
                format!("{:.6}", r.wall_time_s),
                opt(rel),
                self.reference.clone(),
                opt(self.reference_error),
            ];
            let cells: Vec<String> = cells.iter().map(|c| csv_cell(c)).collect();
            out.push_str(&cells.join(","));
            out.push('\n');
        }
        out
    }

    /// Each row's wall time over the exact solver's on the same level (`None` without an
    /// exact row at that level).
    pub fn time_relative_to_exact(&self) -> Vec<Option<f64>> {
        self.rows
            .iter()
            .map(|r| {
                self.rows
                    .iter()
                    .find(|e| e.setting == SolverSetting::Exact && e.level == r.level)
                    .filter(|e| e.wall_time_s > 0.0)
                    .map(|e| r.wall_time_s / e.wall_time_s)
            })
            .collect()
    }

    /// The Markdown table of the runs, one row each: the `lead` columns, the four errors
    /// (`-` where one does not apply), then the `trail` columns. `viscobar converge` and
    /// VERIFICATION.md (section "Falling bar") both render through it.
    pub fn table(&self, lead: &[Column], trail: &[Column]) -> String {
        fn opt(v: Option<f64>) -> String {
            v.map_or("-".to_string(), |v| format!("{v:.3e}"))
        }
        let errors: [Column; 4] = [
            ("L2 error", |r| format!("{:.3e}", r.l2_error)),
            ("H1 error", |r| format!("{:.3e}", r.h1_error)),
            ("energy error", |r| opt(r.energy_error)),
            ("contact time error", |r| opt(r.contact_time_error)),
        ];
        let columns: Vec<&Column> = lead.iter().chain(&errors).chain(trail).collect();
        let mut md = String::from("|");
        for (header, _) in &columns {
            let _ = write!(md, " {header} |");
        }
        let _ = writeln!(md, "\n|{}", "---|".repeat(columns.len()));
        for r in &self.rows {
            md.push('|');
            for (_, cell) in &columns {
                let _ = write!(md, " {} |", cell(r));
            }
            md.push('\n');
        }
        md
    }

    pub fn markdown(&self) -> String {
        let mut md = format!(
            "Scene `{}`, reference: {} (its estimated L2 error: {}); wall time of the steps: {}\n\n",
            self.scene,
            self.reference,
            self.reference_error
                .map_or("not estimated".to_string(), |e| format!("{e:.3e}")),
            if self.repeats == 0 {
                "timed in the parallel error pass".to_string()
            } else {
                format!("median of {} serial repeats", self.repeats)
            }
        );
        md.push_str(&self.table(
            &[
                ("solver", |r| r.setting.solver().to_string()),
                ("setting", |r| r.setting.setting()),
                ("elements", |r| r.elements.to_string()),
                ("dt", |r| format!("{:.3e}", r.dt)),
            ],
            &[("wall time (s)", |r| format!("{:.2e}", r.wall_time_s))],
        ));
        md.push_str("\n| solver | setting | observed order (L2) | observed order (H1) |\n|---|---|---|---|\n");
        for (s, p2, p1) in self.orders() {
            let _ = writeln!(
                md,
                "| {} | {} | {p2:.3} | {p1:.3} |",
                s.solver(),
                s.setting()
            );
        }
        md
    }

    /// Writes `convergence.csv`, and with the `plots` feature `work-precision.png` and
    /// `work-precision.svg`, into `out`.
    pub fn write(&self, out: &Path) -> Result<Vec<PathBuf>, ConvergeError> {
        std::fs::create_dir_all(out).map_err(|source| ConvergeError::Write {
            path: out.to_path_buf(),
            source,
        })?;
        let csv = out.join("convergence.csv");
        write_atomically(&csv, self.csv().as_bytes()).map_err(|source| ConvergeError::Write {
            path: csv.clone(),
            source,
        })?;
        #[cfg_attr(not(feature = "plots"), expect(unused_mut))]
        let mut files = vec![csv];
        #[cfg(feature = "plots")]
        for ext in ["png", "svg"] {
            use crate::study::figure_writer::FigureError;
            let path = out.join(format!("work-precision.{ext}"));
            crate::study::work_precision::write_work_precision(&path, &self.title(), &self.lines())
                .map_err(|e| match e {
                    FigureError::Write { path, source } => ConvergeError::Write { path, source },
                    e => ConvergeError::Draw {
                        path: path.clone(),
                        message: match e {
                            FigureError::Draw { message, .. } => message,
                            e => e.to_string(),
                        },
                    },
                })?;
            files.push(path);
        }
        Ok(files)
    }

    /// Title of the work-precision diagram.
    pub fn title(&self) -> String {
        format!(
            "{}: L2 error against wall time (reference: {})",
            self.scene, self.reference
        )
    }

    /// The lines of the work-precision diagram: `(label, [(wall time, L2 error)])` per setting.
    pub fn lines(&self) -> Vec<(String, Vec<(f64, f64)>)> {
        settings_of(&self.rows)
            .into_iter()
            .map(|s| {
                let pts = self
                    .rows
                    .iter()
                    .filter(|r| r.setting == s)
                    .map(|r| (r.wall_time_s.max(1e-6), r.l2_error.max(1e-300)))
                    .collect();
                (s.label(), pts)
            })
            .collect()
    }
}
