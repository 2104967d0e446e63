//! `bench-table`: the last criterion measurements of `benches/step.rs` and `benches/scenes.rs`
//! as Markdown (median time per step or per run, ns per node-step, and for steps the ratio to
//! the unconstrained step at equal J), read from `target/criterion/{step,scenes,load,setup}/
//! */…/new/estimates.json`, followed by the performance targets, each marked met or not met,
//! and a short headline. With `--update FILE…`, the headline and the tables replace the blocks
//! between `<!-- generated:bench-headline -->` / `<!-- generated:bench-table -->` and their
//! `<!-- end:… -->` markers in each file named (a file must hold at least one of them), so the
//! timings quoted in the READMEs are never typed by hand; each block names the dates of the
//! measurements, the machine and [`UPDATE_COMMAND`].
//!
//! A measurement more than `STALE_AFTER_S` older than the newest one of its group is marked
//! `(stale)` and left out of the targets (and out of the written blocks): criterion keeps the
//! last result of every bench ever run, so a partial run would otherwise mix in rows measured
//! on older code. `--update` also refuses a group measured more than `STALE_AFTER_S` before
//! the newest group.

use crate::performance::timings::{cpu_model, utc_date_time_at};
use crate::verify::{Section, update_document};
use std::collections::BTreeMap;
use std::fmt::Write;
use std::path::{Path, PathBuf};

/// Targets of the unconstrained step, of its diagnostics and of the exact step at the ends.
const BARE_NS_PER_NODE_TARGET: f64 = 2.0;
const DIAGNOSTICS_OVERHEAD_TARGET: f64 = 0.5;
const EXACT_RATIO_TARGET: f64 = 1.15;
/// Targets of the loads: a forced talk scene against its unforced twin, per step; a load that
/// does not separate (two transcendental calls), per node-step.
const FORCED_RATIO_TARGET: f64 = 1.3;
const MIXED_LOAD_NS_TARGET: f64 = 30.0;
/// Targets of the distributed obstacle: the step against the unconstrained one at J = 1e4 and
/// 1e5, and at J = 1e5 with Δt = 10Δx.
const DISTRIBUTED_RATIO_TARGET: f64 = 4.0;
const DISTRIBUTED_DT10DX_RATIO_TARGET: f64 = 15.0;

/// Targets of the set-up and the output: the 400-step run against its steps alone, that run's
/// ns per node-step, and the refined 1e5-element run end to end (ns per node-step). The
/// one-step run is reported for information, without a target.
const SETUP_RATIO_TARGET: f64 = 1.3;
const SETUP_NS_TARGET: f64 = 4.5;
const REFINED_NS_TARGET: f64 = 3.0;

/// Rows measured this long before the newest row of their group are stale.
const STALE_AFTER_S: u64 = 3600;

/// The command that writes the blocks, as the blocks quote it.
pub const UPDATE_COMMAND: &str = concat!(
    "cargo run --release -p viscobar-certificate -- bench-table ",
    "--update README.md benches/README.md"
);

/// Median and modification time (s since the epoch) of an `estimates.json`.
fn median_ns(path: &Path) -> Option<(f64, u64)> {
    let text = std::fs::read_to_string(path).ok()?;
    let v: serde_json::Value = serde_json::from_str(&text).ok()?;
    let modified = std::fs::metadata(path).ok()?.modified().ok()?;
    let age = modified
        .duration_since(std::time::UNIX_EPOCH)
        .ok()?
        .as_secs();
    Some((v["median"]["point_estimate"].as_f64()?, age))
}

/// One group's rows within [`STALE_AFTER_S`] of its newest, the names of the stale ones, and
/// the times of its oldest kept and newest row.
struct Group<K> {
    rows: BTreeMap<K, f64>,
    stale: Vec<K>,
    span: Option<(u64, u64)>,
}

