//! Two runs of the same discretisation side by side, e.g. one scene with two step solvers:
//! the largest difference of the displacements over all nodes and steps.

use crate::linalg::norms::{max_abs, max_distance};
use crate::scene::Scene;
use crate::scene::SceneError;
use crate::scene::SolverMethod;
use crate::study::accuracy::lockstep;
use crate::time::RunError;
use crate::time::simulation::{Simulation, StepRecord};
use crate::time::summary::{Summary, Tracker};

/// How far run `b` is from run `a`, over every step `u^1 … u^N` and every node (and the
/// reactions at the Signorini ends).
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Agreement {
    /// Number of states compared (`N`).
    pub steps: usize,
    /// `max_{n,i} |u_b − u_a|`.
    pub max_difference: f64,
    /// The step `n` where it occurs.
    pub worst_step: usize,
    /// `max_{n,i} |u_a|`, the scale of the displacements.
    pub max_displacement: f64,
    /// `max_{n,j} |r_b − r_a|` over the Signorini ends `j` (0 when there is none; the
    /// reactions of obstacle nodes are not recorded).
    pub max_reaction_difference: f64,
    /// `max_{n,j} |r_a|` over the Signorini ends, the scale of the reactions.
    pub max_reaction: f64,
}

impl Agreement {
    /// Takes the reactions of one step of `a` and `b` into account.
    fn observe_reactions(&mut self, a: &StepRecord, b: &StepRecord) {
        for j in 0..a.reaction.len() {
            self.max_reaction_difference = self
                .max_reaction_difference
                .max((b.reaction[j] - a.reaction[j]).abs());
            self.max_reaction = self.max_reaction.max(a.reaction[j].abs());
        }
    }
}

/// The comparison, and run `b`'s step records (start-up step first) and summary.
#[derive(Clone, Debug)]
pub struct Comparison {
    pub agreement: Agreement,
    pub records: Vec<StepRecord>,
    pub summary: Summary,
}

/// Runs `a` and `b` step by step and compares `u^n` after every step. Both scenes must have
/// the same mesh and time grid (they differ only in the solver, typically). `name` labels
/// `b`'s summary.
pub fn compare(name: &str, a: &Scene, b: &Scene) -> Result<Comparison, RunError> {
    if a.mesh.elements != b.mesh.elements
        || a.time.step != b.time.step
        || a.steps() != b.steps()
        || a.bar.length != b.bar.length
    {
        return Err(SceneError::Invalid {
            field: "mesh/time".into(),
            value: "differ".into(),
            allowed: "the two scenes compared must share mesh, length and time grid".into(),
        }
        .into());
    }
    let mut sims = [Simulation::new(a)?, Simulation::new(b)?];
    let mut tracker = Tracker::new(&sims[1], b.load.density.is_none());
    let mut records = vec![sims[1].first_record()];
    let start = std::time::Instant::now();
    let nodes = sims[0].discretisation().nodes;
    let (mut ua, mut ub) = (vec![0.0; nodes], vec![0.0; nodes]);
    let mut out = Agreement::default();
    out.observe_reactions(&sims[0].first_record(), &sims[1].first_record());
    lockstep(&mut sims, a.steps(), |sims, step| {
        if let [ra, rb] = step[..] {
            out.observe_reactions(&ra, &rb);
            tracker.observe(&rb);
            records.push(rb);
        }
        let [sa, sb] = sims else {
            unreachable!("two runs")
        };
        sa.displacement_into(&mut ua);
        sb.displacement_into(&mut ub);
        let diff = max_distance(&ua, &ub);
        if diff > out.max_difference {
            out.max_difference = diff;
            out.worst_step = sa.step_index();
        }
        out.max_displacement = out.max_displacement.max(max_abs(&ua));
        out.steps = sa.step_index();
    })?;
    let summary = tracker.finish(name, &sims[1], start.elapsed().as_secs_f64());
    Ok(Comparison {
        agreement: out,
        records,
        summary,
    })
}

/// `scene` with step solver `method`: the `[solver]` settings that belong to `method` are kept,
/// those of other methods dropped (so one scene with e.g. `epsilon` set serves every solver of a
/// comparison, the penalty one using it).
pub fn with_solver(scene: &Scene, method: SolverMethod) -> Scene {
    let mut s = scene.clone();
    let spec = &mut s.solver;
    spec.method = method;
    if method != SolverMethod::Osqp {
        spec.eps_abs = None;
        spec.eps_rel = None;
        spec.polish = None;
        spec.max_iter = None;
        spec.adaptive_rho_interval = None;
        spec.accept_inaccurate = None;
    }
    if method != SolverMethod::Penalty {
        spec.epsilon = None;
    }
    s
}
