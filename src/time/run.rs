//! Running a scene end to end: the step loop and the output files (`summary.json`,
//! `history.csv`, `displacement.csv` or `displacement.npy`), written whole or not at all.

use crate::scene::{OutputFormat, Scene};
use crate::time::RunError;
use crate::time::simulation::{NodeValues, Simulation, StepRecord, Unstarted};
use crate::time::summary::{
    Summary, TIME_TEXT_BYTES, Tracker, output_time, output_time_text, push_output_time,
};
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

/// Runs a scene and writes `summary.json`, `history.csv` and the profiles (`displacement.csv`,
/// or `displacement.npy` with `[output] format = "npy"`) into `out`.
/// The scene is set up (discretised, its initial data evaluated) before anything is created, so
/// a refused scene leaves no trace on disk. The files are written into a temporary folder
/// inside `out` and moved into place only when the run has succeeded, so a failed run leaves
/// earlier results untouched; folders it created for `out` are removed again when it fails.
/// A successful run removes the other format's profile file left by an earlier run in `out`
/// (it belonged to the summary just replaced).
/// `progress` shows a progress bar on stderr for long runs (with the `progress` feature).
pub fn run_to_dir(
    name: &str,
    scene: &Scene,
    out: &Path,
    progress: bool,
) -> Result<Summary, RunError> {
    let start = Instant::now();
    // Again here: a scene's fields are public, so this one may not have been validated.
    let format = scene.output.format;
    format.check_available()?;
    let prepared = Simulation::prepare(scene)?;
    let files = ["history.csv", format.file(), "summary.json"];
    let summary = write_whole(
        out,
        &files,
        |path, source| RunError::Write { path, source },
        |tmp| write_run(name, scene, prepared, start, tmp, progress),
    )?;
    for other in [OutputFormat::Csv, OutputFormat::Npy] {
        if other != format {
            let _ = std::fs::remove_file(out.join(other.file()));
        }
    }
    Ok(summary)
}

/// The files a run writes with the default output (bar or plane).
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
        // Left by an earlier process with this id (`remove_stale_partials` spares it): cleared
        // only when it is there, saving the look-up otherwise.
        if std::fs::create_dir(&tmp).is_err() {
            let _ = std::fs::remove_dir_all(&tmp);
            std::fs::create_dir_all(&tmp).map_err(|e| write_err(tmp.clone(), e))?;
        }
        let outcome = write(&tmp).and_then(|value| {
            for file in files {
                std::fs::rename(tmp.join(file), out.join(file))
                    .map_err(|e| write_err(out.join(file), e))?;
            }
            Ok(value)
        });
        // Empty once its files are moved: one `rmdir` rather than a walk of the folder.
        if std::fs::remove_dir(&tmp).is_err() {
            let _ = std::fs::remove_dir_all(&tmp);
        }
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
    prepared: Unstarted,
    start: Instant,
    dir: &Path,
    progress: bool,
) -> Result<Summary, RunError> {
    let path = |file: &str| dir.join(file);
    let create = |path: &PathBuf| {
        std::fs::File::create(path).map_err(|source| RunError::Write {
            path: path.clone(),
            source,
        })
    };
    let hist_path = path("history.csv");
    let mut hist = std::io::BufWriter::with_capacity(HISTORY_BUFFER_BYTES, create(&hist_path)?);
    let io = |path: &PathBuf| {
        let path = path.clone();
        move |source| RunError::Write { path, source }
    };

    let disc = prepared.discretisation();
    let sides: Vec<&str> = disc
        .constraints
        .iter()
        .filter_map(|c| c.side.map(|s| s.name()))
        .collect();
    let obstacle = !disc.ends_only();
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

    // `t = 0` is written before the start-up step moves `u^0` on.
    let sampling = scene.output_sampling();
    let disp_path = path(sampling.file);
    let mut disp = Profiles::new(create(&disp_path)?, disc, sampling).map_err(io(&disp_path))?;
    disp.write(0.0, prepared.node_values())
        .map_err(io(&disp_path))?;
    let mut sim = prepared.start()?;
    let mut tracker = Tracker::new(&sim, scene.load.density.is_none());
    write_history_row(&mut hist, &sim.first_record(), sides.len(), obstacle)
        .map_err(io(&hist_path))?;
    let steps = scene.steps();
    let every = scene.output.every as usize;
    let nodes = sim.discretisation().nodes;
    let bar = Progress::new(progress, steps, nodes);
    let keep = |n: usize| n.is_multiple_of(every) || n == steps;
    if keep(1) {
        disp.write(sim.time(), sim.node_values())
            .map_err(io(&disp_path))?;
    }
    for _ in 1..steps {
        let r = sim.step()?;
        tracker.observe(&r);
        write_history_row(&mut hist, &r, sides.len(), obstacle).map_err(io(&hist_path))?;
        if keep(r.step) {
            disp.write(sim.time(), sim.node_values())
                .map_err(io(&disp_path))?;
        }
        bar.step(r.step);
    }
    bar.finish();
    hist.flush().map_err(io(&hist_path))?;
    disp.finish().map_err(io(&disp_path))?;
    let mut summary = tracker.finish(name, &sim, start.elapsed().as_secs_f64());
    summary.output = Some(sampling);
    let json_path = path("summary.json");
    let json = serde_json::to_string_pretty(&summary).expect("summary serialises");
    std::fs::write(&json_path, json + "\n").map_err(io(&json_path))?;
    Ok(summary)
}

