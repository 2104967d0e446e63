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

pub use crate::bar::discretisation::Discretisation;
use crate::bar::discretisation::InitialData;
use crate::bar::matrices;
use crate::linalg::ldlt::Ldlt;
use crate::linalg::norms::max_abs;
use crate::linalg::tridiag::{SymTridiag, Uniform, dot};
use crate::linalg::update::add_in_place;
use crate::scene::expr::Expression;
use crate::scene::nodal::NodalEvaluator;
use crate::scene::{Condition, Scene, SceneError, SolverMethod};
use crate::step::block_pivot::BlockPivotSolver;
use crate::step::exact::ExactSolver;
use crate::step::osqp::OsqpSolver;
use crate::step::penalty::PenaltySolver;
use crate::step::{SolverReport, StepSolver};
use crate::time::RunError;
use crate::time::clock::{PhaseClock, PhaseTimes};
use crate::time::energy::{measure, potential_of_difference};
use crate::time::rhs::{load_rows_into, rhs_into};

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
            scene.solver.penalty_settings(),
        )?)),
    }
}

/// `acc ← M⁻¹ acc` on the unknowns that carry mass (a contiguous block: the massless ones are
/// end nodes), `acc ← 0` on the massless ones ([`Discretisation::massless`]).
fn solve_on_massive_nodes(
    disc: &Discretisation,
    acc: &mut [f64],
) -> Result<(), crate::linalg::ldlt::NotPositiveDefinite> {
    let n = acc.len();
    let lo = usize::from(disc.massless.contains(&0));
    let hi = n - usize::from(n > 0 && disc.massless.contains(&(n - 1)));
    for &j in &disc.massless {
        acc[j] = 0.0;
    }
    if lo >= hi {
        return Ok(());
    }
    if lo == 0 && hi == n {
        Ldlt::factor(&disc.mass)?.solve_in_place(acc);
    } else {
        Ldlt::factor(&disc.mass.sub(lo, hi - 1))?.solve_in_place(&mut acc[lo..hi]);
    }
    Ok(())
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
    /// `−½ r^{n+1}_j (u^{n+1}_j − u^{n−1}_j)` at each Signorini end: its share of
    /// `contact_dissipation` (0 when not measured).
    pub end_contact_dissipation: [f64; 2],
    /// `Σ_j r^{n+1}_j` over all constrained nodes: the total contact force.
    pub total_reaction: f64,
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
    /// `l = Σ_k f_k(t) g_k(x)` ([`Expression::separate`]): `F^n = Σ_k f_k(t_n) (M g_k)`, the
    /// products `M g_k` computed once. A step where a factor is not finite evaluates `expr`
    /// itself node by node, so that its error names the node.
    Separable {
        expr: Expression,
        terms: Vec<(Expression, Vec<f64>)>,
    },
    /// General `l(x, t)`: nodal values every step, times the full-mesh mass matrix.
    General(GeneralLoad),
}

/// `F^n = M (l(x_i, t_n))_i` with the nodal values evaluated over the node array.
#[derive(Clone, Debug)]
struct GeneralLoad {
    eval: NodalEvaluator,
    mass_full: SymTridiag,
    nodal: Vec<f64>,
    /// `M l` on all nodes, when a clamped end makes the unknowns fewer than the nodes (empty
    /// otherwise: the product goes straight into `force`).
    full: Vec<f64>,
}

impl GeneralLoad {
    fn force_into(&mut self, t: f64, first: usize, force: &mut [f64]) -> Result<(), SceneError> {
        self.eval.eval_into(t, &mut self.nodal)?;
        if force.len() == self.nodal.len() {
            self.mass_full.mul_into(&self.nodal, force);
        } else {
            self.mass_full.mul_into(&self.nodal, &mut self.full);
            force.copy_from_slice(&self.full[first..first + force.len()]);
        }
        Ok(())
    }
}

