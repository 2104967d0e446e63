//! VERIFICATION.md, "Error against run time": every solver setting at 4–5 levels
//! on five scenes, errors against a closed form or a 4x finer exact run, and the wall time of
//! the steps. Two generated blocks: the errors (deterministic; `tests/error_time_doc.rs` checks
//! part of them) and the timings with the machine they were taken on (regenerated only by
//! `verify --timings`). Runs through `viscobar::study::converge` (errors in parallel, then a
//! serial timing pass, median of [`REPEATS`]).

use crate::verify::Section;
use std::fmt::Write as _;
use std::path::{Path, PathBuf};
use viscobar::bar::Simulation;
use viscobar::scene::{self, Scene};
use viscobar::study::converge::{
    ConvergeError, OSQP_EPS, PENALTY_EPSILON, Row, SolverSetting, Study, StudyOptions, study_with,
};

/// Timing repeats per run; the median is kept.
pub const REPEATS: usize = 3;

/// One scene of the study: its name, the overrides giving its coarsest mesh, and its levels.
#[derive(Clone, Copy, Debug)]
pub struct Case {
    pub scene: &'static str,
    pub overrides: &'static [&'static str],
    pub levels: u32,
}

/// The scenes, their coarsest meshes and levels. The closed-form scenes start at their own
/// mesh; the talk scenes at a quarter of theirs (same `dt/dx`), so that their finest level is
/// twice the scene's mesh and the reference (2 levels finer: 4x in space and time, 3200
/// elements) stays affordable.
pub const CASES: [Case; 5] = [
    Case {
        scene: "impact",
        overrides: &[],
        levels: 4,
    },
    Case {
        scene: "falling-bar",
        overrides: &[],
        levels: 4,
    },
    Case {
        scene: "modal",
        overrides: &[],
        levels: 5,
    },
    Case {
        scene: "both-ends-forced",
        overrides: &["mesh.elements=100", "time.step=0.02"],
        levels: 4,
    },
    Case {
        scene: "distributed-forced",
        overrides: &["mesh.elements=100", "time.step=0.02"],
        levels: 4,
    },
];

/// The settings that apply to `scene`: exact, OSQP at each of [`OSQP_EPS`], the penalty at each
/// of [`PENALTY_EPSILON`] unless the scene refuses it (an obstacle: the penalty handles the two
/// Signorini ends only).
pub fn settings_for(scene: &Scene) -> Vec<SolverSetting> {
    let mut out = vec![SolverSetting::Exact];
    out.extend(OSQP_EPS.iter().map(|e| SolverSetting::Osqp(*e)));
    let penalty = SolverSetting::Penalty(PENALTY_EPSILON[0]);
    if Simulation::new(&penalty.apply(scene)).is_ok() {
        out.extend(PENALTY_EPSILON.iter().map(|e| SolverSetting::Penalty(*e)));
    }
    out
}

/// Runs one case: errors in parallel, then `repeats` serial timing repeats (0: none, the
/// times of the error pass, unused by the error block).
pub fn run_case(case: &Case, repeats: usize) -> Result<Study, ConvergeError> {
    let (_, base) = scene::load(case.scene, &owned(case.overrides))?;
    let options = StudyOptions {
        levels: case.levels,
        ratio: None,
        reference_level: None,
        repeats,
    };
    study_with(case.scene, &base, &settings_for(&base), &options)
}

fn owned(v: &[&str]) -> Vec<String> {
    v.iter().map(|s| s.to_string()).collect()
}

fn sci(v: Option<f64>) -> String {
    v.map_or("–".into(), |v| format!("{v:.3e}"))
}

/// The errors of one case as Markdown: the reference and its estimated error, then one row per
/// setting and level. Deterministic.
pub fn errors_markdown(study: &Study) -> String {
    let mut md = format!(
        "**{}** — reference: {}; its estimated L2 error: {}.\n\n",
        study.scene,
        study.reference,
        sci(study.reference_error)
    );
    md.push_str(
        "| solver | setting | elements | dt | L2 error | H1 error | energy error | contact time error |\n\
         |---|---|---|---|---|---|---|---|\n",
    );
    for r in &study.rows {
        let _ = writeln!(
            md,
            "| {} | {} | {} | {:.4e} | {:.3e} | {:.3e} | {} | {} |",
            r.setting.solver(),
            r.setting.setting(),
            r.elements,
            r.dt,
            r.l2_error,
            r.h1_error,
            sci(r.energy_error),
            sci(r.contact_time_error)
        );
    }
    md
}