/// The writer of the profile file in the scene's format.
enum Profiles {
    Csv(ProfileCsv),
    #[cfg(feature = "npy")]
    Npy(crate::time::npy::ProfileNpy),
}

impl Profiles {
    /// Without the `npy` feature an `npy` scene was refused by [`run_to_dir`] before anything
    /// was created; `Unsupported` here all the same rather than a panic.
    fn new(
        file: std::fs::File,
        disc: &crate::time::simulation::Discretisation,
        sampling: crate::scene::OutputSampling,
    ) -> std::io::Result<Self> {
        match sampling.format {
            OutputFormat::Csv => Ok(Self::Csv(ProfileCsv::new(file, disc, sampling))),
            #[cfg(feature = "npy")]
            OutputFormat::Npy => {
                let stride = usize::try_from(sampling.node_stride).unwrap_or(usize::MAX);
                let nodes = written_nodes(stride, disc.nodes)
                    .map(|i| (i, output_time(disc.x(i))))
                    .collect();
                crate::time::npy::ProfileNpy::new(file, sampling.rows, nodes).map(Self::Npy)
            }
            #[cfg(not(feature = "npy"))]
            OutputFormat::Npy => Err(std::io::Error::new(
                std::io::ErrorKind::Unsupported,
                "output.format = \"npy\" needs the cargo feature `npy`",
            )),
        }
    }

    /// The rows of one kept step at time `t` (rounded as every output time is).
    fn write(&mut self, t: f64, values: NodeValues<'_>) -> std::io::Result<()> {
        match self {
            Self::Csv(csv) => csv.write(t, values),
            #[cfg(feature = "npy")]
            Self::Npy(npy) => npy.write(output_time(t), values),
        }
    }

    fn finish(self) -> std::io::Result<()> {
        match self {
            Self::Csv(csv) => csv.finish(),
            #[cfg(feature = "npy")]
            Self::Npy(npy) => npy.finish(),
        }
    }
}

/// Buffer of `history.csv` (a row a step, about 100 bytes).
const HISTORY_BUFFER_BYTES: usize = 1 << 16;
/// `displacement.csv` is written in chunks of about this size: large enough that the write
/// calls cost little next to the formatting, small enough that a short run does not touch
/// (and page-fault in) a buffer larger than its file.
const PROFILE_CHUNK_BYTES: usize = 1 << 17;
/// Room for a row `t,x,u,v\n` with padded fields: `t` and `x` in fields of [`FIELD_BYTES`]
/// (the second written over the first's padding), `u` and `v` of at most 24 bytes each
/// (`-1.2345678901234567e-308`), two separators.
const PROFILE_ROW_MAX_BYTES: usize = 2 * FIELD_BYTES + 2 * NUMBER_BYTES + 2;

