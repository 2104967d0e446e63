//! `displacement.csv` holds the run's own numbers: every `u` and `v` reads back to the bits the
//! simulation held (shortest round-trip formatting), at every kept step.

mod common;
use viscobar::Simulation;
use viscobar::time::run::run_to_dir;

#[test]
fn displacement_csv_reads_back_to_the_simulation_bits() {
    // Values of every size: a kink, contact, and a displacement crossing zero.
    let scene = common::builtin("impact", &["output.every=7"]);
    let dir = std::env::temp_dir().join(format!("viscobar-output-files-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    run_to_dir("impact", &scene, &dir, false).unwrap();
    let text = std::fs::read_to_string(dir.join("displacement.csv")).unwrap();
    std::fs::remove_dir_all(&dir).unwrap();

    let mut sim = Simulation::new(&scene).unwrap();
    let nodes = sim.discretisation().nodes;
    let (mut u, mut v) = (vec![0.0; nodes], vec![0.0; nodes]);
    let mut rows = text.lines().skip(1);
    let mut check = |u: &[f64], v: &[f64]| {
        for i in 0..nodes {
            let row = rows.next().expect("a row a node");
            let f: Vec<f64> = row.split(',').map(|c| c.parse().unwrap()).collect();
            assert_eq!(f[2].to_bits(), u[i].to_bits(), "u in {row}");
            assert_eq!(f[3].to_bits(), v[i].to_bits(), "v in {row}");
        }
    };
    sim.initial_state_into(&mut u, &mut v);
    check(&u, &v);
    let steps = scene.steps();
    let keep = |n: usize| n.is_multiple_of(7) || n == steps;
    let mut kept = 1;
    for n in 1..=steps {
        if n > 1 {
            sim.step().unwrap();
        }
        if keep(n) {
            sim.displacement_into(&mut u);
            sim.velocity_into(&mut v);
            check(&u, &v);
            kept += 1;
        }
    }
    assert!(kept > 2);
    assert!(rows.next().is_none(), "no rows beyond the kept steps");
}