/// The target error of the headline table: the exact solver's L2 error at the second-finest
/// level (so every setting that converges like it reaches it inside the study).
pub fn target_error(study: &Study) -> Option<f64> {
    let exact: Vec<&Row> = setting_rows(study, SolverSetting::Exact);
    (exact.len() >= 2).then(|| exact[exact.len() - 2].l2_error)
}

fn setting_rows(study: &Study, s: SolverSetting) -> Vec<&Row> {
    study.rows.iter().filter(|r| r.setting == s).collect()
}

/// When a setting reaches an error.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Reach {
    /// At this wall time, read off the log-log line between the two bracketing levels.
    At(f64),
    /// Already at the coarsest level, at this wall time (or less).
    AtMost(f64),
    /// Not by the finest level.
    NotReached,
}

/// The wall time at which `rows` (one setting, coarse to fine) reach `target`: on the first
/// pair of consecutive levels with `e_l >= target >= e_{l+1}` (and `e_l > e_{l+1}`), `log t` is
/// interpolated linearly in `log e`.
pub fn time_to_reach(rows: &[&Row], target: f64) -> Reach {
    let Some(first) = rows.first() else {
        return Reach::NotReached;
    };
    if first.l2_error <= target {
        return Reach::AtMost(first.wall_time_s);
    }
    for w in rows.windows(2) {
        let (a, b) = (w[0], w[1]);
        if a.l2_error >= target && target >= b.l2_error && a.l2_error > b.l2_error {
            let s = (target.ln() - a.l2_error.ln()) / (b.l2_error.ln() - a.l2_error.ln());
            return Reach::At(
                (a.wall_time_s.ln() + s * (b.wall_time_s.ln() - a.wall_time_s.ln())).exp(),
            );
        }
    }
    Reach::NotReached
}

fn reach_text(r: Reach) -> String {
    match r {
        Reach::At(t) => format!("{t:.2e}"),
        Reach::AtMost(t) => format!("≤ {t:.2e} (coarsest level)"),
        Reach::NotReached => "not reached".into(),
    }
}

fn reach_time(r: Reach) -> Option<f64> {
    match r {
        Reach::At(t) | Reach::AtMost(t) => Some(t),
        Reach::NotReached => None,
    }
}

/// The timings of one case as Markdown: one row per setting and level, wall time of the steps
/// (median of the repeats) and over the exact solver's on the same level.
pub fn timings_markdown(study: &Study) -> String {
    let mut md = format!("**{}**\n\n", study.scene);
    md.push_str(
        "| solver | setting | elements | wall time of the steps (s) | relative to exact |\n|---|---|---|---|---|\n",
    );
    for (r, rel) in study.rows.iter().zip(study.time_relative_to_exact()) {
        let _ = writeln!(
            md,
            "| {} | {} | {} | {:.3e} | {} |",
            r.setting.solver(),
            r.setting.setting(),
            r.elements,
            r.wall_time_s,
            rel.map_or("–".into(), |v| format!("{v:.2}"))
        );
    }
    md
}

/// The headline table: per scene, the target error, each setting's time to reach it, and the
/// exact solver's speed-up over the fastest OSQP setting reaching it.
pub fn headline_markdown(studies: &[Study]) -> String {
    let settings: Vec<SolverSetting> = {
        let mut v = vec![SolverSetting::Exact];
        v.extend(OSQP_EPS.iter().map(|e| SolverSetting::Osqp(*e)));
        v.extend(PENALTY_EPSILON.iter().map(|e| SolverSetting::Penalty(*e)));
        v
    };
    let mut md = String::from("| scene | target L2 error |");
    for s in &settings {
        let _ = write!(md, " {} (s) |", s.label());
    }
    md.push_str(" exact's speed-up over the fastest OSQP |\n|---|---|");
    md.push_str(&"---|".repeat(settings.len() + 1));
    md.push('\n');
    for st in studies {
        let Some(target) = target_error(st) else {
            continue;
        };
        let _ = write!(md, "| {} | {target:.3e} |", st.scene);
        let mut exact_t = None;
        let mut osqp_best: Option<f64> = None;
        for s in &settings {
            let rows = setting_rows(st, *s);
            if rows.is_empty() {
                md.push_str(" does not apply |");
                continue;
            }
            let r = time_to_reach(&rows, target);
            match s {
                SolverSetting::Exact => exact_t = reach_time(r),
                SolverSetting::Osqp(_) => {
                    if let Some(t) = reach_time(r) {
                        osqp_best = Some(osqp_best.map_or(t, |b: f64| b.min(t)));
                    }
                }
                SolverSetting::Penalty(_) => {}
            }
            let _ = write!(md, " {} |", reach_text(r));
        }
        let speedup = match (exact_t, osqp_best) {
            (Some(e), Some(o)) if e > 0.0 => format!("{:.1}x", o / e),
            _ => "–".into(),
        };
        let _ = writeln!(md, " {speedup} |");
    }
    md
}

