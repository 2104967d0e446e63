//! A run kept in memory with what its files would hold, for callers that want the outputs
//! without files (the Python package): `summary.json`'s [`Summary`], `history.csv`'s text and
//! its columns read back, and the profile table's kept steps and written nodes as arrays, the
//! same sampling, history rows and numbers as [`super::run::run_to_dir`] (its tests compare the
//! files byte for byte). [`Recorded::write_to_dir`] writes the files of `format = "csv"`.
//!
//! The arrays hold the values the files read back to: times and coordinates rounded as
//! [`output_time`] rounds them, every other value exactly (the text is the shortest that reads
//! back to the same double); an empty cell of `history.csv` is NaN.

use crate::bar::Simulation;
use crate::output::files::write_whole;
use crate::output::history;
use crate::output::profiles::{columns, written_nodes};
use crate::output::run::{Certify, observe};
use crate::output::summary::{Summary, Tracker};
use crate::output::text::{output_time, push_time, push_value};
use crate::plane::PlaneSimulation;
use crate::scene::plane::PlaneScene;
use crate::scene::{AnyScene, OutputFormat, OutputSampling, Scene};
use crate::scheme::{Body, RunError, State, StepRecord, Unstarted};
use crate::thermal::ThermalSimulation;
use std::path::{Path, PathBuf};
use std::time::Instant;

/// A finished run's outputs in memory.
#[derive(Clone, Debug)]
pub struct Recorded {
    /// What `summary.json` holds (with `output`, the profile's sampling, set).
    pub summary: Summary,
    /// `history.csv`'s text: the header line and one row per step.
    pub history_text: Vec<u8>,
    /// `history.csv`'s column names, in order.
    pub history_columns: Vec<String>,
    /// Each column's values, one per step, as the file reads back (an empty cell is NaN).
    pub history: Vec<Vec<f64>>,
    /// The profile table's kept steps and written nodes.
    pub profile: Profile,
}

/// The profile table (`displacement.csv`) as arrays, kept step by kept step.
#[derive(Clone, Debug, Default)]
pub struct Profile {
    /// Degrees of freedom per node: 1 on the bar's line, 2 on the plane.
    pub components: usize,
    /// The time of each kept step (rounded as written).
    pub times: Vec<f64>,
    /// The written nodes' `x` (rounded as written).
    pub x: Vec<f64>,
    /// The written nodes' `y` on the plane (rounded as written); empty on the bar.
    pub y: Vec<f64>,
    /// `u` per kept step, written node and component, row-major (0 at clamped ones).
    pub displacement: Vec<f64>,
    /// The velocity `(u^n − u^{n−1})/Δt`, laid out as `displacement`.
    pub velocity: Vec<f64>,
    /// `θ^{n−1/2}` per kept step and written node for a bar with a temperature, else empty.
    pub theta: Vec<f64>,
    /// Whether the table has the column `theta`.
    pub has_theta: bool,
}

impl Profile {
    /// The written nodes.
    pub fn nodes(&self) -> usize {
        self.x.len()
    }

    /// The text of `displacement.csv`.
    pub fn csv(&self) -> Vec<u8> {
        let k = self.components;
        let n = self.nodes();
        let mut out = columns(k, self.has_theta).join(",").into_bytes();
        out.push(b'\n');
        for (s, &t) in self.times.iter().enumerate() {
            for j in 0..n {
                push_time(t, &mut out);
                out.push(b',');
                push_time(self.x[j], &mut out);
                out.push(b',');
                if k == 2 {
                    push_time(self.y[j], &mut out);
                    out.push(b',');
                }
                let at = (s * n + j) * k;
                for field in [&self.displacement, &self.velocity] {
                    for v in &field[at..at + k] {
                        push_value(*v, &mut out);
                        out.push(b',');
                    }
                }
                if self.has_theta {
                    push_value(self.theta[s * n + j], &mut out);
                    out.push(b',');
                }
                *out.last_mut().expect("a row has cells") = b'\n';
            }
        }
        out
    }

    /// Appends one kept step at time `t`, as [`crate::output::profiles::Profiles`] writes it.
    fn keep(&mut self, t: f64, state: State<'_>, dofs: &[Option<usize>]) {
        self.times.push(output_time(t));
        for &dof in dofs {
            let (u, v) = match dof {
                Some(i) => (state.u[i], state.w[i] * state.scale),
                None => (0.0, 0.0),
            };
            self.displacement.push(u);
            self.velocity.push(v);
        }
    }
}

/// Runs a bar (with or without `[heat]`) or plane scene in memory.
pub fn record_any(name: &str, scene: &AnyScene) -> Result<Recorded, RunError> {
    match scene {
        AnyScene::Bar(bar) => record(name, bar),
        AnyScene::Plane(plane) => record_plane(name, plane),
    }
}

