//! The `friction` key of a plane edge, `{ condition = "signorini", gap = …, friction = μ }`:
//! Coulomb's coefficient `μ(s) >= 0`, a number or an expression in the edge's coordinate `s`
//! (absent: frictionless), on Signorini edges only. It is checked finite and `>= 0` at every
//! node of the edge ([`friction_at`]); a node where `μ(s) = 0` is frictionless, so a key that is
//! zero at every node is no key. The frictional step (some `μ(s) > 0`) needs a step solver
//! with a friction law (`exact` or `osqp`) and at most [`MAX_FRICTION_LCP`] unknowns
//! ([`PlaneScene::check_frictional_step`]). An edge with friction may have an obstacle sliding
//! along its tangent, `velocity` (an expression in `t`; absent: 0). Errors name
//! `edges.<edge>.friction`, `edges.<edge>.velocity` (or `solver.method`).

use crate::scene::plane::{EDGE_NAMES, EdgeCondition, EdgeSpec, Edges, PlaneScene};
use crate::scene::solver::SolverMethod;
use crate::scene::{Expression, SceneError};

/// Largest size `m + 3p` of the frictional step's complementarity problem (`m` normals, `p`
/// frictional nodes): its dense matrix, basis inverse and work space take `24 N²` bytes,
/// 400 MB at this limit.
pub const MAX_FRICTION_LCP: u64 = 4096;

/// The key of edge `edge`'s friction (`edges.<edge>.friction`).
pub fn friction_field(edge: usize) -> String {
    format!("edges.{}.friction", EDGE_NAMES[edge])
}

/// `μ(s)` of edge `edge`'s friction `mu` at the node with coordinate `s`; an error names the key
/// and `s` when the value is not finite or negative.
pub fn friction_at(mu: &Expression, edge: usize, s: f64) -> Result<f64, SceneError> {
    let value = mu.eval(s, 0.0)?;
    if value >= 0.0 {
        return Ok(value);
    }
    Err(SceneError::Invalid {
        field: friction_field(edge),
        value: format!("\"{}\" = {value} at s = {s}", mu.text()),
        allowed: "must be finite and >= 0 at every node of the edge (Coulomb's coefficient)".into(),
    })
}

impl EdgeSpec {
    /// The friction coefficient when the key is a constant (a number or an expression without
    /// `s`) that is finite and `>= 0`; `None` when absent, varying along the edge or invalid.
    pub fn constant_friction(&self) -> Option<f64> {
        let text = self.friction.as_deref()?;
        let mu = Expression::parse_edge("friction", text).ok()?;
        let constant = !(mu.depends_on_x() || mu.depends_on_t());
        constant.then(|| mu.eval(0.0, 0.0).ok()).flatten()
    }
}

impl Edges {
    /// The parsed friction of each edge, `[left, right, bottom, top]`: `None` where absent or
    /// the constant 0 (frictionless either way). A constant is checked here, an expression in
    /// `s` at every node when the run is set up. An error names `edges.<edge>.friction`.
    pub fn frictions(&self) -> Result<[Option<Expression>; 4], SceneError> {
        let mut out: [Option<Expression>; 4] = Default::default();
        for (k, e) in self.all().into_iter().enumerate() {
            let Some(text) = &e.friction else { continue };
            let field = friction_field(k);
            if e.condition != EdgeCondition::Signorini {
                return Err(SceneError::Invalid {
                    field,
                    value: text.clone(),
                    allowed: format!(
                        "friction belongs to a Signorini edge only (this edge is {})",
                        format!("{:?}", e.condition).to_lowercase()
                    ),
                });
            }
            let mu = Expression::parse_edge(&field, text)?;
            if mu.depends_on_t() {
                return Err(SceneError::Invalid {
                    field,
                    value: text.clone(),
                    allowed: "a number or an expression in s (friction does not change in time)"
                        .into(),
                });
            }
            if !mu.depends_on_x() && friction_at(&mu, k, 0.0)? == 0.0 {
                continue;
            }
            out[k] = Some(mu);
        }
        Ok(out)
    }

    /// The sliding speed of each edge's obstacle, `[left, right, bottom, top]` (`None` where
    /// absent): an expression in `t` on a Signorini edge with a `friction` key (not the
    /// constant 0), finite at `t = 0` (later times are checked as the run reaches them); an
    /// error names `edges.<edge>.velocity`.
    pub fn velocities(&self) -> Result<[Option<Expression>; 4], SceneError> {
        let mu = self.frictions()?;
        let mut out: [Option<Expression>; 4] = Default::default();
        for (k, e) in self.all().into_iter().enumerate() {
            let Some(text) = &e.velocity else { continue };
            let field = format!("edges.{}.velocity", EDGE_NAMES[k]);
            if e.condition != EdgeCondition::Signorini || mu[k].is_none() {
                return Err(SceneError::Invalid {
                    field,
                    value: text.clone(),
                    allowed: "an obstacle slides along a Signorini edge with friction only \
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
    /// The friction keys as far as they are known without the mesh: each parsed, on a
    /// Signorini edge, a constant finite and `>= 0` ([`Edges::frictions`]), and each
    /// obstacle's sliding speed ([`Edges::velocities`]).
    pub fn validate_friction(&self) -> Result<(), SceneError> {
        self.edges.velocities().map(drop)
    }

    /// The frictional step of `normals` contact normals and `frictional` frictional nodes, the
    /// first on edge `edge` (`frictional > 0`): a solver method with a friction law, and at most
    /// `MAX_FRICTION_LCP` unknowns.
    pub fn check_frictional_step(
        &self,
        normals: usize,
        frictional: usize,
        edge: usize,
    ) -> Result<(), SceneError> {
        if self.solver.method == SolverMethod::Penalty {
            return Err(SceneError::Invalid {
                field: "solver.method".into(),
                value: "penalty".into(),
                allowed: format!(
                    "has no friction law: with `{}` > 0 use \"exact\" or \"osqp\"",
                    friction_field(edge)
                ),
            });
        }
        let size = (normals as u64).saturating_add(3 * frictional as u64);
        if size > MAX_FRICTION_LCP {
            return Err(SceneError::Invalid {
                field: friction_field(edge),
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
