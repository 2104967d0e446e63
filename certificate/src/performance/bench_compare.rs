//! `bench-compare`: the bar's step benches of two commits side by side. Reads criterion's
//! medians of `benches/step.rs` from a base run (`--base`: another worktree's
//! `target/criterion`) and from this checkout's `target/criterion`, runs saved as criterion
//! baselines (`--runs r1,r2,r3`, each a process of its own, alternately on the two commits).
//! For each case of [`CASES`]: the fastest run of each side, their ratio against
//! [`RATIO_LIMIT`], and the median of the runs with the range of the ratios taken pairwise.
//! The fastest run is judged because one binary's step time differs by up to a third from
//! process to process on this machine (`benches/README.md`, "Reading the numbers"). With
//! `--update FILE`, the block between `<!-- generated:bench-compare -->` and
//! `<!-- end:bench-compare -->` is rewritten, stamped with the dates, machine and commands.

use crate::performance::timings::{cpu_model, utc_date_time_at};
use crate::verify::{Section, update_document};
use std::fmt::Write;
use std::path::{Path, PathBuf};
use viscobar::study::converge::median;

/// The cases compared: criterion's id under `target/criterion`, `group/label/J`.
pub const CASES: [&str; 25] = [
    "step/unconstrained-bare/10000",
    "step/unconstrained-bare/100000",
    "step/unconstrained-bare/1000000",
    "step/unconstrained/10000",
    "step/unconstrained/100000",
    "step/unconstrained/1000000",
    "step/exact-one-end/10000",
    "step/exact-one-end/100000",
    "step/exact-one-end/1000000",
    "step/exact-two-ends/10000",
    "step/exact-two-ends/100000",
    "step/exact-two-ends/1000000",
    "step/distributed-exact/10000",
    "step/distributed-exact/100000",
    "step/distributed-exact-dt10dx/100000",
    "load/both-ends/10000",
    "load/both-ends/100000",
    "load/both-ends-forced/10000",
    "load/both-ends-forced/100000",
    "load/both-ends-mixed-load/10000",
    "load/both-ends-mixed-load/100000",
    "load/distributed/10000",
    "load/distributed/100000",
    "load/distributed-forced/10000",
    "load/distributed-forced/100000",
];

/// The sizes of the table's columns.
const SIZES: [&str; 3] = ["10000", "100000", "1000000"];

/// The largest ratio new/base of a step's time allowed (fastest run against fastest run).
pub const RATIO_LIMIT: f64 = 1.15;

/// The command that writes the block, as the block quotes it (followed by its arguments).
pub const COMPARE_COMMAND: &str = "cargo run --release -p viscobar-certificate -- bench-compare";

/// The bench filter of [`CASES`], as the block's commands quote it.
const FILTER: &str = concat!(
    "^step/(unconstrained|unconstrained-bare|exact-one-end|exact-two-ends)/(10000|100000|1000000)$",
    "|^step/(distributed-exact/(10000|100000)|distributed-exact-dt10dx/100000)$",
    "|^load/(both-ends|both-ends-forced|both-ends-mixed-load|distributed|distributed-forced)/(10000|100000)$"
);

/// What the command is given.
pub struct Options {
    /// The twins' factors (block `bench-twins`) instead of the comparison.
    pub twins: bool,
    /// The base commit's `target/criterion`.
    pub base: PathBuf,
    /// The base commit, as the block names it.
    pub base_commit: String,
    /// The criterion baselines of the runs (`new` when not saved under a name).
    pub runs: Vec<String>,
    pub update: Option<PathBuf>,
}

/// A case's median per run (ns) and the modification times of the estimates read.
fn medians(root: &Path, case: &str, runs: &[String]) -> Vec<(f64, u64)> {
    runs.iter()
        .filter_map(|run| {
            let path = root.join(case).join(run).join("estimates.json");
            let text = std::fs::read_to_string(&path).ok()?;
            let v: serde_json::Value = serde_json::from_str(&text).ok()?;
            let at = std::fs::metadata(&path).ok()?.modified().ok()?;
            let at = at.duration_since(std::time::UNIX_EPOCH).ok()?.as_secs();
            Some((v["median"]["point_estimate"].as_f64()?, at))
        })
        .collect()
}

/// Per case: the fastest of the base's and of the new runs and their ratio, the median of
/// each side's runs and their ratio, and the smallest and largest ratio of the runs taken
/// pairwise; with the modification times of the estimates. An error when a case lacks a run
/// on either side.
struct Compared {
    fastest: [f64; 2],
    ratio: f64,
    medians: [f64; 2],
    pairwise: (f64, f64),
}

