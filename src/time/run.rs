//! Running a scene end to end: the step loop and the output files (`summary.json`,
//! `history.csv`, `displacement.csv`), written whole or not at all.

use crate::scene::Scene;
use crate::time::RunError;
use crate::time::simulation::{Simulation, StepRecord};
use crate::time::summary::{Summary, Tracker, output_time};
use std::io::Write;
use std::path::{Path, PathBuf};
use std::time::Instant;

/// Runs a scene in memory, returning every step record (the start-up step first) and the
/// summary. For tests and studies; [`run_to_dir`] streams instead.
pub fn run_in_memory(
    name: &str,
    scene: &Scene,
) -> Result<(Vec<StepRecord>, Summary, Simulation), RunError> {
    let mut sim = Simulation::new(scene)?;
    let mut tracker = Tracker::new(&sim, scene.load.density.is_none());
    let mut records = vec![sim.first_record()];
    let start = Instant::now();
    for _ in 1..scene.steps() {
        let r = sim.step()?;
        tracker.observe(&r);
        records.push(r);
    }
    let summary = tracker.finish(name, &sim, start.elapsed().as_secs_f64());
    Ok((records, summary, sim))
}

/// Runs a scene and writes `summary.json`, `history.csv` and `displacement.csv` into `out`.
/// The scene is set up (discretised, its initial data evaluated) before anything is created, so
/// a refused scene leaves no trace on disk. The files are written into a temporary folder
/// inside `out` and moved into place only when the run has succeeded, so a failed run leaves
/// earlier results untouched; folders it created for `out` are removed again when it fails.
/// `progress` shows a progress bar on stderr for long runs (with the `progress` feature).
pub fn run_to_dir(
    name: &str,
    scene: &Scene,
    out: &Path,
    progress: bool,
) -> Result<Summary, RunError> {
    let start = Instant::now();
    let sim = Simulation::new(scene)?;
    write_whole(
        out,
        &RUN_FILES,
        |path, source| RunError::Write { path, source },
        |tmp| write_run(name, scene, sim, start, tmp, progress),
    )
}

/// The files a run writes (bar or plane).
pub(crate) const RUN_FILES: [&str; 3] = ["history.csv", "displacement.csv", "summary.json"];

/// Writes `files` into `out` whole or not at all: `write` fills a temporary folder inside
/// `out`, whose files are moved into place only when it succeeds, so a failed run leaves
/// earlier results untouched; folders created for `out` are removed again on failure.
pub(crate) fn write_whole<T, E>(
    out: &Path,
    files: &[&str],
    write_err: impl Fn(PathBuf, std::io::Error) -> E,
    write: impl FnOnce(&Path) -> Result<T, E>,
) -> Result<T, E> {
    let created = missing_folders(out);
    let outcome = (|| {
        std::fs::create_dir_all(out).map_err(|e| write_err(out.to_path_buf(), e))?;
        remove_stale_partials(out);
        let tmp = out.join(format!(".viscobar-partial-{}", std::process::id()));
        let _ = std::fs::remove_dir_all(&tmp);
        std::fs::create_dir_all(&tmp).map_err(|e| write_err(tmp.clone(), e))?;
        let outcome = write(&tmp).and_then(|value| {
            for file in files {
                std::fs::rename(tmp.join(file), out.join(file))
                    .map_err(|e| write_err(out.join(file), e))?;
            }
            Ok(value)
        });
        let _ = std::fs::remove_dir_all(&tmp);
        outcome
    })();
    if outcome.is_err() {
        // Deepest first; `remove_dir` leaves a folder that is not empty.
        for folder in &created {
            let _ = std::fs::remove_dir(folder);
        }
    }
    outcome
}

/// `out` and those of its parents that do not exist yet, deepest first.
pub(crate) fn missing_folders(out: &Path) -> Vec<PathBuf> {
    out.ancestors()
        .filter(|p| !p.as_os_str().is_empty())
        .take_while(|p| !p.exists())
        .map(Path::to_path_buf)
        .collect()
}

/// Runs below this many node-steps finish in seconds: no progress bar.
#[cfg(feature = "progress")]
const PROGRESS_MIN_NODE_STEPS: f64 = 2e8;
/// The progress bar is moved every this many steps (cheap next to a step of a large run).
#[cfg(feature = "progress")]
const PROGRESS_EVERY_STEPS: usize = 1024;

