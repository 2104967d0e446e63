//! The scheme's state, its start-up step and its step, for any [`Body`]: see [`Scheme::step`].

use crate::linalg::tridiag::dot;
use crate::scheme::body::{Body, EnergySums, HeatTerms};
use crate::scheme::clock::{PhaseClock, PhaseTimes};
use crate::scheme::contact::{ContactSet, ContactState};
use crate::scheme::error::RunError;
use crate::scheme::load::Load;
use crate::step::solver::add_in_place;
use crate::step::{SolverReport, StepFailure, StepSolver};

/// The diagnostics of one step `u^n → u^{n+1}`.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct StepRecord {
    /// `n + 1`.
    pub step: usize,
    /// `t_{n+1}`.
    pub time: f64,
    /// Whether the energy identity was measured at this step (`[output] diagnostics_every`);
    /// when not, `energy` … `identity_residual` are 0 and mean nothing.
    pub measured: bool,
    /// `E^{n+1/2}`.
    pub energy: f64,
    /// `½ F^n·(u^{n+1} − u^{n−1})`.
    pub work: f64,
    /// `α/(4Δt) |u^{n+1} − u^{n−1}|²_K >= 0`.
    pub viscous_dissipation: f64,
    /// `D = −½ Σ_k r_k (s_k (u^{n+1} − u^{n−1})_{i_k} + g_k^{n+1} − g_k^{n−1}) >= 0`.
    pub contact_dissipation: f64,
    /// `|E^{n+1/2} − E^{n−1/2} − work − obstacle_work − sliding_work + viscous + D + D_f|` over
    /// the largest of those terms (with a temperature: `+ thermal dissipation + exchange +
    /// smoothing − supply − frictional supply`, [`HeatTerms`]), or over the run's energy
    /// resolution `ENERGY_RESOLUTION` times the largest term measured so far where that is
    /// larger.
    pub identity_residual: f64,
    /// The bound the run's certificate holds `identity_residual` to on a measured step: the
    /// body's round-off tolerance plus the step solver's allowance ([`crate::scheme::certify`]).
    pub identity_bound: f64,
    /// `W = −½ Σ_k r_k (g_k^{n+1} − g_k^{n−1})`, the work of moving obstacles (0 when none
    /// moves; of either sign).
    pub obstacle_work: f64,
    /// `D_f = −½ Σ_j r_T,j δ_j >= 0`, the friction dissipation (0 without friction), `δ_j`
    /// relative to a sliding obstacle.
    pub friction_dissipation: f64,
    /// `W_T = ½ Σ_j r_T,j v_j`, the work of obstacles sliding along their edges (0 when none
    /// slides; of either sign).
    pub sliding_work: f64,
    /// Frictional nodes in contact that stick and that slip (`crate::scheme::friction`).
    pub stick_nodes: usize,
    pub slip_nodes: usize,
    /// The thermal terms of a body with a temperature (measured steps; `E^{1/2}`'s at the
    /// start-up step).
    pub heat: Option<HeatTerms>,
    /// The contact state of `u^{n+1}`.
    pub contact: ContactState,
    /// The step solver's iterations (active sets tried, ADMM iterations…).
    pub iterations: u32,
}

/// What a body sets up for a run ([`Scheme::unstarted`]).
pub struct Setup<B> {
    pub body: B,
    /// Built for the body's `C` and `contact.constraints()`.
    pub solver: Box<dyn StepSolver>,
    pub contact: ContactSet,
    pub load: Load,
    /// `u_0` and `u_1` on the unknowns; `u_0` admissible.
    pub displacement: Vec<f64>,
    pub velocity: Vec<f64>,
    /// `N`: the run ends at `u^N`.
    pub steps: usize,
    /// Measure the energy identity at steps `k · diagnostics_every` and at the last.
    pub diagnostics_every: usize,
}

/// `E^{n−1/2}` and `|u^n|²_K`, valid when `measured` (the last step was measured), and the
/// largest term of any identity measured so far (`E^{1/2}` at first).
#[derive(Clone, Copy, Debug)]
struct Balance {
    energy: f64,
    potential: f64,
    measured: bool,
    largest: f64,
}

