//! The plane stepper: the talk's scheme unchanged, with the Q1 matrices of plane strain,
//!
//! ```text
//!   M (u^{n+1} − 2u^n + u^{n−1})/Δt² + K (u^{n+1} + u^{n−1})/2 + α K (u^{n+1} − u^{n−1})/(2Δt) = F^n,
//! ```
//!
//! `F^n = M_full (l(x_i, y_i, t_n))_i` restricted to the unknowns (the load's nodal
//! interpolant, integrated exactly). Clamped degrees of freedom are removed from the unknowns
//! (they stay 0). Each step solves `C z = b` for the increment `z = u^{n+1} − u^n`
//! ([`crate::plane::rhs`]), `C = M/Δt² + (½ + α/(2Δt)) K` factorised once per run
//! ([`SparseCholesky`]), and measures the energy balance ([`crate::plane::energy`]).

use crate::plane::contact::{Contact, ContactMethod, ContactStep};
use crate::plane::energy::{Balance, StrainForms, balance, measure};
use crate::plane::error::PlaneError;
use crate::plane::factor::SparseCholesky;
use crate::plane::matrices::{Material, Pattern, assemble};
use crate::plane::mesh::Grid;
use crate::plane::normals::normals;
use crate::plane::rhs::{RhsTerms, rhs_into};
use crate::scene::expr::Expression;
use crate::scene::plane::PlaneScene;
use crate::step::report::AuditReport;
use crate::time::clock::{PhaseClock, PhaseTimes};

/// The discretised body: grid, unknowns, and `M`, `K` on the unknowns (one pattern).
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
        let full = assemble(&grid, material);
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
        let forms = StrainForms::new(&grid, material, &index);
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

    /// `M_full x_full` at the unknowns, `x` given at every full degree of freedom.
    fn load_rows_into(&self, full_mass: &FullMass, x: &[f64], out: &mut [f64]) {
        let p = &full_mass.pattern;
        for (o, &row) in out.iter_mut().zip(&self.free) {
            let mut s = 0.0;
            for k in p.row_ptr[row]..p.row_ptr[row + 1] {
                s += full_mass.values[k] * x[p.cols[k]];
            }
            *o = s;
        }
    }
}

/// The full-mesh mass matrix, kept for a load that changes in time.
struct FullMass {
    pattern: Pattern,
    values: Vec<f64>,
}

/// How `F^n` is produced.
enum LoadTerm {
    None,
    /// Computed once.
    Constant,
    /// Nodal values every step, times the full-mesh mass.
    General {
        expr: Box<[Expression; 2]>,
        mass: FullMass,
        nodal: Vec<f64>,
    },
}

/// The diagnostics of one step `u^n → u^{n+1}`.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct PlaneRecord {
    /// `n + 1`.
    pub step: usize,
    /// `t_{n+1}`.
    pub time: f64,
    /// `E^{n+1/2}`.
    pub energy: f64,
    /// `½ F^n·(u^{n+1} − u^{n−1})`.
    pub work: f64,
    /// `α/(4Δt) |u^{n+1} − u^{n−1}|²_K`.
    pub viscous_dissipation: f64,
    /// The identity's relative residual (0 for the start-up step, which has no `E^{−1/2}`).
    pub identity_residual: f64,
    /// The contact figures (all 0 without Signorini edges; the start-up step's dissipation
    /// is 0, it has no `u^{−1}`).
    pub contact: ContactStep,
}

/// A running plane simulation; [`PlaneSimulation::step`] allocates nothing.
pub struct PlaneSimulation {
    disc: PlaneDiscretisation,
    chol: SparseCholesky,
    /// The Signorini edges' contact solver (`None` without contact normals, but for OSQP,
    /// which then solves the unconstrained problem, as the bar's does).
    contact: Option<Contact>,
    method: ContactMethod,
    load: LoadTerm,
    n: usize,
    /// `u^n`, `w = u^n − u^{n−1}` on the unknowns.
    u: Vec<f64>,
    w: Vec<f64>,
    z: Vec<f64>,
    rhs: Vec<f64>,
    force: Vec<f64>,
    /// `E^{n−1/2}` and `|u^n|²_K`.
    energy: f64,
    potential: f64,
    first_record: PlaneRecord,
    /// `u_0`, `u_1` at every full degree of freedom (for the output at `t = 0`).
    initial: (Vec<f64>, Vec<f64>),
    /// Wall time per phase of the sampled steps (the bar's [`PhaseTimes`]).
    timing: PhaseTimes,
}

