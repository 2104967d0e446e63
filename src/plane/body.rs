//! The plane body as a [`Body`] of the scheme: its Q1 mass `M` and stiffness `K` on one sparse
//! pattern as kernels (the right-hand side and the energy sums in one pass over the pattern,
//! the `K`-forms cell by cell, [`crate::plane::energy`]), its Signorini edges as a
//! [`ContactSet`] and its step solvers (condensation with an exact LCP, its penalty law, OSQP),
//! each holding the sparse Cholesky factor of `C` made once per run. A run of a plane scene is
//! a [`PlaneSimulation`], the scheme stepping this body.

use crate::linalg::cholesky::SparseCholesky;
use crate::linalg::sparse::Pattern;
use crate::linalg::system::SparseSystem;
use crate::plane::coupling::CoupledSolver;
use crate::plane::energy::{StrainForms, measure};
use crate::plane::heat::PlaneHeat;
use crate::plane::matrices::{Material, assemble, assemble_with};
use crate::plane::mesh::Grid;
use crate::plane::normals::{Normal, edge_motion, normals};
use crate::plane::stress;
use crate::scene::SceneError;
use crate::scene::expr::Expression;
use crate::scene::plane::PENALTY_CONDENSED_MAX_NORMALS;
use crate::scene::plane::{EDGE_NAMES, PlaneScene};
use crate::scheme::body::{Body, EnergySums, FullMassRows, HeatOutputs, HeatTerms};
use crate::scheme::certify::{
    LAMBDA_IDENTITY_ULPS, MAX_IDENTITY_BOUND, PLANE_IDENTITY_TOL, conditioned_bound,
};
use crate::scheme::contact::{ContactSet, Group, Positions};
use crate::scheme::{Load, RunError, Scheme, Setup, Unstarted};
use crate::step::{
    Algorithm, CondensedLcp, CondensedLemke, Osqp, OsqpTresca, SemismoothPenalty, Shape,
    StepSolver, algorithm_for,
};

/// A run of a plane scene: the scheme stepping the plane body.
pub type PlaneSimulation = Scheme<PlaneBody>;

/// The discretised plane body: grid, unknowns, and `M`, `K` on the unknowns (one pattern).
pub struct PlaneDiscretisation {
    pub grid: Grid,
    pub material: Material,
    /// `α`.
    pub alpha: f64,
    /// `Δt`.
    pub dt: f64,
    /// The full degree of freedom of each unknown.
    pub free: Vec<usize>,
    /// The unknown of each full degree of freedom (`None` when clamped).
    pub index: Vec<Option<usize>>,
    pub pattern: Pattern,
    pub mass: Vec<f64>,
    pub stiffness: Vec<f64>,
    /// The `K`-forms of the energy, cell by cell.
    pub forms: StrainForms,
}

impl PlaneDiscretisation {
    /// The grid, the matrices and the unknowns of `scene` (validated).
    pub fn new(scene: &PlaneScene) -> Self {
        let grid = Grid::new(
            scene.plane.width,
            scene.plane.height,
            scene.mesh.nx as usize,
            scene.mesh.ny as usize,
            scene.mesh.y_grading,
        );
        let material = Material {
            lambda: scene.plane.lambda,
            mu: scene.plane.mu,
            density: scene.plane.density,
        };
        let rule = scene.plane.integration;
        let full = assemble_with(&grid, material, rule);
        let [left, right, bottom, top] = scene.edges.clamped();
        let mut index = vec![None; grid.dofs()];
        let mut free = Vec::new();
        for node in 0..grid.nodes() {
            let (i, j) = grid.position(node);
            let clamped = (left && i == 0)
                || (right && i == grid.nx)
                || (bottom && j == 0)
                || (top && j == grid.ny);
            if !clamped {
                for c in 0..2 {
                    index[2 * node + c] = Some(free.len());
                    free.push(2 * node + c);
                }
            }
        }
        let (pattern, from) = full.pattern.restrict(&index);
        let mass = from.iter().map(|&k| full.mass[k]).collect();
        let stiffness = from.iter().map(|&k| full.stiffness[k]).collect();
        let forms = StrainForms::with_rule(&grid, material, &index, rule);
        Self {
            forms,
            grid,
            material,
            alpha: scene.plane.viscosity,
            dt: scene.time.step,
            free,
            index,
            pattern,
            mass,
            stiffness,
        }
    }

