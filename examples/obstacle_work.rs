//! Work of the distributed-obstacle solver per step on the bench scenes (`benches/step.rs`,
//! `distributed`): iterations, whole-bar solves and rows re-solved locally, and the time of
//! the solver against the whole step; first, one converged whole-bar iteration repeated
//! against the plain solve of `C` (minimum of seven rounds; `REPS=k` sets the rounds' length
//! and stops after it).
//!
//!     cargo run --release --example obstacle_work -- 100000 10

use std::cell::RefCell;
use std::rc::Rc;
use std::time::Instant;
use viscobar::bar::Discretisation;
use viscobar::internals::step::block_pivot::BlockPivoting;
use viscobar::step::{SolveInfo, StepFailure, StepSolver};

struct Shared(Rc<RefCell<BlockPivoting>>, Rc<RefCell<f64>>);

impl StepSolver for Shared {
    fn name(&self) -> &'static str {
        "exact"
    }
    fn solve(
        &mut self,
        rhs: &[f64],
        lower: &[f64],
        z: &mut [f64],
        reactions: &mut [f64],
    ) -> Result<SolveInfo, StepFailure> {
        let t = Instant::now();
        let r = self.0.borrow_mut().solve(rhs, lower, z, reactions);
        *self.1.borrow_mut() += t.elapsed().as_secs_f64();
        r
    }
}

fn main() {
    let args: Vec<String> = std::env::args().collect();
    let elements: u64 = args.get(1).map_or(10_000, |a| a.parse().unwrap());
    let ratio: f64 = args.get(2).map_or(1.0, |a| a.parse().unwrap());
    let dt = ratio / elements as f64;
    let text = format!(
        "[bar]\nlength = 1.0\nviscosity = 0.1\n[left]\ncondition = \"free\"\n[right]\n\
         condition = \"free\"\n[initial]\ndisplacement = \"0\"\nvelocity = \"0\"\n[load]\n\
         density = \"-10*cos(pi*x)\"\n[mesh]\nelements = {elements}\n[time]\nstep = {dt}\n\
         end = {}\n[obstacle]\ngap = 0.0\n",
        1000.0 * dt
    );
    let scene = viscobar::Scene::from_toml(&text, &[]).unwrap();
    let disc = Discretisation::new(&scene).unwrap();
    let nodes = disc.constrained_locals();
    repeated(&disc.step_matrix);
    if std::env::var("REPS").is_ok() {
        return;
    }
    let solver = Rc::new(RefCell::new(
        BlockPivoting::new(&disc.step_matrix, &nodes).unwrap(),
    ));
    let solve_time = Rc::new(RefCell::new(0.0));
    let shared = Shared(solver.clone(), solve_time.clone());
    let mut sim = viscobar::Simulation::with_solver(&scene, disc, Box::new(shared)).unwrap();
    for _ in 0..50 {
        sim.step().unwrap();
    }
    let (w0, s0) = (solver.borrow().work(), *solve_time.borrow());
    let steps = 300;
    let mut iterations = 0;
    let start = Instant::now();
    for _ in 0..steps {
        iterations += sim.step().unwrap().iterations;
    }
    let wall = start.elapsed().as_secs_f64();
    let (w, s) = (solver.borrow().work(), *solve_time.borrow() - s0);
    let per = |x: u64| x as f64 / steps as f64;
    println!(
        "J = {elements}, dt/dx = {ratio}: {:.2} iterations, {:.2} full solves, {:.2} local solves, \
         {:.0} local rows per step; step {:.1} µs, solver {:.1} µs",
        iterations as f64 / steps as f64,
        per(w.full_solves - w0.full_solves),
        per(w.local_solves - w0.local_solves),
        per(w.local_rows - w0.local_rows),
        wall / steps as f64 * 1e6,
        s / steps as f64 * 1e6
    );
}

/// One converged solve repeated: the cost of a whole-bar iteration against the plain solve.
#[allow(dead_code)]
pub fn repeated(c: &viscobar::internals::linalg::tridiag::SymTridiag) {
    let n = c.dim();
    let nodes: Vec<usize> = (0..n).collect();
    let b: Vec<f64> = (0..n)
        .map(|i| -(std::f64::consts::PI * i as f64 / n as f64).cos())
        .collect();
    let lo = vec![0.0; n];
    let mut s = BlockPivoting::new(c, &nodes).unwrap();
    let (mut z, mut r) = (vec![0.0; n], vec![0.0; n]);
    s.solve(&b, &lo, &mut z, &mut r).unwrap();
    let reps: usize = std::env::var("REPS").map_or(50, |v| v.parse().unwrap());
    let f = viscobar::internals::linalg::kernels::ldlt::Ldlt::factor(c).unwrap();
    let (mut per, mut plain) = (f64::INFINITY, f64::INFINITY);
    for _ in 0..7 {
        let t = Instant::now();
        for _ in 0..reps {
            s.solve(&b, &lo, &mut z, &mut r).unwrap();
        }
        per = per.min(t.elapsed().as_secs_f64() / reps as f64);
        let t = Instant::now();
        for _ in 0..reps {
            f.solve_into(&b, &mut z);
        }
        plain = plain.min(t.elapsed().as_secs_f64() / reps as f64);
    }
    println!(
        "repeated converged solve: {:.1} µs ({:.2} ns/node), plain Ldlt solve {:.1} µs, ratio {:.2} (min of 7)",
        per * 1e6,
        per * 1e9 / n as f64,
        plain * 1e6,
        per / plain
    );
}