impl PlaneSimulation {
    /// Sets up a run of `scene` with the contact solver its `[solver]` table names
    /// ([`ContactMethod::from_spec`]) and takes the start-up step to `u^1`:
    /// `u^1 = u^0 + Δt u_1 + Δt²/2 M⁻¹(F^0 − K u^0 − α K u_1)` (Taylor, second order for
    /// smooth data), projected onto the admissible set with Signorini edges.
    pub fn new(scene: &PlaneScene) -> Result<Self, PlaneError> {
        Self::with_method(scene, ContactMethod::from_spec(&scene.solver))
    }

    /// [`PlaneSimulation::new`] with the contact problems solved by `method` instead of the
    /// scene's. Without Signorini edges `exact` and `penalty` are the one sparse solve and
    /// `osqp` runs OSQP on the unconstrained problem (the bar's behaviour).
    pub fn with_method(scene: &PlaneScene, method: ContactMethod) -> Result<Self, PlaneError> {
        scene.validate()?;
        let exprs = scene.expressions()?;
        let gaps = scene.edges.gaps()?;
        let disc = PlaneDiscretisation::new(scene);
        let grid = &disc.grid;
        let nodal = |e: &[Expression; 2], t: f64, out: &mut [f64]| -> Result<(), PlaneError> {
            for node in 0..grid.nodes() {
                let (x, y) = grid.point(node);
                for c in 0..2 {
                    out[2 * node + c] = e[c].eval_xy(x, y, t)?;
                }
            }
            Ok(())
        };
        let mut u0_full = vec![0.0; grid.dofs()];
        let mut v0_full = vec![0.0; grid.dofs()];
        nodal(&exprs.displacement, 0.0, &mut u0_full)?;
        nodal(&exprs.velocity, 0.0, &mut v0_full)?;
        for (d, i) in disc.index.iter().enumerate() {
            if i.is_none() {
                (u0_full[d], v0_full[d]) = (0.0, 0.0);
            }
        }
        let normals = normals(&disc.grid, &disc.index, &gaps, &u0_full)?;
        let n = disc.unknowns();
        let mut force = vec![0.0; n];
        let load = match exprs.load {
            None => LoadTerm::None,
            Some(expr) => {
                let full = assemble(grid, disc.material);
                let mass = FullMass {
                    pattern: full.pattern,
                    values: full.mass,
                };
                let mut nodal_values = vec![0.0; grid.dofs()];
                nodal(&expr, 0.0, &mut nodal_values)?;
                disc.load_rows_into(&mass, &nodal_values, &mut force);
                if expr.iter().any(Expression::depends_on_t) {
                    LoadTerm::General {
                        expr: Box::new(expr),
                        mass,
                        nodal: nodal_values,
                    }
                } else {
                    LoadTerm::Constant
                }
            }
        };
        let restrict = |v: &[f64]| disc.free.iter().map(|&d| v[d]).collect::<Vec<f64>>();
        let (u0, v0) = (restrict(&u0_full), restrict(&v0_full));
        // Start-up: the acceleration M⁻¹(F^0 − K u0 − α K v0), M factorised on the pattern
        // that C then reuses.
        let (dt, alpha) = (disc.dt, disc.alpha);
        let mut ku = vec![0.0; n];
        let mut kv = vec![0.0; n];
        disc.pattern.mul_into(&disc.stiffness, &u0, &mut ku);
        disc.pattern.mul_into(&disc.stiffness, &v0, &mut kv);
        let mut acc: Vec<f64> = (0..n).map(|i| force[i] - ku[i] - alpha * kv[i]).collect();
        let mut chol = SparseCholesky::new(&disc.pattern, &disc.mass, "M")?;
        chol.solve_in_place(&mut acc);
        let c = disc.step_matrix();
        chol.factor(&disc.pattern, &c, "C")?;
        let mut z: Vec<f64> = (0..n)
            .map(|i| dt * v0[i] + 0.5 * dt * dt * acc[i])
            .collect();
        // With contact, the Taylor step is projected onto the admissible set in the C-norm
        // (the step problem with b = C z_T), as the bar's start-up does.
        let mut contact_step = ContactStep::default();
        let contact = if normals.is_empty() && !matches!(method, ContactMethod::Osqp(_)) {
            None
        } else {
            let mut contact = Contact::new(normals, &mut chol, method, &disc.pattern, &c)?;
            let mut b = vec![0.0; n];
            disc.pattern.mul_into(&c, &z, &mut b);
            let iterations = contact.step(&mut chol, &b, &u0, &mut z, 1)?;
            let u1: Vec<f64> = u0.iter().zip(&z).map(|(a, b)| a + b).collect();
            contact_step = ContactStep {
                dissipation: 0.0,
                ..contact.measure(&u1, &z, &vec![0.0; n], iterations)
            };
            Some(contact)
        };
        let u: Vec<f64> = u0.iter().zip(&z).map(|(a, b)| a + b).collect();
        let potential0 = disc.forms.quad(&u0);
        let potential = disc.forms.quad(&u);
        let energy =
            0.5 * disc.pattern.quad(&disc.mass, &z) / (dt * dt) + 0.25 * (potential + potential0);
        if !energy.is_finite() {
            return Err(PlaneError::NonFinite { step: 1, time: dt });
        }
        let first_record = PlaneRecord {
            step: 1,
            time: dt,
            energy,
            contact: contact_step,
            ..Default::default()
        };
        Ok(Self {
            chol,
            contact,
            method,
            load,
            n: 1,
            u,
            w: z,
            z: vec![0.0; n],
            rhs: vec![0.0; n],
            force,
            energy,
            potential,
            first_record,
            initial: (u0_full, v0_full),
            disc,
            timing: PhaseTimes::default(),
        })
    }