/// Runs a bar scene (with or without `[heat]`) in memory.
pub fn record(name: &str, scene: &Scene) -> Result<Recorded, RunError> {
    let start = Instant::now();
    let (steps, sampling) = (scene.steps(), scene.output_sampling());
    if scene.heat.is_some() {
        let prepared = ThermalSimulation::prepare(scene)?;
        return record_prepared(name, prepared, steps, sampling, start);
    }
    record_prepared(name, Simulation::prepare(scene)?, steps, sampling, start)
}

/// Runs a plane scene in memory.
pub fn record_plane(name: &str, scene: &PlaneScene) -> Result<Recorded, RunError> {
    let start = Instant::now();
    let prepared = PlaneSimulation::prepare(scene)?;
    record_prepared(
        name,
        prepared,
        scene.steps(),
        scene.output_sampling(),
        start,
    )
}

/// The step loop of `run_to_dir`, keeping the rows and the kept steps in memory.
fn record_prepared<B: Body>(
    name: &str,
    prepared: Unstarted<B>,
    steps: usize,
    sampling: OutputSampling,
    start: Instant,
) -> Result<Recorded, RunError> {
    let groups = prepared.contact().groups().to_vec();
    let has_theta = prepared.body().has_temperature();
    let optional = history::OptionalColumns::of(
        prepared.contact(),
        has_theta,
        prepared.body().heat_outputs(),
    );
    let header = history::header(&groups, optional);
    let history_columns: Vec<String> = header.trim_end().split(',').map(String::from).collect();
    let mut rows = History {
        text: header.into_bytes(),
        columns: vec![Vec::with_capacity(steps); history_columns.len()],
        row: Vec::new(),
    };
    let body = prepared.body();
    let stride = usize::try_from(sampling.node_stride).unwrap_or(usize::MAX);
    let nodes = written_nodes(body.lattice(), stride);
    let components = body.components();
    let dofs: Vec<Option<usize>> = (nodes.iter())
        .flat_map(|&i| (0..components).map(move |c| components * i + c))
        .map(|dof| body.unknown_of(dof))
        .collect();
    let rounded = |i: usize| {
        let (x, y) = body.point(i);
        (output_time(x), y.map(output_time))
    };
    let mut profile = Profile {
        components,
        x: nodes.iter().map(|&i| rounded(i).0).collect(),
        y: nodes.iter().filter_map(|&i| rounded(i).1).collect(),
        has_theta,
        ..Profile::default()
    };
    // Sized once: the kept steps are known (`sampling.kept_steps`).
    let kept = usize::try_from(sampling.kept_steps).unwrap_or(0);
    profile.times.reserve_exact(kept);
    profile.displacement.reserve_exact(kept * dofs.len());
    profile.velocity.reserve_exact(kept * dofs.len());
    if has_theta {
        profile.theta.reserve_exact(kept * nodes.len());
    }
    let keep_step = |profile: &mut Profile, t: f64, state: State<'_>, body: &B| {
        profile.keep(t, state, &dofs);
        if has_theta {
            let theta = nodes.iter().map(|&i| body.temperature(state.u, i));
            profile.theta.extend(theta.map(|v| v.unwrap_or(0.0)));
        }
    };
    // `t = 0` is kept before the start-up step moves `u^0` on.
    keep_step(&mut profile, 0.0, prepared.state(), prepared.body());
    let mut sim = prepared.start()?;
    let mut tracker = Tracker::new(&sim, !sim.is_forced());
    rows.push(&sim.first_record(), &groups, optional);
    let every = sampling.every as usize;
    let keep = |n: usize| n.is_multiple_of(every) || n == steps;
    if keep(1) {
        keep_step(&mut profile, sim.time(), sim.state(), sim.body());
    }
    for _ in 1..steps {
        let r = sim.step()?;
        // A step that breaks the run's certificate ends it, as on the command line.
        observe(&mut tracker, &r, Certify::Strict)?;
        rows.push(&r, &groups, optional);
        if keep(r.step) {
            keep_step(&mut profile, sim.time(), sim.state(), sim.body());
        }
    }
    let mut summary = tracker.finish(name, &sim, start.elapsed().as_secs_f64());
    summary.output = Some(sampling);
    Ok(Recorded {
        summary,
        history_text: rows.text,
        history_columns,
        history: rows.columns,
        profile,
    })
}

/// `history.csv`'s text and its columns read back, row by row.
struct History {
    text: Vec<u8>,
    columns: Vec<Vec<f64>>,
    row: Vec<u8>,
}

