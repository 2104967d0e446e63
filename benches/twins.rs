//! What each optimised twin of the bar's kernels buys on a step: the steps of `benches/step.rs`
//! (`unconstrained`, `exact-two-ends`) with one kernel plain (`Simulation::with_kernels`) beside
//! the default, at J = 1e4, 1e5 and 1e6; the specialised step solvers (`EndEnumeration`, and
//! `BlockPivoting` under an obstacle) beside the general `CondensedLcp`; and, for a load that
//! does not separate, the load evaluation compiled (`NodalEvaluator`) and node by node
//! (`Expression::eval`, the plain version) beside that load's step. `cargo run --release -p
//! viscobar-certificate -- bench-compare --twins --update benches/README.md` writes the factors.

use criterion::{BenchmarkId, Criterion, Throughput, criterion_group, criterion_main};
use viscobar::bar::Kernels;
use viscobar::internals::scene::nodal::NodalEvaluator;
use viscobar::{Scene, Simulation};

/// The bar of `benches/step.rs`: length 1, `α = 0.1`, at rest under the load `−10`, `Δt = Δx`,
/// with Signorini obstacles at gap 0 under both ends or free ends.
fn scene(elements: u64, ends: &str, load: &str) -> Scene {
    let end = if ends == "signorini" {
        "condition = \"signorini\"\ngap = 0.0"
    } else {
        "condition = \"free\""
    };
    let text = format!(
        "[bar]\nlength = 1.0\nviscosity = 0.1\n[left]\n{end}\n[right]\n{end}\n[initial]\n\
         displacement = \"0\"\nvelocity = \"0\"\n[load]\ndensity = \"{load}\"\n[mesh]\n\
         elements = {elements}\n[time]\nstep = {dt}\nend = {t_end}\n",
        dt = 1.0 / elements as f64,
        t_end = 1000.0 / elements as f64,
    );
    Scene::from_toml(&text, &[]).unwrap()
}

/// The kernels of each variant: the default, each twin replaced by its plain version, all
/// plain; and the step solved by the general `CondensedLcp` (contact steps only).
const VARIANTS: [(&str, Kernels); 7] = [
    ("twins", Kernels::TWINS),
    (
        "plain-solve",
        Kernels {
            twisted_solve: false,
            ..Kernels::TWINS
        },
    ),
    (
        "plain-rhs",
        Kernels {
            uniform_rhs: false,
            ..Kernels::TWINS
        },
    ),
    (
        "plain-energy",
        Kernels {
            uniform_energy: false,
            ..Kernels::TWINS
        },
    ),
    (
        "no-warm-start",
        Kernels {
            warm_start: false,
            ..Kernels::TWINS
        },
    ),
    ("plain", Kernels::PLAIN),
    (
        "general-solver",
        Kernels {
            general_solver: true,
            ..Kernels::TWINS
        },
    ),
];

fn bench_twins(c: &mut Criterion) {
    let mut group = c.benchmark_group("twins");
    for elements in [10_000u64, 100_000, 1_000_000] {
        group.throughput(Throughput::Elements(elements + 1));
        for (step, ends) in [("unconstrained", "free"), ("exact-two-ends", "signorini")] {
            for (variant, kernels) in VARIANTS {
                // The warm start and the step solver act on contact steps only.
                if matches!(variant, "no-warm-start" | "general-solver") && ends == "free" {
                    continue;
                }
                let mut sim =
                    Simulation::with_kernels(&scene(elements, ends, "-10"), kernels).unwrap();
                for _ in 0..50 {
                    sim.step().unwrap();
                }
                let id = BenchmarkId::new(format!("{step}-{variant}"), elements);
                group.bench_function(id, |b| b.iter(|| sim.step().unwrap()));
            }
        }
    }
    group.finish();
}