    /// `F^n` into `self.force` (a time-dependent load only).
    fn update_force(&mut self, n: usize) -> Result<(), PlaneError> {
        if let LoadTerm::General { expr, mass, nodal } = &mut self.load {
            let t = n as f64 * self.disc.dt;
            let grid = &self.disc.grid;
            for node in 0..grid.nodes() {
                let (x, y) = grid.point(node);
                for c in 0..2 {
                    nodal[2 * node + c] = expr[c].eval_xy(x, y, t)?;
                }
            }
            self.disc.load_rows_into(mass, nodal, &mut self.force);
        }
        Ok(())
    }

    /// Advances `u^n → u^{n+1}` (one solve with `C`, the sparse products of the right-hand
    /// side, the energy balance) and returns the step's diagnostics. Allocates nothing.
    pub fn step(&mut self) -> Result<PlaneRecord, PlaneError> {
        let n = self.n;
        let clock = PhaseClock::start(self.timing.samples(n));
        self.update_force(n)?;
        let d = &self.disc;
        let terms = RhsTerms {
            pattern: &d.pattern,
            mass: &d.mass,
            stiffness: &d.stiffness,
            inv_dt2: 1.0 / (d.dt * d.dt),
            c_w: 0.5 - d.alpha / (2.0 * d.dt),
        };
        rhs_into(&terms, &self.u, &self.w, &self.force, &mut self.rhs);
        let clock = clock.lap(&mut self.timing.rhs_ns);
        let mut iterations = 0;
        if let Some(contact) = &mut self.contact {
            iterations = contact.step(&mut self.chol, &self.rhs, &self.u, &mut self.z, n + 1)?;
        } else {
            self.z.copy_from_slice(&self.rhs);
            self.chol.solve_in_place(&mut self.z);
        }
        for (u, z) in self.u.iter_mut().zip(&self.z) {
            *u += z;
        }
        let clock = clock.lap(&mut self.timing.solve_ns);
        let contact = self
            .contact
            .as_ref()
            .map(|c| c.measure(&self.u, &self.z, &self.w, iterations))
            .unwrap_or_default();
        let sums = measure(
            &d.pattern,
            &d.mass,
            &d.forms,
            &self.u,
            &self.z,
            &self.w,
            &self.force,
        );
        let Balance {
            energy,
            work,
            viscous,
            residual,
            ..
        } = balance(
            &sums,
            self.energy,
            self.potential,
            d.dt,
            d.alpha,
            contact.dissipation,
        );
        let time = (n + 1) as f64 * d.dt;
        if !(energy.is_finite() && residual.is_finite()) {
            return Err(PlaneError::NonFinite { step: n + 1, time });
        }
        self.energy = energy;
        self.potential = sums.potential;
        std::mem::swap(&mut self.w, &mut self.z);
        self.n = n + 1;
        clock.lap(&mut self.timing.diagnostics_ns);
        Ok(PlaneRecord {
            step: n + 1,
            time,
            energy,
            work,
            viscous_dissipation: viscous,
            identity_residual: residual,
            contact,
        })
    }