/// `m.min(x)` for a running minimum `m` that is never NaN: a NaN `x` is ignored and a tie
/// keeps `m`, as `f64::min` does here, in one `minsd` instead of a NaN blend on the chain.
#[inline(always)]
fn min_of(m: f64, x: f64) -> f64 {
    if x < m { x } else { m }
}

/// [`min_of`] for a running maximum.
#[inline(always)]
fn max_of(m: f64, x: f64) -> f64 {
    if x > m { x } else { m }
}

/// Per-step sums over the constraints ([`Simulation::fill_contact`]).
struct ContactSums {
    min_gap: f64,
    min_reaction: f64,
    max_comp: f64,
    total: f64,
    dissipation: f64,
    /// Nodes in contact, and the first and last of them (constraint indices).
    count: usize,
    first: usize,
    last: usize,
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
    /// Per constraint: its gap `a_j` (read contiguously, not through `disc.constraints`), its
    /// local node, and the constraint indices of the Signorini ends (at most two). `locals`
    /// is empty when constraint `j` is local node `j` (an obstacle: every node, in order), so
    /// that the per-step passes over the constraints read plain slices.
    gaps: Vec<f64>,
    locals: Vec<usize>,
    ends: Vec<usize>,
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

    /// Sets `scene` up as [`Simulation::new`] does, short of the start-up step: for a run
    /// that writes `u^0` and `u_1` first and starts afterwards (without a copy of `u^0`).
    pub fn prepare(scene: &Scene) -> Result<Unstarted, RunError> {
        let disc = Discretisation::new(scene)?;
        let solver = make_solver(scene, &disc)?;
        Self::prepare_with_solver(scene, disc, solver)
    }

    /// Sets up a run with a given step solver (built for `disc.step_matrix` and
    /// `disc.constrained_locals()`), and takes the start-up step to `u^1`.
    ///
    /// Start-up: the Taylor step `u^1_T = u^0 + Δt u_1 + Δt²/2 M⁻¹(F^0 − R u^0 − α R u_1)`,
    /// second order for smooth data, followed by the step's own projection onto `K_h` in the
    /// `C`-norm (the step QP with `b = C (u^1_T − u^0)`), so `u^1` is admissible. With a
    /// redistributed mass `M` is singular: the acceleration is solved on the nodes that carry
    /// mass only and the massless nodes' Taylor term is 0 (their `u^1_T = u^0 + Δt u_1`); the
    /// projection then sets them like any step does.
    pub fn with_solver(
        scene: &Scene,
        disc: Discretisation,
        solver: Box<dyn StepSolver>,
    ) -> Result<Self, RunError> {
        Self::prepare_with_solver(scene, disc, solver)?.start()
    }