/// The energy resolution of a run, in units of the largest term its identity has held: the
/// terms are sums rounded to `ε` of their size, so a step whose terms have all fallen below
/// `ε` times that size (a body brought to rest, its increments the rounding of its
/// displacement) is measured against it, not against its own rounding noise.
pub const ENERGY_RESOLUTION: f64 = f64::EPSILON;

/// A running simulation of a body: holds `u^n` and `w = u^n − u^{n−1}`; [`Scheme::step`]
/// advances one step and allocates nothing.
pub struct Scheme<B: Body> {
    body: B,
    solver: Box<dyn StepSolver>,
    contact: ContactSet,
    load: Load,
    /// `n`: the state held is `u^n`.
    n: usize,
    u: Vec<f64>,
    w: Vec<f64>,
    z: Vec<f64>,
    b: Vec<f64>,
    lower: Vec<f64>,
    reactions: Vec<f64>,
    /// Each frictional node's share of the step's `D_f`, for a body whose heat step follows
    /// its mechanics ([`Body::heat_step`]; empty otherwise).
    friction_work: Vec<f64>,
    balance: Balance,
    diagnostics_every: usize,
    last_step: usize,
    timing: PhaseTimes,
    first_record: StepRecord,
}

/// A displacement and a velocity per unknown: `u` and `w · scale`.
#[derive(Clone, Copy, Debug)]
pub struct State<'a> {
    pub u: &'a [f64],
    pub w: &'a [f64],
    pub scale: f64,
}

impl<B: Body> Scheme<B> {
    /// The scheme set up, `u^0` held, the start-up step not taken ([`Unstarted::start`]).
    pub fn unstarted(setup: Setup<B>) -> Unstarted<B> {
        let n = setup.body.unknowns();
        let (k, reactions) = (setup.contact.len(), setup.contact.reaction_len());
        let frictional = if setup.body.has_temperature() {
            setup.contact.friction().len()
        } else {
            0
        };
        let scheme = Self {
            solver: setup.solver,
            contact: setup.contact,
            load: setup.load,
            n: 0,
            u: setup.displacement,
            w: vec![0.0; n],
            z: vec![0.0; n],
            b: vec![0.0; n],
            lower: vec![0.0; k],
            reactions: vec![0.0; reactions],
            friction_work: vec![0.0; frictional],
            balance: Balance {
                energy: 0.0,
                potential: 0.0,
                measured: true,
                largest: 0.0,
            },
            diagnostics_every: setup.diagnostics_every.max(1),
            last_step: setup.steps,
            timing: PhaseTimes::default(),
            first_record: StepRecord::default(),
            body: setup.body,
        };
        Unstarted {
            scheme,
            v0: setup.velocity,
        }
    }

    /// [`Scheme::unstarted`] and the start-up step.
    pub fn from_setup(setup: Setup<B>) -> Result<Self, RunError> {
        Self::unstarted(setup).start()
    }