fn compare(
    base: &Path,
    new: &Path,
    case: &str,
    runs: &[String],
    span: &mut (u64, u64),
) -> Result<Compared, String> {
    let (b, n) = (medians(base, case, runs), medians(new, case, runs));
    if b.len() != runs.len() || n.len() != runs.len() {
        return Err(format!(
            "{case}: {} base and {} new runs of {} ({})",
            b.len(),
            n.len(),
            runs.len(),
            runs.join(", ")
        ));
    }
    for &(_, at) in b.iter().chain(&n) {
        *span = (span.0.min(at), span.1.max(at));
    }
    let pairwise = (n.iter().zip(&b).map(|(n, b)| n.0 / b.0))
        .fold((f64::INFINITY, 0.0f64), |(lo, hi), r| {
            (lo.min(r), hi.max(r))
        });
    let fastest = |runs: &[(f64, u64)]| runs.iter().map(|r| r.0).fold(f64::INFINITY, f64::min);
    let fastest = [fastest(&b), fastest(&n)];
    Ok(Compared {
        fastest,
        ratio: fastest[1] / fastest[0],
        medians: [b, n].map(|runs| median(runs.iter().map(|r| r.0).collect())),
        pairwise,
    })
}

/// The labels of [`CASES`] in order of appearance, with the sizes measured of each.
fn labels() -> Vec<(&'static str, Vec<&'static str>)> {
    let mut out: Vec<(&str, Vec<&str>)> = Vec::new();
    for case in CASES {
        let (label, j) = case.rsplit_once('/').expect("group/label/J");
        match out.last_mut() {
            Some((l, sizes)) if *l == label => sizes.push(j),
            _ => out.push((label, vec![j])),
        }
    }
    out
}

/// The block: provenance, the table, the verdict and the commands.
pub fn markdown(o: &Options) -> Result<String, String> {
    let here = crate::workspace_root().join("target/criterion");
    let mut span = (u64::MAX, 0u64);
    let (mut rows, mut worst, mut over) = (String::new(), 0.0f64, Vec::new());
    for (label, sizes) in labels() {
        let mut cells = vec![String::new(); SIZES.len()];
        for j in sizes {
            let case = format!("{label}/{j}");
            let c = compare(&o.base, &here, &case, &o.runs, &mut span)?;
            worst = worst.max(c.ratio);
            let ok = c.ratio <= RATIO_LIMIT;
            if !ok {
                over.push(case);
            }
            let column = SIZES.iter().position(|s| *s == j).expect("a size of SIZES");
            cells[column] = format!(
                "{:.1} → {:.1}, {:.3}x {}; medians {:.3}x ({:.2}–{:.2})",
                c.fastest[0] / 1e3,
                c.fastest[1] / 1e3,
                c.ratio,
                if ok { "met" } else { "**not met**" },
                c.medians[1] / c.medians[0],
                c.pairwise.0,
                c.pairwise.1,
            );
        }
        writeln!(rows, "| {label} | {} |", cells.join(" | ")).unwrap();
    }
    let cores = std::thread::available_parallelism().map_or(0, |n| n.get());
    let runs = o.runs.join(",");
    let mut out = format!(
        "Criterion medians measured {} – {} UTC on {} ({cores} cores), {} run(s) of each \
         commit alternately, written by `{COMPARE_COMMAND} --base $BASE/target/criterion \
         --base-commit {} --runs {runs} --update benches/README.md`.\n\n",
        utc_date_time_at(span.0),
        utc_date_time_at(span.1),
        cpu_model(),
        o.runs.len(),
        o.base_commit,
    );
    writeln!(
        out,
        "Per cell: the fastest run's median step in µs on {} → on this commit, their ratio \
         and the limit <= {RATIO_LIMIT}x met or not; then the ratio of the runs' medians and \
         its range over the runs taken pairwise.\n",
        o.base_commit
    )
    .unwrap();
    out.push_str("| step | J = 1e4 | J = 1e5 | J = 1e6 |\n|---|---|---|---|\n");
    out.push_str(&rows);
    writeln!(
        out,
        "\nLimit: every step within {RATIO_LIMIT}x of {}: {} (largest ratio {worst:.3}{}).\n",
        o.base_commit,
        if over.is_empty() { "met" } else { "not met" },
        if over.is_empty() {
            String::new()
        } else {
            format!("; over: {}", over.join(", "))
        }
    )
    .unwrap();
    let bench = format!(
        "cargo bench --bench step -- --warm-up-time 0.5 --measurement-time 2 \
         --save-baseline rK \"{FILTER}\""
    );
    writeln!(
        out,
        "Commands, for K = 1, 2, … in turn (`$BASE` a worktree of {} with its own `target/`): \
         `(cd $BASE && {bench})`, then the same here.",
        o.base_commit
    )
    .unwrap();
    Ok(out)
}

