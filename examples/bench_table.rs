//! Prints the last criterion measurements of `benches/step.rs` as a Markdown table (median
//! time per step, ns per node-step, and the ratio to the unconstrained step at equal J), read
//! from `target/criterion/step/*/*/new/estimates.json`. Run after `cargo bench --bench step`:
//!
//!     cargo run --release --example bench_table

use std::collections::BTreeMap;
use std::path::Path;

fn median_ns(path: &Path) -> Option<f64> {
    let text = std::fs::read_to_string(path).ok()?;
    let v: serde_json::Value = serde_json::from_str(&text).ok()?;
    v["median"]["point_estimate"].as_f64()
}

fn main() {
    let root = Path::new(env!("CARGO_MANIFEST_DIR")).join("target/criterion/step");
    let mut rows: BTreeMap<(u64, String), f64> = BTreeMap::new();
    let Ok(labels) = std::fs::read_dir(&root) else {
        eprintln!(
            "no measurements in {}: run `cargo bench --bench step` first",
            root.display()
        );
        std::process::exit(1);
    };
    for label in labels.flatten() {
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
    println!("| elements | step | median per step | ns per node-step | / unconstrained |");
    println!("|---|---|---|---|---|");
    for ((j, name), t) in &rows {
        let base = rows
            .get(&(*j, "unconstrained".to_string()))
            .copied()
            .unwrap_or(f64::NAN);
        println!(
            "| {j} | {name} | {:.1} µs | {:.2} | {:.3} |",
            t / 1e3,
            t / (*j + 1) as f64,
            t / base
        );
    }
}