impl History {
    fn push(
        &mut self,
        r: &StepRecord,
        groups: &[crate::scheme::contact::Group],
        optional: history::OptionalColumns,
    ) {
        history::row(r, groups, optional, &mut self.row);
        self.text.extend_from_slice(&self.row);
        let line = std::str::from_utf8(&self.row).expect("rows are ASCII");
        let cells = line.trim_end().split(',');
        for (column, cell) in self.columns.iter_mut().zip(cells) {
            column.push(if cell.is_empty() {
                f64::NAN
            } else {
                cell.parse().expect("a written number reads back")
            });
        }
    }
}

impl Recorded {
    /// The text of `summary.json`.
    pub fn summary_json(&self) -> String {
        serde_json::to_string_pretty(&self.summary).expect("summary serialises") + "\n"
    }

    /// Writes `summary.json`, `history.csv` and `displacement.csv` into `out` as
    /// [`super::run::run_to_dir`] does (whole or not at all); the scene's `[output]` format
    /// must be `csv` (the other formats' writers need the run's bodies: run the scene to a
    /// folder instead), else a [`crate::scene::SceneError`] naming `output.format`.
    pub fn write_to_dir(&self, out: &Path) -> Result<(), RunError> {
        let format = self.summary.output.map_or(OutputFormat::Csv, |s| s.format);
        if format != OutputFormat::Csv {
            return Err(crate::scene::SceneError::Invalid {
                field: "output.format".into(),
                value: format!("\"{}\"", format.name()),
                allowed: "a run kept in memory writes \"csv\"; run the scene to a folder for \
                          its other formats"
                    .into(),
            }
            .into());
        }
        let files = ["history.csv", OutputFormat::Csv.file(), "summary.json"];
        let io = |path: PathBuf, source| RunError::Write { path, source };
        write_whole(out, &files, io, |dir| {
            let texts = [
                self.history_text.clone(),
                self.profile.csv(),
                self.summary_json().into_bytes(),
            ];
            for (file, text) in files.iter().zip(texts) {
                let path = dir.join(file);
                std::fs::write(&path, text).map_err(|e| io(path, e))?;
            }
            Ok(())
        })?;
        // As a run to a folder does: the other formats' files of an earlier run go.
        for other in [OutputFormat::Npy, OutputFormat::Vtu] {
            let _ = std::fs::remove_file(out.join(other.file()));
            if let Some(folder) = other.folder() {
                let _ = std::fs::remove_dir_all(out.join(folder));
            }
        }
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::output::run::{run_plane_to_dir, run_to_dir};
    use crate::scene::load_any;

    /// Summary fields measured on the clock, which differ between any two runs.
    const CLOCK_FIELDS: [&str; 3] = ["wall_time_s", "ns_per_unknown_step", "time_shares"];

    fn fresh(tag: &str) -> PathBuf {
        let dir =
            std::env::temp_dir().join(format!("viscobar-memory-{tag}-{}", std::process::id()));
        let _ = std::fs::remove_dir_all(&dir);
        dir
    }

    fn without_clock(text: &str) -> serde_json::Value {
        let mut value: serde_json::Value = serde_json::from_str(text).unwrap();
        for field in CLOCK_FIELDS {
            assert!(
                value.as_object_mut().unwrap().remove(field).is_some(),
                "{field}"
            );
        }
        value
    }

    /// The numbers of a CSV text, column by column (an empty cell is NaN).
    fn csv_columns(text: &str) -> (Vec<String>, Vec<Vec<f64>>) {
        let mut lines = text.lines();
        let names: Vec<String> = lines.next().unwrap().split(',').map(String::from).collect();
        let mut columns = vec![Vec::new(); names.len()];
        for line in lines {
            let cells: Vec<&str> = line.split(',').collect();
            assert_eq!(cells.len(), names.len(), "{line}");
            for (c, cell) in columns.iter_mut().zip(cells) {
                c.push(if cell.is_empty() {
                    f64::NAN
                } else {
                    cell.parse().unwrap()
                });
            }
        }
        (names, columns)
    }

    fn bits(v: &[f64]) -> Vec<u64> {
        v.iter().map(|x| x.to_bits()).collect()
    }

    /// The in-memory run writes the files of the run to a folder byte for byte (summary.json
    /// but for its clock fields), and its arrays are the numbers the files read back to, on a
    /// bar with sampled steps and nodes and unmeasured steps, a bar on an obstacle under every
    /// node (the extent's cells empty before contact), a bar whose obstacle moves
    /// (`obstacle_work`), a thermal bar, a plane and a plane with friction (its tangential
    /// total).
    #[test]
    fn the_memory_run_holds_the_files_of_the_run_to_a_folder() {
        // Each case's scene, overrides and a column that only such a run writes.
        let cases: [(&str, &[&str], &str); 6] = [
            (
                "impact",
                &[
                    "output.every=7",
                    "output.nodes=13",
                    "output.diagnostics_every=4",
                ],
                "gap_left",
            ),
            (
                "distributed-forced",
                &["time.end=2.5"],
                "contact_s_min_obstacle",
            ),
            (
                "impact",
                &["time.end=0.5", "left.gap=\"0.1 - 0.5*t\""],
                "obstacle_work",
            ),
            (
                "thermal-impact",
                &["time.end=0.5", "output.nodes=21"],
                "thermal_energy",
            ),
            (
                "plane-tilted-drop",
                &["time.end=0.2", "output.every=3"],
                "contact_nodes_bottom",
            ),
            (
                "plane-friction-tilted-drop",
                &["time.end=0.3"],
                "tangential_reaction_bottom",
            ),
        ];
        for (name, set, column) in cases {
            let set: Vec<String> = set.iter().map(|s| s.to_string()).collect();
            let (_, scene) = load_any(name, &set).unwrap();
            let (from_run, from_memory) = (fresh(&format!("{name}-run")), fresh(name));
            match &scene {
                AnyScene::Bar(bar) => run_to_dir(name, bar, &from_run, false).map(drop),
                AnyScene::Plane(plane) => run_plane_to_dir(name, plane, &from_run, false).map(drop),
            }
            .unwrap();
            let recorded = record_any(name, &scene).unwrap();
            recorded.write_to_dir(&from_memory).unwrap();
            let read = |dir: &Path, file: &str| std::fs::read_to_string(dir.join(file)).unwrap();
            for file in ["history.csv", "displacement.csv"] {
                assert!(
                    read(&from_run, file) == read(&from_memory, file),
                    "{name}: {file}"
                );
            }
            let summary = read(&from_run, "summary.json");
            assert_eq!(
                without_clock(&summary),
                without_clock(&read(&from_memory, "summary.json")),
                "{name}"
            );
            assert_eq!(
                without_clock(&summary),
                without_clock(&recorded.summary_json())
            );

            let (names, history) = csv_columns(&read(&from_run, "history.csv"));
            assert_eq!(names, recorded.history_columns, "{name}");
            assert!(names.iter().any(|c| c == column), "{name}: {names:?}");
            for (file, memory) in history.iter().zip(&recorded.history) {
                assert_eq!(bits(file), bits(memory), "{name}");
            }
            let (names, table) = csv_columns(&read(&from_run, "displacement.csv"));
            let p = &recorded.profile;
            let (n, k) = (p.nodes(), p.components);
            assert_eq!(table[0].len(), p.times.len() * n, "{name}");
            let column = |c: &str| &table[names.iter().position(|x| x == c).unwrap()];
            let every_node = |v: &[f64]| -> Vec<f64> {
                v.iter().flat_map(|&x| std::iter::repeat_n(x, n)).collect()
            };
            let every_step = |v: &[f64]| -> Vec<f64> { v.repeat(p.times.len()) };
            assert_eq!(bits(column("t")), bits(&every_node(&p.times)), "{name}");
            assert_eq!(bits(column("x")), bits(&every_step(&p.x)), "{name}");
            let component = |v: &[f64], c: usize| -> Vec<f64> {
                v.iter().skip(c).step_by(k).copied().collect()
            };
            let fields: &[(&str, &[f64], usize)] = if k == 1 {
                &[("u", &p.displacement, 0), ("v", &p.velocity, 0)]
            } else {
                assert_eq!(bits(column("y")), bits(&every_step(&p.y)), "{name}");
                &[
                    ("ux", &p.displacement, 0),
                    ("uy", &p.displacement, 1),
                    ("vx", &p.velocity, 0),
                    ("vy", &p.velocity, 1),
                ]
            };
            for (c, values, at) in fields {
                assert_eq!(
                    bits(column(c)),
                    bits(&component(values, *at)),
                    "{name}: {c}"
                );
            }
            assert_eq!(p.has_theta, name == "thermal-impact");
            if p.has_theta {
                assert_eq!(bits(column("theta")), bits(&p.theta), "{name}");
            }
            for dir in [from_run, from_memory] {
                std::fs::remove_dir_all(dir).unwrap();
            }
        }
    }

    /// Only `csv` is written from memory: the other formats are refused naming the key, and
    /// nothing is created.
    #[test]
    fn writing_another_format_from_memory_is_refused_naming_the_key() {
        let set = [
            "time.end=0.05".to_string(),
            "output.format=\"vtu\"".to_string(),
        ];
        let (_, scene) = load_any("plane-strip", &set).unwrap();
        let recorded = record_any("plane-strip", &scene).unwrap();
        let out = fresh("vtu");
        let e = recorded.write_to_dir(&out).unwrap_err();
        assert_eq!(e.exit_code(), 2);
        assert!(e.to_string().contains("`output.format`"), "{e}");
        assert!(!out.exists());
    }
}
