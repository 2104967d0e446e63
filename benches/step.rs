//! Per-step cost of the time stepper, in node-steps per second.
//!
//! `unconstrained`: free-free bar (plain tridiagonal solve). `exact-one-end` / `exact-two-ends`:
//! the same bar pressed by a constant load onto obstacles at gap 0 under one or both ends, so
//! the constraints are active at every step (the worst case of the enumeration). The target is
//! exact <= 1.15x unconstrained at equal J.

use criterion::{BenchmarkId, Criterion, Throughput, criterion_group, criterion_main};
use viscobar::{Scene, Simulation};

fn scene(elements: u64, left: &str, right: &str) -> Scene {
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
    Scene::from_toml(&text, &[]).unwrap()
}

fn bench_step(c: &mut Criterion) {
    let mut group = c.benchmark_group("step");
    for elements in [100u64, 1_000, 10_000, 100_000] {
        group.throughput(Throughput::Elements(elements + 1));
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

criterion_group!(benches, bench_step);
criterion_main!(benches);
