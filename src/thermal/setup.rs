//! Setting a thermal bar scene up: the bar's displacement, constraints and load as for the bar
//! without a temperature, the initial temperature, and the step solver of the coupled step
//! (the factorisations of each exchange state, formed once).

use crate::bar::{Kernels, Simulation};
use crate::scene::Expression;
use crate::scene::{Scene, SceneError};
use crate::scheme::{Body, Load, RunError, Scheme, Setup, Unstarted};
use crate::step::{Algorithm, EndEnumeration, Shape, StepSolver, algorithm_for};
use crate::thermal::body::ThermalBody;
use crate::thermal::solver::{CoupledSolver, DecoupledSolver};
use crate::thermal::system::CoupledEnds;

/// A run of a thermal bar scene: the scheme stepping the bar with a temperature.
pub type ThermalSimulation = Scheme<ThermalBody>;

impl Scheme<ThermalBody> {
    /// Sets up a run of `scene` (which has `[heat]`) and takes the start-up step.
    pub fn new(scene: &Scene) -> Result<Self, RunError> {
        Self::prepare(scene)?.start()
    }

    /// [`ThermalSimulation::new`] with the coupled block solve by the twisted twin or by the
    /// plain sweep as `kernels.twisted_solve` says (the same answers to round-off).
    pub fn with_kernels(scene: &Scene, kernels: Kernels) -> Result<Self, RunError> {
        Self::prepare_with(scene, kernels)?.start()
    }

    /// Sets `scene` up short of the start-up step.
    pub fn prepare(scene: &Scene) -> Result<Unstarted<ThermalBody>, RunError> {
        Self::prepare_with(scene, Kernels::TWINS)
    }

    fn prepare_with(scene: &Scene, kernels: Kernels) -> Result<Unstarted<ThermalBody>, RunError> {
        let Some(heat) = &scene.heat else {
            return Err(SceneError::Invalid {
                field: "heat".into(),
                value: "missing".into(),
                allowed: "the thermal bar needs a [heat] table".into(),
            }
            .into());
        };
        // The mechanical step, coupled or not, is the end enumeration the table gives.
        let Some(Algorithm::EndEnumeration) =
            algorithm_for(scene.solver.method, Shape::ThermalEnds)
        else {
            return Err(SceneError::Invalid {
                field: "solver.method".into(),
                value: format!("{:?}", scene.solver.method).to_lowercase(),
                allowed: "a scene with [heat] takes the exact step solver (\"exact\")".into(),
            }
            .into());
        };
        let expressions = heat.validate(scene.thermal_view(), scene.obstacle.is_some())?;
        let bar = Simulation::prepare_mechanics(scene)?.into_setup();
        let disc = bar.body.discretisation().clone();
        let constraints: Vec<(usize, f64)> =
            disc.constraints.iter().map(|c| (c.node, c.gap)).collect();
        let dx = disc.dx;
        let body = ThermalBody::new(
            bar.body,
            (heat.diffusivity, heat.coupling),
            expressions.clone(),
            &constraints,
        )?;
        let m = body.matrices().clone();
        // [u^0 | θ^0] and [u_1 | 0].
        let mut displacement = bar.displacement;
        let mut velocity = bar.velocity;
        for j in 0..m.n_t {
            let x = (m.t_first + j) as f64 * dx;
            let v = expressions.temperature.eval(x, 0.0)?;
            if !v.is_finite() {
                return Err(crate::scene::error::invalid(
                    "heat.temperature",
                    v,
                    "must be finite at every node",
                )
                .into());
            }
            displacement.push(v);
            velocity.push(0.0);
        }
        let exchange = body.exchange_constraints();
        let masks = 1usize << exchange.len();
        // Crank–Nicolson's matrices of every exchange state, then the implicit Euler steps'.
        let states = || {
            [false, true]
                .into_iter()
                .flat_map(|i| (0..masks).map(move |m| (m, i)))
        };
        let shared = (exchange, body.implicit_flag());
        let solver: Box<dyn StepSolver> = if m.gamma == 0.0 {
            let heat = states()
                .map(|(mask, implicit)| {
                    crate::linalg::Ldlt::factor(&m.step_heat_matrix(mask, implicit))
                })
                .collect::<Result<Vec<_>, _>>()?;
            Box::new(DecoupledSolver::new(bar.solver, heat, m.n_u, shared))
        } else {
            let mut variants: Vec<Box<dyn StepSolver>> = Vec::with_capacity(2 * masks);
            let unknowns = disc.constrained_locals();
            for state in states() {
                let system = CoupledEnds::new(
                    &m,
                    &disc.step_matrix,
                    state,
                    &unknowns,
                    kernels.twisted_solve,
                )
                .map_err(|e| SceneError::Invalid {
                    field: "heat.coupling".into(),
                    value: m.gamma.to_string(),
                    allowed: format!("the coupled step matrix has no block LDLᵀ: {e}"),
                })?;
                variants.push(Box::new(EndEnumeration::on(system, &unknowns, true)));
            }
            Box::new(CoupledSolver::new(variants, shared))
        };
        debug_assert_eq!(displacement.len(), body.unknowns());
        // The load on the whole state (zero on the temperature's rows).
        let load = match &scene.load.density {
            None => Load::none(),
            Some(text) => Load::new(
                vec![Some(Expression::parse("load.density", text, true)?)],
                &body,
            )?,
        };
        Ok(Scheme::unstarted(Setup {
            body,
            solver,
            contact: bar.contact,
            load,
            displacement,
            velocity,
            steps: bar.steps,
            diagnostics_every: bar.diagnostics_every,
        }))
    }
}
