//! Per-step cost of the time stepper, in node-steps per second.
//!
//! `unconstrained`: free-free bar (plain tridiagonal solve). `exact-one-end` / `exact-two-ends`:
//! the same bar pressed by a constant load onto obstacles at gap 0 under one or both ends, so
//! the constraints are active at every step (the worst case of the enumeration). The target is
//! exact <= 1.15x unconstrained at equal J. `unconstrained-bare` is the unconstrained step with
//! the energy balance measured only every 10⁹ steps (`[output] diagnostics_every`): the cost of
//! the diagnostics is the difference to `unconstrained` (target: at most 50 % of bare).

use criterion::{BenchmarkId, Criterion, Throughput, criterion_group, criterion_main};
use viscobar::{Scene, Simulation};

fn scene(elements: u64, left: &str, right: &str) -> Scene {
    scene_with(elements, left, right, &[])
}

fn scene_with(elements: u64, left: &str, right: &str, overrides: &[&str]) -> Scene {
    let end = |c: &str| {
        if c == "signorini" {
            "condition = \"signorini\"\ngap = 0.0".to_string()
        } else {
            format!("condition = \"{c}\"")
        }
    };
    let text = format!(
        "[bar]\nlength = 1.0\nviscosity = 0.1\n[left]\n{}\n[right]\n{}\n[initial]\n\
         displacement = \"0\"\nvelocity = \"0\"\n[load]\ndensity = \"-10\"\n[mesh]\nelements = {elements}\n\
         [time]\nstep = {dt}\nend = {end}\n",
        end(left),
        end(right),
        dt = 1.0 / elements as f64,
        end = 1000.0 / elements as f64,
    );
    let o: Vec<String> = overrides.iter().map(|s| s.to_string()).collect();
    Scene::from_toml(&text, &o).unwrap()
}

/// An obstacle under every node and a load pressing the left half onto it and lifting the
/// right half: a contact set with a boundary, the exact step solving up to J + 2 bounds.
fn distributed(elements: u64, dt_over_dx: f64) -> Scene {
    let dt = format!("time.step={}", dt_over_dx / elements as f64);
    let end = format!("time.end={}", 1000.0 * dt_over_dx / elements as f64);
    scene_with(
        elements,
        "free",
        "free",
        &[
            "obstacle.gap=0.0",
            "load.density=\"-10*cos(pi*x)\"",
            &dt,
            &end,
        ],
    )
}

fn settle_and_bench(
    group: &mut criterion::BenchmarkGroup<'_, criterion::measurement::WallTime>,
    label: &str,
    elements: u64,
    scene: &Scene,
) {
    let mut sim = Simulation::new(scene).unwrap();
    for _ in 0..50 {
        sim.step().unwrap();
    }
    group.bench_with_input(BenchmarkId::new(label, elements), &elements, |b, _| {
        b.iter(|| sim.step().unwrap())
    });
}

fn bench_step(c: &mut Criterion) {
    let mut group = c.benchmark_group("step");
    for elements in [100u64, 1_000, 10_000, 100_000, 1_000_000] {
        group.throughput(Throughput::Elements(elements + 1));
        let bare = ["output.diagnostics_every=1000000000"];
        settle_and_bench(
            &mut group,
            "unconstrained-bare",
            elements,
            &scene_with(elements, "free", "free", &bare),
        );
        for (label, left, right) in [
            ("unconstrained", "free", "free"),
            ("exact-one-end", "signorini", "free"),
            ("exact-two-ends", "signorini", "signorini"),
        ] {
            let mut sim = Simulation::new(&scene(elements, left, right)).unwrap();
            // Settle into contact before timing.
            for _ in 0..50 {
                sim.step().unwrap();
            }
            group.bench_with_input(BenchmarkId::new(label, elements), &elements, |b, _| {
                b.iter(|| sim.step().unwrap())
            });
        }
    }
    group.finish();
}

fn bench_other_solvers(c: &mut Criterion) {
    let mut group = c.benchmark_group("step");
    for elements in [100u64, 1_000, 10_000, 100_000] {
        group.throughput(Throughput::Elements(elements + 1));
        settle_and_bench(
            &mut group,
            "distributed-exact",
            elements,
            &distributed(elements, 1.0),
        );
        settle_and_bench(
            &mut group,
            "penalty-two-ends",
            elements,
            &scene_with(
                elements,
                "signorini",
                "signorini",
                &["solver.method=\"penalty\""],
            ),
        );
        if elements <= 10_000 {
            for (label, eps) in [
                ("osqp-default-two-ends", "1e-5"),
                ("osqp-tight-two-ends", "1e-10"),
            ] {
                let o = [
                    "solver.method=\"osqp\"".to_string(),
                    format!("solver.eps_abs={eps}"),
                    format!("solver.eps_rel={eps}"),
                ];
                let o: Vec<&str> = o.iter().map(String::as_str).collect();
                settle_and_bench(
                    &mut group,
                    label,
                    elements,
                    &scene_with(elements, "signorini", "signorini", &o),
                );
            }
        }
    }
    // The stiff worst case: J = 1e5, dt = 10 dx.
    group.throughput(Throughput::Elements(100_001));
    settle_and_bench(
        &mut group,
        "distributed-exact-dt10dx",
        100_000,
        &distributed(100_000, 10.0),
    );
    group.finish();
}

// No HTML plots: criterion's plotters backend would need a registered font (the project's
// plotters is built with `ab_glyph` only); the numbers are in target/criterion/*/new/.
/// A built-in scene refined to `elements` with `Δt/Δx` kept, long enough for any bench.
fn refined_builtin(name: &str, elements: u64, extra: &[&str]) -> Scene {
    let (_, base) = viscobar::scene::load(name, &[]).unwrap();
    let step = base.time.step * base.mesh.elements as f64 / elements as f64;
    let mut o = vec![
        format!("mesh.elements={elements}"),
        format!("time.step={step}"),
        format!("time.end={}", 1_000_000.0 * step),
    ];
    o.extend(extra.iter().map(|s| s.to_string()));
    viscobar::scene::load(name, &o).unwrap().1
}

/// The load path: each forced talk scene against its unforced twin (the same bar,
/// obstacles and data without the load), and the twin with a load that does not separate
/// (two transcendental calls per node).
fn bench_loads(c: &mut Criterion) {
    let mut group = c.benchmark_group("load");
    for elements in [100u64, 1_000, 10_000, 100_000] {
        group.throughput(Throughput::Elements(elements + 1));
        for (label, name, extra) in [
            ("both-ends", "both-ends", &[][..]),
            ("both-ends-forced", "both-ends-forced", &[][..]),
            (
                "both-ends-mixed-load",
                "both-ends",
                &["load.density=\"0.1*sin(x*t)*exp(-(x-t)^2)\""][..],
            ),
            ("distributed", "distributed", &[][..]),
            ("distributed-forced", "distributed-forced", &[][..]),
        ] {
            settle_and_bench(
                &mut group,
                label,
                elements,
                &refined_builtin(name, elements, extra),
            );
        }
    }
    group.finish();
}

criterion_group! {
    name = benches;
    config = Criterion::default().without_plots();
    targets = bench_step, bench_other_solvers, bench_loads
}
criterion_main!(benches);
