//! The time stepper: the scheme (VI)_h of the talk ("Numerical scheme" slide),
//!
//! ```text
//!   M (u^{n+1} − 2u^n + u^{n−1})/Δt² + R (u^{n+1} + u^{n−1})/2 + α R (u^{n+1} − u^{n−1})/(2Δt)
//!       = F^n + r^{n+1},        0 <= u^{n+1}_j + a_j ⊥ r^{n+1}_j >= 0 at each Signorini node j,
//! ```
//!
//! solved for the increment `z = u^{n+1} − u^n` rather than for `u^{n+1}` (see
//! [`Simulation::step`]). `F^n = M · (l(x_i, t_n))_i` is the load vector of the nodal
//! interpolant of `l`. `r ≥ 0` is the contact reaction, the negative of the element of
//! `∂ψ_{K_h}` in the talk's inclusion.
//!
//! Every step also evaluates the discrete energy balance (multiply the scheme by
//! `(u^{n+1} − u^{n−1})/2`):
//!
//! ```text
//!   E^{n+1/2} − E^{n−1/2} = ½ F^n·δ − α/(4Δt) |δ|²_R + ½ r^{n+1}·δ,   δ = u^{n+1} − u^{n−1},
//!   E^{n+1/2} = ½ |(u^{n+1} − u^n)/Δt|²_M + ¼ (|u^{n+1}|²_R + |u^n|²_R),
//! ```
//!
//! where the contact term `½ r·δ = −½ r_j (u^{n−1}_j + a_j) <= 0` by complementarity.

use crate::bar::matrices;
use crate::linalg::dispatch;
use crate::linalg::tridiag::{Interior, Ldlt, SymTridiag, Uniform, add_in_place, dot};
use crate::scene::SceneError;
use crate::scene::expr::Expression;
use crate::scene::{Condition, Scene, Side, SolverMethod};
use crate::step::block_pivot::BlockPivotSolver;
use crate::step::exact::ExactSolver;
use crate::step::osqp::OsqpSolver;
use crate::step::penalty::PENALTY_DEFAULT_EPSILON;
use crate::step::penalty::PenaltySolver;
use crate::step::{SolverReport, StepSolver};
use crate::time::RunError;
use std::time::Instant;

/// Calls `$body` with `$load` as a `const bool` and the interior coefficients of `M` and `R`
/// as numbers (uniform mesh) or as rows: the four monomorphised kernels of a step.
macro_rules! monomorphise {
    ($load:expr, $uniform:expr, $mass:expr, $stiffness:expr, |$l:ident, $k:ident| $body:expr) => {
        match ($load, $uniform) {
            (true, Some($k)) => {
                const $l: bool = true;
                $body
            }
            (false, Some($k)) => {
                const $l: bool = false;
                $body
            }
            (true, None) => {
                const $l: bool = true;
                let $k = ($mass.rows(), $stiffness.rows());
                $body
            }
            (false, None) => {
                const $l: bool = false;
                let $k = ($mass.rows(), $stiffness.rows());
                $body
            }
        }
    };
}

/// A constrained node counts as in contact when its gap `u + a` is at most this: the exact
/// solver puts active nodes on the obstacle up to the rounding of `u^n + z` (a few ulps of |u|).
pub const CONTACT_GAP_TOL: f64 = 1e-12;

/// A constrained node: `u[node] >= -gap`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Constraint {
    /// The end whose Signorini condition this is, or `None` for an obstacle node.
    pub side: Option<Side>,
    /// Global node index in `0..=J+1`.
    pub node: usize,
    pub gap: f64,
}

/// The space-time discretisation of a scene: the matrices restricted to the nodes that move
/// (clamped end nodes are removed), and the step matrix `C = M/Δt² + R/2 + αR/(2Δt)`.
#[derive(Clone, Debug)]
pub struct Discretisation {
    /// All nodes, `J + 2`.
    pub nodes: usize,
    pub dx: f64,
    pub dt: f64,
    pub alpha: f64,
    /// Global index of the first unknown (1 when the left end is clamped).
    pub first: usize,
    /// Which matrices (the full-mesh mass matrix of a load is rebuilt from it when needed,
    /// rather than kept: J doubles ×3 that most runs never read).
    pub variant: matrices::MatrixVariant,
    /// Mass and stiffness on the unknowns.
    pub mass: SymTridiag,
    pub stiffness: SymTridiag,
    pub step_matrix: SymTridiag,
    pub constraints: Vec<Constraint>,
}

impl Discretisation {
    pub fn new(scene: &Scene) -> Result<Self, SceneError> {
        let nodes = scene.elements() + 1;
        let dx = scene.dx();
        let dt = scene.time.step;
        let alpha = scene.bar.viscosity;
        let variant = scene.bar.matrices;
        let first = usize::from(scene.left.condition == Condition::Clamped);
        let last = nodes - 1 - usize::from(scene.right.condition == Condition::Clamped);
        // In place: no second copy of the full-mesh matrices at set-up.
        let mass = matrices::mass(variant, nodes, dx).into_sub(first, last);
        let stiffness = matrices::stiffness(variant, nodes, dx).into_sub(first, last);
        let step_matrix =
            SymTridiag::combine(1.0 / (dt * dt), &mass, 0.5 + alpha / (2.0 * dt), &stiffness);
        let node_of = |side: Side| if side == Side::Left { 0 } else { nodes - 1 };
        let ends = scene.signorini_ends();
        let end_gap = |node: usize| {
            ends.iter()
                .find(|(side, _)| node_of(*side) == node)
                .copied()
        };
        let constraints = match &scene.obstacle {
            None => ends
                .iter()
                .map(|&(side, gap)| Constraint {
                    side: Some(side),
                    node: node_of(side),
                    gap,
                })
                .collect(),
            Some(obstacle) => {
                let g = obstacle.gap.expression("obstacle.gap")?;
                (first..=last)
                    .map(|node| {
                        let obstacle_gap = g.eval(node as f64 * dx, 0.0)?;
                        Ok(match end_gap(node) {
                            Some((side, a)) => Constraint {
                                side: Some(side),
                                node,
                                gap: a.min(obstacle_gap),
                            },
                            None => Constraint {
                                side: None,
                                node,
                                gap: obstacle_gap,
                            },
                        })
                    })
                    .collect::<Result<Vec<_>, SceneError>>()?
            }
        };
        Ok(Self {
            nodes,
            dx,
            dt,
            alpha,
            first,
            variant,
            mass,
            stiffness,
            step_matrix,
            constraints,
        })
    }

    /// Indices into `constraints` of the Signorini ends (left first), at most two.
    pub fn end_constraints(&self) -> Vec<usize> {
        (0..self.constraints.len())
            .filter(|&j| self.constraints[j].side.is_some())
            .collect()
    }