    /// The start-up step to `u^1`: the Taylor step
    /// `u^1_T = u^0 + Δt u_1 + Δt²/2 M⁻¹(F^0 − K u^0 − α K u_1)`, second order for smooth data,
    /// projected onto `K_h` in the `C`-norm by the step problem with `b = C (u^1_T − u^0)`, so
    /// `u^1` is admissible. With friction the projection obeys Coulomb's law on the slip
    /// `u^1 − u^0` (the previous increment taken as 0), and the record's `D_f` is the friction
    /// work over the step, `−Σ_j r_T,j (u^1 − u^0)_{t_j} >= 0` (docs/friction.md, "The start-up
    /// step"). `z`, `w` and `b` serve as its work space.
    fn start_up(&mut self, v0: &[f64]) -> Result<(), RunError> {
        let (dt, alpha) = (self.body.dt(), self.body.viscosity());
        self.contact.advance_gaps(dt)?;
        if let Some(slide) = self.contact.slide() {
            self.solver.set_obstacle_slide(slide.displacement());
        }
        self.contact.lower_bounds_into(&self.u, &mut self.lower);
        self.body.prepare_step(0, &self.lower, &self.w)?;
        // a = M⁻¹ (F^0 − K u^0 − α K u_1), in z.
        let (acc, kv) = (&mut self.z, &mut self.b);
        self.body.stiffness_mul(&self.u, acc);
        self.body.stiffness_mul(v0, kv);
        let force = self.load.force();
        for i in 0..acc.len() {
            // `0.0 − …` without a load: the bits of a zero force vector.
            let f = force.map_or(0.0, |f| f[i]);
            acc[i] = f - acc[i] - alpha * kv[i];
        }
        self.body.solve_mass(acc)?;
        // The Taylor increment, in w (w becomes the increment z after the step).
        for i in 0..acc.len() {
            self.w[i] = dt * v0[i] + 0.5 * dt * dt * acc[i];
        }
        self.body.complete_start_up(&self.u, v0, &mut self.w)?;
        self.body.step_matrix_mul(&self.w, &mut self.b)?;
        // The start-up's slip is u^1 − u^0: a frictional solver's previous increment is 0.
        self.z.fill(0.0);
        self.solver.set_previous_increment(&self.z);
        let info = (self.solver)
            .solve(&self.b, &self.lower, &mut self.z, &mut self.reactions)
            .map_err(|failure| self.failure(1, failure))?;
        // The friction work over the start-up, `−r_T,j (u^1 − u^0)_{t_j}`, and the heat step.
        let work = &mut self.friction_work;
        (self.contact).friction_work_into(&self.reactions, (&self.z, None), 1.0, work);
        self.body
            .heat_step(0, (&self.z, None), &self.friction_work)?;
        let potential0 = self.body.stiffness_form(&self.u);
        add_in_place(&mut self.u, &self.z);
        self.body.mass_mul(&self.z, &mut self.b);
        let potential = self.body.stiffness_form(&self.u);
        let mut energy =
            0.5 * dot(&self.z, &self.b) * (1.0 / (dt * dt)) + 0.25 * (potential + potential0);
        let heat = self.body.start_up_heat(&self.u);
        if let Some(h) = heat {
            energy += h.energy;
        }
        if !energy.is_finite() {
            return Err(self.failure(1, StepFailure::NonFinite));
        }
        self.balance = Balance {
            energy,
            potential,
            measured: true,
            largest: energy.abs(),
        };
        let mut record = StepRecord {
            step: 1,
            time: dt,
            measured: true,
            energy,
            identity_bound: self.identity_bound(),
            heat,
            iterations: info.iterations,
            ..Default::default()
        };
        let state = (&self.u[..], &self.z[..], &self.w[..], &self.reactions[..]);
        self.contact.measure(state, false, &mut record.contact);
        // The slip u^1 − u^0 is z: w (the Taylor increment, no longer needed) becomes 0.
        self.w.fill(0.0);
        let state = (&self.u[..], &self.z[..], &self.w[..], &self.reactions[..]);
        let friction = self.contact.measure_friction(state, true);
        (record.stick_nodes, record.slip_nodes) = (friction.stick_nodes, friction.slip_nodes);
        // measure_friction's −½ Σ r_T δ of a central slip, doubled: the work over one step.
        record.friction_dissipation = 2.0 * friction.dissipation;
        std::mem::swap(&mut self.w, &mut self.z);
        self.n = 1;
        self.first_record = record;
        Ok(())
    }