/// The obstacle under every node of `benches/step.rs`'s `distributed-exact` (gap 0, the load
/// `−10 cos(πx)` pressing the left half onto it, free ends, `Δt = Δx`): its step by
/// `BlockPivoting` (the default) and by the general `CondensedLcp`, whose dense `S` of
/// `(J + 1)²` doubles and dense pivoting are run up to [`DENSE_OBSTACLE_MAX_ELEMENTS`] only.
fn obstacle(elements: u64) -> Scene {
    let text = format!(
        "[bar]\nlength = 1.0\nviscosity = 0.1\n[left]\ncondition = \"free\"\n[right]\n\
         condition = \"free\"\n[initial]\ndisplacement = \"0\"\nvelocity = \"0\"\n[load]\n\
         density = \"-10*cos(pi*x)\"\n[obstacle]\ngap = \"0.0\"\n[mesh]\nelements = {elements}\n\
         [time]\nstep = {dt}\nend = {t_end}\n",
        dt = 1.0 / elements as f64,
        t_end = 1000.0 / elements as f64,
    );
    Scene::from_toml(&text, &[]).unwrap()
}

/// The largest obstacle bar stepped by the general `CondensedLcp`: its `S` and the Cholesky
/// buffer of `S_AA` hold `2 (J + 1)²` doubles, 2.6 MB here and 1.6 GB at J = 1e4; its set-up
/// factorises all of `S`, and a step's `w = q + S r` is dense.
const DENSE_OBSTACLE_MAX_ELEMENTS: u64 = 400;

fn bench_obstacle(c: &mut Criterion) {
    let mut group = c.benchmark_group("twins-obstacle");
    for elements in [100u64, 400, 10_000] {
        group.throughput(Throughput::Elements(elements + 1));
        for (variant, kernels) in [VARIANTS[0], VARIANTS[6]] {
            if variant == "general-solver" && elements > DENSE_OBSTACLE_MAX_ELEMENTS {
                continue;
            }
            let mut sim = Simulation::with_kernels(&obstacle(elements), kernels).unwrap();
            for _ in 0..50 {
                sim.step().unwrap();
            }
            let id = BenchmarkId::new(format!("distributed-exact-{variant}"), elements);
            group.bench_function(id, |b| b.iter(|| sim.step().unwrap()));
        }
    }
    group.finish();
}

/// The load `0.1*sin(x*t)*exp(-(x-t)^2)` of `load/both-ends-mixed-load`: its step (two free
/// ends here, the load's cost is the same), and its evaluation at the nodes compiled and node
/// by node.
fn bench_load(c: &mut Criterion) {
    const MIXED: &str = "0.1*sin(x*t)*exp(-(x-t)^2)";
    let mut group = c.benchmark_group("twins-load");
    for elements in [10_000u64, 100_000] {
        group.throughput(Throughput::Elements(elements + 1));
        let scene = scene(elements, "free", MIXED);
        let mut sim = Simulation::new(&scene).unwrap();
        for _ in 0..50 {
            sim.step().unwrap();
        }
        let id = BenchmarkId::new("mixed-load-step", elements);
        group.bench_function(id, |b| b.iter(|| sim.step().unwrap()));
        let expr = viscobar::scene::Expression::parse("load.density", MIXED, true).unwrap();
        let xs: Vec<f64> = (0..=elements).map(|i| i as f64 / elements as f64).collect();
        let mut out = vec![0.0; xs.len()];
        let t = 0.37;
        let mut compiled = NodalEvaluator::new(expr.clone(), xs.clone());
        let id = BenchmarkId::new("mixed-load-compiled", elements);
        group.bench_function(id, |b| b.iter(|| compiled.eval_into(t, &mut out).unwrap()));
        let id = BenchmarkId::new("mixed-load-node-by-node", elements);
        group.bench_function(id, |b| {
            b.iter(|| {
                for (o, &x) in out.iter_mut().zip(&xs) {
                    *o = expr.eval(x, t).unwrap();
                }
            })
        });
    }
    group.finish();
}

criterion_group! {
    name = benches;
    config = Criterion::default().without_plots();
    targets = bench_twins, bench_obstacle, bench_load
}
criterion_main!(benches);
