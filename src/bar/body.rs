//! The bar as a [`Body`] of the scheme: its P1 matrices as tridiagonal kernels (the
//! right-hand side and the energy sums, [`crate::bar::kernels`]), its Signorini ends and
//! obstacle as a [`ContactSet`], and its step solvers (end enumeration, block pivoting,
//! penalty, OSQP). A run of a bar scene is a [`Simulation`], the scheme stepping this body.

use crate::bar::discretisation::{Discretisation, InitialData};
use crate::bar::kernels::energy::{energy_sums, potential_of_difference};
use crate::bar::kernels::energy_fast::energy_sums_uniform;
use crate::bar::kernels::rhs::rhs_into;
use crate::bar::kernels::rhs_fast::rhs_into_uniform;
use crate::bar::matrices;
use crate::linalg::kernels::ldlt::NotPositiveDefinite;
use crate::linalg::kernels::ldlt_fast::TwistedLdlt;
use crate::linalg::system::TridiagSystem;
use crate::linalg::tridiag::Uniform;
use crate::scene::expr::Expression;
use crate::scene::{Condition, Scene, SceneError};
use crate::scheme::body::{Body, EnergySums, FullMassRows};
use crate::scheme::certify::{IDENTITY_TOL, MAX_IDENTITY_BOUND, conditioned_bound};
use crate::scheme::contact::{ContactSet, Group, Positions};
use crate::scheme::{Load, RunError, Scheme, Setup, Unstarted};
use crate::step::{
    Algorithm, BlockPivoting, CondensedLcp, Constraints, EndEnumeration, EndPenalty, Osqp,
    SetupError, Shape, StepSolver, algorithm_for,
};

/// A run of a bar scene: the scheme stepping the bar.
pub type Simulation = Scheme<BarBody>;

/// Which version of each of the bar's per-step kernels a run uses: the optimised twins (the
/// default, [`Kernels::TWINS`]) or the plain kernels they are tested against
/// ([`Kernels::PLAIN`]). The results agree to round-off; `benches/twins.rs` measures what each
/// twin buys on a step.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Kernels {
    /// The exact end solver's solves by `ldlt_fast::TwistedLdlt`, else by the plain `Ldlt`.
    pub twisted_solve: bool,
    /// The exact end solver tries the previous step's active set first.
    pub warm_start: bool,
    /// On a uniform mesh, the right-hand side by `rhs_into_uniform`.
    pub uniform_rhs: bool,
    /// On a uniform mesh, the energy sums by `energy_sums_uniform`.
    pub uniform_energy: bool,
    /// `method = "exact"` by the general `CondensedLcp` on the step matrix in place of the
    /// specialised `EndEnumeration` (ends) or `BlockPivoting` (obstacle), their twin (false in
    /// both [`Kernels::TWINS`] and [`Kernels::PLAIN`]; the dense `S` of an obstacle needs
    /// `(J + 1)²` doubles).
    pub general_solver: bool,
}

impl Kernels {
    pub const TWINS: Kernels = Kernels {
        twisted_solve: true,
        warm_start: true,
        uniform_rhs: true,
        uniform_energy: true,
        general_solver: false,
    };
    pub const PLAIN: Kernels = Kernels {
        twisted_solve: false,
        warm_start: false,
        uniform_rhs: false,
        uniform_energy: false,
        general_solver: false,
    };
}

impl Default for Kernels {
    fn default() -> Self {
        Self::TWINS
    }
}

/// The bar on its unknowns: the discretisation and the coefficients its kernels stream.
pub struct BarBody {
    disc: Discretisation,
    kernels: Kernels,
    /// Interior coefficients of `M` and `R` as numbers, when the mesh is uniform.
    uniform: Option<(Uniform, Uniform)>,
    /// `1/Δt²` and `½ − α/(2Δt)`.
    inv_dt2: f64,
    c_w: f64,
    /// `u_0` and `u_1`, evaluated again on request rather than kept (2 × J doubles).
    initial: InitialData,
    /// An upper bound on `κ(C)` ([`crate::linalg::spectrum::condition_bound`]), for the
    /// identity's bound.
    condition: f64,
}