    /// Advances `u^n → u^{n+1}` by the talk's scheme (VI)_h and returns the step's record.
    ///
    /// The scheme (talk, "Numerical scheme") is the inclusion
    ///
    /// ```text
    ///   M (u^{n+1} − 2u^n + u^{n−1})/Δt² + K (u^{n+1} + u^{n−1})/2 + α K (u^{n+1} − u^{n−1})/(2Δt)
    ///       = F^n + Σ_k r_k s_k e_{i_k},   0 <= s_k u^{n+1}_{i_k} + g_k ⊥ r_k >= 0,
    /// ```
    ///
    /// that is `u^{n+1} = argmin over K_h of ½ uᵀCu − F̃ⁿᵀu`, `C = M/Δt² + K/2 + αK/(2Δt)`. It is
    /// solved for the increment `z = u^{n+1} − u^n`, `w = u^n − u^{n−1}`:
    ///
    /// 1. `K_h` in the increment: `s_k z_{i_k} >= lo_k = −g_k − s_k u^n_{i_k}`, the one place
    ///    where a moving obstacle's gap `g_k(t_{n+1})` is read ([`Body::prepare_step`] takes
    ///    these bounds);
    /// 2. `F^n` ([`Load`]) and `b = F^n + M w/Δt² + K((½ − α/(2Δt)) w − u^n)` ([`Body::rhs_into`]):
    ///    algebraically `F̃^n − C u^n`, but without the `O(|u|/Δt²)` terms that cancel there, so
    ///    the round-off in `z` is relative to the increment, not to the displacement;
    /// 3. `z = argmin ½ zᵀCz − bᵀz` over those bounds, with the reactions `r_k` its multipliers,
    ///    by the run's step solver, then `u^{n+1} = u^n + z`;
    /// 4. the contact state of `u^{n+1}` and, on measured steps, the energy identity
    ///    (multiply the scheme by `(u^{n+1} − u^{n−1})/2`)
    ///
    /// ```text
    ///   E^{n+1/2} − E^{n−1/2} = ½ F^n·δ − α/(4Δt) |δ|²_K − D,   δ = u^{n+1} − u^{n−1},
    ///   E^{n+1/2} = ½ |(u^{n+1} − u^n)/Δt|²_M + ¼ (|u^{n+1}|²_K + |u^n|²_K),
    /// ```
    ///
    ///    `D = −½ Σ_k r_k s_k δ_{i_k} = ½ Σ_k r_k (s_k u^{n−1}_{i_k} + g_k) >= 0` by
    ///    complementarity and the admissibility of `u^{n−1}`: contact only dissipates. A moving
    ///    obstacle adds its work `W = −½ Σ_k r_k (g_k^{n+1} − g_k^{n−1})` to the right-hand
    ///    side and `g^{n+1} − g^{n−1}` to `D`'s bracket ([`ContactSet::advance_gaps`],
    ///    [docs/moving-obstacles.md](../../docs/moving-obstacles.md)). With friction the
    ///    right-hand side also loses `D_f = −½ Σ_j r_T,j δ_{t_j} >= 0`
    ///    (`crate::scheme::friction`); the solver reads `w` for the central slip. An obstacle
    ///    sliding along its edge by `v_j` makes the slip relative and adds its work
    ///    `W_T = ½ Σ_j r_T,j v_j` ([`crate::scheme::Slide`]).
    ///
    /// The identity is measured every `[output] diagnostics_every`-th step and at the last; a
    /// measured step after an unmeasured one first recomputes `E^{n−1/2}` from `u^n` and `w`,
    /// so every measured identity is a one-step identity.
    pub fn step(&mut self) -> Result<StepRecord, RunError> {
        let n = self.n;
        let clock = PhaseClock::start(self.timing.samples(n));
        let measure = (n + 1).is_multiple_of(self.diagnostics_every) || n + 1 == self.last_step;
        if measure && !self.balance.measured {
            self.restart_balance();
        }
        // 1. The bounds of the increment (moving obstacles first moved to t_{n+1}): every
        //    consumer of contact (the body's data, the solver, the measures) reads them.
        self.contact.advance_gaps((n + 1) as f64 * self.body.dt())?;
        self.contact.lower_bounds_into(&self.u, &mut self.lower);
        // 2. F^n and b.
        self.body.prepare_step(n, &self.lower, &self.w)?;
        self.load.update(&self.body, n)?;
        let force = self.load.force();
        self.body.rhs_into(&self.u, &self.w, force, &mut self.b);
        let clock = clock.lap(&mut self.timing.rhs_ns);
        // 3. The constrained minimisation, and u^{n+1} = u^n + z.
        self.solver.set_previous_increment(&self.w);
        if let Some(slide) = self.contact.slide() {
            self.solver.set_obstacle_slide(slide.displacement());
        }
        let info = (self.solver)
            .solve_and_advance(
                &self.b,
                &self.lower,
                &mut self.z,
                &mut self.reactions,
                &mut self.u,
            )
            .map_err(|failure| self.failure(n + 1, failure))?;
        // A temperature that follows the mechanics takes its step, heated by friction.
        let work = &mut self.friction_work;
        (self.contact).friction_work_into(&self.reactions, (&self.z, Some(&self.w)), 0.5, work);
        let increments = (&self.z[..], Some(&self.w[..]));
        self.body.heat_step(n, increments, &self.friction_work)?;
        let clock = clock.lap(&mut self.timing.solve_ns);
        // 4. The contact state and the energy identity.
        let mut record = StepRecord {
            step: n + 1,
            time: (n + 1) as f64 * self.body.dt(),
            measured: measure,
            iterations: info.iterations,
            ..Default::default()
        };
        let state = (&self.u[..], &self.z[..], &self.w[..], &self.reactions[..]);
        let contact = self.contact.measure(state, measure, &mut record.contact);
        let friction = self.contact.measure_friction(state, measure);
        (record.stick_nodes, record.slip_nodes) = (friction.stick_nodes, friction.slip_nodes);
        if measure {
            let sums = (self.body).energy_sums(&self.u, &self.z, &self.w, self.load.force());
            record.obstacle_work = self.contact.obstacle_work(&self.reactions);
            record.sliding_work = self.contact.sliding_work(&self.reactions);
            let heat = self.body.heat_terms(&self.u, &self.z, &self.w);
            self.close_balance(&mut record, sums, [contact, friction.dissipation], heat)?;
        }
        if !measure && self.body.heat_outputs().heat_content {
            // A heat balance is kept at every step.
            record.heat = self.body.heat_terms(&self.u, &self.z, &self.w);
        }
        self.balance.measured = measure;
        std::mem::swap(&mut self.w, &mut self.z);
        self.n = n + 1;
        clock.lap(&mut self.timing.diagnostics_ns);
        Ok(record)
    }

