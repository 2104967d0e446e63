//! Memory is O(J), not O(J × steps): a counting allocator records the peak heap of this thread
//! while a run is set up and stepped. The peak must stay within the scene validator's own
//! estimate `scene::BYTES_PER_NODE` per node and within a tighter per-scene budget, and must
//! not grow with the number of steps.
//! (Peak resident memory of the full J = 1e6, 1e4-step run is measured by
//! `cargo run --release -p viscobar-certificate -- peak-memory`, see benches/README.md.)

mod common;

use common::alloc::{live_bytes, peak_bytes, reset_peak};

#[global_allocator]
static GLOBAL: common::alloc::Counting = common::alloc::Counting;

/// Peak heap above the starting level while `steps` steps of `scene` run with the tracker.
fn peak_heap(scene: &viscobar::Scene, steps: usize) -> usize {
    let base = live_bytes();
    reset_peak();
    let mut sim = viscobar::Simulation::new(scene).unwrap();
    let mut tracker = viscobar::output::Tracker::new(&sim, scene.load.density.is_none());
    for _ in 0..steps {
        tracker.observe(&sim.step().unwrap());
    }
    drop((sim, tracker));
    peak_bytes() - base
}

/// Peak heap per node of each scene, in doubles: what the run holds plus one (the test prints
/// the measured figure: `cargo test --release --test memory -- --nocapture`). Tighter than `BYTES_PER_NODE` (64 doubles, the validator's
/// conservative estimate) so that a buffer added back (a full-mesh matrix, the initial data,
/// a start-up temporary, a copy of C) is noticed.
/// `distributed`: the incremental block pivoting keeps per node the pivots, their
/// reciprocals, the forward chain, the margins and four index lists, but no copy of the bounds
/// and no node maps when every node is constrained (measured 37.4 at 4000 elements; 41.4, with
/// a budget of 42, while it kept those).
const DOUBLES_PER_NODE: [(&str, usize); 3] =
    [("both-ends-forced", 31), ("distributed", 38), ("modal", 21)];

#[test]
fn peak_heap_is_linear_in_nodes_and_independent_of_steps() {
    for (name, doubles) in DOUBLES_PER_NODE {
        let (_, scene) = viscobar::scene::load(name, &["mesh.elements=4000".into()]).unwrap();
        let nodes = scene.elements() + 1;
        let short = peak_heap(&scene, 10);
        let long = peak_heap(&scene, 1000);
        let bound = viscobar::scene::BYTES_PER_NODE as usize * nodes;
        assert!(long <= bound, "{name}: peak {long} B > {bound} B");
        let tight = doubles * 8 * nodes;
        println!(
            "{name}: peak heap {:.1} doubles a node",
            long as f64 / (8 * nodes) as f64
        );
        assert!(
            long <= tight,
            "{name}: peak {long} B > {doubles} doubles a node ({tight} B)"
        );
        assert_eq!(
            short, long,
            "{name}: the peak grows with the number of steps"
        );
    }
}