    /// Whether only end nodes are constrained (at most two bounds).
    pub fn ends_only(&self) -> bool {
        self.constraints.iter().all(|c| c.side.is_some())
    }

    /// Number of unknowns.
    pub fn unknowns(&self) -> usize {
        self.mass.dim()
    }

    /// Local (unknown) index of global node `i`.
    pub fn local(&self, node: usize) -> usize {
        node - self.first
    }

    /// `x_i = i Δx`.
    pub fn x(&self, node: usize) -> f64 {
        node as f64 * self.dx
    }

    /// Local indices of the constrained nodes, in order.
    pub fn constrained_locals(&self) -> Vec<usize> {
        self.constraints
            .iter()
            .map(|c| self.local(c.node))
            .collect()
    }
}

/// Builds the step solver a scene asks for.
pub fn make_solver(scene: &Scene, disc: &Discretisation) -> Result<Box<dyn StepSolver>, RunError> {
    let nodes = disc.constrained_locals();
    match scene.solver.method {
        SolverMethod::Exact if disc.ends_only() => {
            Ok(Box::new(ExactSolver::new(&disc.step_matrix, &nodes)?))
        }
        SolverMethod::Exact => Ok(Box::new(BlockPivotSolver::new(&disc.step_matrix, &nodes)?)),
        SolverMethod::Osqp => Ok(Box::new(OsqpSolver::new(
            &disc.step_matrix,
            &nodes,
            scene.solver.osqp_settings(),
        )?)),
        SolverMethod::Penalty => Ok(Box::new(PenaltySolver::new(
            &disc.step_matrix,
            &nodes,
            scene.solver.epsilon.unwrap_or(PENALTY_DEFAULT_EPSILON),
        )?)),
    }
}

/// The clock is read in one step out of this many (timer reads cost ~25 ns each, four a
/// step: sampling keeps that below 1 % of a 100-node step).
pub const TIMING_SAMPLE_EVERY: usize = 32;

/// Wall time per phase of [`Simulation::step`], summed over the sampled steps (one in
/// [`TIMING_SAMPLE_EVERY`], starting with the first): `rhs` (load vector and right-hand
/// side), `solve` (bounds, on a measured step after an unmeasured one the recomputation of
/// `E^{n−1/2}`, the step solver and `u += z`, which the exact end solver merges with its own
/// last pass), `diagnostics` (the energy balance pass, contact state, record). Shares of a
/// run are ratios of these sums.
#[derive(Clone, Copy, Debug, Default, PartialEq, serde::Serialize)]
pub struct PhaseTimes {
    pub sampled_steps: u64,
    pub rhs_ns: u64,
    pub solve_ns: u64,
    pub diagnostics_ns: u64,
}

impl PhaseTimes {
    /// Whether step `n → n + 1` is timed (and counts it).
    fn samples(&mut self, n: usize) -> bool {
        let sampled = n % TIMING_SAMPLE_EVERY == 1;
        self.sampled_steps += u64::from(sampled);
        sampled
    }

    /// The sum of the three phases.
    pub fn total_ns(&self) -> u64 {
        self.rhs_ns + self.solve_ns + self.diagnostics_ns
    }
}

/// The time of the last lap, when this step is sampled.
struct PhaseClock(Option<Instant>);

impl PhaseClock {
    fn start(sampled: bool) -> Self {
        Self(sampled.then(Instant::now))
    }

    /// Adds the time since the last lap to `into`.
    fn lap(self, into: &mut u64) -> Self {
        let Some(then) = self.0 else { return self };
        let now = Instant::now();
        *into += u64::try_from((now - then).as_nanos()).unwrap_or(u64::MAX);
        Self(Some(now))
    }
}

/// The diagnostics of one step, `u^n → u^{n+1}`.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct StepRecord {
    /// `n + 1`.
    pub step: usize,
    /// `t_{n+1}`.
    pub time: f64,
    /// Whether the energy balance was measured at this step (`[output] diagnostics_every`);
    /// when not, `energy` … `identity_residual` are 0 and mean nothing.
    pub measured: bool,
    /// `E^{n+1/2}`.
    pub energy: f64,
    /// `½ F^n·(u^{n+1} − u^{n−1})`.
    pub work: f64,
    /// `α/(4Δt) |u^{n+1} − u^{n−1}|²_R >= 0`.
    pub viscous_dissipation: f64,
    /// `−½ r^{n+1}·(u^{n+1} − u^{n−1}) >= 0`.
    pub contact_dissipation: f64,
    /// `|E^{n+1/2} − E^{n−1/2} − work + viscous + contact|` divided by the largest of those terms.
    pub identity_residual: f64,
    /// `u^{n+1}_j + a_j` at each Signorini end (left first; unused entries 0).
    pub gap: [f64; 2],
    /// `r^{n+1}_j` at each Signorini end.
    pub reaction: [f64; 2],
    /// Over all constrained nodes (ends and obstacle): the least gap, the least reaction and
    /// the largest `|gap · reaction|`.
    pub min_gap: f64,
    pub min_reaction: f64,
    pub max_complementarity: f64,
    /// Constrained nodes in contact (gap at most [`CONTACT_GAP_TOL`]) and the
    /// extent `[x_min, x_max]` of that contact set (`NaN` when empty).
    pub contact_nodes: usize,
    pub contact_extent: [f64; 2],
    pub iterations: u32,
}

/// How the load vector `F^n` is produced, doing no more work than the expression needs.
#[derive(Clone, Debug)]
enum LoadTerm {
    None,
    /// `l` independent of `t`: `F` computed once.
    Constant,
    /// `l = f(t)`: `F^n = f(t_n) M·1`.
    TimeOnly {
        expr: Expression,
        m_one: Vec<f64>,
    },
    /// General `l(x, t)`: nodal values every step, times the full-mesh mass matrix.
    General {
        expr: Expression,
        mass_full: SymTridiag,
        nodal: Vec<f64>,
        full: Vec<f64>,
    },
}

/// A running simulation. Holds `u^n`, `u^n − u^{n−1}` and the matrix products the next step
/// reuses; [`Simulation::step`] advances one step and allocates nothing.
pub struct Simulation {
    disc: Discretisation,
    solver: Box<dyn StepSolver>,
    load: LoadTerm,
    /// `n`: the state held is `u^n`.
    n: usize,
    u: Vec<f64>,
    /// `max_i |u^n_i|`, handed to the step solver (see [`StepSolver::set_state_scale`]).
    u_scale: f64,
    /// `w = u^n − u^{n−1}`.
    w: Vec<f64>,
    z: Vec<f64>,
    rhs: Vec<f64>,
    force: Vec<f64>,
    lower: Vec<f64>,
    reactions: Vec<f64>,
    locals: Vec<usize>,
    /// `1/Δt²` and `½ − α/(2Δt)`.
    inv_dt2: f64,
    c_w: f64,
    /// `|u^n|²_R` and `E^{n−1/2}`, valid when `measured` (the last step was measured).
    potential: f64,
    energy: f64,
    measured: bool,
    /// Measure the energy balance at steps `k·diagnostics_every` and at `last_step`.
    diagnostics_every: usize,
    last_step: usize,
    timing: PhaseTimes,
    /// Interior coefficients of `M` and `R` as numbers, when the mesh is uniform.
    uniform: Option<(Uniform, Uniform)>,
    /// `u_0` and `u_1`, evaluated again on request rather than kept (2 × J doubles).
    initial: InitialData,
    first_record: StepRecord,
}