    /// `E^{n−1/2}` and `|u^n|²_K` from `u^n` and `w` (`u^{n−1} = u^n − w`), after steps whose
    /// identity was not measured.
    fn restart_balance(&mut self) {
        let dt = self.body.dt();
        let potential = self.body.stiffness_form(&self.u);
        let before = self.body.stiffness_form_of_difference(&self.u, &self.w);
        self.balance.potential = potential;
        self.balance.energy =
            0.5 * self.body.mass_form(&self.w) * (1.0 / (dt * dt)) + 0.25 * (potential + before);
        if let Some(heat) = self.body.heat_energy(&self.u) {
            self.balance.energy += heat;
        }
    }

    /// The energy identity of the step just taken from its sums, the contact term `D` and the
    /// friction term `D_f` and the thermal terms of a body with a temperature, into `record`;
    /// the balance moves on to `n + 1`.
    fn close_balance(
        &mut self,
        record: &mut StepRecord,
        sums: EnergySums,
        [contact, friction]: [f64; 2],
        heat: Option<HeatTerms>,
    ) -> Result<(), RunError> {
        let (dt, alpha) = (self.body.dt(), self.body.viscosity());
        let before = self.balance.energy;
        let mut energy = 0.5 * sums.kinetic * (1.0 / (dt * dt))
            + 0.25 * (sums.potential + self.balance.potential);
        if let Some(h) = heat {
            energy += h.energy;
        }
        let viscous = if alpha > 0.0 {
            alpha / (4.0 * dt) * sums.viscous
        } else {
            0.0
        };
        let work = 0.5 * sums.work;
        let (obstacle, sliding) = (record.obstacle_work, record.sliding_work);
        // Subtracting a zero obstacle work is exact: fixed obstacles keep their bits.
        let mut residual =
            energy - before - work - obstacle - sliding + viscous + contact + friction;
        let mut scale = [
            energy,
            before,
            work.abs(),
            viscous,
            contact.abs(),
            obstacle.abs(),
            friction.abs(),
            sliding.abs(),
        ]
        .into_iter()
        .fold(0.0, f64::max);
        if let Some(h) = heat {
            // A zero smoothing term (Crank–Nicolson steps) adds nothing: their bits stay.
            residual += h.dissipation + h.exchange + h.smoothing - h.supply;
            // Zero without friction heating the body: the thermal bar keeps its bits.
            residual -= h.frictional_supply;
            let heating = h.frictional_supply.abs();
            scale = [
                h.dissipation,
                h.exchange.abs(),
                h.supply.abs(),
                h.smoothing,
                heating,
            ]
            .into_iter()
            .fold(scale, f64::max);
        }
        if !(energy.is_finite() && residual.is_finite()) {
            return Err(self.failure(record.step, StepFailure::NonFinite));
        }
        self.balance.largest = self.balance.largest.max(scale);
        let scale = scale.max(ENERGY_RESOLUTION * self.balance.largest);
        record.energy = energy;
        record.work = work;
        record.viscous_dissipation = viscous;
        record.contact_dissipation = contact;
        record.friction_dissipation = friction;
        record.heat = heat;
        record.identity_residual = if scale > 0.0 {
            residual.abs() / scale
        } else {
            0.0
        };
        record.identity_bound = self.identity_bound();
        self.balance.potential = sums.potential;
        self.balance.energy = energy;
        Ok(())
    }