    /// [`Simulation::with_solver`] short of the start-up step.
    fn prepare_with_solver(
        scene: &Scene,
        disc: Discretisation,
        solver: Box<dyn StepSolver>,
    ) -> Result<Unstarted, RunError> {
        scene.validate()?;
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
        // `force` holds F^n; a time-independent load fills it once, here. Without a load it
        // stays empty (the kernels do not read it; `load_vector` gives zeros).
        let mut force = if scene.load.density.is_some() {
            vec![0.0; n]
        } else {
            Vec::new()
        };
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
                    match expr.separate() {
                        None => LoadTerm::General(GeneralLoad {
                            eval: NodalEvaluator::new(
                                expr,
                                (0..nodes).map(|i| disc.x(i)).collect(),
                            ),
                            mass_full: matrices::mass(disc.variant, nodes, disc.dx),
                            nodal: vec![0.0; nodes],
                            full: if n == nodes {
                                Vec::new()
                            } else {
                                vec![0.0; nodes]
                            },
                        }),
                        Some(parts) => {
                            let mut terms = Vec::with_capacity(parts.len());
                            for p in parts {
                                let g = (0..nodes)
                                    .map(|i| p.space.eval(disc.x(i), 0.0))
                                    .collect::<Result<Vec<_>, _>>()?;
                                let mut mg = vec![0.0; n];
                                load_rows_into(&disc, |i| g[i], &mut mg);
                                terms.push((p.time, mg));
                            }
                            LoadTerm::Separable { expr, terms }
                        }
                    }
                }
            }
        };
        let mut locals = disc.constrained_locals();
        let k = locals.len();
        let gaps: Vec<f64> = disc.constraints.iter().map(|c| c.gap).collect();
        let ends = disc.end_constraints();
        if locals.iter().enumerate().all(|(j, &l)| j == l) {
            locals = Vec::new();
        }
        // u^0 and u_1 on the unknowns, in the storage of the full-mesh vectors.
        let restrict = |mut v: Vec<f64>| {
            v.truncate(range.end);
            v.drain(..range.start);
            v
        };
        let (u, v0) = (restrict(u0_full), restrict(v0_full));
        let sim = Self {
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
            gaps,
            locals,
            ends,
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
        Ok(Unstarted { sim, v0 })
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
            // `0.0 − …` without a load: the bits of a zero force vector.
            let f = self.force.get(i).copied().unwrap_or(0.0);
            acc[i] = f - acc[i] - self.disc.alpha * rv[i];
        }
        solve_on_massive_nodes(&self.disc, acc)?;
        // The Taylor increment, in w (w becomes the increment z after the step).
        for i in 0..acc.len() {
            self.w[i] = dt * v0[i] + 0.5 * dt * dt * acc[i];
        }
        self.disc.step_matrix.mul_into(&self.w, &mut self.rhs);
        self.fill_lower();
        self.solver.set_state_scale(max_abs(&self.u));
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
        self.fill_contact(&mut record, false);
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

    /// The load vector `F^n` on the unknowns, as the step from `t_n` uses it (for checks of
    /// the load path; the next step recomputes its own).
    pub fn load_vector(&mut self, n: usize) -> Result<&[f64], SceneError> {
        self.update_force(n)?;
        if matches!(self.load, LoadTerm::None) {
            self.force.resize(self.u.len(), 0.0);
        }
        Ok(&self.force)
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
            LoadTerm::Separable { expr, terms } => {
                let mut finite = true;
                for (k, (f, mg)) in terms.iter().enumerate() {
                    let Ok(fk) = f.eval(0.0, t) else {
                        finite = false;
                        break;
                    };
                    if k == 0 {
                        self.force.iter_mut().zip(mg).for_each(|(o, g)| *o = fk * g);
                    } else {
                        self.force
                            .iter_mut()
                            .zip(mg)
                            .for_each(|(o, g)| *o += fk * g);
                    }
                }
                if !finite {
                    // Off the hot path: name the node where `l` itself is not finite, or (a
                    // factor overflowing while the product does not) take `M l` directly.
                    let x = |i: usize| i as f64 * self.disc.dx;
                    for i in 0..self.disc.nodes {
                        expr.eval(x(i), t)?;
                    }
                    load_rows_into(
                        &self.disc,
                        |i| expr.eval(x(i), t).unwrap_or(f64::NAN),
                        &mut self.force,
                    );
                }
            }
            LoadTerm::General(general) => general.force_into(t, first, &mut self.force)?,
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
        self.fill_lower();
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
        // The contact state, and with `measure` the contact dissipation, in one pass.
        let contact = self.fill_contact(&mut record, measure);
        if measure {
            self.measure_into(&mut record, has_load, contact)?;
        }
        self.measured = measure;
        std::mem::swap(&mut self.w, &mut self.z);
        self.n = n + 1;
        clock.lap(&mut self.timing.diagnostics_ns);
        Ok(record)
    }

    /// The energy balance of the step just taken (`u = u^{n+1}`, `z` its increment, `w` the
    /// previous one) into `record`; `self.energy`, `self.potential` move on to `n + 1`.
    /// `contact` is the contact dissipation `−½ Σ_j r_j (z_j + w_j)`, summed in constraint order
    /// by [`Simulation::fill_contact`] (which also records the ends' shares).
    fn measure_into(
        &mut self,
        record: &mut StepRecord,
        has_load: bool,
        contact: f64,
    ) -> Result<(), RunError> {
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

    /// `lower_j = −a_j − u^n_j` for every constraint.
    fn fill_lower(&mut self) {
        let (lower, gaps, u) = (&mut self.lower[..], &self.gaps[..], &self.u[..]);
        if self.locals.is_empty() {
            for ((lo, &a), &u) in lower.iter_mut().zip(gaps).zip(&u[..gaps.len()]) {
                *lo = -a - u;
            }
        } else {
            for ((lo, &a), &l) in lower.iter_mut().zip(gaps).zip(&self.locals) {
                *lo = -a - u[l];
            }
        }
    }

    /// The contact state of `u = u^{n+1}` into `record`; with `dissipation` also the contact
    /// dissipation `−½ Σ_j r_j (z_j + w_j)` (returned; 0 without) and the ends' shares. One
    /// pass over the constraints, in their order (the sums' bits depend on it).
    fn fill_contact(&self, record: &mut StepRecord, dissipation: bool) -> f64 {
        let s = if self.locals.is_empty() {
            if dissipation {
                self.contact_pass::<true>(|j| j)
            } else {
                self.contact_pass::<false>(|j| j)
            }
        } else {
            let locals = &self.locals[..];
            if dissipation {
                self.contact_pass::<true>(|j| locals[j])
            } else {
                self.contact_pass::<false>(|j| locals[j])
            }
        };
        for (e, &j) in self.ends.iter().enumerate() {
            let l = self.locals.get(j).copied().unwrap_or(j);
            record.gap[e] = self.u[l] + self.gaps[j];
            record.reaction[e] = self.reactions[j];
            if dissipation {
                // `+= −½ r δ` has the bits of `−= ½ r δ` (negation is exact).
                record.end_contact_dissipation[e] =
                    -0.5 * self.reactions[j] * (self.z[l] + self.w[l]);
            }
        }
        let (min_gap, min_reaction) = if self.gaps.is_empty() {
            (0.0, 0.0)
        } else {
            (s.min_gap, s.min_reaction)
        };
        let x = |j: usize| self.disc.x(self.disc.constraints[j].node);
        record.min_gap = min_gap;
        record.min_reaction = min_reaction;
        record.max_complementarity = s.max_comp;
        record.contact_nodes = s.count;
        record.contact_extent = if s.count > 0 {
            [x(s.first), x(s.last)]
        } else {
            [f64::NAN, f64::NAN]
        };
        record.total_reaction = s.total;
        s.dissipation
    }

    /// The sums of [`Simulation::fill_contact`], constraint `j` at local node `local(j)`.
    #[inline(always)]
    fn contact_pass<const DISSIPATION: bool>(&self, local: impl Fn(usize) -> usize) -> ContactSums {
        let k = self.gaps.len();
        let (gaps, reactions) = (&self.gaps[..k], &self.reactions[..k]);
        let (u, z, w) = (&self.u[..], &self.z[..], &self.w[..]);
        let mut s = ContactSums {
            min_gap: f64::INFINITY,
            min_reaction: f64::INFINITY,
            max_comp: 0.0,
            total: 0.0,
            dissipation: 0.0,
            count: 0,
            first: 0,
            last: 0,
        };
        for j in 0..k {
            let l = local(j);
            let gap = u[l] + gaps[j];
            let reaction = reactions[j];
            s.total += reaction;
            s.min_gap = min_of(s.min_gap, gap);
            s.min_reaction = min_of(s.min_reaction, reaction);
            s.max_comp = max_of(s.max_comp, (gap * reaction).abs());
            if gap <= CONTACT_GAP_TOL {
                if s.count == 0 {
                    s.first = j;
                }
                s.last = j;
                s.count += 1;
            }
            if DISSIPATION {
                s.dissipation += -0.5 * reaction * (z[l] + w[l]);
            }
        }
        s
    }

    /// `u^n_j + a_j` at every constrained node, in the order of `constraints`.
    pub fn constraint_gaps_into(&self, out: &mut [f64]) {
        for (j, (o, &a)) in out.iter_mut().zip(&self.gaps).enumerate() {
            *o = self.u[self.locals.get(j).copied().unwrap_or(j)] + a;
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

    /// `u^n` and `(u^n − u^{n−1})/Δt` node by node, with the bits of
    /// [`Simulation::displacement_into`] and [`Simulation::velocity_into`], read in place.
    pub fn node_values(&self) -> NodeValues<'_> {
        NodeValues {
            first: self.disc.first,
            u: &self.u,
            w: &self.w,
            scale: 1.0 / self.disc.dt,
        }
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

/// A simulation set up, `u^0` and `u_1` evaluated, the start-up step not taken yet
/// ([`Simulation::prepare`]).
pub struct Unstarted {
    /// Holds `u^0` in `u`.
    sim: Simulation,
    /// `u_1` on the unknowns.
    v0: Vec<f64>,
}

impl Unstarted {
    /// `u_0` and `u_1` node by node (0 at a clamped node, as
    /// [`Simulation::initial_state_into`] gives them).
    pub fn node_values(&self) -> NodeValues<'_> {
        NodeValues {
            first: self.sim.disc.first,
            u: &self.sim.u,
            w: &self.v0,
            scale: 1.0,
        }
    }

    pub fn discretisation(&self) -> &Discretisation {
        &self.sim.disc
    }

    /// Takes the start-up step to `u^1` (see [`Simulation::with_solver`]).
    pub fn start(self) -> Result<Simulation, RunError> {
        let Self { mut sim, v0 } = self;
        sim.start_up(&v0)?;
        Ok(sim)
    }
}

/// A displacement and a velocity at each node, read from a state on the unknowns (a clamped
/// node reads 0, 0).
#[derive(Clone, Copy, Debug)]
pub struct NodeValues<'a> {
    first: usize,
    u: &'a [f64],
    /// The velocity is `w · scale`.
    w: &'a [f64],
    scale: f64,
}

impl NodeValues<'_> {
    /// Displacement and velocity at global node `node`.
    #[inline]
    pub fn at(&self, node: usize) -> (f64, f64) {
        match node.checked_sub(self.first) {
            Some(i) if i < self.u.len() => (self.u[i], self.w[i] * self.scale),
            _ => (0.0, 0.0),
        }
    }
}