/// The twins of [`twins_markdown`]: name, plain version, the step and the variant of
/// `benches/twins.rs` whose median over the default's is the factor.
const TWINS: [(&str, &str, &str, &str); 8] = [
    (
        "`ldlt_fast::TwistedLdlt`",
        "`ldlt::Ldlt`",
        "unconstrained",
        "plain-solve",
    ),
    (
        "`ldlt_fast::TwistedLdlt`",
        "`ldlt::Ldlt`",
        "exact-two-ends",
        "plain-solve",
    ),
    (
        "`rhs_fast::rhs_into_uniform`",
        "`rhs::rhs_into`",
        "unconstrained",
        "plain-rhs",
    ),
    (
        "`energy_fast::energy_sums_uniform`",
        "`energy::energy_sums`",
        "unconstrained",
        "plain-energy",
    ),
    (
        "warm start (exact end solver)",
        "enumeration every step",
        "exact-two-ends",
        "no-warm-start",
    ),
    ("all of the above", "all plain", "unconstrained", "plain"),
    ("all of the above", "all plain", "exact-two-ends", "plain"),
    (
        "`EndEnumeration`",
        "`CondensedLcp`",
        "exact-two-ends",
        "general-solver",
    ),
];

/// The sizes of the obstacle's step in `benches/twins.rs` (`twins-obstacle`), and those at
/// which the general `CondensedLcp` is run (its `DENSE_OBSTACLE_MAX_ELEMENTS`).
const OBSTACLE_SIZES: [&str; 3] = ["100", "400", "10000"];
const DENSE_OBSTACLE_SIZES: [&str; 2] = ["100", "400"];

/// The block `bench-twins`: each twin's factor on a step (the step's median with the plain
/// version over its median with the twin) at J = 1e4, 1e5, 1e6, from this checkout's last run
/// of `benches/twins.rs`; and the compiled load evaluation's, as the step's median plus the
/// node-by-node evaluation's minus the compiled one's, over the step's.
pub fn twins_markdown() -> Result<String, String> {
    let root = crate::workspace_root().join("target/criterion");
    let new = ["new".to_string()];
    let mut span = (u64::MAX, 0u64);
    let mut read = |case: String| -> Result<f64, String> {
        let m = medians(&root, &case, &new);
        let &(t, at) = m.first().ok_or(format!("{case}: no measurement"))?;
        span = (span.0.min(at), span.1.max(at));
        Ok(t)
    };
    let mut rows = String::new();
    for (twin, plain, step, variant) in TWINS {
        let mut cells = Vec::new();
        for j in SIZES {
            let p = read(format!("twins/{step}-{variant}/{j}"))?;
            let t = read(format!("twins/{step}-twins/{j}"))?;
            cells.push(format!("{:.2}x", p / t));
        }
        writeln!(
            rows,
            "| {twin} | {plain} | {step} | {} |",
            cells.join(" | ")
        )
        .unwrap();
    }
    let mut cells = Vec::new();
    for j in &SIZES[..2] {
        let step = read(format!("twins-load/mixed-load-step/{j}"))?;
        let compiled = read(format!("twins-load/mixed-load-compiled/{j}"))?;
        let plain = read(format!("twins-load/mixed-load-node-by-node/{j}"))?;
        cells.push(format!("{:.2}x", (step - compiled + plain) / step));
    }
    writeln!(
        rows,
        "| `nodal::NodalEvaluator` | `Expression::eval` node by node | both-ends-mixed-load | \
         {} | not measured |",
        cells.join(" | ")
    )
    .unwrap();
    // The thermal step (benches/thermal.rs): its twin, and its cost over the mechanical step.
    let (mut thermal, mut cells) = (Vec::new(), Vec::new());
    for j in &SIZES[..2] {
        let t = read(format!("thermal/thermal/{j}"))?;
        cells.push(format!(
            "{:.2}x",
            read(format!("thermal/thermal-plain-solve/{j}"))? / t
        ));
        thermal.push(t);
    }
    writeln!(
        rows,
        "| `block_tridiag_fast::TwistedBlockLdlt` | `block_tridiag::BlockLdlt` | thermal | {} | \
         not measured |",
        cells.join(" | ")
    )
    .unwrap();
    let mut unpaired = Vec::new();
    for (j, t) in SIZES[..2].iter().zip(&thermal) {
        unpaired.push(t / read(format!("thermal/mechanical/{j}"))?);
    }
    let obstacle = obstacle_table(&mut read)?;
    let mut paired = Vec::new();
    for j in &SIZES[..2] {
        let (ratio, at) = paired_ratio(&root, j)?;
        span = (span.0.min(at), span.1.max(at));
        paired.push(ratio);
    }
    let worst = paired.iter().copied().fold(0.0f64, f64::max);
    let thermal_line = format!(
        "\nThe thermal step over the mechanical step, the two timed one after the other in each \
         sample (`thermal/paired`, the median of its samples' ratios): {:.2}x at J = 1e4, \
         {:.2}x at J = 1e5; target <= {THERMAL_RATIO_LIMIT}x {}. Timed apart (`thermal/thermal` \
         over `thermal/mechanical`): {:.2}x and {:.2}x.\n",
        paired[0],
        paired[1],
        if worst <= THERMAL_RATIO_LIMIT {
            "met"
        } else {
            "**not met**"
        },
        unpaired[0],
        unpaired[1],
    );
    let cores = std::thread::available_parallelism().map_or(0, |n| n.get());
    let mut out = format!(
        "Criterion medians measured {} – {} UTC on {} ({cores} cores) by `cargo bench --bench \
         twins -- --warm-up-time 0.5 --measurement-time 2` and `cargo bench --bench thermal -- \
         --warm-up-time 1 --measurement-time 3`, written by `{COMPARE_COMMAND} --twins \
         --update benches/README.md`.\n\n",
        utc_date_time_at(span.0),
        utc_date_time_at(span.1),
        cpu_model(),
    );
    out.push_str(
        "| twin | plain version | step | J = 1e4 | J = 1e5 | J = 1e6 |\n|---|---|---|---|---|---|\n",
    );
    out.push_str(&rows);
    out.push_str(&thermal_line);
    out.push_str(&obstacle);
    Ok(out)
}