    /// The bound of this step's identity residual: the body's round-off tolerance and what the
    /// solver's law allows its answers ([`crate::scheme::certify`]).
    fn identity_bound(&self) -> f64 {
        self.body.identity_tolerance() + self.solver.identity_allowance()
    }

    fn failure(&self, step: usize, failure: StepFailure) -> RunError {
        RunError::Step {
            step,
            time: step as f64 * self.body.dt(),
            solver: self.solver.name().to_string(),
            failure,
        }
    }

    /// The body.
    pub fn body(&self) -> &B {
        &self.body
    }

    /// The constraints.
    pub fn contact(&self) -> &ContactSet {
        &self.contact
    }

    /// Whether something can feed energy in: a load, a moving or sliding obstacle, or a
    /// temperature (heat may come in through the ends, a source or an exchange); without any a
    /// run cannot gain energy.
    pub fn is_forced(&self) -> bool {
        self.load.force().is_some()
            || self.contact.is_moving()
            || self.contact.is_sliding()
            || self.body.has_temperature()
    }

    /// The load vector `F^n` on the unknowns (zeros without a load), as the step from `t_n`
    /// uses it (for checks of the load path; the next step recomputes its own).
    pub fn load_vector(&mut self, n: usize) -> Result<Vec<f64>, RunError> {
        self.load.update(&self.body, n)?;
        Ok(match self.load.force() {
            Some(f) => f.to_vec(),
            None => vec![0.0; self.u.len()],
        })
    }

    /// The record of the start-up step (`E^{1/2}`, the contact state of `u^1`).
    pub fn first_record(&self) -> StepRecord {
        self.first_record
    }