impl BarBody {
    /// An upper bound on `κ(C)`, the step matrix's condition number (at most 6 times it).
    pub fn condition(&self) -> f64 {
        self.condition
    }

    pub fn discretisation(&self) -> &Discretisation {
        &self.disc
    }

    /// Initial displacement and velocity at all nodes (evaluated again: not kept in memory).
    pub fn initial_state_into(&self, u: &mut [f64], v: &mut [f64]) {
        self.initial
            .eval_into(&self.disc, u, v)
            .expect("the same evaluation succeeded at set-up");
    }
}

impl Body for BarBody {
    /// [`conditioned_bound`] of the bar's `C`.
    fn identity_tolerance(&self) -> f64 {
        conditioned_bound(IDENTITY_TOL, self.disc.unknowns(), self.condition)
    }

    const NAME: &'static str = "bar";

    fn unknowns(&self) -> usize {
        self.disc.unknowns()
    }

    fn dt(&self) -> f64 {
        self.disc.dt
    }

    fn viscosity(&self) -> f64 {
        self.disc.alpha
    }

    /// The optimised twins on a uniform mesh (`rhs_into_uniform`, `energy_sums_uniform`),
    /// else the plain kernels.
    fn rhs_into(&self, u: &[f64], w: &[f64], force: Option<&[f64]>, b: &mut [f64]) {
        let (mass, stiffness) = (&self.disc.mass, &self.disc.stiffness);
        let (inv_dt2, c_w) = (self.inv_dt2, self.c_w);
        let uniform = self.uniform.filter(|_| self.kernels.uniform_rhs);
        match (uniform, force) {
            (Some(k), Some(f)) => {
                rhs_into_uniform::<true>(mass, stiffness, k, c_w, inv_dt2, u, w, f, b)
            }
            (Some(k), None) => {
                rhs_into_uniform::<false>(mass, stiffness, k, c_w, inv_dt2, u, w, &[], b)
            }
            (None, _) => rhs_into(mass, stiffness, c_w, inv_dt2, u, w, force, b),
        }
    }

    fn energy_sums(&self, u: &[f64], z: &[f64], w: &[f64], force: Option<&[f64]>) -> EnergySums {
        let (mass, stiffness) = (&self.disc.mass, &self.disc.stiffness);
        let uniform = self.uniform.filter(|_| self.kernels.uniform_energy);
        match (uniform, force) {
            (Some(k), Some(f)) => energy_sums_uniform::<true>(mass, stiffness, k, u, z, w, f),
            (Some(k), None) => energy_sums_uniform::<false>(mass, stiffness, k, u, z, w, &[]),
            (None, _) => energy_sums(mass, stiffness, u, z, w, force),
        }
    }

    fn stiffness_form(&self, x: &[f64]) -> f64 {
        self.disc.stiffness.quad(x)
    }

    fn stiffness_form_of_difference(&self, u: &[f64], w: &[f64]) -> f64 {
        potential_of_difference(&self.disc.stiffness, u, w)
    }

    fn mass_form(&self, x: &[f64]) -> f64 {
        self.disc.mass.quad(x)
    }

    fn mass_mul(&self, x: &[f64], y: &mut [f64]) {
        self.disc.mass.mul_into(x, y);
    }

    fn stiffness_mul(&self, x: &[f64], y: &mut [f64]) {
        self.disc.stiffness.mul_into(x, y);
    }

    fn step_matrix_mul(&mut self, x: &[f64], y: &mut [f64]) -> Result<(), RunError> {
        self.disc.step_matrix.mul_into(x, y);
        Ok(())
    }