fn fresh<K: Ord + Clone>(rows: BTreeMap<K, (f64, u64)>) -> Group<K> {
    let newest = rows.values().map(|r| r.1).max();
    let mut group = Group {
        rows: BTreeMap::new(),
        stale: Vec::new(),
        span: None,
    };
    for (k, (t, at)) in rows {
        if at + STALE_AFTER_S < newest.unwrap_or(0) {
            group.stale.push(k);
        } else {
            group.rows.insert(k, t);
            group.span = Some(group.span.map_or((at, at), |(a, b)| (a.min(at), b.max(at))));
        }
    }
    group
}

/// `(size, label) -> (median ns, time)` of a group laid out as `group/label/size/new`.
fn step_rows(root: &Path) -> BTreeMap<(u64, String), (f64, u64)> {
    let mut rows = BTreeMap::new();
    for label in std::fs::read_dir(root).into_iter().flatten().flatten() {
        let name = label.file_name().to_string_lossy().into_owned();
        for size in std::fs::read_dir(label.path())
            .into_iter()
            .flatten()
            .flatten()
        {
            let Ok(j) = size.file_name().to_string_lossy().parse::<u64>() else {
                continue;
            };
            if let Some(t) = median_ns(&size.path().join("new/estimates.json")) {
                rows.insert((j, name.clone()), t);
            }
        }
    }
    rows
}

/// `label -> (median ns, time)` of a group laid out as `group/label/new`.
fn named_rows(root: &Path) -> BTreeMap<String, (f64, u64)> {
    let mut rows = BTreeMap::new();
    for entry in std::fs::read_dir(root).into_iter().flatten().flatten() {
        let name = entry.file_name().to_string_lossy().into_owned();
        if let Some(t) = median_ns(&entry.path().join("new/estimates.json")) {
            rows.insert(name, t);
        }
    }
    rows
}

fn verdict(ok: bool) -> &'static str {
    if ok { "met" } else { "not met" }
}

/// Node-steps of each run of the `setup` group (`benches/scenes.rs`).
fn setup_node_steps(name: &str) -> f64 {
    match name {
        "one-step" => 16_385.0,
        "refined-1e5" | "refined-1e5-npy" => 100_001.0 * 1600.0,
        _ => 16_385.0 * 400.0,
    }
}

/// The last measurements of the four groups.
struct Measurements {
    steps: Group<(u64, String)>,
    scenes: Group<String>,
    loads: Group<(u64, String)>,
    setup: Group<String>,
}

impl Measurements {
    fn read(target: &Path) -> Self {
        Self {
            steps: fresh(step_rows(&target.join("step"))),
            scenes: fresh(named_rows(&target.join("scenes"))),
            loads: fresh(step_rows(&target.join("load"))),
            setup: fresh(named_rows(&target.join("setup"))),
        }
    }

