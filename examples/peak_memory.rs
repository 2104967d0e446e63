//! Peak resident memory of a long run (issue 7: J = 1e6 with 1e4 steps under 200 MB). Runs
//! `run::run_to_dir` (what `viscobar run` does) on a viscoelastic bar (α = 0.1, Δt = Δx) with
//! J + 1 elements and the given number of steps, writing its outputs into
//! `target/peak-memory/` (displacement.csv keeps t = 0 and the last step only), then prints the
//! run's summary figures and the peak resident set size of this process (`VmHWM` in
//! /proc/self/status). ENDS is `free` (free-free, released with velocity sin(πx)), or
//! `one-end` / `two-ends`: an `impact`-like bar flying rigidly at velocity −1 onto Signorini
//! obstacles at gap 0.5·STEPS·Δt under its left end or both ends, so contact starts halfway
//! through the run and the exact end solver keeps its columns and reduced factors. With
//! `100000 2000` it gives `run`'s end-to-end ns_per_node_step at J = 1e5, to compare with the
//! step bench:
//!
//!     cargo run --release --example peak_memory -- [ELEMENTS] [STEPS] [ENDS]   # default 1000000 10000 free

use std::path::Path;

fn vm_hwm_kib() -> Option<u64> {
    let status = std::fs::read_to_string("/proc/self/status").ok()?;
    let line = status.lines().find(|l| l.starts_with("VmHWM:"))?;
    line.split_whitespace().nth(1)?.parse().ok()
}

fn main() {
    let mut args = std::env::args().skip(1);
    let elements: u64 = args
        .next()
        .map_or(1_000_000, |s| s.parse().expect("ELEMENTS"));
    let steps: u64 = args.next().map_or(10_000, |s| s.parse().expect("STEPS"));
    let ends = args.next().unwrap_or_else(|| "free".into());
    let dt = 1.0 / elements as f64;
    let end = steps as f64 * dt;
    let signorini = format!("condition = \"signorini\"\ngap = {}", 0.5 * end);
    let (left, right, velocity) = match ends.as_str() {
        "free" => ("condition = \"free\"", "condition = \"free\"", "sin(pi*x)"),
        "one-end" => (signorini.as_str(), "condition = \"free\"", "-1"),
        "two-ends" => (signorini.as_str(), signorini.as_str(), "-1"),
        other => panic!("ENDS is free, one-end or two-ends, not {other}"),
    };
    let scene = viscobar::Scene::from_toml(
        &format!(
            "[bar]\nlength = 1.0\nviscosity = 0.1\n[left]\n{left}\n[right]\n{right}\n\
             [initial]\ndisplacement = \"0\"\nvelocity = \"{velocity}\"\n[mesh]\n\
             elements = {elements}\n[time]\nstep = {dt}\nend = {end}\n[output]\nevery = {steps}\n"
        ),
        &[],
    )
    .expect("scene");
    let before = vm_hwm_kib();
    let out = Path::new(env!("CARGO_MANIFEST_DIR")).join("target/peak-memory");
    let summary = viscobar::time::run::run_to_dir("peak-memory", &scene, &out, false).expect("run");
    let peak = vm_hwm_kib().expect("/proc/self/status has VmHWM");
    println!(
        "{ends}: elements {elements}, steps {}, nodes {}: wall {:.1} s, {:.2} ns per node-step",
        summary.steps, summary.nodes, summary.wall_time_s, summary.ns_per_node_step
    );
    let s = summary.time_shares;
    println!(
        "time shares of the steps: solver {:.2}, rhs {:.2}, diagnostics {:.2} \
         ({} sampled steps; stepping {:.2} of the wall time)",
        s.solver, s.rhs, s.diagnostics, s.sampled_steps, s.stepping
    );
    println!(
        "peak RSS (VmHWM) {:.1} MB (before the run {:.1} MB); target 200 MB: {}",
        peak as f64 * 1024.0 / 1e6,
        before.unwrap_or(0) as f64 * 1024.0 / 1e6,
        if peak as f64 * 1024.0 <= 200e6 {
            "met"
        } else {
            "not met"
        }
    );
}
