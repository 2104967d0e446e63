//! The exact frictional step against the frictionless exact step at about 1e4 unknowns with
//! 100 contact normals (the performance target: at most 4x), their set-up, and OSQP's Tresca
//! fixed point beside them.
//!
//! A block `2 × 1` on `99 × 50` cells (10 200 unknowns), `λ = 1`, `μ_L = ½`, `α = 0.02`,
//! `Δt = h`, on a Signorini floor at gap 0 (its 100 bottom nodes in contact every step), with
//! Coulomb friction `μ = 0.3` or without: `resting` under vertical gravity (every node sticks),
//! `sliding` under gravity tilted to `(0.6, −0.8)` with `μ = 0.5` (every node slips).
//! `plane-friction/step/*` is one step (right-hand side, the step solve, the energy balance)
//! after 20 steps of settling; `plane-friction/setup/*` the set-up of a run (the factor of `C`,
//! `S`, the LCP); after criterion's groups the bench prints the ratios from medians of its own
//! timings.

use criterion::{BenchmarkId, Criterion, criterion_group, criterion_main};
use std::time::Instant;
use viscobar::plane::PlaneSimulation;
use viscobar::scene::plane::PlaneScene;
use viscobar::scene::{SolverMethod, SolverSpec};

/// Cells of the block: `nx + 1 = 100` contact normals, 10 200 unknowns.
const CELLS: (u64, u64) = (99, 50);

/// The block on its floor: `friction` on the bottom edge (`None`: frictionless), `load` the
/// gravity density.
fn block(friction: Option<f64>, load: [&str; 2], method: SolverMethod) -> PlaneScene {
    let (nx, ny) = CELLS;
    let h = 2.0 / nx as f64;
    let friction = friction.map_or(String::new(), |mu| format!(", friction = {mu}"));
    let text = format!(
        "[plane]\nwidth = 2.0\nheight = {height}\nlambda = 1.0\nmu = 0.5\nviscosity = 0.02\n\
         [edges]\nbottom = {{ condition = \"signorini\", gap = 0{friction} }}\n\
         [load]\ndensity = [\"{}\", \"{}\"]\n\
         [mesh]\nnx = {nx}\nny = {ny}\n[time]\nstep = {h}\nend = {end}\n",
        load[0],
        load[1],
        height = h * ny as f64,
        end = 1000.0 * h
    );
    let mut scene = PlaneScene::from_toml(&text, &[]).unwrap();
    scene.solver = SolverSpec {
        method,
        ..SolverSpec::default()
    };
    scene
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

const VERTICAL: [&str; 2] = ["0", "-1"];
const TILTED: [&str; 2] = ["0.6", "-0.8"];

fn bench(c: &mut Criterion) {
    let mut group = c.benchmark_group("plane-friction");
    group.sample_size(10);
    let cases = [
        ("frictionless", block(None, VERTICAL, SolverMethod::Exact)),
        ("resting", block(Some(0.3), VERTICAL, SolverMethod::Exact)),
        ("sliding", block(Some(0.5), TILTED, SolverMethod::Exact)),
        (
            "osqp-resting",
            block(Some(0.3), VERTICAL, SolverMethod::Osqp),
        ),
    ];
    let mut rows = Vec::new();
    for (name, scene) in &cases {
        let mut sim = PlaneSimulation::new(scene).unwrap();
        let n = sim.discretisation().unknowns();
        let m = sim.contact().len();
        for _ in 0..20 {
            sim.step().unwrap();
        }
        let id = format!("{name}/{n}-m{m}");
        group.bench_function(BenchmarkId::new("step", &id), |b| {
            b.iter(|| sim.step().unwrap())
        });
        let step = median(21, || {
            sim.step().unwrap();
        });
        let last = sim.step().unwrap();
        let setup = if name.starts_with("osqp") {
            None
        } else {
            group.bench_function(BenchmarkId::new("setup", &id), |b| {
                b.iter(|| PlaneSimulation::new(scene).unwrap())
            });
            Some(median(5, || {
                PlaneSimulation::new(scene).unwrap();
            }))
        };
        rows.push((*name, n, m, last, step, setup));
    }
    group.finish();
    let (free_step, free_setup) = (rows[0].4, rows[0].5.unwrap_or(f64::NAN));
    println!(
        "\n| case | unknowns | m | stick / slip | iterations | step ms | step / frictionless | set-up s | set-up / frictionless |\n|---|---|---|---|---|---|---|---|---|"
    );
    for (name, n, m, last, step, setup) in rows {
        println!(
            "| {name} | {n} | {m} | {} / {} | {} | {:.3} | {:.2} | {} | {} |",
            last.stick_nodes,
            last.slip_nodes,
            last.iterations,
            step * 1e3,
            step / free_step,
            setup.map_or("–".into(), |s| format!("{s:.3}")),
            setup.map_or("–".into(), |s| format!("{:.2}", s / free_setup)),
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