#[cfg(test)]
mod contact_pass_tests {
    use super::*;

    /// The passes over the constraints as they were before issue 17 made them read contiguous
    /// slices (through `disc.constraints` and the local of each, with `f64::min`/`max`): the
    /// reference the contiguous passes must reproduce bit for bit.
    fn reference(sim: &Simulation, dissipation: bool) -> (StepRecord, f64) {
        let mut record = StepRecord::default();
        let locals = sim.disc.constrained_locals();
        // After `step`, `w` holds the increment just taken and `z` the one before it.
        let (z, w) = (&sim.w, &sim.z);
        let mut contact = 0.0;
        let mut end = 0;
        if dissipation {
            for (j, &l) in locals.iter().enumerate() {
                let share = -0.5 * sim.reactions[j] * (z[l] + w[l]);
                contact += share;
                if sim.disc.constraints[j].side.is_some() {
                    record.end_contact_dissipation[end] = share;
                    end += 1;
                }
            }
        }
        let (mut min_gap, mut min_reaction, mut max_comp) = (f64::INFINITY, f64::INFINITY, 0.0f64);
        let (mut count, mut lo, mut hi) = (0, f64::NAN, f64::NAN);
        let mut total = 0.0;
        end = 0;
        for (j, c) in sim.disc.constraints.iter().enumerate() {
            let gap = sim.u[locals[j]] + c.gap;
            let reaction = sim.reactions[j];
            if c.side.is_some() {
                record.gap[end] = gap;
                record.reaction[end] = reaction;
                end += 1;
            }
            total += reaction;
            min_gap = min_gap.min(gap);
            min_reaction = min_reaction.min(reaction);
            max_comp = max_comp.max((gap * reaction).abs());
            if gap <= CONTACT_GAP_TOL {
                let x = sim.disc.x(c.node);
                if count == 0 {
                    lo = x;
                }
                hi = x;
                count += 1;
            }
        }
        if sim.disc.constraints.is_empty() {
            (min_gap, min_reaction) = (0.0, 0.0);
        }
        record.min_gap = min_gap;
        record.min_reaction = min_reaction;
        record.max_complementarity = max_comp;
        record.contact_nodes = count;
        record.contact_extent = [lo, hi];
        record.total_reaction = total;
        (record, contact)
    }

