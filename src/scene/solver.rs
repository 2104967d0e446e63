//! The `[solver]` table of a scene, bar or plane: the step solver and its settings.

use crate::scene::SceneError;
use crate::step::end_penalty::PenaltySettings;
use crate::step::osqp::OsqpSettings;
use serde::{Deserialize, Serialize};

pub use crate::step::algorithm::SolverMethod;

/// The `[solver]` table. Every setting but `method` belongs to one method; naming it with
/// another method is refused (see [`crate::scene::Scene::validate`]), so a setting is never
/// silently ignored.
#[derive(Clone, Debug, Default, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct SolverSpec {
    #[serde(default)]
    pub method: SolverMethod,
    /// OSQP absolute tolerance (default [`OSQP_DEFAULT_EPS`](crate::step::osqp::OSQP_DEFAULT_EPS)).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub eps_abs: Option<f64>,
    /// OSQP relative tolerance (default [`OSQP_DEFAULT_EPS`](crate::step::osqp::OSQP_DEFAULT_EPS)).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub eps_rel: Option<f64>,
    /// OSQP solution polishing (default true).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub polish: Option<bool>,
    /// OSQP iteration limit per step (default [`OSQP_DEFAULT_MAX_ITER`](crate::step::osqp::OSQP_DEFAULT_MAX_ITER)).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub max_iter: Option<u32>,
    /// OSQP iterations between step-size (rho) adaptations (default
    /// [`OSQP_DEFAULT_ADAPTIVE_RHO_INTERVAL`](crate::step::osqp::OSQP_DEFAULT_ADAPTIVE_RHO_INTERVAL)); fixed so that runs are bit-identical.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub adaptive_rho_interval: Option<u32>,
    /// Accept OSQP's "solved inaccurate" (default false), counted in `summary.json`.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub accept_inaccurate: Option<bool>,
    /// Penalty parameter ε of (PP) (default [`PENALTY_DEFAULT_EPSILON`](crate::step::end_penalty::PENALTY_DEFAULT_EPSILON)).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub epsilon: Option<f64>,
}

impl SolverSpec {
    /// The penalty settings this spec asks for, the defaults for those not given.
    pub fn penalty_settings(&self) -> PenaltySettings {
        let d = PenaltySettings::default();
        PenaltySettings {
            epsilon: self.epsilon.unwrap_or(d.epsilon),
        }
    }

    /// The OSQP settings this spec asks for, OSQP's defaults for those not given.
    pub fn osqp_settings(&self) -> OsqpSettings {
        let d = OsqpSettings::default();
        OsqpSettings {
            eps_abs: self.eps_abs.unwrap_or(d.eps_abs),
            eps_rel: self.eps_rel.unwrap_or(d.eps_rel),
            polish: self.polish.unwrap_or(d.polish),
            max_iter: self.max_iter.unwrap_or(d.max_iter),
            adaptive_rho_interval: self
                .adaptive_rho_interval
                .unwrap_or(d.adaptive_rho_interval),
            accept_inaccurate: self.accept_inaccurate.unwrap_or(d.accept_inaccurate),
        }
    }

    /// The settings that are set and belong to `method`s other than `self.method`, by name.
    fn foreign_settings(&self) -> Vec<(&'static str, SolverMethod)> {
        let osqp = [
            ("eps_abs", self.eps_abs.is_some()),
            ("eps_rel", self.eps_rel.is_some()),
            ("polish", self.polish.is_some()),
            ("max_iter", self.max_iter.is_some()),
            (
                "adaptive_rho_interval",
                self.adaptive_rho_interval.is_some(),
            ),
            ("accept_inaccurate", self.accept_inaccurate.is_some()),
        ];
        let penalty = [("epsilon", self.epsilon.is_some())];
        let mut out = Vec::new();
        for (owner, list) in [
            (SolverMethod::Osqp, &osqp[..]),
            (SolverMethod::Penalty, &penalty[..]),
        ] {
            if owner != self.method {
                out.extend(
                    list.iter()
                        .filter(|(_, set)| *set)
                        .map(|(n, _)| (*n, owner)),
                );
            }
        }
        out
    }

    /// Refuses a setting of another method and out-of-range values, naming `solver.<key>`
    /// (shared by bar and plane scenes).
    pub(crate) fn validate(&self) -> Result<(), SceneError> {
        if let Some((name, owner)) = self.foreign_settings().first() {
            return Err(SceneError::Invalid {
                field: format!("solver.{name}"),
                value: "set".into(),
                allowed: format!(
                    "applies only to method \"{}\", not to \"{}\"",
                    owner.name(),
                    self.method.name()
                ),
            });
        }
        // Given values are checked whatever the method (a foreign one was refused above).
        self.osqp_settings().validate()?;
        self.penalty_settings().validate()?;
        Ok(())
    }
}