/// The machine line: CPU model (`/proc/cpuinfo`), cores available, build profile, the date
/// (UTC) and the load average when the study started (other processes sharing the cores show
/// there).
pub fn machine_line(load_at_start: &str) -> String {
    let cpu = cpu_model();
    let cores = std::thread::available_parallelism().map_or(0, |n| n.get());
    let profile = if cfg!(debug_assertions) {
        "debug"
    } else {
        "release"
    };
    format!(
        "Machine: {cpu}, {cores} cores available, `{profile}` build; study started {} (UTC); \
         load average at the start {load_at_start} (1, 5, 15 min; above 0 means other \
         processes shared the cores, and the times are noisier for it).",
        utc_date_time()
    )
}

/// The CPU model named by `/proc/cpuinfo`, or `unknown CPU`.
pub fn cpu_model() -> String {
    std::fs::read_to_string("/proc/cpuinfo")
        .ok()
        .and_then(|t| {
            t.lines()
                .find(|l| l.starts_with("model name"))
                .and_then(|l| l.split_once(':'))
                .map(|(_, v)| v.trim().to_string())
        })
        .unwrap_or_else(|| "unknown CPU".into())
}

/// The first three fields of `/proc/loadavg`, or `unknown`.
pub fn load_average() -> String {
    std::fs::read_to_string("/proc/loadavg")
        .ok()
        .map(|t| t.split_whitespace().take(3).collect::<Vec<_>>().join(" "))
        .unwrap_or_else(|| "unknown".into())
}

/// Now as `YYYY-MM-DD HH:MM` (UTC), from the system clock.
fn utc_date_time() -> String {
    utc_date_time_at(
        std::time::SystemTime::now()
            .duration_since(std::time::UNIX_EPOCH)
            .map_or(0, |d| d.as_secs()),
    )
}

/// `secs` since the Unix epoch as `YYYY-MM-DD HH:MM` (UTC; civil-from-days, H. Hinnant).
pub fn utc_date_time_at(secs: u64) -> String {
    let days = (secs / 86_400) as i64;
    let (h, m) = ((secs % 86_400) / 3600, (secs % 3600) / 60);
    let z = days + 719_468;
    let era = z.div_euclid(146_097);
    let doe = z - era * 146_097;
    let yoe = (doe - doe / 1460 + doe / 36_524 - doe / 146_096) / 365;
    let doy = doe - (365 * yoe + yoe / 4 - yoe / 100);
    let mp = (5 * doy + 2) / 153;
    let d = doy - (153 * mp + 2) / 5 + 1;
    let mo = if mp < 10 { mp + 3 } else { mp - 9 };
    let y = yoe + era * 400 + i64::from(mo <= 2);
    format!("{y:04}-{mo:02}-{d:02} {h:02}:{m:02}")
}

/// Ids of the two generated blocks.
pub const ERRORS_ID: &str = "error-time-errors";
pub const TIMINGS_ID: &str = "error-time-timings";

