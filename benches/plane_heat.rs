//! The thermo-mechanical plane step against the mechanical plane step at about 1e4 unknowns
//! with 100 frictional normals (the performance target: at most 3x).
//!
//! The sliding block of `benches/plane_friction.rs`: `2 × 1` on `99 × 50` cells (10 200
//! unknowns, 5 100 nodes), `λ = 1`, `μ_L = ½`, `α = 0.02`, `Δt = h`, on a Signorini floor at gap
//! 0 with Coulomb friction `μ = 0.5` under gravity tilted to `(0.6, −0.8)` (its bottom nodes slip
//! where in contact), `mechanical` without `[heat]`, `thermal` with it (`γ = 0`, `κ = 0.05`,
//! the bottom's `frictional_heating = 0.75`, the top held at `θ = 0`) and `coupled` with
//! `γ = 0.5` (Lemke's method on the coupled `S`, [`viscobar`]'s `plane::coupling`).
//! `plane-heat/step/*` is one step after 20 steps of settling. After criterion's group the bench
//! times each thermal step and the mechanical one one after the other in each of [`PAIRS`]
//! samples (the machine's speed drifts) and prints the median of the samples' ratios beside its
//! target.

use criterion::{BenchmarkId, Criterion, criterion_group, criterion_main};
use std::time::Instant;
use viscobar::plane::PlaneSimulation;
use viscobar::scene::plane::PlaneScene;

/// Cells of the block: `nx + 1 = 100` contact normals, 10 200 unknowns.
const CELLS: (u64, u64) = (99, 50);
/// The target: the thermo-mechanical step costs at most this many mechanical steps.
const TARGET: f64 = 3.0;
/// Samples of the paired timing, and steps of each side per sample.
const PAIRS: usize = 21;
const STEPS_PER_SAMPLE: usize = 5;

/// The sliding block, with the temperature coupled by `γ` when `heat = Some(γ)`.
fn block(heat: Option<f64>) -> PlaneScene {
    let (nx, ny) = CELLS;
    let h = 2.0 / nx as f64;
    let heat = match heat {
        Some(gamma) => format!(
            "[heat]\ncoupling = {gamma:?}\ndiffusivity = 0.05\n\
             bottom = {{ frictional_heating = 0.75 }}\n\
             top = {{ condition = \"temperature\", value = 0 }}\n"
        ),
        None => String::new(),
    };
    let text = format!(
        "[plane]\nwidth = 2.0\nheight = {height}\nlambda = 1.0\nmu = 0.5\nviscosity = 0.02\n\
         [edges]\nbottom = {{ condition = \"signorini\", gap = 0, friction = 0.5 }}\n\
         [load]\ndensity = [\"0.6\", \"-0.8\"]\n\
         [mesh]\nnx = {nx}\nny = {ny}\n[time]\nstep = {h}\nend = {end}\n{heat}",
        height = h * ny as f64,
        end = 1000.0 * h
    );
    PlaneScene::from_toml(&text, &[]).unwrap()
}

/// The simulation of `scene` after 20 steps of settling.
fn settled(scene: &PlaneScene) -> PlaneSimulation {
    let mut sim = PlaneSimulation::new(scene).unwrap();
    for _ in 0..20 {
        sim.step().unwrap();
    }
    sim
}

/// Seconds per step of `STEPS_PER_SAMPLE` steps of `sim`.
fn timed(sim: &mut PlaneSimulation) -> f64 {
    let start = Instant::now();
    for _ in 0..STEPS_PER_SAMPLE {
        sim.step().unwrap();
    }
    start.elapsed().as_secs_f64() / STEPS_PER_SAMPLE as f64
}

fn median(mut v: Vec<f64>) -> f64 {
    v.sort_by(f64::total_cmp);
    v[v.len() / 2]
}

fn bench(c: &mut Criterion) {
    let mut group = c.benchmark_group("plane-heat");
    group.sample_size(10);
    let (mechanical, thermal, coupled) = (block(None), block(Some(0.0)), block(Some(0.5)));
    let cases = [("thermal", &thermal), ("coupled", &coupled)];
    for (name, scene) in [("mechanical", &mechanical)].into_iter().chain(cases) {
        let mut sim = settled(scene);
        let n = sim.discretisation().unknowns();
        let m = sim.contact().len();
        let id = format!("{name}/{n}-m{m}");
        group.bench_function(BenchmarkId::new("step", &id), |b| {
            b.iter(|| sim.step().unwrap())
        });
    }
    group.finish();
    println!(
        "\n| case | unknowns | m | stick / slip | mechanical step ms | thermal step ms | thermal / mechanical | target |\n|---|---|---|---|---|---|---|---|"
    );
    for (name, scene) in cases {
        let (mut a, mut b) = (settled(&mechanical), settled(scene));
        let (n, m) = (a.discretisation().unknowns(), a.contact().len());
        let mut pairs = Vec::with_capacity(PAIRS);
        for _ in 0..PAIRS {
            let t_thermal = timed(&mut b);
            let t_mechanical = timed(&mut a);
            pairs.push((t_mechanical, t_thermal));
        }
        let last = b.step().unwrap();
        assert!(
            last.heat.unwrap().frictional_heating > 0.0,
            "friction heats"
        );
        let ratio = median(pairs.iter().map(|(a, b)| b / a).collect());
        let step = |k: usize| median(pairs.iter().map(|p| [p.0, p.1][k]).collect()) * 1e3;
        println!(
            "| sliding, {name} | {n} | {m} | {} / {} | {:.3} | {:.3} | {ratio:.2}x | <= {TARGET}x {} |",
            last.stick_nodes,
            last.slip_nodes,
            step(0),
            step(1),
            if ratio <= TARGET { "met" } else { "not met" }
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