    /// Unknowns.
    pub fn unknowns(&self) -> usize {
        self.free.len()
    }

    /// `C = M/Δt² + (½ + α/(2Δt)) K` on the pattern.
    pub fn step_matrix(&self) -> Vec<f64> {
        let (a, b) = (
            1.0 / (self.dt * self.dt),
            0.5 + self.alpha / (2.0 * self.dt),
        );
        self.mass
            .iter()
            .zip(&self.stiffness)
            .map(|(m, k)| a * m + b * k)
            .collect()
    }
}

/// The plane body on its unknowns.
pub struct PlaneBody {
    disc: PlaneDiscretisation,
    /// The contact normals of the Signorini edges, one per constraint of the contact set.
    normals: Vec<Normal>,
    /// `C` on the pattern.
    c: Vec<f64>,
    /// `1/Δt²` and `½ − α/(2Δt)`.
    inv_dt2: f64,
    c_w: f64,
    /// An upper bound on `κ(C)` ([`condition_bound`]), for the identity's bound.
    condition: f64,
    /// The temperature of a scene with `[heat]` ([`crate::plane::heat`]).
    heat: Option<Box<PlaneHeat>>,
}

/// An upper bound on `κ₂(C)` in one pass over the pattern: `λ_max(C)` is at most the largest
/// absolute row sum, and `λ_min(C) >= λ_min(M)/Δt² >= min_i Σ_j M_ij / (9 Δt²)` (`K` is
/// positive semi-definite; on a rectangle Q1's mass matrix is the tensor product of P1's, each
/// at least a third of its row-sum lumping as a quadratic form, so at least a ninth; the row
/// sums on the unknowns alone are at most the full ones).
fn condition_bound(p: &Pattern, c: &[f64], mass: &[f64], dt: f64) -> f64 {
    let (mut largest, mut least) = (0.0f64, f64::INFINITY);
    for i in 0..p.n {
        let row = p.row_ptr[i]..p.row_ptr[i + 1];
        largest = largest.max(c[row.clone()].iter().map(|v| v.abs()).sum());
        least = least.min(mass[row].iter().sum());
    }
    if least > 0.0 {
        largest * 9.0 * dt * dt / least
    } else {
        f64::INFINITY
    }
}

impl PlaneBody {
    pub fn discretisation(&self) -> &PlaneDiscretisation {
        &self.disc
    }

    /// The contact normals, in the order of the contact set's constraints.
    pub fn normals(&self) -> &[Normal] {
        &self.normals
    }

    /// `x · scale` on the unknowns at every full degree of freedom (`2 node + c`; clamped
    /// ones 0).
    pub fn scatter_into(&self, x: &[f64], scale: f64, out: &mut [f64]) {
        out.fill(0.0);
        for (&d, v) in self.disc.free.iter().zip(x) {
            out[d] = v * scale;
        }
    }
}

impl Body for PlaneBody {
    const NAME: &'static str = "plane";

    /// `PLANE_IDENTITY_TOL + LAMBDA_IDENTITY_ULPS ε λ/μ`, with [`conditioned_bound`]'s terms of
    /// the `n` unknowns and of `C`'s conditioning (bounded at set-up): the volumetric energy
    /// weighs the solve's round-off by `λ` ([`crate::scheme::certify::LAMBDA_IDENTITY_ULPS`]).
    fn identity_tolerance(&self) -> f64 {
        let m = self.disc.material;
        let volumetric = LAMBDA_IDENTITY_ULPS * f64::EPSILON * m.lambda / m.mu;
        // A temperature adds its nodes' sums and its heat step's `κΔt/h²`.
        let (nodes, ratio) = self
            .heat
            .as_ref()
            .map_or((0, 0.0), |h| (self.disc.grid.nodes(), h.diffusion_ratio()));
        conditioned_bound(
            PLANE_IDENTITY_TOL + volumetric,
            self.unknowns() + nodes,
            self.condition + ratio,
        )
    }