/// The obstacle's table: `BlockPivoting`'s factor over the general `CondensedLcp` on the step
/// of an obstacle under every node, at the sizes the dense solver is run.
fn obstacle_table(read: &mut impl FnMut(String) -> Result<f64, String>) -> Result<String, String> {
    let mut cells = Vec::new();
    for j in OBSTACLE_SIZES {
        let t = read(format!("twins-obstacle/distributed-exact-twins/{j}"))?;
        cells.push(if DENSE_OBSTACLE_SIZES.contains(&j) {
            let p = read(format!(
                "twins-obstacle/distributed-exact-general-solver/{j}"
            ))?;
            format!("{:.2}x", p / t)
        } else {
            "not run".into()
        });
    }
    let mut out = String::from(
        "\nUnder an obstacle at every node (the step of `distributed-exact`, `benches/step.rs`), \
         the specialised solver over the general one. The general `CondensedLcp` holds the dense \
         `S = E C⁻¹ Eᵀ` of the J + 1 bounds and a Cholesky buffer for `S_AA`, `2 (J + 1)²` \
         doubles; its set-up forms `S` by J + 1 solves and factorises it whole, and a step's \
         `w = q + S r` and refactorisations of `S_AA` are dense: it is not run beyond J = 400 \
         (at J = 1e4 its arrays alone would take 1.6 GB).\n\n\
         | twin | general solver | step | J = 100 | J = 400 | J = 1e4 |\n|---|---|---|---|---|---|\n",
    );
    writeln!(
        out,
        "| `BlockPivoting` | `CondensedLcp` | distributed-exact | {} |",
        cells.join(" | ")
    )
    .unwrap();
    Ok(out)
}

/// The median over the samples of `thermal/paired/J` (`benches/thermal.rs`) of the thermal
/// step's time over the mechanical step's, and the modification time of its `pairs.csv`.
fn paired_ratio(root: &Path, j: &str) -> Result<(f64, u64), String> {
    let path = root.join(format!("thermal/paired/{j}/pairs.csv"));
    let text = std::fs::read_to_string(&path)
        .map_err(|e| format!("cannot read {}: {e}", path.display()))?;
    let mut ratios = Vec::new();
    for line in text.lines().skip(1) {
        let pair: Vec<f64> = line.split(',').filter_map(|v| v.parse().ok()).collect();
        match pair[..] {
            [t, m] if t > 0.0 && m > 0.0 => ratios.push(t / m),
            _ => return Err(format!("{}: not a pair of times: {line}", path.display())),
        }
    }
    if ratios.is_empty() {
        return Err(format!("{}: no samples", path.display()));
    }
    let at = std::fs::metadata(&path).and_then(|m| m.modified()).ok();
    let at = at.and_then(|t| t.duration_since(std::time::UNIX_EPOCH).ok());
    let at = at.ok_or(format!("{}: no modification time", path.display()))?;
    Ok((median(ratios), at.as_secs()))
}