impl Simulation {
    /// Sets up a run of `scene` with the solver it names.
    pub fn new(scene: &Scene) -> Result<Self, RunError> {
        let disc = Discretisation::new(scene)?;
        let solver = make_solver(scene, &disc)?;
        Self::with_solver(scene, disc, solver)
    }

    /// Sets up a run with a given step solver (built for `disc.step_matrix` and
    /// `disc.constrained_locals()`), and takes the start-up step to `u^1`.
    ///
    /// Start-up: the Taylor step `u^1_T = u^0 + Δt u_1 + Δt²/2 M⁻¹(F^0 − R u^0 − α R u_1)`,
    /// second order for smooth data, followed by the step's own projection onto `K_h` in the
    /// `C`-norm (the step QP with `b = C (u^1_T − u^0)`), so `u^1` is admissible.
    pub fn with_solver(
        scene: &Scene,
        disc: Discretisation,
        solver: Box<dyn StepSolver>,
    ) -> Result<Self, RunError> {
        let nodes = disc.nodes;
        let n = disc.unknowns();
        let dt = disc.dt;
        let alpha = disc.alpha;
        let initial = InitialData {
            displacement: Expression::parse(
                "initial.displacement",
                &scene.initial.displacement,
                false,
            )?,
            velocity: Expression::parse("initial.velocity", &scene.initial.velocity, false)?,
            clamped: [&scene.left, &scene.right].map(|end| end.condition == Condition::Clamped),
        };
        let mut u0_full = vec![0.0; nodes];
        let mut v0_full = vec![0.0; nodes];
        initial.eval_into(&disc, &mut u0_full, &mut v0_full)?;
        for c in &disc.constraints {
            if u0_full[c.node] < -c.gap {
                return Err(SceneError::Inadmissible {
                    field: "initial.displacement".into(),
                    gap_field: c
                        .side
                        .map_or("obstacle.gap".to_string(), |s| format!("{}.gap", s.name())),
                    node: c.node,
                    x: disc.x(c.node),
                    value: u0_full[c.node],
                    gap: c.gap,
                }
                .into());
            }
        }
        let range = disc.first..disc.first + n;
        // `force` holds F^n; a time-independent load fills it once, here.
        let mut force = vec![0.0; n];
        let load = match &scene.load.density {
            None => LoadTerm::None,
            Some(text) => {
                let expr = Expression::parse("load.density", text, true)?;
                if !expr.depends_on_t() {
                    let nodal = (0..nodes)
                        .map(|i| expr.eval(disc.x(i), 0.0))
                        .collect::<Result<Vec<_>, _>>()?;
                    load_rows_into(&disc, |i| nodal[i], &mut force);
                    LoadTerm::Constant
                } else if !expr.depends_on_x() {
                    let mut m_one = vec![0.0; n];
                    load_rows_into(&disc, |_| 1.0, &mut m_one);
                    LoadTerm::TimeOnly { expr, m_one }
                } else {
                    LoadTerm::General {
                        expr,
                        mass_full: matrices::mass(disc.variant, nodes, disc.dx),
                        nodal: vec![0.0; nodes],
                        full: vec![0.0; nodes],
                    }
                }
            }
        };
        let locals = disc.constrained_locals();
        let k = locals.len();
        // u^0 and u_1 on the unknowns, in the storage of the full-mesh vectors.
        let restrict = |mut v: Vec<f64>| {
            v.truncate(range.end);
            v.drain(..range.start);
            v
        };
        let (u, v0) = (restrict(u0_full), restrict(v0_full));
        let mut sim = Self {
            solver,
            load,
            n: 0,
            u,
            u_scale: 0.0,
            w: vec![0.0; n],
            z: vec![0.0; n],
            rhs: vec![0.0; n],
            force,
            lower: vec![0.0; k],
            reactions: vec![0.0; k],
            locals,
            inv_dt2: 1.0 / (dt * dt),
            c_w: 0.5 - alpha / (2.0 * dt),
            potential: 0.0,
            energy: 0.0,
            measured: true,
            diagnostics_every: scene.output.diagnostics_every as usize,
            last_step: scene.steps(),
            timing: PhaseTimes::default(),
            uniform: disc.mass.uniform().zip(disc.stiffness.uniform()),
            initial,
            first_record: StepRecord::default(),
            disc,
        };
        sim.start_up(&v0)?;
        Ok(sim)
    }

    /// The start-up step; `z`, `w` and `rhs` serve as its work space (no J-sized temporaries).
    fn start_up(&mut self, v0: &[f64]) -> Result<(), RunError> {
        let dt = self.disc.dt;
        self.update_force(0)?;
        // a = M⁻¹ (F^0 − R u^0 − α R u_1), in z.
        let (acc, rv) = (&mut self.z, &mut self.rhs);
        self.disc.stiffness.mul_into(&self.u, acc);
        self.disc.stiffness.mul_into(v0, rv);
        for i in 0..acc.len() {
            acc[i] = self.force[i] - acc[i] - self.disc.alpha * rv[i];
        }
        Ldlt::factor(&self.disc.mass)?.solve_in_place(acc);
        // The Taylor increment, in w (w becomes the increment z after the step).
        for i in 0..acc.len() {
            self.w[i] = dt * v0[i] + 0.5 * dt * dt * acc[i];
        }
        self.disc.step_matrix.mul_into(&self.w, &mut self.rhs);
        for (j, c) in self.disc.constraints.iter().enumerate() {
            self.lower[j] = -c.gap - self.u[self.locals[j]];
        }
        self.solver
            .set_state_scale(self.u.iter().fold(0.0f64, |m, v| m.max(v.abs())));
        let info = self
            .solver
            .solve(&self.rhs, &self.lower, &mut self.z, &mut self.reactions)
            .map_err(|failure| RunError::Step {
                step: 1,
                time: dt,
                solver: self.solver.name().to_string(),
                failure,
            })?;
        let potential0 = self.disc.stiffness.quad(&self.u);
        self.u_scale = add_in_place(&mut self.u, &self.z);
        let mz = &mut self.rhs;
        self.disc.mass.mul_into(&self.z, mz);
        self.potential = self.disc.stiffness.quad(&self.u);
        self.energy = 0.5 * dot(&self.z, mz) * self.inv_dt2 + 0.25 * (self.potential + potential0);
        if !self.energy.is_finite() {
            return Err(self.failure(1, crate::step::StepFailure::NonFinite));
        }
        std::mem::swap(&mut self.w, &mut self.z);
        self.n = 1;
        let mut record = StepRecord {
            step: 1,
            time: dt,
            measured: true,
            energy: self.energy,
            iterations: info.iterations,
            ..Default::default()
        };
        self.fill_contact(&mut record);
        self.first_record = record;
        Ok(())
    }