    /// The step solver's name in outputs (`exact`, `osqp`, `penalty`).
    pub fn solver_name(&self) -> &'static str {
        self.solver.name()
    }

    /// The step solver's own statistics (audit residuals…), if it keeps any.
    pub fn solver_report(&self) -> Option<SolverReport> {
        self.solver.report()
    }

    /// Wall time spent in each phase of the steps taken so far, measured on a sample of the
    /// steps (`PhaseTimes`).
    pub fn phase_times(&self) -> PhaseTimes {
        self.timing
    }

    /// `n`: the state held is `u^n`.
    pub fn step_index(&self) -> usize {
        self.n
    }

    /// `t_n`.
    pub fn time(&self) -> f64 {
        self.n as f64 * self.body.dt()
    }

    /// `u^n` on the unknowns.
    pub fn displacement(&self) -> &[f64] {
        &self.u
    }

    /// The degrees of freedom of the mesh, clamped ones included.
    pub fn dofs(&self) -> usize {
        self.body.nodes() * self.body.components()
    }

    /// `u^n` at every degree of freedom of the mesh (`components · node + c`; clamped ones 0).
    pub fn displacement_into(&self, out: &mut [f64]) {
        for (dof, o) in out.iter_mut().enumerate() {
            *o = self.body.unknown_of(dof).map_or(0.0, |i| self.u[i]);
        }
    }

    /// [`Scheme::displacement_into`] as a new vector.
    pub fn displacement_dofs(&self) -> Vec<f64> {
        let mut out = vec![0.0; self.dofs()];
        self.displacement_into(&mut out);
        out
    }

    /// The velocity `(u^n − u^{n−1})/Δt` at `t_{n−1/2}` at every degree of freedom of the mesh.
    pub fn velocity_into(&self, out: &mut [f64]) {
        let scale = 1.0 / self.body.dt();
        for (dof, o) in out.iter_mut().enumerate() {
            *o = self.body.unknown_of(dof).map_or(0.0, |i| self.w[i] * scale);
        }
    }

    /// `u^n` and the velocity `(u^n − u^{n−1})/Δt` at `t_{n−1/2}` on the unknowns.
    pub fn state(&self) -> State<'_> {
        State {
            u: &self.u,
            w: &self.w,
            scale: 1.0 / self.body.dt(),
        }
    }

    /// The reactions of the last step, one per constraint.
    pub fn reactions(&self) -> &[f64] {
        &self.reactions[..self.contact.len()]
    }

    /// The tangential reactions of the last step, one per frictional node (empty without).
    pub fn tangential_reactions(&self) -> &[f64] {
        &self.reactions[self.contact.len()..]
    }

    /// The last step's two increments `u^{n+1} − u^n` and the one before: their sum at a
    /// tangent is the slip that the step's record classifies
    /// ([`crate::scheme::ContactSet::node_state`]).
    pub fn increments(&self) -> [&[f64]; 2] {
        [&self.w, &self.z]
    }

    /// The gaps `s_k u^n_{i_k} + g_k` of every constraint.
    pub fn gaps_into(&self, out: &mut [f64]) {
        self.contact.gaps_into(&self.u, out);
    }
}

/// A scheme set up, `u^0` and `u_1` held, the start-up step not taken yet.
pub struct Unstarted<B: Body> {
    /// Holds `u^0` in `u`.
    scheme: Scheme<B>,
    /// `u_1` on the unknowns.
    v0: Vec<f64>,
}

impl<B: Body> Unstarted<B> {
    /// `u_0` and `u_1` on the unknowns.
    pub fn state(&self) -> State<'_> {
        State {
            u: &self.scheme.u,
            w: &self.v0,
            scale: 1.0,
        }
    }

    pub fn body(&self) -> &B {
        &self.scheme.body
    }

    pub fn contact(&self) -> &ContactSet {
        &self.scheme.contact
    }

    /// The set-up back, short of the start-up step: for a body that extends this one (the
    /// thermal bar takes the bar's body, solver, constraints, load and initial data).
    pub fn into_setup(self) -> Setup<B> {
        let Self { scheme, v0 } = self;
        Setup {
            body: scheme.body,
            solver: scheme.solver,
            contact: scheme.contact,
            load: scheme.load,
            displacement: scheme.u,
            velocity: v0,
            steps: scheme.last_step,
            diagnostics_every: scheme.diagnostics_every,
        }
    }

    /// Takes the start-up step to `u^1`: the Taylor step projected onto `K_h` in the `C`-norm.
    pub fn start(self) -> Result<Scheme<B>, RunError> {
        let Self { mut scheme, v0 } = self;
        scheme.start_up(&v0)?;
        Ok(scheme)
    }
}