/// `displacement.csv`: one row `t,x,u,v` a written node at each kept step. `t` and `x` are
/// rounded (see [`output_time`]) and written as `Display` would, `x` formatted once per run;
/// `u` and `v` in the shortest form that reads back to the same `f64` (Żmij; `1.5e-7` rather
/// than `0.00000015`), several times faster than `core::fmt`. Rows are built in a chunk that
/// goes to the file when nearly full; `t` and `x` are copied as fixed-size fields of
/// [`FIELD_BYTES`] (the bytes after the text are garbage) and the next field overwrites them.
struct ProfileCsv {
    file: std::fs::File,
    /// The chunk, `PROFILE_CHUNK_BYTES` long; `len` bytes of it are rows.
    chunk: Vec<u8>,
    len: usize,
    /// The written nodes: every `stride`-th and the last of `nodes`.
    stride: usize,
    nodes: usize,
    /// The written nodes' `x,` texts one after the other, then [`FIELD_BYTES`] of padding, so
    /// that a field can be copied from any text's start: half the memory of padded fields.
    xs: Vec<u8>,
    /// The length of each text in `xs`.
    x_lens: Vec<u16>,
    /// Rows whose `t` or `x` text is longer than a field (a time or a bar beyond 1e22, written
    /// in full by `Display`) go through this slow path instead.
    long_fields: bool,
}

/// Room for the text of a rounded `t` or `x` and its comma: 12 digits, a point, up to 10
/// leading zeros (`0.0000000000123456789012,`) and a sign fit.
const FIELD_BYTES: usize = 32;

impl ProfileCsv {
    fn new(
        file: std::fs::File,
        disc: &crate::time::simulation::Discretisation,
        sampling: crate::scene::OutputSampling,
    ) -> Self {
        let stride = usize::try_from(sampling.node_stride).unwrap_or(usize::MAX);
        let nodes = disc.nodes;
        let capacity = usize::try_from(sampling.nodes_written).unwrap_or(0);
        // Most texts are 12 digits, a point and a comma, with a leading `0.` or `0.00`.
        let mut xs = Vec::with_capacity(capacity.saturating_mul(18).saturating_add(FIELD_BYTES));
        let mut x_lens = Vec::with_capacity(capacity);
        let mut long_fields = false;
        let mut fast = [0; TIME_TEXT_BYTES];
        for i in written_nodes(stride, nodes) {
            let start = xs.len();
            if let Some(len) = output_time_text(disc.x(i), &mut fast) {
                // A fixed-size copy, then the garbage after the text dropped.
                fast[len] = b',';
                xs.extend_from_slice(&fast[..FIELD_BYTES]);
                xs.truncate(start + len + 1);
            } else {
                push_output_time(disc.x(i), &mut xs);
                xs.push(b',');
            }
            let len = xs.len() - start;
            long_fields |= len > FIELD_BYTES;
            // At most 330 bytes (`Display` of an f64 and a comma).
            x_lens.push(u16::try_from(len).unwrap_or(u16::MAX));
        }
        xs.resize(xs.len() + FIELD_BYTES, 0);
        let mut chunk = vec![0; PROFILE_CHUNK_BYTES];
        let header = b"t,x,u,v\n";
        chunk[..header.len()].copy_from_slice(header);
        Self {
            file,
            chunk,
            len: header.len(),
            stride,
            nodes,
            xs,
            x_lens,
            long_fields,
        }
    }