    fn unknowns(&self) -> usize {
        self.disc.unknowns()
    }

    fn dt(&self) -> f64 {
        self.disc.dt
    }

    fn viscosity(&self) -> f64 {
        self.disc.alpha
    }

    /// One pass over the shared pattern of `M` and `K`.
    fn rhs_into(&self, u: &[f64], w: &[f64], force: Option<&[f64]>, b: &mut [f64]) {
        let (p, mass, stiffness) = (&self.disc.pattern, &self.disc.mass, &self.disc.stiffness);
        for (r, br) in b.iter_mut().enumerate() {
            let (mut mw, mut ky) = (0.0, 0.0);
            for k in p.row_ptr[r]..p.row_ptr[r + 1] {
                let c = p.cols[k];
                mw += mass[k] * w[c];
                ky += stiffness[k] * (self.c_w * w[c] - u[c]);
            }
            *br = force.map_or(0.0, |f| f[r]) + mw * self.inv_dt2 + ky;
        }
        // A coupled temperature's load, `ζ` eliminated (crate::plane::coupling).
        if let Some(load) = self.heat.as_ref().and_then(|h| h.thermal_load()) {
            for (br, l) in b.iter_mut().zip(load) {
                *br += l;
            }
        }
    }

    fn energy_sums(&self, u: &[f64], z: &[f64], w: &[f64], force: Option<&[f64]>) -> EnergySums {
        let d = &self.disc;
        measure(&d.pattern, &d.mass, &d.forms, u, z, w, force)
    }

    fn stiffness_form(&self, x: &[f64]) -> f64 {
        self.disc.forms.quad(x)
    }

    fn stiffness_form_of_difference(&self, u: &[f64], w: &[f64]) -> f64 {
        self.disc.forms.quad_pair(|k| u[k] - w[k], |_| 0.0).0
    }

    fn mass_form(&self, x: &[f64]) -> f64 {
        self.disc.pattern.quad(&self.disc.mass, x)
    }

    fn mass_mul(&self, x: &[f64], y: &mut [f64]) {
        self.disc.pattern.mul_into(&self.disc.mass, x, y);
    }

    fn stiffness_mul(&self, x: &[f64], y: &mut [f64]) {
        self.disc.pattern.mul_into(&self.disc.stiffness, x, y);
    }

    /// `C x`; with a coupled temperature `S x` of the start-up's state
    /// (`src/plane/coupling.rs`), the matrix its step solver projects with.
    fn step_matrix_mul(&mut self, x: &[f64], y: &mut [f64]) -> Result<(), RunError> {
        self.disc.pattern.mul_into(&self.c, x, y);
        match &mut self.heat {
            Some(heat) => heat.add_schur_product(x, y),
            None => Ok(()),
        }
    }

    fn solve_mass(&self, a: &mut [f64]) -> Result<(), RunError> {
        SparseCholesky::new(&self.disc.pattern, &self.disc.mass, "M")?.solve_in_place(a);
        Ok(())
    }

    fn full_mass_rows(&self) -> FullMassRows {
        let full = assemble(&self.disc.grid, self.disc.material);
        let free = self.disc.free.clone();
        Box::new(move |x, out| {
            let p = &full.pattern;
            for (o, &row) in out.iter_mut().zip(&free) {
                let mut s = 0.0;
                for k in p.row_ptr[row]..p.row_ptr[row + 1] {
                    s += full.mass[k] * x[p.cols[k]];
                }
                *o = s;
            }
        })
    }

    fn nodes(&self) -> usize {
        self.disc.grid.nodes()
    }

    fn elements(&self) -> usize {
        self.disc.grid.cells()
    }