    fn failure(&self, step: usize, failure: crate::step::StepFailure) -> RunError {
        RunError::Step {
            step,
            time: step as f64 * self.disc.dt,
            solver: self.solver.name().to_string(),
            failure,
        }
    }

    /// `F^n` into `self.force`.
    fn update_force(&mut self, n: usize) -> Result<(), SceneError> {
        let t = n as f64 * self.disc.dt;
        let first = self.disc.first;
        match &mut self.load {
            LoadTerm::None | LoadTerm::Constant => {}
            LoadTerm::TimeOnly { expr, m_one } => {
                let f = expr.eval(0.0, t)?;
                for (fi, mi) in self.force.iter_mut().zip(m_one.iter()) {
                    *fi = f * mi;
                }
            }
            LoadTerm::General {
                expr,
                mass_full,
                nodal,
                full,
            } => {
                for (i, v) in nodal.iter_mut().enumerate() {
                    *v = expr.eval(i as f64 * self.disc.dx, t)?;
                }
                mass_full.mul_into(nodal, full);
                let n = self.force.len();
                self.force.copy_from_slice(&full[first..first + n]);
            }
        }
        Ok(())
    }

    /// Advances `u^n → u^{n+1}` and returns the step's diagnostics.
    ///
    /// Increment form: with `w = u^n − u^{n−1}` the scheme reads
    /// `C z = F^n + M w/Δt² + (½ − α/(2Δt)) R w − R u^n + r`, which is algebraically the talk's
    /// `C u^{n+1} = F̃^n + r` but never forms the O(|u|/Δt²) terms that cancel there, so the
    /// round-off in `z` is relative to the increment, not to the displacement.
    ///
    /// The energy balance (an extra read-only pass) is measured every `[output]
    /// diagnostics_every`-th step and at the last step; other steps report the contact state
    /// only (`measured = false`). A measured step whose predecessor was not measured recomputes
    /// `E^{n−1/2}` from `u^n` and `w` first, so every measured identity is a one-step identity.
    pub fn step(&mut self) -> Result<StepRecord, RunError> {
        let n = self.n;
        let clock = PhaseClock::start(self.timing.samples(n));
        self.update_force(n)?;
        let has_load = !matches!(self.load, LoadTerm::None);
        let (inv_dt2, c_w) = (self.inv_dt2, self.c_w);
        let (mass, stiffness) = (&self.disc.mass, &self.disc.stiffness);
        let (u, w, force) = (&self.u[..], &self.w[..], &self.force[..]);
        let rhs = &mut self.rhs;
        monomorphise!(has_load, self.uniform, mass, stiffness, |LOAD, k| {
            rhs_into::<LOAD, _>(mass, stiffness, k, c_w, inv_dt2, u, w, force, rhs)
        });
        let clock = clock.lap(&mut self.timing.rhs_ns);
        for (j, c) in self.disc.constraints.iter().enumerate() {
            self.lower[j] = -c.gap - self.u[self.locals[j]];
        }
        let measure = (n + 1).is_multiple_of(self.diagnostics_every) || n + 1 == self.last_step;
        if measure && !self.measured {
            // E^{n−1/2} from u^n and w (u^{n−1} = u^n − w), before u moves on.
            let (mass, stiffness) = (&self.disc.mass, &self.disc.stiffness);
            self.potential = stiffness.quad(&self.u);
            self.energy = 0.5 * mass.quad(&self.w) * inv_dt2
                + 0.25 * (self.potential + potential_of_difference(stiffness, &self.u, &self.w));
        }
        self.solver.set_state_scale(self.u_scale);
        let (info, u_scale) = self
            .solver
            .solve_and_advance(
                &self.rhs,
                &self.lower,
                &mut self.u,
                &mut self.z,
                &mut self.reactions,
            )
            .map_err(|failure| self.failure(n + 1, failure))?;
        self.u_scale = u_scale;
        let clock = clock.lap(&mut self.timing.solve_ns);
        let dt = self.disc.dt;
        let mut record = StepRecord {
            step: n + 1,
            time: (n + 1) as f64 * dt,
            measured: measure,
            iterations: info.iterations,
            ..Default::default()
        };
        if measure {
            self.measure_into(&mut record, has_load)?;
        }
        self.measured = measure;
        self.fill_contact(&mut record);
        std::mem::swap(&mut self.w, &mut self.z);
        self.n = n + 1;
        clock.lap(&mut self.timing.diagnostics_ns);
        Ok(record)
    }

    /// The energy balance of the step just taken (`u = u^{n+1}`, `z` its increment, `w` the
    /// previous one) into `record`; `self.energy`, `self.potential` move on to `n + 1`.
    fn measure_into(&mut self, record: &mut StepRecord, has_load: bool) -> Result<(), RunError> {
        let (mass, stiffness) = (&self.disc.mass, &self.disc.stiffness);
        let (u, z, w, f) = (&self.u[..], &self.z[..], &self.w[..], &self.force[..]);
        let sums = monomorphise!(has_load, self.uniform, mass, stiffness, |LOAD, k| {
            measure::<LOAD, _>(mass, stiffness, k, u, z, w, f)
        });
        let dt = self.disc.dt;
        let energy = 0.5 * sums.kinetic * self.inv_dt2 + 0.25 * (sums.potential + self.potential);
        // The viscous sum is computed regardless; it only counts when α > 0.
        let viscous = if self.disc.alpha > 0.0 {
            self.disc.alpha / (4.0 * dt) * sums.viscous
        } else {
            0.0
        };
        let work = 0.5 * sums.work;
        let mut contact = 0.0;
        for (j, &l) in self.locals.iter().enumerate() {
            contact -= 0.5 * self.reactions[j] * (self.z[l] + self.w[l]);
        }
        let residual = energy - self.energy - work + viscous + contact;
        let scale = [energy, self.energy, work.abs(), viscous, contact.abs()]
            .into_iter()
            .fold(0.0, f64::max);
        if !(energy.is_finite() && residual.is_finite()) {
            return Err(self.failure(record.step, crate::step::StepFailure::NonFinite));
        }
        record.energy = energy;
        record.work = work;
        record.viscous_dissipation = viscous;
        record.contact_dissipation = contact;
        record.identity_residual = if scale > 0.0 {
            residual.abs() / scale
        } else {
            0.0
        };
        self.potential = sums.potential;
        self.energy = energy;
        Ok(())
    }

