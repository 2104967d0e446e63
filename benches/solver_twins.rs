//! The bar's specialised step solvers against the general condensed LCP on the same step
//! problem (`step::algorithm` keeps a specialised one only where it buys 1.2x): the bar of
//! `benches/step.rs` (length 1, `Δt = Δx`) at the talk's sizes (100, 400 elements) and 1e4,
//! pressed onto its obstacles so that every timed solve is in contact, warm-started:
//! `end-enumeration` / `end-penalty` against `condensed-lcp` / `condensed-penalty` on both
//! ends, `block-pivoting` against `condensed-lcp` under an obstacle at every node (≤ 400).

use criterion::{BenchmarkId, Criterion, criterion_group, criterion_main};
use viscobar::Scene;
use viscobar::bar::Discretisation;
use viscobar::internals::linalg::system::TridiagSystem;
use viscobar::internals::linalg::tridiag::SymTridiag;
use viscobar::internals::step::{BlockPivoting, CondensedLcp, EndEnumeration, EndPenalty};
use viscobar::step::{Constraints, PenaltySettings, StepSolver};

/// The bar's step matrix at `elements` elements (both ends Signorini at gap 0).
fn step_matrix(elements: u64) -> SymTridiag {
    let text = format!(
        "[bar]\nlength = 1.0\nviscosity = 0.1\n[left]\ncondition = \"signorini\"\ngap = 0.0\n\
         [right]\ncondition = \"signorini\"\ngap = 0.0\n[initial]\ndisplacement = \"0\"\n\
         velocity = \"0\"\n[load]\ndensity = \"-10\"\n[mesh]\nelements = {elements}\n[time]\n\
         step = {dt}\nend = 1.0\n",
        dt = 1.0 / elements as f64,
    );
    let scene = Scene::from_toml(&text, &[]).unwrap();
    Discretisation::new(&scene).unwrap().step_matrix
}

/// Times `solver` on a step problem that presses every bound (a downward `b`, `lo = 0`).
fn time(
    c: &mut Criterion,
    group: &str,
    (name, elements): (&str, u64),
    solver: &mut dyn StepSolver,
    n: usize,
    m: usize,
) {
    let rhs: Vec<f64> = (0..n).map(|i| -1.0 - 0.1 * (i as f64 / n as f64)).collect();
    let lower = vec![0.0; m];
    let (mut z, mut r) = (vec![0.0; n], vec![0.0; m]);
    solver.solve(&rhs, &lower, &mut z, &mut r).unwrap();
    assert!(
        r.iter().all(|&v| v > 0.0),
        "{name}/{elements}: not in contact"
    );
    let mut group = c.benchmark_group(group);
    group.bench_function(BenchmarkId::new(name, elements), |bench| {
        bench.iter(|| solver.solve(&rhs, &lower, &mut z, &mut r).unwrap())
    });
    group.finish();
}

fn general(c: &SymTridiag, nodes: &[usize], epsilon: f64) -> CondensedLcp<TridiagSystem> {
    let system = TridiagSystem::new(c).unwrap();
    CondensedLcp::new(system, Constraints::lower_bounds(nodes), epsilon).unwrap()
}

fn bench_solver_twins(crit: &mut Criterion) {
    let epsilon = PenaltySettings::default().epsilon;
    for elements in [100u64, 400, 10_000] {
        let c = step_matrix(elements);
        let n = c.dim();
        let ends = [0, n - 1];
        let id = |name| (name, elements);
        let g = "solver-twins";
        time(
            crit,
            g,
            id("end-enumeration"),
            &mut EndEnumeration::new(&c, &ends).unwrap(),
            n,
            2,
        );
        time(
            crit,
            g,
            id("condensed-lcp-ends"),
            &mut general(&c, &ends, 0.0),
            n,
            2,
        );
        let settings = PenaltySettings { epsilon };
        time(
            crit,
            g,
            id("end-penalty"),
            &mut EndPenalty::new(&c, &ends, settings).unwrap(),
            n,
            2,
        );
        time(
            crit,
            g,
            id("condensed-penalty-ends"),
            &mut general(&c, &ends, epsilon),
            n,
            2,
        );
        if elements <= 400 {
            let nodes: Vec<usize> = (0..n).collect();
            time(
                crit,
                g,
                id("block-pivoting"),
                &mut BlockPivoting::new(&c, &nodes).unwrap(),
                n,
                n,
            );
            time(
                crit,
                g,
                id("condensed-lcp-obstacle"),
                &mut general(&c, &nodes, 0.0),
                n,
                n,
            );
        }
    }
}

criterion_group! {
    name = benches;
    config = Criterion::default().sample_size(20).without_plots();
    targets = bench_solver_twins
}
criterion_main!(benches);