    /// On the unknowns that carry mass (a contiguous block: the massless ones are end nodes,
    /// [`Discretisation::massless`]), by the factorisation the step solves with.
    fn solve_mass(&self, acc: &mut [f64]) -> Result<(), RunError> {
        let n = acc.len();
        let disc = &self.disc;
        let lo = usize::from(disc.massless.contains(&0));
        let hi = n - usize::from(n > 0 && disc.massless.contains(&(n - 1)));
        for &j in &disc.massless {
            acc[j] = 0.0;
        }
        if lo >= hi {
            return Ok(());
        }
        let solved: Result<(), NotPositiveDefinite> = if lo == 0 && hi == n {
            TwistedLdlt::factor(&disc.mass).map(|f| f.solve_in_place(acc))
        } else {
            let sub = disc.mass.sub(lo, hi - 1);
            TwistedLdlt::factor(&sub).map(|f| f.solve_in_place(&mut acc[lo..hi]))
        };
        Ok(solved?)
    }

    /// The full-mesh mass of the matrix variant (the load vector does not follow
    /// `[bar] mass`: it is always the P1 load vector of the interpolated force).
    fn full_mass_rows(&self) -> FullMassRows {
        let disc = &self.disc;
        let mass = matrices::mass(disc.variant, disc.nodes, disc.dx);
        let (first, n) = (disc.first, disc.unknowns());
        let mut full = if n == disc.nodes {
            Vec::new()
        } else {
            vec![0.0; disc.nodes]
        };
        Box::new(move |x, out| {
            if full.is_empty() {
                mass.mul_into(x, out);
            } else {
                mass.mul_into(x, &mut full);
                out.copy_from_slice(&full[first..first + n]);
            }
        })
    }

    fn nodes(&self) -> usize {
        self.disc.nodes
    }

    fn elements(&self) -> usize {
        self.disc.nodes - 1
    }

    fn lattice(&self) -> [usize; 2] {
        [self.disc.nodes, 1]
    }

    fn components(&self) -> usize {
        1
    }

    fn point(&self, node: usize) -> (f64, Option<f64>) {
        (self.disc.x(node), None)
    }

    fn unknown_of(&self, node: usize) -> Option<usize> {
        node.checked_sub(self.disc.first)
            .filter(|&i| i < self.disc.unknowns())
    }
}

/// An upper bound on `κ(C)` (at most 6 times it; infinite where `C` is numerically singular,
/// [`crate::linalg::spectrum::condition_bound`]); a scene so stiff
/// that the identity's bound would exceed [`MAX_IDENTITY_BOUND`] is refused naming
/// `time.step`.
fn condition_of(disc: &Discretisation) -> Result<f64, SceneError> {
    let condition =
        crate::linalg::spectrum::condition_bound(&disc.step_matrix).unwrap_or(f64::INFINITY);
    let bound = conditioned_bound(IDENTITY_TOL, disc.unknowns(), condition);
    if bound > MAX_IDENTITY_BOUND {
        return Err(SceneError::Invalid {
            field: "time.step".into(),
            value: disc.dt.to_string(),
            allowed: format!(
                "a step matrix with condition number {condition:.1e} (bar.viscosity = {}, \
                 Δt/Δx = {:.1e}) holds the energy identity only to {bound:.1e}, above \
                 {MAX_IDENTITY_BOUND:e}: take a smaller step or viscosity",
                disc.alpha,
                disc.dt / disc.dx
            ),
        });
    }
    Ok(condition)
}

/// Builds the step solver a scene asks for, for `disc`'s step matrix and constrained nodes.
pub fn make_solver(scene: &Scene, disc: &Discretisation) -> Result<Box<dyn StepSolver>, RunError> {
    make_solver_with(scene, disc, Kernels::TWINS)
}

