//! Prints the last criterion measurements of `benches/step.rs` and `benches/scenes.rs` as
//! Markdown (median time per step or per run, ns per node-step, and for steps the ratio to the
//! unconstrained step at equal J), read from `target/criterion/{step,scenes,load,setup}/*/…/new/
//! estimates.json`, followed by the targets of issues 7 and 17, each marked met or not met. Run after
//! `cargo bench --bench step` and `cargo bench --bench scenes`:
//!
//!     cargo run --release --example bench_table
//!
//! A measurement more than [`STALE_AFTER_S`] older than the newest one of its group is
//! marked `(stale)` and left out of the targets: criterion keeps the last result of every
//! bench ever run, so a partial run would otherwise mix in rows measured on older code.

use std::collections::BTreeMap;
use std::path::Path;

/// Issue 7's targets.
const BARE_NS_PER_NODE_TARGET: f64 = 2.0;
const DIAGNOSTICS_OVERHEAD_TARGET: f64 = 0.5;
const EXACT_RATIO_TARGET: f64 = 1.15;
/// Issue 17's targets: a forced talk scene against its unforced twin, per step; a load that
/// does not separate (two transcendental calls), per node-step.
const FORCED_RATIO_TARGET: f64 = 1.3;
const MIXED_LOAD_NS_TARGET: f64 = 30.0;

/// Issue 17's set-up and output targets: a one-step run of the 16384-element two-end bar (ms),
/// the 400-step run against its steps alone, that run's ns per node-step, and the refined
/// 1e5-element run end to end (ns per node-step).
const ONE_STEP_MS_TARGET: f64 = 5.0;
const SETUP_RATIO_TARGET: f64 = 1.3;
const SETUP_NS_TARGET: f64 = 4.5;
const REFINED_NS_TARGET: f64 = 3.0;

/// Rows measured this long before the newest row of their group are stale.
const STALE_AFTER_S: u64 = 3600;

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

/// Drops the modification times, keeping rows measured within [`STALE_AFTER_S`] of the
/// newest; returns the fresh rows and the names of the stale ones.
fn fresh<K: Ord + Clone>(rows: BTreeMap<K, (f64, u64)>) -> (BTreeMap<K, f64>, Vec<K>) {
    let newest = rows.values().map(|r| r.1).max().unwrap_or(0);
    let mut stale = Vec::new();
    let mut kept = BTreeMap::new();
    for (k, (t, at)) in rows {
        if at + STALE_AFTER_S < newest {
            stale.push(k);
        } else {
            kept.insert(k, t);
        }
    }
    (kept, stale)
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

fn verdict(ok: bool) -> &'static str {
    if ok { "met" } else { "not met" }
}