    /// Wall time spent in each phase of the steps taken so far, measured on a sample of the
    /// steps (see [`PhaseTimes`]).
    pub fn phase_times(&self) -> PhaseTimes {
        self.timing
    }

    fn fill_contact(&self, record: &mut StepRecord) {
        let (mut min_gap, mut min_reaction, mut max_comp) = (f64::INFINITY, f64::INFINITY, 0.0f64);
        let (mut count, mut lo, mut hi) = (0, f64::NAN, f64::NAN);
        let mut end = 0;
        for (j, c) in self.disc.constraints.iter().enumerate() {
            let gap = self.u[self.locals[j]] + c.gap;
            let reaction = self.reactions[j];
            if c.side.is_some() {
                record.gap[end] = gap;
                record.reaction[end] = reaction;
                end += 1;
            }
            min_gap = min_gap.min(gap);
            min_reaction = min_reaction.min(reaction);
            max_comp = max_comp.max((gap * reaction).abs());
            if gap <= CONTACT_GAP_TOL {
                let x = self.disc.x(c.node);
                if count == 0 {
                    lo = x;
                }
                hi = x;
                count += 1;
            }
        }
        if self.disc.constraints.is_empty() {
            (min_gap, min_reaction) = (0.0, 0.0);
        }
        record.min_gap = min_gap;
        record.min_reaction = min_reaction;
        record.max_complementarity = max_comp;
        record.contact_nodes = count;
        record.contact_extent = [lo, hi];
    }

    /// `u^n_j + a_j` at every constrained node, in the order of `constraints`.
    pub fn constraint_gaps_into(&self, out: &mut [f64]) {
        for (j, c) in self.disc.constraints.iter().enumerate() {
            out[j] = self.u[self.locals[j]] + c.gap;
        }
    }

    /// The reactions of the last step at every constrained node.
    pub fn reactions(&self) -> &[f64] {
        &self.reactions
    }

    /// The record of the start-up step (`E^{1/2}`, contact state of `u^1`).
    pub fn first_record(&self) -> StepRecord {
        self.first_record
    }

    pub fn discretisation(&self) -> &Discretisation {
        &self.disc
    }

    pub fn solver_name(&self) -> &'static str {
        self.solver.name()
    }

    /// The step solver's own statistics (audit residuals...), if it keeps any.
    pub fn solver_report(&self) -> Option<SolverReport> {
        self.solver.report()
    }

    /// Index `n` of the current state `u^n`.
    pub fn step_index(&self) -> usize {
        self.n
    }

    pub fn time(&self) -> f64 {
        self.n as f64 * self.disc.dt
    }

    /// `u^n` on all `J + 2` nodes (clamped nodes are 0).
    pub fn displacement_into(&self, out: &mut [f64]) {
        out.fill(0.0);
        out[self.disc.first..self.disc.first + self.u.len()].copy_from_slice(&self.u);
    }

    /// `(u^n − u^{n−1})/Δt` on all nodes: the velocity at `t_{n−1/2}`.
    pub fn velocity_into(&self, out: &mut [f64]) {
        out.fill(0.0);
        let inv = 1.0 / self.disc.dt;
        for (o, w) in out[self.disc.first..].iter_mut().zip(&self.w) {
            *o = w * inv;
        }
    }

    pub fn displacement(&self) -> Vec<f64> {
        let mut out = vec![0.0; self.disc.nodes];
        self.displacement_into(&mut out);
        out
    }

    /// Initial displacement and velocity at all nodes (evaluated again: not kept in memory).
    pub fn initial_state(&self) -> (Vec<f64>, Vec<f64>) {
        let mut u = vec![0.0; self.disc.nodes];
        let mut v = vec![0.0; self.disc.nodes];
        self.initial_state_into(&mut u, &mut v);
        (u, v)
    }

    /// [`Simulation::initial_state`] into `u` and `v` (all nodes).
    pub fn initial_state_into(&self, u: &mut [f64], v: &mut [f64]) {
        self.initial
            .eval_into(&self.disc, u, v)
            .expect("the same evaluation succeeded at set-up");
    }
}

/// The initial data of a scene.
struct InitialData {
    displacement: Expression,
    velocity: Expression,
    /// Left and right end clamped.
    clamped: [bool; 2],
}

impl InitialData {
    /// `u_0`, `u_1` at all nodes; at a clamped node they must vanish (up to
    /// [`CLAMPED_START_TOL`]) and are set to 0.
    fn eval_into(
        &self,
        disc: &Discretisation,
        u: &mut [f64],
        v: &mut [f64],
    ) -> Result<(), SceneError> {
        let nodes = disc.nodes;
        for i in 0..nodes {
            u[i] = self.displacement.eval(disc.x(i), 0.0)?;
            v[i] = self.velocity.eval(disc.x(i), 0.0)?;
        }
        for (side, clamped, node) in [
            (Side::Left, self.clamped[0], 0),
            (Side::Right, self.clamped[1], nodes - 1),
        ] {
            if !clamped {
                continue;
            }
            for (field, value) in [
                ("initial.displacement", u[node]),
                ("initial.velocity", v[node]),
            ] {
                if value.abs() > CLAMPED_START_TOL {
                    return Err(SceneError::Invalid {
                        field: field.into(),
                        value: value.to_string(),
                        allowed: format!(
                            "must vanish at the clamped {} end (x = {})",
                            side.name(),
                            disc.x(node)
                        ),
                    });
                }
            }
            u[node] = 0.0;
            v[node] = 0.0;
        }
        Ok(())
    }
}

/// `(M_full x)_i` at the unknowns `i`, row by row (the same arithmetic as
/// [`SymTridiag::mul_into`]), without keeping the full-mesh mass matrix beyond this call.
fn load_rows_into(disc: &Discretisation, x: impl Fn(usize) -> f64, out: &mut [f64]) {
    let mass_full = matrices::mass(disc.variant, disc.nodes, disc.dx);
    for (k, o) in out.iter_mut().enumerate() {
        *o = row_of(&mass_full, &x, disc.first + k, disc.nodes);
    }
}

/// Initial data at a clamped node must vanish up to this (expressions such as `(1-x)/2` at
/// `x = 1` evaluate to exactly 0, but `sin(pi*x)` at `x = 1` gives 1.2e-16).
pub const CLAMPED_START_TOL: f64 = 1e-12;

/// Row `i` of `A x` in difference form, `s_i x_i + A_i,i−1 (x_{i−1} − x_i) + A_i,i+1 (x_{i+1} −
/// x_i)`, in the order of [`SymTridiag::mul_into`]; for the end rows (any `i`, with branches).
fn row_of(a: &SymTridiag, x: impl Fn(usize) -> f64, i: usize, n: usize) -> f64 {
    let mut r = a.row_sums()[i] * x(i);
    if i > 0 {
        r += a.off[i - 1] * (x(i - 1) - x(i));
    }
    if i + 1 < n {
        r += a.off[i] * (x(i + 1) - x(i));
    }
    r
}

