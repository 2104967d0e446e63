//! `bench-compare`: the bar's step benches of two commits side by side. Reads criterion's
//! medians of `benches/step.rs` from a base run (`--base`: another worktree's
//! `target/criterion`) and from this checkout's `target/criterion`, for each case of
//! [`CASES`] the median of both, their ratio and whether it is within [`RATIO_LIMIT`]. Each
//! side may hold several runs saved as criterion baselines (`--runs r1,r2,r3`, run alternately
//! on the two commits): a case's figure is then the median of its runs' medians, and the table
//! shows the smallest and largest ratio of the runs taken pairwise. With `--update FILE`, the
//! block between `<!-- generated:bench-compare -->` and `<!-- end:bench-compare -->` is
//! rewritten, stamped with the measurement dates, the machine and the commands.

use crate::timings::{cpu_model, utc_date_time_at};
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

/// The largest ratio new/base of a step's median allowed.
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

/// Per case: the median of the base's and of the new runs, their ratio, and the smallest
/// and largest ratio of the runs taken pairwise; with the modification times of the
/// estimates. An error when a case lacks a run on either side.
struct Compared {
    base: f64,
    new: f64,
    ratio: f64,
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
    let (base, new) = (
        median(b.iter().map(|r| r.0).collect()),
        median(n.iter().map(|r| r.0).collect()),
    );
    Ok(Compared {
        base,
        new,
        ratio: new / base,
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
                "{:.1} → {:.1}, {:.3}x ({:.2}–{:.2}) {}",
                c.base / 1e3,
                c.new / 1e3,
                c.ratio,
                c.pairwise.0,
                c.pairwise.1,
                if ok { "met" } else { "**not met**" }
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
        "Per cell: the median step in µs on {} → on this commit, the ratio (its range over \
         the runs taken pairwise) and the limit <= {RATIO_LIMIT}x met or not.\n",
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
const TWINS: [(&str, &str, &str, &str); 7] = [
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
];

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
    // The thermal step (benches/thermal.rs): its twins, and its cost over the mechanical step.
    let mut thermal = Vec::new();
    for j in &SIZES[..2] {
        thermal.push(read(format!("thermal/thermal/{j}"))?);
    }
    let thermal_twins = [
        (
            "`block_tridiag_fast::TwistedBlockLdlt`",
            "`block_tridiag::BlockLdlt`",
            "plain-solve",
        ),
        (
            "`thermal::energy_fast::interior_sums`",
            "the energy terms node by node",
            "plain-energy",
        ),
    ];
    for (twin, plain, variant) in thermal_twins {
        let mut cells = Vec::new();
        for (j, t) in SIZES[..2].iter().zip(&thermal) {
            let p = read(format!("thermal/thermal-{variant}/{j}"))?;
            cells.push(format!("{:.2}x", p / t));
        }
        writeln!(
            rows,
            "| {twin} | {plain} | thermal | {} | not measured |",
            cells.join(" | ")
        )
        .unwrap();
    }
    let mut ratios = Vec::new();
    for (j, t) in SIZES[..2].iter().zip(&thermal) {
        ratios.push(t / read(format!("thermal/mechanical/{j}"))?);
    }
    let worst = ratios.iter().copied().fold(0.0f64, f64::max);
    let thermal_line = format!(
        "\nThe thermal step over the mechanical step (`thermal/thermal` over `thermal/mechanical`): \
         {:.2}x at J = 1e4, {:.2}x at J = 1e5; target <= {THERMAL_RATIO_LIMIT}x {}.\n",
        ratios[0],
        ratios[1],
        if worst <= THERMAL_RATIO_LIMIT {
            "met"
        } else {
            "**not met**"
        }
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
    Ok(out)
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
            viscobar::output::files::write_atomically(path, new.as_bytes())
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