/// The thermal step's target over the mechanical step (benches/README.md, "Targets").
pub const THERMAL_RATIO_LIMIT: f64 = 3.0;

/// `bench-compare`: prints the block, or with `update` rewrites it in that file. The exit
/// code: 0; 1 when a measurement is missing or the file cannot be updated.
pub fn run(o: &Options) -> i32 {
    let (id, md) = if o.twins {
        ("bench-twins", twins_markdown())
    } else {
        ("bench-compare", markdown(o))
    };
    let result = md.and_then(|md| match &o.update {
        None => {
            print!("{md}");
            Ok(())
        }
        Some(path) => {
            let doc = std::fs::read_to_string(path)
                .map_err(|e| format!("cannot read {}: {e}", path.display()))?;
            let section = Section { id, markdown: md };
            let new = update_document(&doc, &[section])
                .map_err(|e| format!("{}: {e}", path.display()))?;
            viscobar::internals::output::files::write_atomically(path, new.as_bytes())
                .map_err(|e| format!("cannot write {}: {e}", path.display()))
        }
    });
    match result {
        Ok(()) => 0,
        Err(e) => {
            eprintln!("error: {e}");
            1
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A fresh folder under the system's temporary one.
    fn scratch(name: &str) -> PathBuf {
        let dir = std::env::temp_dir().join(format!("bench-compare-{name}-{}", std::process::id()));
        let _ = std::fs::remove_dir_all(&dir);
        std::fs::create_dir_all(&dir).unwrap();
        dir
    }

    /// Criterion's `estimates.json` of `case` under `root`, run `run`, with this median (ns).
    fn estimate(root: &Path, case: &str, run: &str, median: f64) {
        let dir = root.join(case).join(run);
        std::fs::create_dir_all(&dir).unwrap();
        let json = format!("{{\"median\": {{\"point_estimate\": {median}}}}}");
        std::fs::write(dir.join("estimates.json"), json).unwrap();
    }

    #[test]
    fn the_fastest_runs_are_compared_and_the_medians_shown_beside() {
        let (base, new) = (scratch("base"), scratch("new"));
        let case = "step/unconstrained/10000";
        let runs: Vec<String> = ["a", "b", "c"].map(String::from).into();
        for (run, b, n) in [
            ("a", 100.0, 150.0),
            ("b", 140.0, 110.0),
            ("c", 150.0, 160.0),
        ] {
            estimate(&base, case, run, b);
            estimate(&new, case, run, n);
        }
        let mut span = (u64::MAX, 0);
        let c = compare(&base, &new, case, &runs, &mut span).unwrap();
        assert_eq!(c.fastest, [100.0, 110.0]);
        assert_eq!(c.ratio, 110.0 / 100.0);
        assert_eq!(c.medians, [140.0, 150.0]);
        assert_eq!(c.pairwise, (110.0 / 140.0, 150.0 / 100.0));
        assert!(span.0 <= span.1);
        // A run missing on one side is an error naming the case.
        std::fs::remove_dir_all(new.join(case).join("c")).unwrap();
        let e = compare(&base, &new, case, &runs, &mut span).err().unwrap();
        assert!(e.starts_with(case), "{e}");
    }

    #[test]
    fn the_paired_ratio_is_the_median_of_the_samples_ratios() {
        let root = scratch("paired");
        let dir = root.join("thermal/paired/10000");
        std::fs::create_dir_all(&dir).unwrap();
        // Ratios 3, 2 and 5: their median 3, not their least (2), their mean (10/3) or the
        // ratio of the medians (100/40).
        let csv = "thermal_ns,mechanical_ns\n300,100\n80,40\n100,20\n";
        std::fs::write(dir.join("pairs.csv"), csv).unwrap();
        assert_eq!(paired_ratio(&root, "10000").unwrap().0, 3.0);
        std::fs::write(dir.join("pairs.csv"), "thermal_ns,mechanical_ns\n300,0\n").unwrap();
        assert!(paired_ratio(&root, "10000").is_err());
        std::fs::write(dir.join("pairs.csv"), "thermal_ns,mechanical_ns\n").unwrap();
        assert!(paired_ratio(&root, "10000").is_err());
        assert!(paired_ratio(&root, "100000").is_err());
    }
}