fn main() {
    let target = Path::new(env!("CARGO_MANIFEST_DIR")).join("target/criterion");
    let (rows, stale) = fresh(step_rows(&target.join("step")));
    if rows.is_empty() && !target.join("load").exists() && !target.join("setup").exists() {
        eprintln!("no measurements in target/criterion/step: run `cargo bench --bench step` first");
        std::process::exit(1);
    }
    let get = |j: u64, name: &str| rows.get(&(j, name.to_string())).copied();
    println!("| elements | step | median per step | ns per node-step | / unconstrained |");
    println!("|---|---|---|---|---|");
    for ((j, name), t) in &rows {
        let base = get(*j, "unconstrained").unwrap_or(f64::NAN);
        println!(
            "| {j} | {name} | {:.1} µs | {:.2} | {:.3} |",
            t / 1e3,
            t / (*j + 1) as f64,
            t / base
        );
    }
    for (j, name) in &stale {
        println!("| {j} | {name} (stale) | | | |");
    }
    let scenes = target.join("scenes");
    let mut all_scenes = BTreeMap::new();
    for entry in std::fs::read_dir(&scenes).into_iter().flatten().flatten() {
        let name = entry.file_name().to_string_lossy().into_owned();
        if let Some(t) = median_ns(&entry.path().join("new/estimates.json")) {
            all_scenes.insert(name, t);
        }
    }
    let (scene_rows, stale_scenes) = fresh(all_scenes);
    if !scene_rows.is_empty() {
        println!();
        println!("| scene (default size, end to end) | median per run | ns per node-step |");
        println!("|---|---|---|");
        for (name, t) in &scene_rows {
            let (_, scene) = viscobar::scene::load(name, &[]).expect("talk scene");
            let node_steps = (scene.elements() + 1) as f64 * scene.steps() as f64;
            println!("| {name} | {:.1} ms | {:.2} |", t / 1e6, t / node_steps);
        }
        for name in &stale_scenes {
            println!("| {name} (stale) | | |");
        }
    }
    let (loads, stale_loads) = fresh(step_rows(&target.join("load")));
    if !loads.is_empty() {
        println!();
        println!("| elements | scene | median per step | ns per node-step | / unforced twin |");
        println!("|---|---|---|---|---|");
        for ((j, name), t) in &loads {
            let twin = name
                .strip_suffix("-forced")
                .or(name.strip_suffix("-mixed-load"));
            let ratio = twin
                .and_then(|tw| loads.get(&(*j, tw.to_string())))
                .map(|b| format!("{:.3}", t / b))
                .unwrap_or_default();
            println!(
                "| {j} | {name} | {:.1} µs | {:.2} | {ratio} |",
                t / 1e3,
                t / (*j + 1) as f64
            );
        }
        for (j, name) in &stale_loads {
            println!("| {j} | {name} (stale) | | | |");
        }
        println!();
        println!("Targets (issue 17, loads):");
        for ((j, name), t) in &loads {
            if let Some(twin) = name.strip_suffix("-forced") {
                if let Some(b) = loads.get(&(*j, twin.to_string())) {
                    println!(
                        "- {name} at J = {j}: {:.3}x its unforced twin (target <= {FORCED_RATIO_TARGET}): {}",
                        t / b,
                        verdict(t / b <= FORCED_RATIO_TARGET)
                    );
                }
            } else if name.ends_with("-mixed-load") {
                let per = t / (*j + 1) as f64;
                println!(
                    "- {name} at J = {j}: {per:.2} ns per node-step (target <= {MIXED_LOAD_NS_TARGET}): {}",
                    verdict(per <= MIXED_LOAD_NS_TARGET)
                );
            }
        }
    }
    let mut setup_runs = BTreeMap::new();
    for entry in std::fs::read_dir(target.join("setup"))
        .into_iter()
        .flatten()
        .flatten()
    {
        let name = entry.file_name().to_string_lossy().into_owned();
        if let Some(t) = median_ns(&entry.path().join("new/estimates.json")) {
            setup_runs.insert(name, t);
        }
    }
    let (setup, stale_setup) = fresh(setup_runs);
    if !setup.is_empty() {
        // Node-steps of each run (`benches/scenes.rs`, group `setup`).
        let node_steps = |name: &str| match name {
            "one-step" => 16_385.0,
            "refined-1e5" | "refined-1e5-npy" => 100_001.0 * 1600.0,
            _ => 16_385.0 * 400.0,
        };
        println!();
        println!("| run (`setup` group, files written) | median | ns per node-step |");
        println!("|---|---|---|");
        for (name, t) in &setup {
            println!(
                "| {name} | {:.2} ms | {:.2} |",
                t / 1e6,
                t / node_steps(name)
            );
        }
        for name in &stale_setup {
            println!("| {name} (stale) | | |");
        }
        println!();
        println!("Targets (issue 17, set-up and output):");
        if let Some(t) = setup.get("one-step") {
            println!(
                "- one-step run, 16384 elements: {:.2} ms (target <= {ONE_STEP_MS_TARGET}): {}",
                t / 1e6,
                verdict(t / 1e6 <= ONE_STEP_MS_TARGET)
            );
        }
        if let (Some(run), Some(steps)) = (setup.get("400-steps"), setup.get("400-steps-stepping"))
        {
            println!(
                "- 400-step run: {:.2}x its steps alone (target <= {SETUP_RATIO_TARGET}): {}",
                run / steps,
                verdict(run / steps <= SETUP_RATIO_TARGET)
            );
            let per = run / node_steps("400-steps");
            println!(
                "- 400-step run: {per:.2} ns per node-step (target <= {SETUP_NS_TARGET}): {}",
                verdict(per <= SETUP_NS_TARGET)
            );
        }
        if let Some(t) = setup.get("refined-1e5") {
            let per = t / node_steps("refined-1e5");
            println!(
                "- refined run, 1e5 elements, 1600 steps, default output: {per:.2} ns per node-step (target <= {REFINED_NS_TARGET}): {}",
                verdict(per <= REFINED_NS_TARGET)
            );
        }
        if let Some(t) = setup.get("refined-1e5-npy") {
            let per = t / node_steps("refined-1e5-npy");
            println!(
                "- refined run as above writing displacement.npy (feature `npy`): {per:.2} ns per node-step (target <= {REFINED_NS_TARGET}): {}",
                verdict(per <= REFINED_NS_TARGET)
            );
        }
    }
    println!();
    println!("Targets (issue 7):");
    let sizes: Vec<u64> = rows.keys().map(|k| k.0).collect();
    if let Some(bare) = get(100_000, "unconstrained-bare") {
        let per_node = bare / 100_001.0;
        println!(
            "- unconstrained step without diagnostics at J = 1e5: {per_node:.2} ns per node-step \
             (target <= {BARE_NS_PER_NODE_TARGET}): {}",
            verdict(per_node <= BARE_NS_PER_NODE_TARGET)
        );
    }
    let mut seen = std::collections::BTreeSet::new();
    for j in sizes.iter().copied().filter(|j| seen.insert(*j)) {
        let (Some(bare), Some(full)) = (get(j, "unconstrained-bare"), get(j, "unconstrained"))
        else {
            continue;
        };
        let over = full / bare - 1.0;
        println!(
            "- diagnostics at J = {j}: +{:.0} % over the bare step (target <= {:.0} %): {}",
            100.0 * over,
            100.0 * DIAGNOSTICS_OVERHEAD_TARGET,
            verdict(over <= DIAGNOSTICS_OVERHEAD_TARGET)
        );
        let Some(base) = get(j, "unconstrained") else {
            continue;
        };
        for name in ["exact-one-end", "exact-two-ends"] {
            if let Some(t) = get(j, name) {
                println!(
                    "- {name} at J = {j}: {:.3}x unconstrained (target <= {EXACT_RATIO_TARGET}): {}",
                    t / base,
                    verdict(t / base <= EXACT_RATIO_TARGET)
                );
            }
        }
    }
}
