//! Each talk scene end to end at its default size (`viscobar::study::figures::talk_scenes`): set-up,
//! start-up and every step with the energy balance, through `run::run_in_memory` (no files
//! written, so disk speed does not enter). Throughput in node-steps.

use criterion::{Criterion, Throughput, criterion_group, criterion_main};
use viscobar::study::figures::talk_scenes;
use viscobar::time::run::run_in_memory;

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

criterion_group! {
    name = benches;
    config = Criterion::default().without_plots();
    targets = bench_scenes
}
criterion_main!(benches);
