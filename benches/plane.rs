//! The plane body's step against one solve with the factor of `C`, at 1e3 … 1e5 unknowns (and
//! 1e6 with `VISCOBAR_BENCH_PLANE_1E6=1`: about 5 s of set-up and 1 GB for the factor).
//!
//! A cantilever-like body on `nx × nx/2` cells of `(0, 2) × (0, 1)`, left edge clamped,
//! `λ = 1`, `μ = ½`, `α = 0.02`, `Δt = h`, under a constant load (as the sparse-Cholesky probe
//! in `../shared/notes/faer-sparse-cholesky.md`). `plane-step/N` is a whole step (right-hand
//! side, solve, energy balance), `plane-solve/N` one solve; after criterion's groups the bench
//! prints the ratio step / solve from medians of its own timings.

use criterion::{BenchmarkId, Criterion, Throughput, criterion_group, criterion_main};
use std::time::Instant;
use viscobar::plane::PlaneSimulation;
use viscobar::scene::plane::PlaneScene;

fn scene(nx: u64) -> PlaneScene {
    let dt = 2.0 / nx as f64;
    let text = format!(
        "[plane]\nwidth = 2.0\nheight = 1.0\nlambda = 1.0\nmu = 0.5\nviscosity = 0.02\n\
         [edges]\nleft = {{ condition = \"clamped\" }}\n[load]\ndensity = [\"0\", \"-1\"]\n\
         [mesh]\nnx = {nx}\nny = {ny}\n[time]\nstep = {dt}\nend = {end}\n",
        ny = nx / 2,
        end = 1000.0 * dt
    );
    PlaneScene::from_toml(&text, &[]).unwrap()
}

/// Cells along x: about 1e3, 1e4, 1e5 (and 1e6) unknowns.
fn sizes() -> Vec<u64> {
    let mut v = vec![32, 100, 316];
    if std::env::var_os("VISCOBAR_BENCH_PLANE_1E6").is_some() {
        v.push(1000);
    }
    v
}

/// Median wall time of `f` over `runs` calls, seconds.
fn median(runs: usize, mut f: impl FnMut()) -> f64 {
    let mut t: Vec<f64> = (0..runs)
        .map(|_| {
            let s = Instant::now();
            f();
            s.elapsed().as_secs_f64()
        })
        .collect();
    t.sort_by(f64::total_cmp);
    t[runs / 2]
}

fn bench(c: &mut Criterion) {
    let mut group = c.benchmark_group("plane");
    group.sample_size(10);
    let mut ratios = Vec::new();
    for nx in sizes() {
        let mut sim = PlaneSimulation::new(&scene(nx)).unwrap();
        let n = sim.discretisation().unknowns();
        group.throughput(Throughput::Elements(n as u64));
        group.bench_function(BenchmarkId::new("plane-step", n), |b| {
            b.iter(|| sim.step().unwrap())
        });
        let mut x: Vec<f64> = (0..n).map(|i| (i as f64 * 0.37).sin()).collect();
        group.bench_function(BenchmarkId::new("plane-solve", n), |b| {
            b.iter(|| sim.solve_in_place(&mut x))
        });
        let runs = if n > 200_000 { 5 } else { 21 };
        let step = median(runs, || {
            sim.step().unwrap();
        });
        let solve = median(runs, || sim.solve_in_place(&mut x));
        ratios.push((n, step, solve));
    }
    group.finish();
    println!("\n| unknowns | step ms | solve ms | step / solve |\n|---|---|---|---|");
    for (n, step, solve) in ratios {
        println!(
            "| {n} | {:.3} | {:.3} | {:.2} |",
            step * 1e3,
            solve * 1e3,
            step / solve
        );
    }
}

// No HTML plots, as in benches/step.rs (criterion's plotters backend would need a font).
criterion_group! {
    name = benches;
    config = Criterion::default().without_plots();
    targets = bench
}
criterion_main!(benches);
