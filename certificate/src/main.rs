//! The certificate's commands: `verify` regenerates the measured tables of VERIFICATION.md,
//! `solver-agreement` prints one of them, `bench-table` writes the criterion timings into
//! README.md and benches/README.md, `bench-compare` the bar's steps beside another commit's,
//! `peak-memory` measures a long run's resident memory.

use clap::{Parser, Subcommand};
use std::path::PathBuf;
use viscobar_certificate::bar::{stiff, stiff_runs};
use viscobar_certificate::performance::peak_memory::Ends;
use viscobar_certificate::performance::{bench_compare, bench_table, peak_memory, timings};
use viscobar_certificate::solvers::agreement;
use viscobar_certificate::verify;

#[derive(Parser)]
#[command(
    name = "viscobar-certificate",
    version,
    about = "The certificate of viscobar: the measured tables of its documents"
)]
struct Cli {
    #[command(subcommand)]
    command: Command,
}

#[derive(Subcommand)]
enum Command {
    /// Recompute the measured figures of VERIFICATION.md and print them as Markdown.
    Verify {
        /// Rewrite the generated blocks of this file in place instead of printing.
        #[arg(long, value_name = "FILE")]
        update: Option<PathBuf>,
        /// The stiff and extreme case matrix instead (full size: 1e6 nodes, 1e6-step runs).
        #[arg(long)]
        stiff: bool,
        /// The tolerance registry instead: each tolerance's measured worst / tolerance.
        #[arg(long, conflicts_with_all = ["stiff", "timings"])]
        tolerances: bool,
        /// "Error against run time" instead: its error and timing blocks (machine-dependent:
        /// the machine and date are written beside the times).
        #[arg(long, conflicts_with = "stiff")]
        timings: bool,
        /// With --timings: also write work-precision-<scene>.png into this folder.
        #[arg(long, value_name = "DIR", requires = "timings")]
        figures: Option<PathBuf>,
    },
    /// Print the measured figures of VERIFICATION.md's section "Step solvers" (the generated
    /// block `solver-agreement`, which `verify --update VERIFICATION.md` writes) as Markdown.
    SolverAgreement,
    /// Print criterion's last measurements of the step and scene benches as Markdown tables,
    /// with the performance targets (run `cargo bench --bench step` and `--bench scenes` first).
    BenchTable {
        /// Rewrite the generated timing blocks of these files instead of printing.
        #[arg(long, value_name = "FILE", num_args = 1..)]
        update: Option<Vec<PathBuf>>,
    },
    /// Print criterion's medians of the bar's step benches beside a base commit's (another
    /// worktree's `target/criterion`), with the ratio and the 1.15x limit, as Markdown.
    BenchCompare {
        /// The base commit's `target/criterion`.
        #[arg(long, value_name = "DIR", required_unless_present = "twins")]
        base: Option<PathBuf>,
        /// The base commit, as the block names it.
        #[arg(long, value_name = "REV", required_unless_present = "twins")]
        base_commit: Option<String>,
        /// Instead, each optimised twin's factor on a step, from `cargo bench --bench twins`
        /// (the block `bench-twins`).
        #[arg(long)]
        twins: bool,
        /// The criterion baselines of the runs on both sides (`--save-baseline`), comma-separated.
        #[arg(long, value_delimiter = ',', default_value = "new")]
        runs: Vec<String>,
        /// Rewrite the block (`bench-compare` or `bench-twins`) of this file instead of printing.
        #[arg(long, value_name = "FILE")]
        update: Option<PathBuf>,
    },
    /// Run a long viscoelastic bar to files and print its timings and the peak resident memory
    /// of this process (target: 1e6 elements, 1e4 steps under 200 MB).
    PeakMemory {
        /// Elements of the bar (Δt = Δx = 1/ELEMENTS).
        #[arg(default_value_t = 1_000_000)]
        elements: u64,
        /// Time steps.
        #[arg(default_value_t = 10_000)]
        steps: u64,
        /// The ends: free-free, or Signorini obstacles under one or both ends.
        #[arg(value_enum, default_value_t = Ends::Free)]
        ends: Ends,
    },
}

fn main() {
    let code = match Cli::parse().command {
        Command::Verify {
            update,
            stiff,
            tolerances,
            timings,
            figures,
        } => run_verify(update, stiff, tolerances, timings.then_some(figures)),
        Command::SolverAgreement => match agreement::markdown() {
            Ok(md) => {
                print!("{md}");
                0
            }
            Err(e) => {
                eprintln!("error: {e}");
                e.exit_code()
            }
        },
        Command::BenchTable { update } => bench_table::run(update.as_deref()),
        Command::BenchCompare {
            base,
            base_commit,
            twins,
            runs,
            update,
        } => bench_compare::run(&bench_compare::Options {
            base: base.unwrap_or_default(),
            base_commit: base_commit.unwrap_or_default(),
            twins,
            runs,
            update,
        }),
        Command::PeakMemory {
            elements,
            steps,
            ends,
        } => match peak_memory::run(elements, steps, ends) {
            Ok(()) => 0,
            Err(e) => {
                eprintln!("error: {e}");
                e.exit_code()
            }
        },
    };
    std::process::exit(code);
}

/// `verify`; `timings`: `Some(figures folder)` for `--timings`. The exit code: 0, 1 for a
/// failed run or an unwritable file, 2 for bad input.
fn run_verify(
    update: Option<PathBuf>,
    stiff: bool,
    tolerances: bool,
    timings: Option<Option<PathBuf>>,
) -> i32 {
    let sections = if let Some(figures) = timings {
        timings::sections(figures.as_deref())
    } else if stiff || tolerances {
        let results = stiff_runs::run_all(stiff::Size::Full);
        if stiff {
            Ok(vec![verify::stiff_section(&results)])
        } else {
            verify::rigid_drift()
                .and_then(|(drift, _)| verify::tolerances_section(&results, drift))
                .map(|s| vec![s])
                .map_err(Into::into)
        }
    } else {
        verify::sections()
    };
    let sections = match sections {
        Ok(s) => s,
        Err(e) => {
            eprintln!("error: {e}");
            return e.exit_code();
        }
    };
    let Some(path) = update else {
        print!("{}", verify::render(&sections));
        return 0;
    };
    let result = std::fs::read_to_string(&path)
        .map_err(|e| format!("cannot read {}: {e}", path.display()))
        .and_then(|doc| {
            verify::update_document(&doc, &sections).map_err(|e| format!("{}: {e}", path.display()))
        })
        .and_then(|doc| {
            viscobar::internals::output::files::write_atomically(&path, doc.as_bytes())
                .map_err(|e| format!("cannot write {}: {e}", path.display()))
        });
    match result {
        Ok(()) => 0,
        Err(e) => {
            eprintln!("error: {e}");
            1
        }
    }
}
