//! Two runs of the same discretisation side by side, e.g. one scene (bar or plane) with two
//! step solvers: the largest difference of the displacements over all degrees of freedom and
//! steps, and of the reactions of each group of constraints.

use crate::linalg::norms::{max_abs, max_distance};
use crate::output::summary::{Summary, Tracker};
use crate::scene::SceneError;
use crate::scene::SolverMethod;
use crate::scheme::RunError;
use crate::scheme::StepRecord;
use crate::study::accuracy::lockstep;
use crate::study::refine::StudyScene;

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
    /// `max_{n,g} |r_b − r_a|` over the groups `g` of constraints (an end or edge, the whole
    /// obstacle), each group's total reaction (0 without constraints).
    pub max_reaction_difference: f64,
    /// `max_{n,g} |r_a|` over the groups, the scale of the reactions.
    pub max_reaction: f64,
}

impl Agreement {
    /// Takes the reactions of one step of `a` and `b` into account.
    fn observe_reactions(&mut self, a: &StepRecord, b: &StepRecord) {
        for (ga, gb) in a.contact.groups.iter().zip(&b.contact.groups) {
            self.max_reaction_difference = self
                .max_reaction_difference
                .max((gb.reaction - ga.reaction).abs());
            self.max_reaction = self.max_reaction.max(ga.reaction.abs());
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
pub fn compare<S: StudyScene>(name: &str, a: &S, b: &S) -> Result<Comparison, RunError> {
    if a.elements() != b.elements()
        || a.dt() != b.dt()
        || a.steps() != b.steps()
        || a.spacing() != b.spacing()
    {
        return Err(SceneError::Invalid {
            field: "mesh/time".into(),
            value: "differ".into(),
            allowed: "the two scenes compared must share mesh, length and time grid".into(),
        }
        .into());
    }
    let mut sims = [a.simulation()?, b.simulation()?];
    let mut tracker = Tracker::new(&sims[1], !sims[1].is_forced());
    let mut records = vec![sims[1].first_record()];
    let start = std::time::Instant::now();
    let dofs = sims[0].dofs();
    let (mut ua, mut ub) = (vec![0.0; dofs], vec![0.0; dofs]);
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
pub fn with_solver<S: StudyScene>(scene: &S, method: SolverMethod) -> S {
    let mut s = scene.clone();
    let spec = s.solver_mut();
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