/// `b = F + M w/Δt² + R ((½ − α/(2Δt)) w − u)` in one pass, both products in difference form.
/// The interior rows are [`RhsInterior`], run through [`dispatch::run`]; `LOAD = false` skips
/// the force.
#[allow(clippy::too_many_arguments)]
#[inline(never)]
fn rhs_into<const LOAD: bool, K: Interior>(
    mass: &SymTridiag,
    stiffness: &SymTridiag,
    (mi, ri): (K, K),
    c_w: f64,
    inv_dt2: f64,
    u: &[f64],
    w: &[f64],
    force: &[f64],
    rhs: &mut [f64],
) {
    let n = rhs.len();
    let (u, w) = (&u[..n], &w[..n]);
    let force = if LOAD { &force[..n] } else { &[][..] };
    let y = |i: usize| c_w * w[i] - u[i];
    let wi = |i: usize| w[i];
    for i in [0, n.saturating_sub(1)].into_iter().take(n.min(2)) {
        let b = row_of(stiffness, y, i, n) + row_of(mass, wi, i, n) * inv_dt2;
        rhs[i] = if LOAD { b + force[i] } else { b };
    }
    if n < 3 {
        return;
    }
    // R's interior rows sum to exactly 0 on a uniform mesh: its node term is then left out.
    macro_rules! kernel {
        ($s_r:literal) => {
            RhsInterior::<LOAD, $s_r, K> {
                coefficients: (mi, ri),
                c_w,
                inv_dt2,
                u,
                w,
                force,
                rhs,
            }
        };
    }
    if K::UNIFORM && ri.s(1) == 0.0 {
        dispatch::run(kernel!(false))
    } else {
        dispatch::run(kernel!(true))
    }
}

/// The interior rows of [`rhs_into`] with its arguments, for [`dispatch::run`].
///
/// Rows `1..n−1` (`n >= 3`). Row `i` of `A x` in difference form
/// is `s_i x_i + A_i,i−1 (x_i−1 − x_i) + A_i,i+1 (x_i+1 − x_i) = (s_i x_i − g_i−1) + g_i` with the
/// edge flux `g_i = A_i,i+1 (x_i+1 − x_i)`: the same bits as [`row_of`] (negation is exact),
/// but each flux is computed once, for the two rows it enters, and carried to the next row.
/// `S_R = false` drops `s_i y_i` from the stiffness rows (for `s_i = 0`; only the sign of a
/// zero result can differ). No branch in the loop, so it vectorises, carried values included.
struct RhsInterior<'a, const LOAD: bool, const S_R: bool, K> {
    coefficients: (K, K),
    c_w: f64,
    inv_dt2: f64,
    u: &'a [f64],
    w: &'a [f64],
    force: &'a [f64],
    rhs: &'a mut [f64],
}

impl<const LOAD: bool, const S_R: bool, K: Interior> dispatch::Kernel
    for RhsInterior<'_, LOAD, S_R, K>
{
    type Output = ();
    #[inline(always)]
    fn call(self) {
        let Self {
            coefficients: (mi, ri),
            c_w,
            inv_dt2,
            u,
            w,
            force,
            rhs,
        } = self;
        let n = rhs.len();
        let y = |i: usize| c_w * w[i] - u[i];
        let (mut y_i, mut w_i) = (y(1), w[1]);
        let mut g_y = ri.e(0) * (y_i - y(0));
        let mut g_w = mi.e(0) * (w_i - w[0]);
        for i in 1..n - 1 {
            let (y_next, w_next) = (y(i + 1), w[i + 1]);
            let (g_y_next, g_w_next) = (ri.e(i) * (y_next - y_i), mi.e(i) * (w_next - w_i));
            let ry = if S_R {
                (ri.s(i) * y_i - g_y) + g_y_next
            } else {
                g_y_next - g_y
            };
            let mw = (mi.s(i) * w_i - g_w) + g_w_next;
            let b = ry + mw * inv_dt2;
            rhs[i] = if LOAD { b + force[i] } else { b };
            (y_i, w_i, g_y, g_w) = (y_next, w_next, g_y_next, g_w_next);
        }
    }
}

/// The sums of the energy balance of one step.
#[derive(Clone, Copy, Debug, Default)]
struct StepSums {
    /// `zᵀ M z`.
    kinetic: f64,
    /// `|u^{n+1}|²_R`.
    potential: f64,
    /// `|z + w|²_R`.
    viscous: f64,
    /// `F·(z + w)`.
    work: f64,
}

/// The energy sums of a step, after `u += z` (so `u = u^{n+1}`), in one read-only pass; with
/// `w` the previous increment and `z` this one: `zᵀMz`, `|u|²_R`, `|z + w|²_R`, `F·(z + w)`.
/// Quadratic forms in difference form, `xᵀAx = Σ s_i x_i² − Σ A_i,i+1 (x_{i+1} − x_i)²`, so
/// rigid motion adds no round-off (see [`SymTridiag::quad`]); interior terms weighted as
/// [`Interior`] says.
#[inline(never)]
#[allow(clippy::too_many_arguments)]
fn measure<const LOAD: bool, K: Interior>(
    mass: &SymTridiag,
    stiffness: &SymTridiag,
    (mi, ri): (K, K),
    u: &[f64],
    z: &[f64],
    w: &[f64],
    force: &[f64],
) -> StepSums {
    let n = u.len();
    if n == 0 {
        return StepSums::default();
    }
    let (z, w) = (&z[..n], &w[..n]);
    let force = if LOAD { &force[..n] } else { &[][..] };
    let d = |i: usize| z[i] + w[i];
    // Quantities: node and edge parts of zᵀMz, |u|²_R, |d|²_R, then F·d, over the interior
    // nodes i with their elements (i, i+1), weighted. One accumulator each: seven independent
    // addition chains keep the adders busy (more lanes measured slower here), and the order
    // is fixed, so the sums are deterministic.
    let mut acc = [0.0f64; 7];
    if K::UNIFORM {
        // R's interior rows sum to exactly 0: its node sums are then not needed.
        acc = if ri.scale_s() == 0.0 {
            uniform_measure::<LOAD, false>(u, z, w, force)
        } else {
            uniform_measure::<LOAD, true>(u, z, w, force)
        };
    } else {
        for i in 1..n.saturating_sub(1) {
            let (zi, ui, di) = (z[i], u[i], d(i));
            let (dz, du, dd) = (z[i + 1] - zi, u[i + 1] - ui, d(i + 1) - di);
            acc[0] += mi.ws(i) * zi * zi;
            acc[1] += mi.we(i) * dz * dz;
            acc[2] += ri.ws(i) * ui * ui;
            acc[3] += ri.we(i) * du * du;
            acc[4] += ri.ws(i) * di * di;
            acc[5] += ri.we(i) * dd * dd;
            if LOAD {
                acc[6] += force[i] * di;
            }
        }
    }
    let sum = |q: usize| acc[q];
    let form = |k: K, node: usize, edge: usize| k.scale_s() * sum(node) - k.scale_e() * sum(edge);
    let mut sums = StepSums {
        kinetic: form(mi, 0, 1),
        potential: form(ri, 2, 3),
        viscous: form(ri, 4, 5),
        work: sum(6),
    };
    // End nodes with their own row sums; the element (0, 1).
    let (sm, sr) = (mass.row_sums(), stiffness.row_sums());
    for i in [0, n - 1].into_iter().take(n.min(2)) {
        let (zi, ui, di) = (z[i], u[i], d(i));
        sums.kinetic += sm[i] * zi * zi;
        sums.potential += sr[i] * ui * ui;
        sums.viscous += sr[i] * di * di;
        if LOAD {
            sums.work += force[i] * di;
        }
    }
    if n > 1 {
        let (em, er) = (mass.off[0], stiffness.off[0]);
        let (dz, du, dd) = (z[1] - z[0], u[1] - u[0], d(1) - d(0));
        sums.kinetic -= em * dz * dz;
        sums.potential -= er * du * du;
        sums.viscous -= er * dd * dd;
    }
    sums
}

