//! The plane body's step against one solve with the factor of `C`, at 1e3 … 1e5 unknowns (1e6
//! with `VISCOBAR_BENCH_PLANE_1E6=1`: about 5 s of set-up and 1 GB for the factor): a body on
//! `nx × nx/2` cells of `(0, 2) × (0, 1)`, left edge clamped, `λ = 1`, `μ = ½`, `α = 0.02`,
//! `Δt = h`, constant load (`docs/sparse-cholesky.md`); `plane-step/N` a whole step,
//! `plane-solve/N` one solve; the bench prints step / solve from medians of its own timings.
//!
//! `plane-contact`: a block resting on a Signorini floor (every bottom node in contact), the
//! exact step against the free-bottom step of the same body, 1e4 … 2e5 unknowns with up to 200
//! normals and 1e5 with 500; it prints the ratio, the set-up of `S` and OSQP's step over the
//! exact one (up to 5e4 unknowns). `plane-contact/kratos-block-30x15-200-steps`: the built-in
//! `plane-block-drop` end to end in memory, the size of a Kratos comparison run.
//!
//! `plane-scale`: the resting block at 1e5 unknowns with 1000 normals (exact step) and 5000
//! (the penalty law's sparse Newton iteration), against its free step.

use criterion::{BenchmarkId, Criterion, Throughput, criterion_group, criterion_main};
use std::time::Instant;
use viscobar::internals::linalg::cholesky::SparseCholesky;
use viscobar::plane::PlaneSimulation;
use viscobar::scene::plane::PlaneScene;
use viscobar::scene::{SolverMethod, SolverSpec};

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
        let d = sim.discretisation();
        let n = d.unknowns();
        let mut chol = SparseCholesky::new(&d.pattern, &d.step_matrix(), "C").unwrap();
        group.throughput(Throughput::Elements(n as u64));
        group.bench_function(BenchmarkId::new("plane-step", n), |b| {
            b.iter(|| sim.step().unwrap())
        });
        let mut x: Vec<f64> = (0..n).map(|i| (i as f64 * 0.37).sin()).collect();
        group.bench_function(BenchmarkId::new("plane-solve", n), |b| {
            b.iter(|| chol.solve_in_place(&mut x))
        });
        let runs = if n > 200_000 { 5 } else { 21 };
        let step = median(runs, || {
            sim.step().unwrap();
        });
        let solve = median(runs, || chol.solve_in_place(&mut x));
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

/// A block `2 × H` (square cells, `nx × ny`) resting under gravity on a floor at its bottom
/// edge (Signorini, gap 0, the `nx + 1` bottom nodes in contact every step), `λ = 1`, `μ = ½`,
/// `α = 0.02`, `Δt = h`; `contact = false` gives the same body with a free bottom (the
/// unconstrained step the exact step is measured against).
fn resting(nx: u64, ny: u64, contact: bool) -> PlaneScene {
    let h = 2.0 / nx as f64;
    let bottom = if contact {
        "{ condition = \"signorini\", gap = 0 }"
    } else {
        "{ condition = \"free\" }"
    };
    let text = format!(
        "[plane]\nwidth = 2.0\nheight = {height}\nlambda = 1.0\nmu = 0.5\nviscosity = 0.02\n\
         [edges]\nbottom = {bottom}\n[load]\ndensity = [\"0\", \"-1\"]\n\
         [mesh]\nnx = {nx}\nny = {ny}\n[time]\nstep = {h}\nend = {end}\n",
        height = h * ny as f64,
        end = 1000.0 * h
    );
    PlaneScene::from_toml(&text, &[]).unwrap()
}

/// `(nx, ny)` of the contact bench: about 1e4 unknowns with 100 and 200 contact normals, 4e4
/// and 2e5 with 200, and 500 normals at 1e5 unknowns.
const CONTACT_SIZES: [(u64, u64); 5] = [(99, 50), (199, 24), (199, 100), (199, 500), (499, 100)];

/// The exact step with contact against the unconstrained step of the same body, the set-up of
/// `S` (m solves, blocked), and OSQP's step where it is affordable (at most 5e4 unknowns).
fn bench_contact(c: &mut Criterion) {
    let mut group = c.benchmark_group("plane-contact");
    group.sample_size(10);
    let mut rows = Vec::new();
    for (nx, ny) in CONTACT_SIZES {
        let t = Instant::now();
        let mut free = PlaneSimulation::new(&resting(nx, ny, false)).unwrap();
        let setup_free = t.elapsed().as_secs_f64();
        let t = Instant::now();
        let mut sim = PlaneSimulation::new(&resting(nx, ny, true)).unwrap();
        let setup_contact = t.elapsed().as_secs_f64();
        let n = sim.discretisation().unknowns();
        let m = sim.contact().len();
        // Settle into contact before timing.
        for _ in 0..20 {
            sim.step().unwrap();
        }
        let id = format!("{n}-m{m}");
        group.bench_function(BenchmarkId::new("exact-step", &id), |b| {
            b.iter(|| sim.step().unwrap())
        });
        group.bench_function(BenchmarkId::new("free-step", &id), |b| {
            b.iter(|| free.step().unwrap())
        });
        let runs = if n > 100_000 { 5 } else { 21 };
        let exact = median(runs, || {
            sim.step().unwrap();
        });
        let unconstrained = median(runs, || {
            free.step().unwrap();
        });
        let active = sim.step().unwrap().contact.contact_nodes;
        let osqp = (n <= 50_000).then(|| {
            let mut scene = resting(nx, ny, true);
            scene.solver = SolverSpec {
                method: SolverMethod::Osqp,
                ..SolverSpec::default()
            };
            let mut o = PlaneSimulation::new(&scene).unwrap();
            for _ in 0..20 {
                o.step().unwrap();
            }
            median(5, || {
                o.step().unwrap();
            })
        });
        rows.push((
            n,
            m,
            active,
            exact,
            unconstrained,
            setup_contact - setup_free,
            osqp,
        ));
    }
    group.finish();
    println!(
        "\n| unknowns | m | in contact | exact step ms | free step ms | exact / free | S set-up s | OSQP step / exact |\n|---|---|---|---|---|---|---|---|"
    );
    for (n, m, active, exact, free, setup, osqp) in rows {
        println!(
            "| {n} | {m} | {active} | {:.3} | {:.3} | {:.2} | {:.3} | {} |",
            exact * 1e3,
            free * 1e3,
            exact / free,
            setup,
            osqp.map_or("–".to_string(), |o| format!("{:.1}", o / exact))
        );
    }
}