/// A progress bar on stderr for long runs; nothing without the `progress` feature.
struct Progress {
    #[cfg(feature = "progress")]
    bar: Option<indicatif::ProgressBar>,
}

impl Progress {
    #[cfg_attr(not(feature = "progress"), expect(unused_variables))]
    fn new(show: bool, steps: usize, nodes: usize) -> Self {
        #[cfg(feature = "progress")]
        let bar = (show && steps as f64 * nodes as f64 > PROGRESS_MIN_NODE_STEPS).then(|| {
            let bar = indicatif::ProgressBar::new(steps as u64);
            bar.set_style(
                indicatif::ProgressStyle::with_template("{bar:40} {pos}/{len} steps, eta {eta}")
                    .expect("static template"),
            );
            bar
        });
        Self {
            #[cfg(feature = "progress")]
            bar,
        }
    }

    #[cfg_attr(not(feature = "progress"), expect(unused_variables))]
    fn step(&self, step: usize) {
        #[cfg(feature = "progress")]
        if let Some(b) = &self.bar
            && step.is_multiple_of(PROGRESS_EVERY_STEPS)
        {
            b.set_position(step as u64);
        }
    }

    fn finish(self) {
        #[cfg(feature = "progress")]
        if let Some(b) = self.bar {
            b.finish_and_clear();
        }
    }
}

fn write_run(
    name: &str,
    scene: &Scene,
    mut sim: Simulation,
    start: Instant,
    dir: &Path,
    progress: bool,
) -> Result<Summary, RunError> {
    let open = |file: &str| -> Result<(PathBuf, std::io::BufWriter<std::fs::File>), RunError> {
        let path = dir.join(file);
        let f = std::fs::File::create(&path).map_err(|source| RunError::Write {
            path: path.clone(),
            source,
        })?;
        Ok((path, std::io::BufWriter::with_capacity(1 << 20, f)))
    };
    let (hist_path, mut hist) = open("history.csv")?;
    let (disp_path, mut disp) = open("displacement.csv")?;
    let io = |path: &PathBuf| {
        let path = path.clone();
        move |source| RunError::Write { path, source }
    };

    let mut tracker = Tracker::new(&sim, scene.load.density.is_none());
    let sides: Vec<&str> = sim
        .discretisation()
        .constraints
        .iter()
        .filter_map(|c| c.side.map(|s| s.name()))
        .collect();
    let obstacle = !sim.discretisation().ends_only();
    let mut header = String::from(
        "step,t,energy,work,viscous_dissipation,contact_dissipation,identity_residual",
    );
    for s in &sides {
        header.push_str(&format!(",gap_{s},reaction_{s}"));
    }
    if obstacle {
        header.push_str(",contact_nodes,contact_x_min,contact_x_max,min_gap");
    }
    header.push_str(",iterations");
    writeln!(hist, "{header}").map_err(io(&hist_path))?;
    write_history_row(&mut hist, &sim.first_record(), sides.len(), obstacle)
        .map_err(io(&hist_path))?;

    let nodes = sim.discretisation().nodes;
    let disc = sim.discretisation();
    writeln!(disp, "t,x,u,v").map_err(io(&disp_path))?;
    let mut u = vec![0.0; nodes];
    let mut v = vec![0.0; nodes];
    sim.initial_state_into(&mut u, &mut v);
    // The written x, rounded once for the run rather than at every kept step.
    let sampling = scene.output_sampling();
    let written: Vec<usize> = (0..nodes)
        .filter(|&i| sampling.writes_node(i, nodes))
        .collect();
    let xs: Vec<String> = written
        .iter()
        .map(|&i| output_time(disc.x(i)).to_string())
        .collect();
    write_profile(&mut disp, 0.0, &xs, &written, &u, &v).map_err(io(&disp_path))?;
    let steps = scene.steps();
    let every = scene.output.every as usize;
    let bar = Progress::new(progress, steps, nodes);
    let keep = |n: usize| n.is_multiple_of(every) || n == steps;
    if keep(1) {
        sim.displacement_into(&mut u);
        sim.velocity_into(&mut v);
        write_profile(&mut disp, sim.time(), &xs, &written, &u, &v).map_err(io(&disp_path))?;
    }
    for _ in 1..steps {
        let r = sim.step()?;
        tracker.observe(&r);
        write_history_row(&mut hist, &r, sides.len(), obstacle).map_err(io(&hist_path))?;
        if keep(r.step) {
            sim.displacement_into(&mut u);
            sim.velocity_into(&mut v);
            write_profile(&mut disp, sim.time(), &xs, &written, &u, &v).map_err(io(&disp_path))?;
        }
        bar.step(r.step);
    }
    bar.finish();
    hist.flush().map_err(io(&hist_path))?;
    disp.flush().map_err(io(&disp_path))?;
    let mut summary = tracker.finish(name, &sim, start.elapsed().as_secs_f64());
    summary.output = Some(sampling);
    let json_path = dir.join("summary.json");
    let json = serde_json::to_string_pretty(&summary).expect("summary serialises");
    std::fs::write(&json_path, json + "\n").map_err(io(&json_path))?;
    Ok(summary)
}

