//! `peak-memory`: the peak resident memory of a long run (target: J = 1e6 with 1e4 steps under
//! 200 MB). Runs `run::run_to_dir` (what `viscobar run` does) on a viscoelastic bar (α = 0.1,
//! Δt = Δx) with the given elements and steps, writing its outputs into `target/peak-memory/`
//! (displacement.csv keeps t = 0 and the last step only), then prints the run's summary figures
//! and the peak resident set size of this process (`VmHWM` in /proc/self/status). [`Ends`]:
//! free-free, released with velocity sin(πx); or an `impact`-like bar flying rigidly at velocity
//! −1 onto Signorini obstacles at gap 0.5·STEPS·Δt under its left end or both ends, so contact
//! starts halfway through the run and the exact end solver keeps its columns and reduced
//! factors. With `100000 2000` it gives `run`'s end-to-end ns_per_unknown_step at J = 1e5, to
//! compare with the step bench.

use viscobar::scheme::RunError;

/// The ends of the bar.
#[derive(Clone, Copy, Debug, PartialEq, Eq, clap::ValueEnum)]
pub enum Ends {
    /// Free-free, released with velocity sin(πx).
    Free,
    /// A Signorini obstacle under the left end.
    OneEnd,
    /// Signorini obstacles under both ends.
    TwoEnds,
}

/// Target of the peak resident memory, bytes.
pub const PEAK_TARGET_BYTES: f64 = 200e6;

fn vm_hwm_kib() -> Option<u64> {
    let status = std::fs::read_to_string("/proc/self/status").ok()?;
    let line = status.lines().find(|l| l.starts_with("VmHWM:"))?;
    line.split_whitespace().nth(1)?.parse().ok()
}

/// Runs the bar and prints its figures; the run's error (a scene refused: exit 2) otherwise.
pub fn run(elements: u64, steps: u64, ends: Ends) -> Result<(), RunError> {
    let dt = 1.0 / elements as f64;
    let end = steps as f64 * dt;
    let signorini = format!("condition = \"signorini\"\ngap = {}", 0.5 * end);
    let (left, right, velocity) = match ends {
        Ends::Free => ("condition = \"free\"", "condition = \"free\"", "sin(pi*x)"),
        Ends::OneEnd => (signorini.as_str(), "condition = \"free\"", "-1"),
        Ends::TwoEnds => (signorini.as_str(), signorini.as_str(), "-1"),
    };
    let scene = viscobar::Scene::from_toml(
        &format!(
            "[bar]\nlength = 1.0\nviscosity = 0.1\n[left]\n{left}\n[right]\n{right}\n\
             [initial]\ndisplacement = \"0\"\nvelocity = \"{velocity}\"\n[mesh]\n\
             elements = {elements}\n[time]\nstep = {dt}\nend = {end}\n[output]\nevery = {steps}\n"
        ),
        &[],
    )?;
    let before = vm_hwm_kib();
    let out = crate::workspace_root().join("target/peak-memory");
    let summary = viscobar::run_to_dir("peak-memory", &scene, &out, false)?;
    let peak = vm_hwm_kib();
    let ends = match ends {
        Ends::Free => "free",
        Ends::OneEnd => "one-end",
        Ends::TwoEnds => "two-ends",
    };
    println!(
        "{ends}: elements {elements}, steps {}, nodes {}: wall {:.1} s, {:.2} ns per node-step",
        summary.steps, summary.nodes, summary.wall_time_s, summary.ns_per_unknown_step
    );
    let s = summary.time_shares;
    println!(
        "time shares of the steps: solver {:.2}, rhs {:.2}, diagnostics {:.2} \
         ({} sampled steps; stepping {:.2} of the wall time)",
        s.solver, s.rhs, s.diagnostics, s.sampled_steps, s.stepping
    );
    let mb = |kib: u64| kib as f64 * 1024.0 / 1e6;
    match peak {
        Some(peak) => println!(
            "peak RSS (VmHWM) {:.1} MB (before the run {:.1} MB); target 200 MB: {}",
            mb(peak),
            before.map_or(0.0, mb),
            if peak as f64 * 1024.0 <= PEAK_TARGET_BYTES {
                "met"
            } else {
                "not met"
            }
        ),
        None => println!(
            "peak RSS unknown: /proc/self/status has no VmHWM; target 200 MB: not measured"
        ),
    }
    Ok(())
}