/// The built-in `plane-block-drop` at the size of a Kratos comparison run (Kratos 10.4.4 takes
/// 12–28 s for it on this machine): a 30 × 15 block falling onto a floor for 200 steps,
/// undamped (α = 0, as a Newmark run) and with the talk's α = 0.1; set-up and the 200 exact
/// steps end to end in memory (`run_plane_in_memory`: the scene validated, the factor, `S`,
/// every record).
fn bench_kratos(c: &mut Criterion) {
    use viscobar::output::run_plane_in_memory;
    use viscobar::scene::{AnyScene, load_any};
    let mut group = c.benchmark_group("plane-contact");
    group.sample_size(20);
    let mut rows = Vec::new();
    for (id, set) in [
        ("kratos-block-30x15-200-steps", vec![]),
        (
            "kratos-block-30x15-200-steps-alpha0.1",
            vec!["plane.viscosity=0.1".to_string()],
        ),
    ] {
        let AnyScene::Plane(scene) = load_any("plane-block-drop", &set).unwrap().1 else {
            panic!("plane-block-drop is a plane scene");
        };
        group.bench_function(id, |b| {
            b.iter(|| run_plane_in_memory("plane-block-drop", &scene).unwrap())
        });
        let t = median(21, || {
            run_plane_in_memory("plane-block-drop", &scene).unwrap();
        });
        rows.push((id, t));
    }
    group.finish();
    println!("\n| run (set-up + 200 steps, in memory) | median ms |\n|---|---|");
    for (id, t) in rows {
        println!("| {id} | {:.2} |", t * 1e3);
    }
}

/// `(nx, ny, solver)` of the scale bench: 1e5 unknowns with 1000 contact normals (exact,
/// condensed `S` of 8 MB), and with 5000 (the penalty law beyond the condensed switch: the
/// sparse Newton iteration, no dense matrix).
const SCALE_SIZES: [(u64, u64, SolverMethod); 2] = [
    (999, 49, SolverMethod::Exact),
    (4999, 9, SolverMethod::Penalty),
];

/// Contact at scale: the resting block's contact step at 1e5 unknowns with 1000 normals
/// (exact) and 5000 (penalty, sparse), against the free step of the same body; prints the
/// set-up of each run and the ratio.
fn bench_scale(c: &mut Criterion) {
    let mut group = c.benchmark_group("plane-scale");
    group.sample_size(10);
    let mut rows = Vec::new();
    for (nx, ny, method) in SCALE_SIZES {
        let t = Instant::now();
        let mut free = PlaneSimulation::new(&resting(nx, ny, false)).unwrap();
        let setup_free = t.elapsed().as_secs_f64();
        let mut scene = resting(nx, ny, true);
        scene.solver = SolverSpec {
            method,
            ..SolverSpec::default()
        };
        let t = Instant::now();
        let mut sim = PlaneSimulation::new(&scene).unwrap();
        let setup = t.elapsed().as_secs_f64();
        let n = sim.discretisation().unknowns();
        let m = sim.contact().len();
        for _ in 0..20 {
            sim.step().unwrap();
        }
        let id = format!("{n}-m{m}");
        let name = format!("{}-step", sim.solver_name());
        group.bench_function(BenchmarkId::new(name, &id), |b| {
            b.iter(|| sim.step().unwrap())
        });
        group.bench_function(BenchmarkId::new("free-step", &id), |b| {
            b.iter(|| free.step().unwrap())
        });
        let step = median(5, || {
            sim.step().unwrap();
        });
        let unconstrained = median(5, || {
            free.step().unwrap();
        });
        let active = sim.step().unwrap().contact.contact_nodes;
        rows.push((
            n,
            m,
            sim.solver_name(),
            active,
            step,
            unconstrained,
            setup,
            setup_free,
        ));
    }
    group.finish();
    println!(
        "\n| unknowns | m | solver | in contact | step ms | free step ms | step / free | set-up s | free set-up s |\n|---|---|---|---|---|---|---|---|---|"
    );
    for (n, m, solver, active, step, free, setup, setup_free) in rows {
        println!(
            "| {n} | {m} | {solver} | {active} | {:.3} | {:.3} | {:.2} | {setup:.2} | {setup_free:.2} |",
            step * 1e3,
            free * 1e3,
            step / free
        );
    }
}

// No HTML plots, as in benches/step.rs (criterion's plotters backend would need a font).
criterion_group! {
    name = benches;
    config = Criterion::default().without_plots();
    targets = bench, bench_contact, bench_kratos, bench_scale
}
criterion_main!(benches);
