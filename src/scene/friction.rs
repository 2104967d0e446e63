//! The `friction` key of a plane edge, `{ condition = "signorini", gap = …, friction = μ }`:
//! Coulomb's coefficient `μ >= 0` (a finite number; absent, 0: frictionless), on Signorini
//! edges only, with a step solver that has a friction law (`exact` or `osqp`); and its
//! obstacle's `velocity` along the edge's tangent (an expression in `t`, absent: 0), on an
//! edge with friction only. Errors name `edges.<edge>.friction`, `edges.<edge>.velocity` (or
//! `solver.method`).

use crate::scene::plane::{EDGE_NAMES, EdgeCondition, Edges, PlaneScene};
use crate::scene::solver::SolverMethod;
use crate::scene::{Expression, SceneError};

/// Largest size `m + 3p` of the frictional step's complementarity problem (`m` normals, `p`
/// frictional nodes): its dense matrix, basis inverse and work space take `24 N²` bytes,
/// 400 MB at this limit.
pub const MAX_FRICTION_LCP: u64 = 4096;

impl Edges {
    /// The friction coefficient of each edge, `[left, right, bottom, top]` (0 where absent);
    /// an error names `edges.<edge>.friction`.
    pub fn frictions(&self) -> Result<[f64; 4], SceneError> {
        let mut out = [0.0; 4];
        for (k, e) in self.all().into_iter().enumerate() {
            let Some(mu) = e.friction else { continue };
            let field = format!("edges.{}.friction", EDGE_NAMES[k]);
            if !(mu.is_finite() && mu >= 0.0) {
                return Err(SceneError::Invalid {
                    field,
                    value: mu.to_string(),
                    allowed: "must be a finite number >= 0 (Coulomb's coefficient)".into(),
                });
            }
            if e.condition != EdgeCondition::Signorini {
                return Err(SceneError::Invalid {
                    field,
                    value: mu.to_string(),
                    allowed: format!(
                        "friction belongs to a Signorini edge only (this edge is {})",
                        format!("{:?}", e.condition).to_lowercase()
                    ),
                });
            }
            out[k] = mu;
        }
        Ok(out)
    }

    /// The sliding speed of each edge's obstacle, `[left, right, bottom, top]` (`None` where
    /// absent): an expression in `t` on a Signorini edge with friction > 0, finite at `t = 0`
    /// (later times are checked as the run reaches them); an error names
    /// `edges.<edge>.velocity`.
    pub fn velocities(&self) -> Result<[Option<Expression>; 4], SceneError> {
        let mu = self.frictions()?;
        let mut out: [Option<Expression>; 4] = Default::default();
        for (k, e) in self.all().into_iter().enumerate() {
            let Some(text) = &e.velocity else { continue };
            let field = format!("edges.{}.velocity", EDGE_NAMES[k]);
            if e.condition != EdgeCondition::Signorini || mu[k] <= 0.0 {
                return Err(SceneError::Invalid {
                    field,
                    value: text.clone(),
                    allowed: "an obstacle slides along a Signorini edge with friction > 0 only \
                              (its speed along the edge's tangent)"
                        .into(),
                });
            }
            let speed = Expression::parse_time(&field, text)?;
            speed.eval(0.0, 0.0)?;
            out[k] = Some(speed);
        }
        Ok(out)
    }
}

impl PlaneScene {
    /// The friction keys: values, edges, sliding speeds, the solver method, and the size of the frictional
    /// step's problem (at most `MAX_FRICTION_LCP`, counting every node of a frictional edge).
    pub fn validate_friction(&self) -> Result<(), SceneError> {
        let mu = self.edges.frictions()?;
        self.edges.velocities()?;
        let Some(edge) = (0..4).find(|&k| mu[k] > 0.0) else {
            return Ok(());
        };
        if self.solver.method == SolverMethod::Penalty {
            return Err(SceneError::Invalid {
                field: "solver.method".into(),
                value: "penalty".into(),
                allowed: format!(
                    "has no friction law: with `edges.{}.friction` > 0 use \"exact\" or \"osqp\"",
                    EDGE_NAMES[edge]
                ),
            });
        }
        let [l, r, b, t] = self.edges.clamped();
        let along_y = (self.mesh.ny + 1).saturating_sub(u64::from(b) + u64::from(t));
        let along_x = (self.mesh.nx + 1).saturating_sub(u64::from(l) + u64::from(r));
        let frictional: u64 = (0..4)
            .filter(|&k| mu[k] > 0.0)
            .map(|k| if k < 2 { along_y } else { along_x })
            .sum();
        let size = self.contact_normals().saturating_add(3 * frictional);
        if size > MAX_FRICTION_LCP {
            return Err(SceneError::Invalid {
                field: format!("edges.{}.friction", EDGE_NAMES[edge]),
                value: format!("{size} unknowns of the frictional step"),
                allowed: format!(
                    "at most {MAX_FRICTION_LCP} (m normals + 3 per frictional node; its dense \
                     matrices take 24 N^2 bytes): coarsen the frictional edges' mesh"
                ),
            });
        }
        Ok(())
    }
}