/// Lanes of the energy sums: row `i` adds into lane `(i − 1) mod LANES`.
const LANES: usize = 4;

/// Running sums of [`uniform_measure`], lane by lane.
type Lanes = [[f64; LANES]; 7];

/// The interior sums of [`measure`] on a uniform mesh (weights 1): `Σ z_i²`, `Σ (Δz_i)²`,
/// `Σ u_i²`, `Σ (Δu_i)²`, `Σ d_i²`, `Σ (Δd_i)²`, `Σ F_i d_i` over `i = 1..n−1` with `d = z + w`,
/// `Δx_i = x_{i+1} − x_i`. [`LANES`] lanes per sum, added at the end in a fixed order, which
/// shortens the additions' dependency chains; `S_R = false` skips `Σ u_i²` and `Σ d_i²` (left
/// 0). The whole blocks of [`LANES`] rows run as AVX vector instructions when the CPU has
/// them ([`measure_blocks_avx`]: the compiler does not vectorise this loop by itself, the
/// overlapping loads of rows `i` and `i + 1` defeat it), with the same bits as the portable
/// [`measure_rows`] (see [`dispatch`]).
fn uniform_measure<const LOAD: bool, const S_R: bool>(
    u: &[f64],
    z: &[f64],
    w: &[f64],
    force: &[f64],
) -> [f64; 7] {
    let (rows, zero) = (1..u.len().saturating_sub(1), [[0.0; LANES]; 7]);
    #[cfg(target_arch = "x86_64")]
    let acc = if dispatch::has_avx() {
        let blocks = rows.len() / LANES;
        // SAFETY: the CPU supports AVX.
        let acc = unsafe { measure_blocks_avx::<LOAD, S_R>(u, z, w, force, blocks) };
        measure_rows::<LOAD, S_R>((u, z, w, force), 1 + LANES * blocks..rows.end, acc)
    } else {
        measure_rows::<LOAD, S_R>((u, z, w, force), rows, zero)
    };
    #[cfg(not(target_arch = "x86_64"))]
    let acc = measure_rows::<LOAD, S_R>((u, z, w, force), rows, zero);
    acc.map(|[a, b, c, d]| (a + b) + (c + d))
}

/// Rows `rows` of [`uniform_measure`], portable, row `i` into lane `(i − 1) mod LANES` of
/// `acc`: all the rows, or the rows after [`measure_blocks_avx`]'s blocks.
fn measure_rows<const LOAD: bool, const S_R: bool>(
    (u, z, w, force): (&[f64], &[f64], &[f64], &[f64]),
    rows: std::ops::Range<usize>,
    mut acc: Lanes,
) -> Lanes {
    for i in rows {
        let lane = (i - 1) % LANES;
        let (zi, ui, di) = (z[i], u[i], z[i] + w[i]);
        let (dz, du, dd) = (z[i + 1] - zi, u[i + 1] - ui, (z[i + 1] + w[i + 1]) - di);
        acc[0][lane] += zi * zi;
        acc[1][lane] += dz * dz;
        if S_R {
            acc[2][lane] += ui * ui;
            acc[4][lane] += di * di;
        }
        acc[3][lane] += du * du;
        acc[5][lane] += dd * dd;
        if LOAD {
            acc[6][lane] += force[i] * di;
        }
    }
    acc
}

/// Rows `1..1 + LANES · blocks` of [`measure_rows`] in AVX instructions, from zero sums:
/// each lane's sums see the same operations in the same order, so the bits are the same.
#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx")]
fn measure_blocks_avx<const LOAD: bool, const S_R: bool>(
    u: &[f64],
    z: &[f64],
    w: &[f64],
    force: &[f64],
    blocks: usize,
) -> Lanes {
    use std::arch::x86_64::{
        __m256d, _mm256_add_pd, _mm256_loadu_pd, _mm256_mul_pd, _mm256_setzero_pd,
        _mm256_storeu_pd, _mm256_sub_pd,
    };
    let end = 1 + LANES * blocks;
    let (u, z, w) = (&u[..end + 1], &z[..end + 1], &w[..end + 1]);
    let force = if LOAD { &force[..end] } else { &[][..] };
    // Four entries from `i`, bounds-checked (the loop's indices stay below `end + 1`). Macros,
    // not closures: a closure is not compiled for AVX, and a vector it returns would go
    // through memory.
    macro_rules! load {
        ($x:expr, $i:expr) => {{
            let four: &[f64; LANES] = $x[$i..$i + LANES].try_into().expect("four entries");
            // SAFETY: `four` is four readable doubles; unaligned loads are allowed.
            unsafe { _mm256_loadu_pd(four.as_ptr()) }
        }};
    }
    macro_rules! square_into {
        ($acc:expr, $x:expr) => {{
            let x: __m256d = $x;
            $acc = _mm256_add_pd($acc, _mm256_mul_pd(x, x));
        }};
    }
    let mut acc = [_mm256_setzero_pd(); 7];
    for i in (1..end).step_by(LANES) {
        let (zh, uh, wh) = (load!(z, i), load!(u, i), load!(w, i));
        let (za, ua, wa) = (load!(z, i + 1), load!(u, i + 1), load!(w, i + 1));
        let (dh, da) = (_mm256_add_pd(zh, wh), _mm256_add_pd(za, wa));
        square_into!(acc[0], zh);
        square_into!(acc[1], _mm256_sub_pd(za, zh));
        if S_R {
            square_into!(acc[2], uh);
            square_into!(acc[4], dh);
        }
        square_into!(acc[3], _mm256_sub_pd(ua, uh));
        square_into!(acc[5], _mm256_sub_pd(da, dh));
        if LOAD {
            acc[6] = _mm256_add_pd(acc[6], _mm256_mul_pd(load!(force, i), dh));
        }
    }
    let mut sums = [[0.0; LANES]; 7];
    for (lanes, v) in sums.iter_mut().zip(acc) {
        // SAFETY: `lanes` has room for four doubles.
        unsafe { _mm256_storeu_pd(lanes.as_mut_ptr(), v) };
    }
    sums
}