/// The whole study (`verify --timings`): both blocks, and with `figures` the diagrams
/// `work-precision-<scene>.png` written there. Cases run one after the other; in each, errors
/// in parallel, then the serial timing pass.
pub fn sections(figures: Option<&Path>) -> Result<Vec<Section>, ConvergeError> {
    let machine = machine_line(&load_average());
    let studies = CASES
        .iter()
        .map(|c| run_case(c, REPEATS))
        .collect::<Result<Vec<Study>, ConvergeError>>()?;
    let errors: Vec<String> = studies.iter().map(errors_markdown).collect();
    let mut timings = machine;
    timings.push_str("\n\nTime to reach the target error (s):\n\n");
    timings.push_str(&headline_markdown(&studies));
    for st in &studies {
        timings.push('\n');
        timings.push_str(&timings_markdown(st));
    }
    if let Some(dir) = figures {
        write_figures(&studies, dir)?;
    }
    Ok(vec![
        Section {
            id: ERRORS_ID,
            markdown: errors.join("\n"),
        },
        Section {
            id: TIMINGS_ID,
            markdown: timings,
        },
    ])
}

/// `work-precision-<scene>.png` per study into `dir`.
pub fn write_figures(studies: &[Study], dir: &Path) -> Result<Vec<PathBuf>, ConvergeError> {
    let mut files = Vec::new();
    for st in studies {
        std::fs::create_dir_all(dir).map_err(|source| ConvergeError::Write {
            path: dir.to_path_buf(),
            source,
        })?;
        let path = dir.join(format!("work-precision-{}.png", st.scene));
        viscobar::study::work_precision::write_work_precision(&path, &st.title(), &st.lines())
            .map_err(|e| ConvergeError::Draw {
                path: path.clone(),
                message: e.to_string(),
            })?;
        files.push(path);
    }
    Ok(files)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn row(level: u32, l2_error: f64, wall_time_s: f64) -> Row {
        Row {
            setting: SolverSetting::Exact,
            level,
            elements: 100 << level,
            dx: 0.01 / f64::from(1u32 << level),
            dt: 0.01 / f64::from(1u32 << level),
            steps: 100 << level,
            l2_error,
            h1_error: l2_error,
            energy_error: None,
            contact_time_error: None,
            wall_time_s,
        }
    }

    /// Round-off of the log-log interpolation (a few ulps of `exp(ln t)`).
    const INTERPOLATION_TOL: f64 = 1e-12;

    #[test]
    fn the_time_to_reach_an_error_is_read_off_the_log_log_line_between_bracketing_levels() {
        // error = 1/t: halfway in log between 1e-2 and 1e-3 is 10^-2.5 at 10^2.5 s.
        let rows = [
            row(0, 1e-1, 10.0),
            row(1, 1e-2, 100.0),
            row(2, 1e-3, 1000.0),
        ];
        let r: Vec<&Row> = rows.iter().collect();
        let Reach::At(t) = time_to_reach(&r, 10f64.powf(-2.5)) else {
            panic!("bracketed")
        };
        assert!((t / 10f64.powf(2.5) - 1.0).abs() < INTERPOLATION_TOL, "{t}");
        // A level's own error gives its own time.
        let Reach::At(t) = time_to_reach(&r, 1e-2) else {
            panic!("bracketed")
        };
        assert!((t / 100.0 - 1.0).abs() < INTERPOLATION_TOL, "{t}");
        assert_eq!(time_to_reach(&r, 1.0), Reach::AtMost(10.0));
        assert_eq!(time_to_reach(&r, 1e-4), Reach::NotReached);
        // A plateau (the penalty's ε floor) does not bracket: the first falling pair does.
        let flat = [row(0, 1e-2, 1.0), row(1, 1e-2, 2.0), row(2, 1e-4, 4.0)];
        let f: Vec<&Row> = flat.iter().collect();
        let Reach::At(t) = time_to_reach(&f, 1e-3) else {
            panic!("bracketed by levels 1 and 2")
        };
        assert!((t / 2f64.powf(1.5) - 1.0).abs() < INTERPOLATION_TOL, "{t}");
    }

    #[test]
    fn known_instants_have_their_civil_dates() {
        // `date -u -d @SECS '+%F %R'` for each.
        for (secs, text) in [
            (0, "1970-01-01 00:00"),
            (951_782_400, "2000-02-29 00:00"),
            (1_795_393_800, "2026-11-23 00:30"),
        ] {
            assert_eq!(utc_date_time_at(secs), text);
        }
    }

    #[test]
    fn the_date_is_a_civil_utc_date() {
        let d = utc_date_time();
        let year: i32 = d[..4].parse().unwrap();
        assert!(year >= 2024, "{d}");
        assert_eq!(
            (&d[4..5], &d[7..8], &d[10..11], &d[13..14]),
            ("-", "-", " ", ":")
        );
    }
}