    fn lattice(&self) -> [usize; 2] {
        [self.disc.grid.nx + 1, self.disc.grid.ny + 1]
    }

    fn components(&self) -> usize {
        2
    }

    fn point(&self, node: usize) -> (f64, Option<f64>) {
        let (x, y) = self.disc.grid.point(node);
        (x, Some(y))
    }

    fn unknown_of(&self, dof: usize) -> Option<usize> {
        self.disc.index[dof]
    }

    /// `crate::plane::stress`: the cell-centre stresses, averaged at the nodes; a coupled
    /// temperature adds its `−γθ` to the diagonal at each node (`σ_zz` too: plane strain's
    /// thermal stress is isotropic), so the von Mises stress keeps its value.
    fn nodal_stress(&self, u: &[f64], v: &[f64]) -> Option<Vec<[f64; 4]>> {
        let d = &self.disc;
        let (mut uf, mut vf) = (vec![0.0; d.grid.dofs()], vec![0.0; d.grid.dofs()]);
        self.scatter_into(u, 1.0, &mut uf);
        self.scatter_into(v, 1.0, &mut vf);
        let cells = stress::cell_stress(&d.grid, d.material, d.alpha, &uf, &vf);
        let mut nodal = stress::nodal_stress(&d.grid, &cells);
        if let Some(heat) = &self.heat {
            for (node, s) in nodal.iter_mut().enumerate() {
                if let Some(thermal) = heat.thermal_stress(node) {
                    for k in [0, 1, 3] {
                        s[k] -= thermal;
                    }
                }
            }
        }
        Some(nodal)
    }

    fn has_temperature(&self) -> bool {
        self.heat.is_some()
    }

    fn heat_outputs(&self) -> HeatOutputs {
        self.heat
            .as_ref()
            .map_or_else(HeatOutputs::default, |h| h.outputs())
    }

    fn prepare_step(&mut self, n: usize, lower: &[f64], w_old: &[f64]) -> Result<(), RunError> {
        match &mut self.heat {
            Some(heat) => heat.prepare(n, lower, w_old),
            None => Ok(()),
        }
    }

    /// With a coupled temperature, the Taylor step's acceleration gains `M⁻¹ γ G θ^0`.
    fn complete_start_up(
        &self,
        _u0: &[f64],
        _v0: &[f64],
        increment: &mut [f64],
    ) -> Result<(), RunError> {
        let Some(heat) = &self.heat else {
            return Ok(());
        };
        let mut a = vec![0.0; increment.len()];
        if heat.initial_thermal_force(&mut a) {
            self.solve_mass(&mut a)?;
            let half_dt2 = 0.5 * self.disc.dt * self.disc.dt;
            for (z, ai) in increment.iter_mut().zip(&a) {
                *z += half_dt2 * ai;
            }
        }
        Ok(())
    }

    fn heat_step(
        &mut self,
        n: usize,
        increments: (&[f64], Option<&[f64]>),
        friction_work: &[f64],
    ) -> Result<(), RunError> {
        match &mut self.heat {
            Some(heat) => heat.step(n, increments, friction_work),
            None => Ok(()),
        }
    }

    fn start_up_heat(&self, _u: &[f64]) -> Option<HeatTerms> {
        self.heat.as_ref().map(|h| h.start_up_terms())
    }

    fn heat_energy(&self, _u: &[f64]) -> Option<f64> {
        self.heat.as_ref().map(|h| h.energy())
    }

    fn heat_terms(&self, _u: &[f64], _z: &[f64], _w: &[f64]) -> Option<HeatTerms> {
        self.heat.as_ref().map(|h| h.terms())
    }

    fn temperature(&self, _u: &[f64], node: usize) -> Option<f64> {
        self.heat.as_ref().map(|h| h.temperature(node))
    }
}

