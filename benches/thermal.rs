//! Per-step cost of the thermal bar against the bar without a temperature, in node-steps per
//! second (group `thermal`): the same two-end bar pressed by a constant load onto obstacles at
//! gap 0 (contact active at every step), `mechanical` without `[heat]`, `thermal` with a
//! coupled temperature (γ = 0.1, κ = 0.05, an exchange with the obstacle at the left end, the
//! right end insulated), `thermal-plain-solve` with the coupled solve by the plain block sweep
//! instead of its twisted twin; `paired` times the thermal and the mechanical step one after
//! the other in each sample and writes each sample's two times per step to `pairs.csv` beside
//! criterion's estimates. Target (benches/README.md): thermal <= 3x mechanical at J = 1e4 …
//! 1e5, the median of the samples' ratios; the factors are in the twins block
//! (`bench-compare --twins`).

use criterion::{
    BenchmarkId, Criterion, SamplingMode, Throughput, criterion_group, criterion_main,
};
use std::path::PathBuf;
use std::time::Instant;
use viscobar::Scene;
use viscobar::bar::Kernels;
use viscobar::thermal::ThermalSimulation;

fn scene(elements: u64, heat: bool) -> Scene {
    let heat = if heat {
        "[heat]\ncoupling = 0.1\ndiffusivity = 0.05\ntemperature = \"0.5 + 0.5*cos(3*x)\"\n\
         left = { condition = \"exchange\", coefficient = 2.0, obstacle = \"1\" }\n\
         right = { condition = \"insulated\" }\n"
    } else {
        ""
    };
    let text = format!(
        "[bar]\nlength = 1.0\nviscosity = 0.1\n[left]\ncondition = \"signorini\"\ngap = 0.0\n\
         [right]\ncondition = \"signorini\"\ngap = 0.0\n[initial]\ndisplacement = \"0\"\n\
         velocity = \"0\"\n[load]\ndensity = \"-10\"\n{heat}[mesh]\nelements = {elements}\n\
         [time]\nstep = {dt}\nend = {end}\n",
        dt = 1.0 / elements as f64,
        end = 1000.0 / elements as f64,
    );
    Scene::from_toml(&text, &[]).unwrap()
}

fn bench_thermal(c: &mut Criterion) {
    let mut group = c.benchmark_group("thermal");
    for elements in [10_000u64, 100_000] {
        group.throughput(Throughput::Elements(elements + 1));
        let mut bar = viscobar::Simulation::new(&scene(elements, false)).unwrap();
        let mut thermal = ThermalSimulation::new(&scene(elements, true)).unwrap();
        let with = |kernels| ThermalSimulation::with_kernels(&scene(elements, true), kernels);
        let plain_solve = Kernels {
            twisted_solve: false,
            ..Kernels::TWINS
        };
        let mut plain = with(plain_solve).unwrap();
        // Settle into contact before timing.
        for _ in 0..50 {
            bar.step().unwrap();
            thermal.step().unwrap();
            plain.step().unwrap();
        }
        group.bench_with_input(
            BenchmarkId::new("mechanical", elements),
            &elements,
            |b, _| b.iter(|| bar.step().unwrap()),
        );
        group.bench_with_input(BenchmarkId::new("thermal", elements), &elements, |b, _| {
            b.iter(|| thermal.step().unwrap())
        });
        let id = BenchmarkId::new("thermal-plain-solve", elements);
        group.bench_with_input(id, &elements, |b, _| b.iter(|| plain.step().unwrap()));
        // Both steps in each sample: a drift of the machine's speed reaches both of its times.
        let mut pairs: Vec<[f64; 2]> = Vec::new();
        let id = BenchmarkId::new("paired", elements);
        group.sampling_mode(SamplingMode::Flat);
        group.bench_with_input(id, &elements, |b, _| {
            b.iter_custom(|iters| {
                let start = Instant::now();
                for _ in 0..iters {
                    thermal.step().unwrap();
                }
                let t_thermal = start.elapsed();
                let start = Instant::now();
                for _ in 0..iters {
                    bar.step().unwrap();
                }
                let t_mechanical = start.elapsed();
                let per_step = |t: std::time::Duration| t.as_nanos() as f64 / iters as f64;
                pairs.push([per_step(t_thermal), per_step(t_mechanical)]);
                t_thermal + t_mechanical
            })
        });
        group.sampling_mode(SamplingMode::Auto);
        write_pairs(elements, &pairs);
    }
    group.finish();
}

/// Criterion's sample count: the last this many pairs are the measurement's (the ones before
/// are its warm-up's).
const SAMPLES: usize = 100;

/// `thermal/paired/J/pairs.csv` under criterion's folder: per sample, the thermal and the
/// mechanical step's time (ns per step). Nothing when the bench was filtered out.
fn write_pairs(elements: u64, pairs: &[[f64; 2]]) {
    if pairs.len() < SAMPLES {
        return;
    }
    let root = match std::env::var_os("CRITERION_HOME") {
        Some(home) => PathBuf::from(home),
        None => std::env::var_os("CARGO_TARGET_DIR")
            .map_or_else(|| PathBuf::from("target"), PathBuf::from)
            .join("criterion"),
    };
    let dir = root.join(format!("thermal/paired/{elements}"));
    let mut text = String::from("thermal_ns,mechanical_ns\n");
    for [t, m] in &pairs[pairs.len() - SAMPLES..] {
        text.push_str(&format!("{t},{m}\n"));
    }
    std::fs::create_dir_all(&dir)
        .and_then(|()| std::fs::write(dir.join("pairs.csv"), text))
        .expect("cannot write pairs.csv");
}

criterion_group! {
    name = benches;
    config = Criterion::default().without_plots().sample_size(SAMPLES);
    targets = bench_thermal
}
criterion_main!(benches);