/// [`make_solver`] with the exact end solver's kernels as `kernels` says.
fn make_solver_with(
    scene: &Scene,
    disc: &Discretisation,
    kernels: Kernels,
) -> Result<Box<dyn StepSolver>, RunError> {
    let nodes = disc.constrained_locals();
    let shape = if disc.ends_only() {
        Shape::BarEnds
    } else {
        Shape::BarObstacle
    };
    let algorithm = algorithm_for(scene.solver.method, shape);
    if kernels.general_solver
        && matches!(
            algorithm,
            Some(Algorithm::EndEnumeration | Algorithm::BlockPivoting)
        )
    {
        let system = TridiagSystem::new(&disc.step_matrix)?;
        let constraints = Constraints::lower_bounds(&nodes);
        return Ok(Box::new(CondensedLcp::new(system, constraints, 0.0)?));
    }
    match algorithm {
        Some(Algorithm::EndEnumeration) => Ok(Box::new(EndEnumeration::with_options(
            &disc.step_matrix,
            &nodes,
            kernels.twisted_solve,
            kernels.warm_start,
        )?)),
        Some(Algorithm::BlockPivoting) => {
            Ok(Box::new(BlockPivoting::new(&disc.step_matrix, &nodes)?))
        }
        Some(Algorithm::Osqp) => Ok(Box::new(Osqp::new(
            &disc.step_matrix,
            &nodes,
            scene.solver.osqp_settings(),
        )?)),
        Some(Algorithm::EndPenalty) => Ok(Box::new(EndPenalty::new(
            &disc.step_matrix,
            &nodes,
            scene.solver.penalty_settings(),
        )?)),
        None => Err(SetupError::TooManyBounds {
            solver: scene.solver.method.name(),
            nodes: nodes.len(),
        }
        .into()),
        Some(other) => unreachable!("the table gives the bar {other:?}"),
    }
}

/// The bar's constraints: one per Signorini end, or one per node under an obstacle (the
/// ends' gaps the smaller of theirs and the obstacle's), lower bounds `u >= −g`.
fn contact_set(disc: &Discretisation) -> ContactSet {
    let k = disc.constraints.len();
    let gaps = disc.constraints.iter().map(|c| c.gap).collect();
    let mut groups: Vec<Group> = (disc.constraints.iter().enumerate())
        .filter_map(|(j, c)| {
            c.side.map(|side| Group {
                name: side.name(),
                range: j..j + 1,
            })
        })
        .collect();
    if disc.ends_only() {
        let locals = disc.constrained_locals();
        let positions = disc.constraints.iter().map(|c| disc.x(c.node)).collect();
        ContactSet::new(gaps, locals, Vec::new(), Positions::List(positions), groups)
    } else {
        // Every unknown, in order: constraint k bounds unknown k.
        groups.push(Group {
            name: "obstacle",
            range: 0..k,
        });
        let positions = Positions::Grid {
            first: disc.first,
            spacing: disc.dx,
        };
        ContactSet::new(gaps, Vec::new(), Vec::new(), positions, groups)
    }
}

/// The scheme set up for `scene` on `disc` with `solver` (built for `disc.step_matrix` and
/// `disc.constrained_locals()`): initial data evaluated and checked admissible, the load.
fn setup(
    scene: &Scene,
    disc: Discretisation,
    solver: Box<dyn StepSolver>,
    kernels: Kernels,
) -> Result<Setup<BarBody>, RunError> {
    scene.validate()?;
    let (nodes, n, dt, alpha) = (disc.nodes, disc.unknowns(), disc.dt, disc.alpha);
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
    let ends = scene.signorini_ends();
    for c in &disc.constraints {
        if u0_full[c.node] < -c.gap {
            // The key whose gap bounds the node: an end's own, or the obstacle's where it is
            // the smaller one under that end.
            let end_gap = |side| ends.iter().find(|(s, _)| *s == side).map(|e| e.1);
            let gap_field = match c.side {
                Some(side) if end_gap(side) == Some(c.gap) => format!("{}.gap", side.name()),
                _ => "obstacle.gap".to_string(),
            };
            return Err(SceneError::Inadmissible {
                field: "initial.displacement".into(),
                gap_field,
                node: c.node,
                x: disc.x(c.node),
                value: u0_full[c.node],
                gap: c.gap,
            }
            .into());
        }
    }
    // u^0 and u_1 on the unknowns, in the storage of the full-mesh vectors.
    let range = disc.first..disc.first + n;
    let restrict = |mut v: Vec<f64>| {
        v.truncate(range.end);
        v.drain(..range.start);
        v
    };
    let (displacement, velocity) = (restrict(u0_full), restrict(v0_full));
    let contact = contact_set(&disc).with_motion(disc.motion.clone());
    let condition = condition_of(&disc)?;
    let body = BarBody {
        condition,
        kernels,
        uniform: disc.mass.uniform().zip(disc.stiffness.uniform()),
        inv_dt2: 1.0 / (dt * dt),
        c_w: 0.5 - alpha / (2.0 * dt),
        initial,
        disc,
    };
    let load = match &scene.load.density {
        None => Load::none(),
        Some(text) => Load::new(
            vec![Some(Expression::parse("load.density", text, true)?)],
            &body,
        )?,
    };
    Ok(Setup {
        body,
        solver,
        contact,
        load,
        displacement,
        velocity,
        steps: scene.steps(),
        diagnostics_every: scene.output.diagnostics_every as usize,
    })
}