    /// The contact solver (`None` without Signorini edges): normals, `S`, last reactions.
    pub fn contact(&self) -> Option<&Contact> {
        self.contact.as_ref().filter(|c| !c.is_empty())
    }

    /// The method solving the step problems (named even without Signorini edges).
    pub fn method(&self) -> ContactMethod {
        self.method
    }

    /// OSQP's audit so far and its accepted "solved inaccurate" steps (OSQP only, with or
    /// without contact normals).
    pub fn osqp_report(&self) -> Option<(&AuditReport, u64)> {
        let c = self.contact.as_ref()?;
        Some((c.audit()?, c.inaccurate_steps()?))
    }

    /// The record of the start-up step.
    pub fn first_record(&self) -> PlaneRecord {
        self.first_record
    }

    pub fn discretisation(&self) -> &PlaneDiscretisation {
        &self.disc
    }

    /// Wall time spent in each phase of the steps taken so far, measured on a sample of the
    /// steps: `rhs` (load and right-hand side), `solve` (the solve with the factor of `C` or
    /// the contact solver, and `u += z`), `diagnostics` (contact figures, energy balance).
    pub fn phase_times(&self) -> PhaseTimes {
        self.timing
    }

    /// `n`: the state held is `u^n`.
    pub fn step_index(&self) -> usize {
        self.n
    }

    pub fn time(&self) -> f64 {
        self.n as f64 * self.disc.dt
    }

    /// Stored values of the factor of `C`.
    pub fn factor_len(&self) -> usize {
        self.chol.factor_len()
    }

    /// `u^n` at every full degree of freedom (`2 node + c`; clamped ones 0).
    pub fn displacement_into(&self, out: &mut [f64]) {
        out.fill(0.0);
        for (&d, u) in self.disc.free.iter().zip(&self.u) {
            out[d] = *u;
        }
    }

    /// `(u^n − u^{n−1})/Δt` at every full degree of freedom: the velocity at `t_{n−1/2}`.
    pub fn velocity_into(&self, out: &mut [f64]) {
        out.fill(0.0);
        let inv = 1.0 / self.disc.dt;
        for (&d, w) in self.disc.free.iter().zip(&self.w) {
            out[d] = w * inv;
        }
    }

    /// `u^n` at every full degree of freedom.
    pub fn displacement(&self) -> Vec<f64> {
        let mut out = vec![0.0; self.disc.grid.dofs()];
        self.displacement_into(&mut out);
        out
    }

    /// `u_0` and `u_1` at every full degree of freedom (0 on clamped edges).
    pub fn initial_state(&self) -> (&[f64], &[f64]) {
        (&self.initial.0, &self.initial.1)
    }

    /// The unknowns `u^n`.
    pub fn unknowns(&self) -> &[f64] {
        &self.u
    }

    /// The solve with `C` alone, for the benches: `x ← C⁻¹ x` (allocates nothing).
    pub fn solve_in_place(&mut self, x: &mut [f64]) {
        self.chol.solve_in_place(x);
    }
}