    /// The rows of one kept step at time `t`.
    fn write(&mut self, t: f64, values: NodeValues<'_>) -> std::io::Result<()> {
        let mut fast = [0; TIME_TEXT_BYTES];
        let (t_field, t_len): ([u8; FIELD_BYTES], u8) = match output_time_text(t, &mut fast) {
            Some(len) if !self.long_fields => {
                fast[len] = b',';
                field(&fast, len + 1)
            }
            _ => {
                let mut t_text = Vec::with_capacity(FIELD_BYTES);
                push_output_time(t, &mut t_text);
                t_text.push(b',');
                if self.long_fields || t_text.len() > FIELD_BYTES {
                    return self.write_long(&t_text, values);
                }
                let len = t_text.len();
                t_text.resize(FIELD_BYTES, 0);
                field(&t_text, len)
            }
        };
        let t_len = usize::from(t_len);
        let (mut bu, mut bv) = (zmij::Buffer::new(), zmij::Buffer::new());
        // Locals rather than fields in the loop (the file write would make them reloaded).
        let (file, chunk, xs) = (&mut self.file, &mut self.chunk[..], &self.xs[..]);
        let mut len = self.len;
        let mut x_at = 0;
        for (j, &x_len) in self.x_lens.iter().enumerate() {
            let (u, v) = values.at(written_node(j, self.stride, self.nodes));
            if len > PROFILE_CHUNK_BYTES - PROFILE_ROW_MAX_BYTES {
                file.write_all(&chunk[..len])?;
                len = 0;
            }
            let Some(row) = chunk[len..].first_chunk_mut::<PROFILE_ROW_MAX_BYTES>() else {
                unreachable!("a chunk has room for a row after the check above")
            };
            row[..FIELD_BYTES].copy_from_slice(&t_field);
            let mut at = t_len;
            row[at..at + FIELD_BYTES].copy_from_slice(&xs[x_at..x_at + FIELD_BYTES]);
            let x_len = usize::from(x_len);
            x_at += x_len;
            at += x_len;
            at += put_number(&mut row[at..], bu.format(u).as_bytes());
            row[at] = b',';
            at += 1;
            at += put_number(&mut row[at..], bv.format(v).as_bytes());
            row[at] = b'\n';
            len += at + 1;
        }
        self.len = len;
        Ok(())
    }

    /// [`ProfileCsv::write`] for texts longer than a field.
    fn write_long(&mut self, t_text: &[u8], values: NodeValues<'_>) -> std::io::Result<()> {
        self.long_fields = true;
        self.file.write_all(&self.chunk[..self.len])?;
        self.len = 0;
        let mut rows = Vec::new();
        let (mut bu, mut bv) = (zmij::Buffer::new(), zmij::Buffer::new());
        let mut x_at = 0;
        for (i, &x_len) in written_nodes(self.stride, self.nodes).zip(&self.x_lens) {
            let (u, v) = values.at(i);
            let x_len = usize::from(x_len);
            rows.extend_from_slice(t_text);
            rows.extend_from_slice(&self.xs[x_at..x_at + x_len]);
            x_at += x_len;
            rows.extend_from_slice(bu.format(u).as_bytes());
            rows.push(b',');
            rows.extend_from_slice(bv.format(v).as_bytes());
            rows.push(b'\n');
            if rows.len() > PROFILE_CHUNK_BYTES {
                self.file.write_all(&rows)?;
                rows.clear();
            }
        }
        self.file.write_all(&rows)
    }

    fn finish(self) -> std::io::Result<()> {
        let mut file = self.file;
        file.write_all(&self.chunk[..self.len])
    }
}

/// Longest text of a Żmij number (`-1.2345678901234567e-308`).
const NUMBER_BYTES: usize = 24;

/// Copies `text` (a Żmij number) to the start of `to` and returns its length. Most are 16 to
/// 24 bytes: then two overlapping 16-byte copies through registers instead of a `memcpy` call.
/// `to` has room for [`NUMBER_BYTES`] (the row's bound).
#[inline(always)]
fn put_number(to: &mut [u8], text: &[u8]) -> usize {
    // A longer text fails the slicing below rather than being cut.
    let n = text.len();
    let to = &mut to[..NUMBER_BYTES];
    if let (Some(head), Some(tail)) = (text.first_chunk::<16>(), text[..n].last_chunk::<16>()) {
        let (head, tail) = (u128::from_ne_bytes(*head), u128::from_ne_bytes(*tail));
        to[n - 16..n].copy_from_slice(&tail.to_ne_bytes());
        to[..16].copy_from_slice(&head.to_ne_bytes());
    } else {
        to[..n].copy_from_slice(&text[..n]);
    }
    n
}