/// A scene with `[heat]` refused where the bar without a temperature is set up (it runs as
/// the thermal bar, `crate::thermal`).
fn without_heat(scene: &Scene) -> Result<(), SceneError> {
    match scene.heat {
        None => Ok(()),
        Some(_) => Err(SceneError::Invalid {
            field: "heat".into(),
            value: "(set)".into(),
            allowed: "a scene with a temperature runs as the thermal bar (`viscobar run`); \
                      this takes bar scenes without [heat]"
                .into(),
        }),
    }
}

impl Scheme<BarBody> {
    /// Sets up a run of `scene` with the solver it names and takes the start-up step.
    pub fn new(scene: &Scene) -> Result<Self, RunError> {
        Self::prepare(scene)?.start()
    }

    /// Sets `scene` up as [`Simulation::new`] does, short of the start-up step: for a run
    /// that writes `u^0` and `u_1` first and starts afterwards (without a copy of `u^0`).
    pub fn prepare(scene: &Scene) -> Result<Unstarted<BarBody>, RunError> {
        without_heat(scene)?;
        Self::prepare_mechanics(scene)
    }

    /// The bar of `scene` set up as [`Simulation::prepare`] does, its `[heat]` table (if any)
    /// left to the caller: the displacement of the thermal bar.
    pub fn prepare_mechanics(scene: &Scene) -> Result<Unstarted<BarBody>, RunError> {
        let disc = Discretisation::new(scene)?;
        let solver = make_solver(scene, &disc)?;
        Ok(Scheme::unstarted(setup(
            scene,
            disc,
            solver,
            Kernels::TWINS,
        )?))
    }

    /// [`Simulation::new`] with the kernels `kernels` names (the same answers to round-off).
    pub fn with_kernels(scene: &Scene, kernels: Kernels) -> Result<Self, RunError> {
        let disc = Discretisation::new(scene)?;
        let solver = make_solver_with(scene, &disc, kernels)?;
        Scheme::from_setup(setup(scene, disc, solver, kernels)?)
    }

    /// Sets up a run with a given step solver (built for `disc.step_matrix` and
    /// `disc.constrained_locals()`), and takes the start-up step.
    pub fn with_solver(
        scene: &Scene,
        disc: Discretisation,
        solver: Box<dyn StepSolver>,
    ) -> Result<Self, RunError> {
        without_heat(scene)?;
        Scheme::from_setup(setup(scene, disc, solver, Kernels::TWINS)?)
    }

    pub fn discretisation(&self) -> &Discretisation {
        &self.body().disc
    }

    /// Initial displacement and velocity at all nodes (evaluated again: not kept in memory).
    pub fn initial_state(&self) -> (Vec<f64>, Vec<f64>) {
        let nodes = self.body().disc.nodes;
        let (mut u, mut v) = (vec![0.0; nodes], vec![0.0; nodes]);
        self.body().initial_state_into(&mut u, &mut v);
        (u, v)
    }
}
