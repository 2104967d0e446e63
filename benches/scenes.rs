//! Each talk scene end to end at its default size (`viscobar::study::figures::talk_scenes`): set-up,
//! start-up and every step with the energy balance, through `run::run_in_memory` (no files
//! written, so disk speed does not enter). Throughput in node-steps.
//!
//! Group `setup` (set-up and output): `run::run_to_dir` (what `viscobar run` does,
//! files written into a fresh `target/bench-setup/`) of the two-end bar `both-ends` with 16384 elements
//! for one step (`one-step`) and for 400 steps keeping `t = 0` and the last step
//! (`400-steps`, `[output] every = 400`), the same 400 steps alone (`400-steps-stepping`: the
//! set-up outside the timing), and the refined run `both-ends` with 1e5 elements and
//! Δt = 3.125e-5 to t = 0.05 with its default output (`refined-1e5`, 1600 steps), and with
//! `--features npy` the same writing `displacement.npy` (`refined-1e5-npy`).

use criterion::{BatchSize, BenchmarkId, Criterion, Throughput, criterion_group, criterion_main};
use std::path::Path;
use std::time::{Duration, Instant};
use viscobar::output::{run_in_memory, run_to_dir};
use viscobar::study::figures::talk_scenes;

fn bench_scenes(c: &mut Criterion) {
    let mut group = c.benchmark_group("scenes");
    group.sample_size(10);
    for name in talk_scenes() {
        let (_, scene) = viscobar::scene::load(name, &[]).unwrap();
        let node_steps = (scene.elements() as u64 + 1) * scene.steps() as u64;
        group.throughput(Throughput::Elements(node_steps));
        group.bench_function(name, |b| b.iter(|| run_in_memory(name, &scene).unwrap()));
    }
    group.finish();
}

/// `both-ends` with `overrides`.
fn both_ends(overrides: &[&str]) -> viscobar::Scene {
    let o: Vec<String> = overrides.iter().map(|s| s.to_string()).collect();
    viscobar::scene::load("both-ends", &o).unwrap().1
}

fn bench_setup(c: &mut Criterion) {
    let out = Path::new(env!("CARGO_MANIFEST_DIR")).join("target/bench-setup");
    let mut group = c.benchmark_group("setup");
    group.sample_size(10);
    #[cfg_attr(not(feature = "npy"), expect(unused_mut))]
    let mut runs = vec![
        (
            "one-step",
            both_ends(&["mesh.elements=16384", "time.end=0.005"]),
        ),
        (
            "400-steps",
            both_ends(&["mesh.elements=16384", "time.end=2", "output.every=400"]),
        ),
        (
            "refined-1e5",
            both_ends(&[
                "mesh.elements=100000",
                "time.step=0.00003125",
                "time.end=0.05",
            ]),
        ),
    ];
    // With `--features npy`: the refined run writing `displacement.npy` instead.
    #[cfg(feature = "npy")]
    runs.push((
        "refined-1e5-npy",
        both_ends(&[
            "mesh.elements=100000",
            "time.step=0.00003125",
            "time.end=0.05",
            "output.format=npy",
        ]),
    ));
    for (label, scene) in &runs {
        let node_steps = (scene.elements() as u64 + 1) * scene.steps() as u64;
        group.throughput(Throughput::Elements(node_steps));
        // Into a fresh folder each time (removed outside the timing): replacing the files of
        // an earlier run makes ext4 start writing the new ones out at the rename, which is
        // disk traffic, not the run.
        group.bench_function(BenchmarkId::from_parameter(label), |b| {
            b.iter_batched(
                || {
                    let _ = std::fs::remove_dir_all(&out);
                },
                |()| run_to_dir(label, scene, &out, false).unwrap(),
                BatchSize::PerIteration,
            )
        });
    }
    // The steps of `400-steps` alone: set up and start outside the timing.
    let scene = &runs[1].1;
    group.throughput(Throughput::Elements(
        (scene.elements() as u64 + 1) * scene.steps() as u64,
    ));
    group.bench_function("400-steps-stepping", |b| {
        b.iter_custom(|iters| {
            let mut total = Duration::ZERO;
            for _ in 0..iters {
                let mut sim = viscobar::Simulation::new(scene).unwrap();
                let start = Instant::now();
                for _ in 1..scene.steps() {
                    std::hint::black_box(sim.step().unwrap());
                }
                total += start.elapsed();
            }
            total
        })
    });
    group.finish();
    let _ = std::fs::remove_dir_all(&out);
}

criterion_group! {
    name = benches;
    config = Criterion::default().without_plots();
    targets = bench_scenes, bench_setup
}
criterion_main!(benches);