/// `|u − w|²_R` in difference form (`u^{n−1} = u^n − w` for a step whose predecessor was not
/// measured; not on the per-step path).
fn potential_of_difference(stiffness: &SymTridiag, u: &[f64], w: &[f64]) -> f64 {
    let v = |i: usize| u[i] - w[i];
    let n = u.len();
    let mut q = 0.0;
    for i in 0..n {
        q += stiffness.row_sums()[i] * v(i) * v(i);
    }
    for i in 0..n.saturating_sub(1) {
        let d = v(i + 1) - v(i);
        q -= stiffness.off[i] * d * d;
    }
    q
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Relative difference allowed between the two summation orders of `n` terms: each sum
    /// carries at most about `n ε` of its absolute-value sum.
    fn sum_tol(n: usize) -> f64 {
        4.0 * n as f64 * f64::EPSILON
    }

    /// The uniform-mesh energy sums (four lanes, R's zero node sums skipped) agree with the
    /// row-by-row kernel, for every tail length of the four-lane loop.
    #[test]
    fn uniform_and_row_energy_sums_agree() {
        for n in [2usize, 3, 4, 5, 6, 7, 50, 51, 52, 53] {
            let dx = 1.0 / (n - 1) as f64;
            let m = matrices::mass(matrices::MatrixVariant::Consistent, n, dx);
            let r = matrices::stiffness(matrices::MatrixVariant::Consistent, n, dx);
            let k = m.uniform().zip(r.uniform()).expect("a uniform mesh");
            let v = |a: f64| {
                (0..n)
                    .map(|i| (a * i as f64 + 0.3).sin())
                    .collect::<Vec<_>>()
            };
            let (u, z, w, f) = (v(0.7), v(1.3), v(2.1), v(0.4));
            let uniform = measure::<true, Uniform>(&m, &r, k, &u, &z, &w, &f);
            let rows = measure::<true, _>(&m, &r, (m.rows(), r.rows()), &u, &z, &w, &f);
            let pairs = [
                (uniform.kinetic, rows.kinetic),
                (uniform.potential, rows.potential),
                (uniform.viscous, rows.viscous),
                (uniform.work, rows.work),
            ];
            for (p, q) in pairs {
                // Scale: the sums of |terms| are at most of the size of the quadratic forms of
                // |x| under |A|, bounded here by ‖A‖∞ max|x|² n.
                let scale = (m.inf_norm() + r.inf_norm()) * 4.0 * n as f64;
                assert!((p - q).abs() <= sum_tol(n) * scale, "n = {n}: {p} vs {q}");
            }
            assert!(uniform.kinetic != 0.0 && uniform.potential != 0.0);
        }
    }

    /// The AVX and the baseline builds of the streaming kernels give the same bits (see
    /// [`dispatch`]), on data with large common parts and tiny differences (the rigid-like
    /// motion where round-off would show), for every tail length of the vector loops
    /// (mutation-checked: an AVX energy sum fed the wrong difference fails it).
    #[cfg(target_arch = "x86_64")]
    #[test]
    fn kernels_give_the_same_bits_with_and_without_avx() {
        if !dispatch::has_avx() {
            eprintln!("this CPU has no AVX: only the baseline build runs, nothing to compare");
            return;
        }
        for n in [3usize, 4, 5, 6, 7, 8, 9, 10, 101, 1002] {
            let dx = 1.0 / (n - 1) as f64;
            let m = matrices::mass(matrices::MatrixVariant::Consistent, n, dx);
            let r = matrices::stiffness(matrices::MatrixVariant::Consistent, n, dx);
            let k = m.uniform().zip(r.uniform()).expect("a uniform mesh");
            let v = |a: f64, offset: f64, amp: f64| {
                (0..n)
                    .map(|i| offset + amp * (a * i as f64 + 0.3).sin())
                    .collect::<Vec<_>>()
            };
            let (u, z, w, f) = (
                v(0.7, 1e3, 1e-6),
                v(1.3, 0.0, 1.0),
                v(2.1, 1e-2, 1e-9),
                v(0.4, -1.0, 0.1),
            );
            let (c_w, inv_dt2): (f64, f64) = (-4999.5, 1.0 / (dx * dx));
            let bits = |x: &[f64]| x.iter().map(|v| v.to_bits()).collect::<Vec<_>>();
            for s_r in [false, true] {
                let (mut a, mut b) = (vec![0.0; n], vec![0.0; n]);
                let (ki, ui, wi, fi) = (k, &u[..], &w[..], &f[..]);
                macro_rules! both {
                    ($s:literal) => {
                        let kernel = |rhs| RhsInterior::<true, $s, Uniform> {
                            coefficients: ki,
                            c_w,
                            inv_dt2,
                            u: ui,
                            w: wi,
                            force: fi,
                            rhs,
                        };
                        dispatch::baseline(kernel(&mut a));
                        dispatch::run(kernel(&mut b));
                    };
                }
                if s_r {
                    both!(true);
                } else {
                    both!(false);
                }
                assert_eq!(bits(&a), bits(&b), "rhs, n = {n}, s_R {s_r}");
                let blocks = (n - 2) / LANES;
                let (p, q) = if s_r {
                    let portable = measure_rows::<true, true>(
                        (&u, &z, &w, &f),
                        1..1 + LANES * blocks,
                        [[0.0; LANES]; 7],
                    );
                    // SAFETY: the CPU has AVX (checked above).
                    let avx = unsafe { measure_blocks_avx::<true, true>(&u, &z, &w, &f, blocks) };
                    (portable, avx)
                } else {
                    let portable = measure_rows::<true, false>(
                        (&u, &z, &w, &f),
                        1..1 + LANES * blocks,
                        [[0.0; LANES]; 7],
                    );
                    // SAFETY: the CPU has AVX (checked above).
                    let avx = unsafe { measure_blocks_avx::<true, false>(&u, &z, &w, &f, blocks) };
                    (portable, avx)
                };
                let (p, q) = (p.concat(), q.concat());
                assert_eq!(bits(&p), bits(&q), "energy sums, n = {n}, s_R {s_r}");
            }
        }
    }
}