/// The field of the text `text[..len]`: `text`'s first `W` bytes (`text` at least that long;
/// a fixed-size copy, the bytes past the text unread), with the length (at most `W`).
fn field<const W: usize>(text: &[u8], len: usize) -> ([u8; W], u8) {
    let mut f = [0; W];
    f.copy_from_slice(&text[..W]);
    (f, len.min(W) as u8)
}

/// Every `stride`-th of `nodes` nodes and the last ([`crate::scene::OutputSampling::writes_node`]).
fn written_nodes(stride: usize, nodes: usize) -> impl Iterator<Item = usize> {
    let count = nodes
        .checked_sub(1)
        .map_or(0, |l| l.div_ceil(stride.max(1)) + 1);
    (0..count).map(move |j| written_node(j, stride, nodes))
}

/// The `j`-th of [`written_nodes`]: `j·stride`, the last node for the final one.
#[inline(always)]
fn written_node(j: usize, stride: usize, nodes: usize) -> usize {
    j.saturating_mul(stride.max(1)).min(nodes.saturating_sub(1))
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

#[cfg(test)]
mod tests {
    use super::*;

    /// The written nodes are every `stride`-th and the last, each once, in order, and
    /// `written_node` indexes them (the rows' loop uses it).
    #[test]
    fn written_nodes_are_every_strideth_and_the_last() {
        for nodes in 0..40 {
            for stride in 1..9 {
                let mut expected: Vec<usize> = (0..nodes).step_by(stride).collect();
                if nodes > 0 && (nodes - 1) % stride != 0 {
                    expected.push(nodes - 1);
                }
                let got: Vec<usize> = written_nodes(stride, nodes).collect();
                assert_eq!(got, expected, "{nodes} nodes, stride {stride}");
                for (j, &i) in expected.iter().enumerate() {
                    assert_eq!(written_node(j, stride, nodes), i);
                }
            }
        }
    }

    fn fresh(tag: &str) -> PathBuf {
        let dir = std::env::temp_dir().join(format!("viscobar-whole-{tag}-{}", std::process::id()));
        let _ = std::fs::remove_dir_all(&dir);
        dir
    }

    /// A folder left with this process's id (not removed as stale: the id is alive) is cleared
    /// and reused; the temporary folder is gone afterwards, whether the write succeeds or fails.
    #[test]
    fn write_whole_reuses_a_left_folder_and_removes_its_own() {
        let out = fresh("left");
        let tmp = out.join(format!(".viscobar-partial-{}", std::process::id()));
        std::fs::create_dir_all(tmp.join("sub")).unwrap();
        std::fs::write(tmp.join("a.csv"), "old").unwrap();
        let io = |path: PathBuf, e: std::io::Error| format!("{}: {e}", path.display());
        let ok = write_whole(&out, &["a.csv"], io, |dir| {
            assert!(!dir.join("sub").exists(), "the left folder is cleared");
            std::fs::write(dir.join("a.csv"), "new").map_err(|e| e.to_string())
        });
        assert_eq!(ok, Ok(()));
        assert_eq!(std::fs::read_to_string(out.join("a.csv")).unwrap(), "new");
        assert!(!tmp.exists());
        let failed: Result<(), String> = write_whole(&out, &["a.csv"], io, |dir| {
            std::fs::write(dir.join("a.csv"), "half").unwrap();
            Err("failed".to_string())
        });
        assert!(failed.is_err());
        assert_eq!(std::fs::read_to_string(out.join("a.csv")).unwrap(), "new");
        assert!(
            !tmp.exists(),
            "a failed write's folder, not empty, is removed too"
        );
        std::fs::remove_dir_all(&out).unwrap();
    }
}