    fn spans(&self) -> [(&'static str, Option<(u64, u64)>); 4] {
        [
            ("step", self.steps.span),
            ("scenes", self.scenes.span),
            ("load", self.loads.span),
            ("setup", self.setup.span),
        ]
    }

    /// The oldest and newest kept row over all groups.
    fn span(&self) -> Option<(u64, u64)> {
        let spans = self.spans();
        let kept = spans.iter().filter_map(|s| s.1);
        let first = kept.clone().map(|s| s.0).min()?;
        Some((first, kept.map(|s| s.1).max()?))
    }

    /// Refuses a group measured more than `STALE_AFTER_S` before the newest one.
    fn check_one_run(&self) -> Result<(), String> {
        let Some((_, newest)) = self.span() else {
            return Err("no measurements in target/criterion: run the benches first".into());
        };
        for (name, span) in self.spans() {
            if let Some((_, last)) = span
                && last + STALE_AFTER_S < newest
            {
                return Err(format!(
                    "group `{name}` was last measured at {} UTC, more than an hour before the \
                     newest measurement ({} UTC): rerun it so that every block comes from one run",
                    utc_date_time_at(last),
                    utc_date_time_at(newest)
                ));
            }
        }
        Ok(())
    }

    fn step(&self, j: u64, name: &str) -> Option<f64> {
        self.steps.rows.get(&(j, name.to_string())).copied()
    }

    /// Ratio of a step to the unconstrained step at the same J.
    fn step_ratio(&self, j: u64, name: &str) -> Option<f64> {
        Some(self.step(j, name)? / self.step(j, "unconstrained")?)
    }

    /// Every table and every target line; with `list_stale`, the stale rows too.
    fn tables(&self, list_stale: bool) -> String {
        let mut out = String::new();
        self.step_table(&mut out, list_stale);
        self.scene_table(&mut out, list_stale);
        self.load_table(&mut out, list_stale);
        self.setup_table(&mut out, list_stale);
        self.step_targets(&mut out);
        out
    }

    fn step_table(&self, out: &mut String, list_stale: bool) {
        if self.steps.rows.is_empty() {
            return;
        }
        let _ = writeln!(
            out,
            "| elements | step | median per step | ns per node-step | / unconstrained |"
        );
        let _ = writeln!(out, "|---|---|---|---|---|");
        for ((j, name), t) in &self.steps.rows {
            let base = self.step(*j, "unconstrained").unwrap_or(f64::NAN);
            let _ = writeln!(
                out,
                "| {j} | {name} | {:.1} µs | {:.2} | {:.3} |",
                t / 1e3,
                t / (*j + 1) as f64,
                t / base
            );
        }
        for (j, name) in self.steps.stale.iter().filter(|_| list_stale) {
            let _ = writeln!(out, "| {j} | {name} (stale) | | | |");
        }
        let distributed: Vec<(u64, &str, f64, f64)> = [
            (10_000, "distributed-exact", DISTRIBUTED_RATIO_TARGET),
            (100_000, "distributed-exact", DISTRIBUTED_RATIO_TARGET),
            (
                100_000,
                "distributed-exact-dt10dx",
                DISTRIBUTED_DT10DX_RATIO_TARGET,
            ),
        ]
        .into_iter()
        .filter_map(|(j, name, target)| Some((j, name, self.step_ratio(j, name)?, target)))
        .collect();
        if !distributed.is_empty() {
            let _ = writeln!(out, "\nTargets (distributed obstacle):");
            for (j, name, ratio, target) in distributed {
                let _ = writeln!(
                    out,
                    "- {name} at J = {j}: {ratio:.3}x unconstrained (target <= {target}): {}",
                    verdict(ratio <= target)
                );
            }
        }
    }

    fn scene_table(&self, out: &mut String, list_stale: bool) {
        if self.scenes.rows.is_empty() {
            return;
        }
        let _ = writeln!(
            out,
            "\n| scene (default size, end to end) | median per run | ns per node-step |"
        );
        let _ = writeln!(out, "|---|---|---|");
        for (name, t) in &self.scenes.rows {
            let (_, scene) = viscobar::scene::load(name, &[]).expect("talk scene");
            let node_steps = (scene.elements() + 1) as f64 * scene.steps() as f64;
            let _ = writeln!(
                out,
                "| {name} | {:.1} ms | {:.2} |",
                t / 1e6,
                t / node_steps
            );
        }
        for name in self.scenes.stale.iter().filter(|_| list_stale) {
            let _ = writeln!(out, "| {name} (stale) | | |");
        }
    }

    /// The unforced twin of a forced or mixed-load scene.
    fn twin(name: &str) -> Option<&str> {
        name.strip_suffix("-forced")
            .or(name.strip_suffix("-mixed-load"))
    }

    fn load_table(&self, out: &mut String, list_stale: bool) {
        let loads = &self.loads.rows;
        if loads.is_empty() {
            return;
        }
        let _ = writeln!(
            out,
            "\n| elements | scene | median per step | ns per node-step | / unforced twin |"
        );
        let _ = writeln!(out, "|---|---|---|---|---|");
        for ((j, name), t) in loads {
            let ratio = Self::twin(name)
                .and_then(|tw| loads.get(&(*j, tw.to_string())))
                .map(|b| format!("{:.3}", t / b))
                .unwrap_or_default();
            let _ = writeln!(
                out,
                "| {j} | {name} | {:.1} µs | {:.2} | {ratio} |",
                t / 1e3,
                t / (*j + 1) as f64
            );
        }
        for (j, name) in self.loads.stale.iter().filter(|_| list_stale) {
            let _ = writeln!(out, "| {j} | {name} (stale) | | | |");
        }
        let _ = writeln!(out, "\nTargets (loads):");
        for ((j, name), t) in loads {
            if let Some(twin) = name.strip_suffix("-forced") {
                if let Some(b) = loads.get(&(*j, twin.to_string())) {
                    let _ = writeln!(
                        out,
                        "- {name} at J = {j}: {:.3}x its unforced twin (target <= {FORCED_RATIO_TARGET}): {}",
                        t / b,
                        verdict(t / b <= FORCED_RATIO_TARGET)
                    );
                }
            } else if name.ends_with("-mixed-load") {
                let per = t / (*j + 1) as f64;
                let _ = writeln!(
                    out,
                    "- {name} at J = {j}: {per:.2} ns per node-step (target <= {MIXED_LOAD_NS_TARGET}): {}",
                    verdict(per <= MIXED_LOAD_NS_TARGET)
                );
            }
        }
    }

    fn setup_table(&self, out: &mut String, list_stale: bool) {
        let setup = &self.setup.rows;
        if setup.is_empty() {
            return;
        }
        let _ = writeln!(
            out,
            "\n| run (`setup` group, files written) | median | ns per node-step |"
        );
        let _ = writeln!(out, "|---|---|---|");
        for (name, t) in setup {
            let _ = writeln!(
                out,
                "| {name} | {:.2} ms | {:.2} |",
                t / 1e6,
                t / setup_node_steps(name)
            );
        }
        for name in self.setup.stale.iter().filter(|_| list_stale) {
            let _ = writeln!(out, "| {name} (stale) | | |");
        }
        let _ = writeln!(out, "\nTargets (set-up and output):");
        if let (Some(run), Some(steps)) = (setup.get("400-steps"), setup.get("400-steps-stepping"))
        {
            let _ = writeln!(
                out,
                "- 400-step run: {:.3}x its steps alone (target <= {SETUP_RATIO_TARGET}): {}",
                run / steps,
                verdict(run / steps <= SETUP_RATIO_TARGET)
            );
            let per = run / setup_node_steps("400-steps");
            let _ = writeln!(
                out,
                "- 400-step run: {per:.2} ns per node-step (target <= {SETUP_NS_TARGET}): {}",
                verdict(per <= SETUP_NS_TARGET)
            );
        }
        for (name, what) in [
            (
                "refined-1e5",
                "refined run, 1e5 elements, 1600 steps, default output",
            ),
            (
                "refined-1e5-npy",
                "refined run as above writing displacement.npy (feature `npy`)",
            ),
        ] {
            if let Some(t) = setup.get(name) {
                let per = t / setup_node_steps(name);
                let _ = writeln!(
                    out,
                    "- {what}: {per:.2} ns per node-step (target <= {REFINED_NS_TARGET}): {}",
                    verdict(per <= REFINED_NS_TARGET)
                );
            }
        }
    }

    fn step_targets(&self, out: &mut String) {
        if self.steps.rows.is_empty() {
            return;
        }
        let _ = writeln!(out, "\nTargets (bar steps):");
        if let Some(bare) = self.step(100_000, "unconstrained-bare") {
            let per_node = bare / 100_001.0;
            let _ = writeln!(
                out,
                "- unconstrained step without diagnostics at J = 1e5: {per_node:.2} ns per node-step \
                 (target <= {BARE_NS_PER_NODE_TARGET}): {}",
                verdict(per_node <= BARE_NS_PER_NODE_TARGET)
            );
        }
        let sizes: std::collections::BTreeSet<u64> = self.steps.rows.keys().map(|k| k.0).collect();
        for j in sizes {
            let (Some(bare), Some(full)) = (
                self.step(j, "unconstrained-bare"),
                self.step(j, "unconstrained"),
            ) else {
                continue;
            };
            let over = full / bare - 1.0;
            let _ = writeln!(
                out,
                "- diagnostics at J = {j}: +{:.0} % over the bare step (target <= {:.0} %): {}",
                100.0 * over,
                100.0 * DIAGNOSTICS_OVERHEAD_TARGET,
                verdict(over <= DIAGNOSTICS_OVERHEAD_TARGET)
            );
            for name in ["exact-one-end", "exact-two-ends"] {
                if let Some(r) = self.step_ratio(j, name) {
                    let _ = writeln!(
                        out,
                        "- {name} at J = {j}: {r:.3}x unconstrained (target <= {EXACT_RATIO_TARGET}): {}",
                        verdict(r <= EXACT_RATIO_TARGET)
                    );
                }
            }
        }
    }

    /// The targets of the loads, the distributed obstacle and the set-up in four lines (and the
    /// step's cost at J = 1e5 for scale); a figure this run did not measure is said to be missing.
    fn headline(&self) -> String {
        const MISSING: &str = "not measured in this run";
        let mut out = String::new();
        let per_node = |t: f64, j: u64| t / (j + 1) as f64;
        let steps = match (
            self.step(100_000, "unconstrained"),
            self.step(100_000, "unconstrained-bare"),
        ) {
            (Some(full), Some(bare)) => format!(
                "{:.2} ns per node-step with the energy balance, {:.2} without",
                per_node(full, 100_000),
                per_node(bare, 100_000)
            ),
            _ => MISSING.into(),
        };
        let _ = writeln!(out, "- **Steps**, unconstrained, J = 1e5: {steps}.");
        let loads = &self.loads.rows;
        let forced: Vec<f64> = loads
            .iter()
            .filter_map(|((j, name), t)| {
                let twin = name.strip_suffix("-forced")?;
                Some(t / loads.get(&(*j, twin.to_string()))?)
            })
            .collect();
        let mixed: Vec<f64> = loads
            .iter()
            .filter(|((_, name), _)| name.ends_with("-mixed-load"))
            .map(|((j, _), t)| per_node(*t, *j))
            .collect();
        // `what` with the range of `v` in place of `{}`, then the target and its verdict.
        let range = |v: &[f64], digits: usize, what: &str, target: f64| {
            let (lo, hi) = v
                .iter()
                .fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), &x| {
                    (a.min(x), b.max(x))
                });
            if v.is_empty() {
                format!("{} {MISSING}", what.replace("{}", "…"))
            } else {
                format!(
                    "{} (target <= {target}: {})",
                    what.replace("{}", &format!("{lo:.digits$}–{hi:.digits$}")),
                    verdict(hi <= target)
                )
            }
        };
        let _ = writeln!(
            out,
            "- **Loads**, J = 1e2 … 1e5: a forced talk scene costs {}; a load that does not \
             separate costs {}.",
            range(
                &forced,
                3,
                "{}x its unforced twin per step",
                FORCED_RATIO_TARGET
            ),
            range(&mixed, 1, "{} ns per node-step", MIXED_LOAD_NS_TARGET),
        );
        let ratio = |j: u64, name: &str, target: f64| {
            self.step_ratio(j, name).map_or(MISSING.to_string(), |r| {
                format!("{r:.3}x (target <= {target}: {})", verdict(r <= target))
            })
        };
        let _ = writeln!(
            out,
            "- **Distributed obstacle**, against the unconstrained step: {} at J = 1e4, {} at \
             J = 1e5, {} at J = 1e5 with Δt = 10Δx.",
            ratio(10_000, "distributed-exact", DISTRIBUTED_RATIO_TARGET),
            ratio(100_000, "distributed-exact", DISTRIBUTED_RATIO_TARGET),
            ratio(
                100_000,
                "distributed-exact-dt10dx",
                DISTRIBUTED_DT10DX_RATIO_TARGET
            ),
        );
        let setup = &self.setup.rows;
        let one_step = setup
            .get("one-step")
            .map_or(MISSING.to_string(), |t| format!("{:.2} ms", t / 1e6));
        let four_hundred = match (setup.get("400-steps"), setup.get("400-steps-stepping")) {
            (Some(run), Some(steps)) => {
                let per = run / setup_node_steps("400-steps");
                format!(
                    "{:.3}x its steps alone (target <= {SETUP_RATIO_TARGET}: {}) and {per:.2} ns \
                     per node-step (target <= {SETUP_NS_TARGET}: {})",
                    run / steps,
                    verdict(run / steps <= SETUP_RATIO_TARGET),
                    verdict(per <= SETUP_NS_TARGET)
                )
            }
            _ => MISSING.into(),
        };
        let refined = |name: &str| {
            setup.get(name).map_or(MISSING.to_string(), |t| {
                let per = t / setup_node_steps(name);
                format!(
                    "{per:.2} ns per node-step (target <= {REFINED_NS_TARGET}: {})",
                    verdict(per <= REFINED_NS_TARGET)
                )
            })
        };
        let _ = writeln!(
            out,
            "- **Set-up and output**, two-end bar of 16384 elements: a one-step run takes {one_step}; \
             a 400-step run costs {four_hundred}. The refined run (1e5 elements, 1600 steps, \
             default output) costs {} end to end, {} writing `displacement.npy`.",
            refined("refined-1e5"),
            refined("refined-1e5-npy"),
        );
        out
    }

    /// The line that opens each written block: when, where, and by which command.
    fn provenance(&self) -> String {
        let (first, last) = self.span().unwrap_or((0, 0));
        let cores = std::thread::available_parallelism().map_or(0, |n| n.get());
        format!(
            "Criterion medians measured {} – {} UTC on {} ({cores} cores), written by `{UPDATE_COMMAND}`.\n\n",
            utc_date_time_at(first),
            utc_date_time_at(last),
            cpu_model()
        )
    }
}

