//! Per-step cost of the thermal bar against the bar without a temperature, in node-steps per
//! second (group `thermal`): the same two-end bar pressed by a constant load onto obstacles at
//! gap 0 (contact active at every step), `mechanical` without `[heat]`, `thermal` with a
//! coupled temperature (γ = 0.1, κ = 0.05, an exchange with the obstacle at the left end, the
//! right end insulated), `thermal-plain-solve` with the coupled solve by the plain block sweep
//! instead of its twisted twin, and `thermal-plain-energy` with the energy terms summed node by
//! node instead of in four lanes. Target (benches/README.md): thermal <= 3x mechanical at
//! J = 1e4 … 1e5; the factors are in the twins block (`bench-compare --twins`).

use criterion::{BenchmarkId, Criterion, Throughput, criterion_group, criterion_main};
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
        let plain_energy = Kernels {
            uniform_energy: false,
            ..Kernels::TWINS
        };
        let (mut plain, mut plain_sums) = (with(plain_solve).unwrap(), with(plain_energy).unwrap());
        // Settle into contact before timing.
        for _ in 0..50 {
            bar.step().unwrap();
            thermal.step().unwrap();
            plain.step().unwrap();
            plain_sums.step().unwrap();
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
        let id = BenchmarkId::new("thermal-plain-energy", elements);
        group.bench_with_input(id, &elements, |b, _| b.iter(|| plain_sums.step().unwrap()));
    }
    group.finish();
}

criterion_group! {
    name = benches;
    config = Criterion::default().without_plots();
    targets = bench_thermal
}
criterion_main!(benches);