    fn same_contact_bits(a: &StepRecord, b: &StepRecord) -> bool {
        let bits = |r: &StepRecord| {
            let mut v = vec![
                r.total_reaction,
                r.min_gap,
                r.min_reaction,
                r.max_complementarity,
                r.contact_extent[0],
                r.contact_extent[1],
            ];
            v.extend(
                r.gap
                    .iter()
                    .chain(&r.reaction)
                    .chain(&r.end_contact_dissipation),
            );
            v.into_iter().map(f64::to_bits).collect::<Vec<_>>()
        };
        bits(a) == bits(b) && a.contact_nodes == b.contact_nodes
    }

    /// Every step of scenes with an obstacle (free, clamped and Signorini ends), with ends only,
    /// and with steps not measured: the bounds, the contact state and the contact dissipation
    /// have the bits of the per-constraint loops. (An extent ending at a wrong node fails it;
    /// `min_of`'s tie rule is not exercised: these runs have no `±0` ties.)
    #[test]
    fn the_contiguous_passes_have_the_bits_of_the_per_constraint_loops() {
        let cases: [(&str, &[&str]); 6] = [
            ("distributed", &["mesh.elements=200"]),
            (
                "distributed-forced",
                &["mesh.elements=150", "output.diagnostics_every=3"],
            ),
            (
                "distributed",
                &[
                    "mesh.elements=100",
                    "left.condition=\"clamped\"",
                    "initial.velocity=\"-0.5*x\"",
                ],
            ),
            (
                "distributed",
                &[
                    "mesh.elements=100",
                    "left.condition=\"signorini\"",
                    "left.gap=0.25",
                    "right.condition=\"signorini\"",
                    "right.gap=0.15",
                ],
            ),
            ("impact", &["output.diagnostics_every=2"]),
            ("both-ends", &[]),
        ];
        for (name, overrides) in cases {
            let o: Vec<String> = overrides.iter().map(|s| s.to_string()).collect();
            let (_, scene) = crate::scene::load(name, &o).unwrap();
            let mut sim = Simulation::new(&scene).unwrap();
            let (first, _) = reference(&sim, false);
            assert!(
                same_contact_bits(&sim.first_record(), &first),
                "{name}: start-up"
            );
            let mut contacts = 0;
            for step in 0..400.min(scene.steps() - 1) {
                let expected_lower: Vec<f64> = (sim.disc.constraints.iter())
                    .zip(sim.disc.constrained_locals())
                    .map(|(c, l)| -c.gap - sim.u[l])
                    .collect();
                sim.fill_lower();
                assert!(
                    (sim.lower.iter().map(|v| v.to_bits()))
                        .eq(expected_lower.iter().map(|v| v.to_bits())),
                    "{name}: bounds at step {step}"
                );
                let record = sim.step().unwrap();
                let (expected, contact) = reference(&sim, record.measured);
                assert!(same_contact_bits(&record, &expected), "{name}: step {step}");
                if record.measured {
                    assert_eq!(
                        record.contact_dissipation.to_bits(),
                        contact.to_bits(),
                        "{name}: dissipation at step {step}"
                    );
                }
                contacts += record.contact_nodes;
            }
            assert!(contacts > 0, "{name}: no contact, nothing compared");
        }
    }
}