/// Replaces, in each file, the generated blocks it holds; every file is checked before any
/// is written, and each is written whole or not at all.
fn update_files(files: &[PathBuf], m: &Measurements) -> Result<(), String> {
    m.check_one_run()?;
    let head = m.provenance();
    let sections = [
        Section {
            id: "bench-headline",
            markdown: format!("{head}{}", m.headline()),
        },
        Section {
            id: "bench-table",
            markdown: format!("{head}{}", m.tables(false)),
        },
    ];
    let mut written = Vec::new();
    for path in files {
        let doc = std::fs::read_to_string(path)
            .map_err(|e| format!("cannot read {}: {e}", path.display()))?;
        let present: Vec<Section> = sections
            .iter()
            .filter(|s| doc.contains(&format!("<!-- generated:{} -->\n", s.id)))
            .cloned()
            .collect();
        if present.is_empty() {
            return Err(format!(
                "{} holds neither `<!-- generated:bench-headline -->` nor \
                 `<!-- generated:bench-table -->`",
                path.display()
            ));
        }
        let new =
            update_document(&doc, &present).map_err(|e| format!("{}: {e}", path.display()))?;
        written.push((path, new));
    }
    for (path, text) in written {
        viscobar::internals::output::files::write_atomically(path, text.as_bytes())
            .map_err(|e| format!("cannot write {}: {e}", path.display()))?;
    }
    Ok(())
}

/// `bench-table`: prints the tables, the targets and the headline, or with `update` rewrites
/// the blocks of those files. The exit code: 0; 1 without measurements or when a file cannot be
/// updated.
pub fn run(update: Option<&[PathBuf]>) -> i32 {
    let target = crate::workspace_root().join("target/criterion");
    let m = Measurements::read(&target);
    match update {
        None => {
            if m.span().is_none() {
                eprintln!(
                    "no measurements in target/criterion: run `cargo bench --bench step` first"
                );
                return 1;
            }
            print!("{}", m.tables(true));
            println!("\nHeadline:\n{}", m.headline());
            0
        }
        Some(files) => match update_files(files, &m) {
            Ok(()) => 0,
            Err(e) => {
                eprintln!("error: {e}");
                1
            }
        },
    }
}