/// The contact set of the Signorini edges' normals: `u·n <= g` at each, `n = σ e_c`, is the
/// gap `−σ u_c + g >= 0`, pushed along `−n`; one group per edge.
fn contact_set(normals: &[Normal]) -> ContactSet {
    let mut groups: Vec<Group> = Vec::new();
    for (k, nk) in normals.iter().enumerate() {
        match groups.last_mut() {
            Some(g) if g.name == EDGE_NAMES[nk.edge] => g.range.end = k + 1,
            _ => groups.push(Group {
                name: EDGE_NAMES[nk.edge],
                range: k..k + 1,
            }),
        }
    }
    ContactSet::new(
        normals.iter().map(|nk| nk.gap).collect(),
        normals.iter().map(|nk| nk.unknown).collect(),
        normals.iter().map(|nk| -nk.sign).collect(),
        Positions::List(normals.iter().map(|nk| nk.s).collect()),
        groups,
    )
}

/// The scheme set up for a plane scene: matrices, initial data (checked admissible), the
/// contact set, the load and the step solver its `[solver]` table names.
fn setup(scene: &PlaneScene) -> Result<Setup<PlaneBody>, RunError> {
    scene.validate()?;
    let exprs = scene.expressions()?;
    let gaps = scene.edges.gaps()?;
    let disc = PlaneDiscretisation::new(scene);
    let grid = &disc.grid;
    let nodal = |e: &[Expression; 2], out: &mut [f64]| -> Result<(), RunError> {
        for node in 0..grid.nodes() {
            let (x, y) = grid.point(node);
            for c in 0..2 {
                out[2 * node + c] = e[c].eval_xy(x, y, 0.0)?;
            }
        }
        Ok(())
    };
    let mut u0_full = vec![0.0; grid.dofs()];
    let mut v0_full = vec![0.0; grid.dofs()];
    nodal(&exprs.displacement, &mut u0_full)?;
    nodal(&exprs.velocity, &mut v0_full)?;
    for (d, i) in disc.index.iter().enumerate() {
        if i.is_none() {
            (u0_full[d], v0_full[d]) = (0.0, 0.0);
        }
    }
    let normals = normals(&disc.grid, &disc.index, &gaps, &u0_full)?;
    let mu = scene.edges.frictions()?;
    let friction = crate::plane::friction::frictional_nodes(&normals, &disc.index, &mu)?;
    if let Some(&first) = friction.normals.first() {
        scene.check_frictional_step(normals.len(), friction.len(), normals[first].edge)?;
    }
    let velocities = scene.edges.velocities()?;
    let slide = crate::plane::friction::sliding_obstacles(
        &velocities,
        &normals,
        &friction,
        scene.time.step,
    )?;
    let contact = contact_set(&normals)
        .with_motion(edge_motion(&gaps, &normals))
        .with_friction(friction.clone())
        .with_slide(slide);
    let friction_nodes = friction.clone();
    let restrict = |v: &[f64]| disc.free.iter().map(|&d| v[d]).collect::<Vec<f64>>();
    let (displacement, velocity) = (restrict(&u0_full), restrict(&v0_full));
    let c = disc.step_matrix();
    let system = || SparseSystem::new(&disc.pattern, &c, "C");
    let constraints = contact.constraints();
    let shape = if !friction.is_empty() {
        Shape::PlaneFriction
    } else if constraints.len() as u64 <= PENALTY_CONDENSED_MAX_NORMALS {
        Shape::PlaneNormals
    } else {
        Shape::ManyPlaneNormals
    };
    let heat = match &scene.heat {
        Some(table) => {
            let parsed = table.validate(&scene.edges)?;
            Some(Box::new(PlaneHeat::new(
                grid,
                (&normals, &friction_nodes),
                &disc.free,
                parsed,
                disc.dt,
            )?))
        }
        None => None,
    };
    let method = scene.solver.method;
    let epsilon = || scene.solver.penalty_settings().epsilon;
    let coupled = heat
        .as_ref()
        .and_then(|h| h.coupled_solver_parts((&disc.pattern, &c), &constraints, &friction_nodes));
    let solver: Box<dyn StepSolver> = match (coupled, algorithm_for(method, shape)) {
        // A coupled temperature: the exact solver of each state's `S` (the scene's
        // validation admits the exact method only).
        (Some((parts, exchange, implicit)), _) => {
            Box::new(CoupledSolver::new(parts, exchange, implicit))
        }
        (None, Some(Algorithm::CondensedLcp)) => {
            Box::new(CondensedLcp::new(system()?, constraints, 0.0)?)
        }
        (None, Some(Algorithm::CondensedPenalty)) => {
            Box::new(CondensedLcp::new(system()?, constraints, epsilon())?)
        }
        (None, Some(Algorithm::SemismoothPenalty)) => {
            Box::new(SemismoothPenalty::new(system()?, constraints, epsilon())?)
        }
        (None, Some(Algorithm::Osqp)) => Box::new(Osqp::with_system(
            system()?,
            constraints,
            scene.solver.osqp_settings(),
        )?),
        (None, Some(Algorithm::CondensedLemke)) => {
            Box::new(CondensedLemke::new(system()?, constraints, friction)?)
        }
        (None, Some(Algorithm::OsqpTresca)) => Box::new(OsqpTresca::new(
            system()?,
            constraints,
            friction,
            scene.solver.osqp_settings(),
        )?),
        // The scene's validation refuses a method the table has not (penalty with friction).
        (None, None) => {
            return Err(SceneError::Invalid {
                field: "solver.method".into(),
                value: method.name().into(),
                allowed: format!("has no algorithm for the {}", shape.describe()),
            }
            .into());
        }
        (None, Some(other)) => unreachable!("the table gives the plane {other:?}"),
    };
    let (dt, alpha) = (disc.dt, disc.alpha);
    let condition = condition_bound(&disc.pattern, &c, &disc.mass, dt);
    let bound = conditioned_bound(PLANE_IDENTITY_TOL, disc.unknowns(), condition);
    if bound > MAX_IDENTITY_BOUND {
        return Err(SceneError::Invalid {
            field: "time.step".into(),
            value: dt.to_string(),
            allowed: format!(
                "a step matrix with condition number up to {condition:.1e} holds the energy \
                 identity only to {bound:.1e}, above {MAX_IDENTITY_BOUND:e}: take a smaller step"
            ),
        }
        .into());
    }
    if let Some(h) = &heat {
        let bound = conditioned_bound(
            PLANE_IDENTITY_TOL,
            disc.unknowns() + disc.grid.nodes(),
            condition + h.diffusion_ratio(),
        );
        if bound > MAX_IDENTITY_BOUND {
            return Err(SceneError::Invalid {
                field: "heat.diffusivity".into(),
                value: scene
                    .heat
                    .as_ref()
                    .map_or(0.0, |t| t.diffusivity)
                    .to_string(),
                allowed: format!(
                    "a heat step with κΔt/h² = {:.1e} holds the energy identity only to \
                     {bound:.1e}, above {MAX_IDENTITY_BOUND:e}: take a smaller diffusivity or step",
                    h.diffusion_ratio()
                ),
            }
            .into());
        }
    }
    let body = PlaneBody {
        heat,
        normals,
        condition,
        c,
        inv_dt2: 1.0 / (dt * dt),
        c_w: 0.5 - alpha / (2.0 * dt),
        disc,
    };
    let load = match exprs.load {
        None => Load::none(),
        Some([x, y]) => Load::new(vec![Some(x), Some(y)], &body)?,
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

impl Scheme<PlaneBody> {
    /// Sets up a run of `scene` with the step solver its `[solver]` table names and takes
    /// the start-up step.
    pub fn new(scene: &PlaneScene) -> Result<Self, RunError> {
        Scheme::from_setup(setup(scene)?)
    }

    /// [`PlaneSimulation::new`] short of the start-up step.
    pub fn prepare(scene: &PlaneScene) -> Result<Unstarted<PlaneBody>, RunError> {
        Ok(Scheme::unstarted(setup(scene)?))
    }

    pub fn discretisation(&self) -> &PlaneDiscretisation {
        &self.body().disc
    }
}