fn write_history_row(
    w: &mut impl Write,
    r: &StepRecord,
    k: usize,
    obstacle: bool,
) -> std::io::Result<()> {
    if r.measured {
        write!(
            w,
            "{},{},{},{},{},{},{}",
            r.step,
            output_time(r.time),
            r.energy,
            r.work,
            r.viscous_dissipation,
            r.contact_dissipation,
            r.identity_residual
        )?;
    } else {
        // Not measured ([output] diagnostics_every): empty cells, not zeros.
        write!(w, "{},{},,,,,", r.step, output_time(r.time))?;
    }
    for j in 0..k {
        write!(w, ",{},{}", r.gap[j], r.reaction[j])?;
    }
    if obstacle {
        let [lo, hi] = r.contact_extent;
        let x = |v: f64| {
            if v.is_nan() {
                String::new()
            } else {
                v.to_string()
            }
        };
        write!(w, ",{},{},{},{}", r.contact_nodes, x(lo), x(hi), r.min_gap)?;
    }
    writeln!(w, ",{}", r.iterations)
}

/// One row a written node (`nodes`, with their `xs`), `t,x,u,v`: `t` and `x` rounded (see [`output_time`]), `x` from the run's
/// `xs` (formatted once per run), `u` and `v` in the shortest form that reads back to the same
/// `f64` (Żmij; `1.5e-7` rather than `0.00000015`), several times faster than `core::fmt`.
fn write_profile(
    w: &mut impl Write,
    t: f64,
    xs: &[String],
    nodes: &[usize],
    u: &[f64],
    v: &[f64],
) -> std::io::Result<()> {
    let t = output_time(t).to_string();
    let (mut bu, mut bv) = (zmij::Buffer::new(), zmij::Buffer::new());
    for (x, &i) in xs.iter().zip(nodes) {
        let (u, v) = (u[i], v[i]);
        w.write_all(t.as_bytes())?;
        w.write_all(b",")?;
        w.write_all(x.as_bytes())?;
        w.write_all(b",")?;
        w.write_all(bu.format(u).as_bytes())?;
        w.write_all(b",")?;
        w.write_all(bv.format(v).as_bytes())?;
        w.write_all(b"\n")?;
    }
    Ok(())
}

/// Writes `bytes` to `path` whole or not at all: a temporary file in the same folder, then a
/// rename.
pub fn write_atomically(path: &Path, bytes: &[u8]) -> std::io::Result<()> {
    let dir = path
        .parent()
        .filter(|p| !p.as_os_str().is_empty())
        .unwrap_or(Path::new("."));
    let name = path
        .file_name()
        .map_or("out".into(), |n| n.to_string_lossy().into_owned());
    let tmp = dir.join(format!(".{name}.partial-{}", std::process::id()));
    let result = std::fs::write(&tmp, bytes).and_then(|()| std::fs::rename(&tmp, path));
    if result.is_err() {
        let _ = std::fs::remove_file(&tmp);
    }
    result
}

/// Removes the temporary folders that interrupted runs (killed before they could clean up)
/// left in `out`, unless their process is still running.
pub(crate) fn remove_stale_partials(out: &Path) {
    let Ok(entries) = std::fs::read_dir(out) else {
        return;
    };
    for entry in entries.flatten() {
        let name = entry.file_name().to_string_lossy().into_owned();
        let Some(pid) = name.strip_prefix(".viscobar-partial-") else {
            continue;
        };
        let alive = Path::new("/proc").join(pid).exists();
        if !alive {
            let _ = std::fs::remove_dir_all(entry.path());
        }
    }
}
