//! The plane contact certificate (VERIFICATION.md, "Plane contact"): the bar with contact as
//! an exact special case ([`crate::study::plane_checks::bar_case`]), the contact conditions and
//! the energy identity on the built-in contact scenes, the exact solver against OSQP and the
//! penalty, and the observed convergence of the tilted drop. The tests
//! (`tests/plane_contact.rs`) assert on the same computations.

use crate::plane::PlaneError;
use crate::plane::contact::ContactMethod;
use crate::plane::simulation::PlaneSimulation;
use crate::scene::plane::{AnyScene, PlaneScene, load_any};
use crate::step::osqp::OsqpSettings;
use crate::study::converge::ConvergeError;
use crate::time::RunError;

/// The built-in scenes of the solver comparison.
pub const CONTACT_SCENES: [&str; 2] = ["plane-tilted-drop", "plane-curved-obstacle"];

/// A built-in plane scene with overrides.
pub fn plane_scene(name: &str, set: &[String]) -> Result<PlaneScene, ConvergeError> {
    match load_any(name, set)?.1 {
        AnyScene::Plane(s) => Ok(*s),
        AnyScene::Bar(_) => Err(ConvergeError::BadInput(format!("{name} is a bar scene"))),
    }
}

/// A plane failure in a study: bad input or a failed run.
pub fn plane_error(e: PlaneError) -> ConvergeError {
    match e {
        PlaneError::Scene(s) => ConvergeError::Scene(s),
        other => ConvergeError::Run(RunError::SolverSetup {
            solver: crate::plane::run::SOLVER_NAME.into(),
            reason: other.to_string(),
        }),
    }
}

/// One method against the exact solver over a whole run: the largest differences of `u` (at
/// every degree of freedom) and of the reactions, over every step, with the exact run's
/// `max |u|` and `max r`.
#[derive(Clone, Debug)]
pub struct Agreement {
    pub method: &'static str,
    pub steps: usize,
    pub max_u_deviation: f64,
    pub max_u: f64,
    pub max_reaction_deviation: f64,
    pub max_reaction: f64,
    /// Largest contact set of the exact run, and the steps with contact.
    pub max_active: usize,
    pub contact_steps: usize,
    /// OSQP: the audit's worst ratio to its tolerance over all checks.
    pub audit_worst_ratio: Option<f64>,
    /// Mean iterations per step of the method.
    pub mean_iterations: f64,
}

/// OSQP's settings in the comparison: the bar's defaults (`eps = 1e-10`, polished).
pub fn osqp_method() -> ContactMethod {
    ContactMethod::Osqp(OsqpSettings::default())
}

/// Runs `scene` with the exact solver and with `method` side by side.
pub fn agreement(scene: &PlaneScene, method: ContactMethod) -> Result<Agreement, ConvergeError> {
    let mut e = PlaneSimulation::new(scene).map_err(plane_error)?;
    let mut o = PlaneSimulation::with_method(scene, method).map_err(plane_error)?;
    let mut a = Agreement {
        method: method.name(),
        steps: scene.steps(),
        max_u_deviation: 0.0,
        max_u: 0.0,
        max_reaction_deviation: 0.0,
        max_reaction: 0.0,
        max_active: 0,
        contact_steps: 0,
        audit_worst_ratio: None,
        mean_iterations: 0.0,
    };
    let mut iterations = 0u64;
    let compare = |e: &PlaneSimulation, o: &PlaneSimulation, a: &mut Agreement| {
        for (x, y) in e.unknowns().iter().zip(o.unknowns()) {
            a.max_u_deviation = a.max_u_deviation.max((x - y).abs());
            a.max_u = a.max_u.max(x.abs());
        }
        let (re, ro) = (
            e.contact().expect("a contact scene").reactions(),
            o.contact().expect("a contact scene").reactions(),
        );
        for (x, y) in re.iter().zip(ro) {
            a.max_reaction_deviation = a.max_reaction_deviation.max((x - y).abs());
            a.max_reaction = a.max_reaction.max(*x);
        }
    };
    compare(&e, &o, &mut a);
    for _ in 1..scene.steps() {
        let re = e.step().map_err(plane_error)?;
        let ro = o.step().map_err(plane_error)?;
        iterations += u64::from(ro.contact.iterations);
        a.max_active = a.max_active.max(re.contact.active);
        a.contact_steps += usize::from(re.contact.active > 0);
        compare(&e, &o, &mut a);
    }
    a.mean_iterations = iterations as f64 / (scene.steps().max(2) - 1) as f64;
    a.audit_worst_ratio = o.contact().and_then(|c| c.audit()).map(|r| {
        [
            r.primal_violation.unwrap_or_default().max_over_tolerance,
            r.negative_reaction.max_over_tolerance,
            r.complementarity.unwrap_or_default().max_over_tolerance,
            r.stationarity.max_over_tolerance,
            r.stationarity_displacement.max_over_tolerance,
        ]
        .into_iter()
        .fold(0.0, f64::max)
    });
    Ok(a)
}
