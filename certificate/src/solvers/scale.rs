//! Contact at scale: the sparse penalty solver (the penalty law beyond the condensed switch,
//! `viscobar::step::SemismoothPenalty`) against the condensed one on the same step problems.

use viscobar::internals::linalg::system::SparseSystem;
use viscobar::internals::step::{CondensedLcp, SemismoothPenalty};
use viscobar::plane::{PlaneDiscretisation, PlaneSimulation};
use viscobar::scene::plane::{PlaneScene, plane_builtin_text};
use viscobar::scheme::RunError;
use viscobar::step::StepSolver;

/// The compliances compared.
pub const EPSILONS: [f64; 2] = [1e-3, 1e-6];
/// Step problems compared per compliance.
pub const PROBLEMS: usize = 12;

fn failed(solver: &'static str) -> impl Fn(viscobar::step::StepFailure) -> RunError {
    move |failure| RunError::Step {
        step: 0,
        time: 0.0,
        solver: solver.into(),
        failure,
    }
}

/// On the tilted drop's step matrix and bottom edge, [`PROBLEMS`] right-hand sides pressing a
/// growing part of the edge into a floor 0.01 away: the largest difference of `z` (over
/// `max |z|`) and of the reactions (over `max r`) between the two solvers at `epsilon`.
pub fn sparse_penalty_agreement(epsilon: f64) -> Result<f64, RunError> {
    let text = plane_builtin_text("plane-tilted-drop").expect("a built-in scene");
    let scene = PlaneScene::from_toml(text, &[])?;
    let disc = PlaneDiscretisation::new(&scene);
    let c = disc.step_matrix();
    let constraints = PlaneSimulation::prepare(&scene)?.contact().constraints();
    let m = constraints.len();
    let system = || SparseSystem::new(&disc.pattern, &c, "C");
    let mut condensed = CondensedLcp::new(system()?, constraints.clone(), epsilon)?;
    let mut sparse = SemismoothPenalty::new(system()?, constraints, epsilon)?;
    let n = disc.unknowns();
    let (mut za, mut zb) = (vec![0.0; n], vec![0.0; n]);
    let (mut ra, mut rb) = (vec![0.0; m], vec![0.0; m]);
    let mut worst = 0.0f64;
    for step in 0..PROBLEMS {
        let b: Vec<f64> = (0..n)
            .map(|i| {
                let d = disc.free[i];
                let x = disc.grid.point(d / 2).0;
                if d % 2 == 1 {
                    -(1.0 + step as f64) * (1.5 - x) * 40.0
                } else {
                    0.3
                }
            })
            .collect();
        let lower = vec![-0.01; m];
        condensed
            .solve(&b, &lower, &mut za, &mut ra)
            .map_err(failed("penalty (condensed)"))?;
        sparse
            .solve(&b, &lower, &mut zb, &mut rb)
            .map_err(failed("penalty (sparse)"))?;
        let scale_u = za.iter().fold(0.0f64, |a, v| a.max(v.abs()));
        let scale_r = ra.iter().fold(0.0f64, |a, v| a.max(*v));
        for (a, b) in za.iter().zip(&zb) {
            worst = worst.max((a - b).abs() / scale_u);
        }
        if scale_r > 0.0 {
            for (a, b) in ra.iter().zip(&rb) {
                worst = worst.max((a - b).abs() / scale_r);
            }
        }
    }
    Ok(worst)
}
