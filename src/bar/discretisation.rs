//! The space discretisation of a scene: P1 elements on `J + 2` nodes, the matrices restricted
//! to the nodes that move (clamped ends removed), the constrained nodes, the step matrix
//! `C = M/Δt² + R/2 + αR/(2Δt)` and the initial data evaluated at the nodes.

use crate::bar::matrices;
use crate::linalg::tridiag::SymTridiag;
use crate::scene::SceneError;
use crate::scene::expr::Expression;
use crate::scene::nodal::{BLOCK, block_pool, eval_block};
use crate::scene::{Condition, Scene, Side};
use crate::scheme::contact::{GapMotion, MovingGap};

/// A constrained node: `u[node] >= -gap`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Constraint {
    /// The end whose Signorini condition this is, or `None` for an obstacle node.
    pub side: Option<Side>,
    /// Global node index in `0..=J+1`.
    pub node: usize,
    pub gap: f64,
}

/// The space-time discretisation of a scene: the matrices restricted to the nodes that move
/// (clamped end nodes are removed), and the step matrix `C = M/Δt² + R/2 + αR/(2Δt)`.
#[derive(Clone, Debug)]
pub struct Discretisation {
    /// All nodes, `J + 2`.
    pub nodes: usize,
    pub dx: f64,
    pub dt: f64,
    pub alpha: f64,
    /// Global index of the first unknown (1 when the left end is clamped).
    pub first: usize,
    /// Which matrices (the full-mesh mass matrix of a load is rebuilt from it when needed,
    /// rather than kept: J doubles ×3 that most runs never read).
    pub variant: matrices::MatrixVariant,
    /// Which mass matrix `mass` is (`[bar] mass`). The load vector does not follow it: it is
    /// always `M_consistent · (l(x_i))_i`, the P1 load vector of the interpolated force per
    /// unit length, whatever the inertia.
    pub mass_variant: matrices::MassVariant,
    /// Local indices of the unknowns that carry no mass (the Signorini end nodes of a
    /// redistributed mass; empty otherwise), in increasing order.
    pub massless: Vec<usize>,
    /// Mass and stiffness on the unknowns.
    pub mass: SymTridiag,
    pub stiffness: SymTridiag,
    pub step_matrix: SymTridiag,
    pub constraints: Vec<Constraint>,
    /// The Signorini ends whose obstacle moves (a gap `a(t)` that depends on `t`): the
    /// constraints' gaps at every step (`constraints` hold them at `t = 0`); `None` when none
    /// moves.
    pub motion: Option<GapMotion>,
}

/// The moving end obstacles of `scene` on its `constraints`: a Signorini end whose `a(t)`
/// depends on `t` moves its constraint's gap to `min(a(t), g)`, `g` the obstacle's gap at the
/// end node under an obstacle (its constraint's gap at `t = 0` is that bound's too).
fn end_motion(scene: &Scene, constraints: &[Constraint]) -> Option<GapMotion> {
    let obstacle = scene
        .obstacle
        .as_ref()
        .and_then(|o| o.gap.expression("obstacle.gap").ok());
    let mut laws = Vec::new();
    let mut moving = Vec::new();
    for (side, a) in scene.moving_ends() {
        if !a.depends_on_t() {
            continue;
        }
        let Some(k) = constraints.iter().position(|c| c.side == Some(side)) else {
            continue;
        };
        let x = constraints[k].node as f64 * scene.dx();
        let cap = obstacle
            .as_ref()
            .and_then(|g| g.eval(x, 0.0).ok())
            .unwrap_or(f64::INFINITY);
        moving.push(MovingGap {
            constraint: k,
            law: laws.len(),
            s: 0.0,
            cap,
        });
        laws.push(a);
    }
    GapMotion::new(laws, moving)
}

impl Discretisation {
    pub fn new(scene: &Scene) -> Result<Self, SceneError> {
        // A scene built in code has not been through `Scene::from_toml`'s validation.
        scene.validate()?;
        let nodes = scene.elements() + 1;
        let dx = scene.dx();
        let dt = scene.time.step;
        let alpha = scene.bar.viscosity;
        let variant = scene.bar.matrices;
        let first = usize::from(scene.left.condition == Condition::Clamped);
        let last = nodes - 1 - usize::from(scene.right.condition == Condition::Clamped);
        let mass_variant = scene.bar.mass;
        let signorini = [&scene.left, &scene.right].map(|e| e.condition == Condition::Signorini);
        // In place: no second copy of the full-mesh matrices at set-up.
        let mass = match mass_variant {
            matrices::MassVariant::Consistent => matrices::mass(variant, nodes, dx),
            _ => matrices::mass_matrix(mass_variant, signorini, nodes, dx).map_err(|e| {
                SceneError::Invalid {
                    field: "mesh.elements".into(),
                    value: e.elements.to_string(),
                    allowed: format!("with `bar.mass` = \"{}\": {e}", mass_variant.name()),
                }
            })?,
        }
        .into_sub(first, last);
        let massless = if mass_variant == matrices::MassVariant::Redistributed {
            [0, nodes - 1]
                .into_iter()
                .zip(signorini)
                .filter_map(|(node, s)| s.then_some(node - first))
                .collect()
        } else {
            Vec::new()
        };
        let stiffness = matrices::stiffness(variant, nodes, dx).into_sub(first, last);
        let step_matrix =
            SymTridiag::combine(1.0 / (dt * dt), &mass, 0.5 + alpha / (2.0 * dt), &stiffness);
        let node_of = |side: Side| if side == Side::Left { 0 } else { nodes - 1 };
        let ends = scene.signorini_ends();
        let end_gap = |node: usize| {
            ends.iter()
                .find(|(side, _)| node_of(*side) == node)
                .copied()
        };
        let constraints = match &scene.obstacle {
            None => ends
                .iter()
                .map(|&(side, gap)| Constraint {
                    side: Some(side),
                    node: node_of(side),
                    gap,
                })
                .collect(),
            Some(obstacle) => {
                let g = obstacle.gap.expression("obstacle.gap")?;
                (first..=last)
                    .map(|node| {
                        let obstacle_gap = g.eval(node as f64 * dx, 0.0)?;
                        Ok(match end_gap(node) {
                            Some((side, a)) => Constraint {
                                side: Some(side),
                                node,
                                gap: a.min(obstacle_gap),
                            },
                            None => Constraint {
                                side: None,
                                node,
                                gap: obstacle_gap,
                            },
                        })
                    })
                    .collect::<Result<Vec<_>, SceneError>>()?
            }
        };
        let motion = end_motion(scene, &constraints);
        Ok(Self {
            nodes,
            dx,
            dt,
            alpha,
            first,
            variant,
            mass_variant,
            massless,
            mass,
            stiffness,
            step_matrix,
            constraints,
            motion,
        })
    }

    /// Indices into `constraints` of the Signorini ends (left first), at most two.
    pub fn end_constraints(&self) -> Vec<usize> {
        (0..self.constraints.len())
            .filter(|&j| self.constraints[j].side.is_some())
            .collect()
    }

    /// Whether only end nodes are constrained (at most two bounds).
    pub fn ends_only(&self) -> bool {
        self.constraints.iter().all(|c| c.side.is_some())
    }

    /// Number of unknowns.
    pub fn unknowns(&self) -> usize {
        self.mass.dim()
    }

    /// Local (unknown) index of global node `i`.
    pub fn local(&self, node: usize) -> usize {
        node - self.first
    }

    /// `x_i = i Δx`.
    pub fn x(&self, node: usize) -> f64 {
        node as f64 * self.dx
    }

    /// Local indices of the constrained nodes, in order.
    pub fn constrained_locals(&self) -> Vec<usize> {
        self.constraints
            .iter()
            .map(|c| self.local(c.node))
            .collect()
    }
}

/// Initial data at a clamped node must vanish up to this (expressions such as `(1-x)/2` at
/// `x = 1` evaluate to exactly 0, but `sin(pi*x)` at `x = 1` gives 1.2e-16).
pub const CLAMPED_START_TOL: f64 = 1e-12;

/// The initial data of a scene: displacement and velocity expressions, and which ends are clamped.
pub struct InitialData {
    pub(crate) displacement: Expression,
    pub(crate) velocity: Expression,
    /// Left and right end clamped.
    pub(crate) clamped: [bool; 2],
}

/// Significant digits of the bar length written into a suggested expression (`L = J·Δx`
/// rounded, so that `1/640 · 640` prints as `1`, not `0.9999999999999999`).
const LENGTH_DIGITS: usize = 12;

impl InitialData {
    /// `expression` multiplied by a ramp that vanishes at every clamped end: `(L − x)/L` for the
    /// right end, `x/L` for the left, `4x(L − x)/L²` for both (1 at mid-bar).
    fn ramped(&self, expression: &Expression, disc: &Discretisation) -> String {
        let length = disc.x(disc.nodes - 1);
        let l = format!("{length:.prec$e}", prec = LENGTH_DIGITS - 1)
            .parse::<f64>()
            .unwrap_or(length)
            .to_string();
        let text = expression.text().trim();
        match self.clamped {
            [true, true] => format!("({text})*4*x*({l} - x)/({l}*{l})"),
            [true, false] => format!("({text})*x/{l}"),
            _ => format!("({text})*({l} - x)/{l}"),
        }
    }

    /// `u_0`, `u_1` at all nodes; at a clamped node they must vanish (up to
    /// [`CLAMPED_START_TOL`]) and are set to 0.
    pub fn eval_into(
        &self,
        disc: &Discretisation,
        u: &mut [f64],
        v: &mut [f64],
    ) -> Result<(), SceneError> {
        let nodes = disc.nodes;
        // Block by block over the node array (`scene::nodal`, the same bits); at the first
        // block holding a value that is not finite, node by node from there, so the error is
        // the one the plain loop gives (the first node, displacement before velocity).
        let pools = &mut [block_pool(&self.displacement), block_pool(&self.velocity)];
        let mut x_block = [0.0; BLOCK];
        for start in (0..nodes).step_by(BLOCK) {
            let end = (start + BLOCK).min(nodes);
            let xs = &mut x_block[..end - start];
            for (k, x) in xs.iter_mut().enumerate() {
                *x = disc.x(start + k);
            }
            let (ub, vb) = (&mut u[start..end], &mut v[start..end]);
            eval_block(&self.displacement, xs, 0.0, ub, &mut pools[0]);
            eval_block(&self.velocity, xs, 0.0, vb, &mut pools[1]);
            if ub.iter().chain(vb.iter()).any(|w| !w.is_finite()) {
                for i in start..nodes {
                    u[i] = self.displacement.eval(disc.x(i), 0.0)?;
                    v[i] = self.velocity.eval(disc.x(i), 0.0)?;
                }
                break;
            }
        }
        for (side, clamped, node) in [
            (Side::Left, self.clamped[0], 0),
            (Side::Right, self.clamped[1], nodes - 1),
        ] {
            if !clamped {
                continue;
            }
            for (field, value, expression) in [
                ("initial.displacement", u[node], &self.displacement),
                ("initial.velocity", v[node], &self.velocity),
            ] {
                if value.abs() > CLAMPED_START_TOL {
                    return Err(SceneError::Invalid {
                        field: field.into(),
                        value: value.to_string(),
                        allowed: format!(
                            "must vanish at the clamped {} end (x = {}); to make the data \
                             consistent, multiply it by a ramp that vanishes there, e.g. \
                             {field} = \"{}\"",
                            side.name(),
                            disc.x(node),
                            self.ramped(expression, disc)
                        ),
                    });
                }
            }
            u[node] = 0.0;
            v[node] = 0.0;
        }
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The block evaluation of the initial data reports the error the node-by-node loop
    /// gives: the first node where either field is not finite, displacement first.
    #[test]
    fn initial_data_errors_name_the_first_bad_node_across_blocks() {
        for (displacement, velocity) in [
            ("if(x > 0.45, 1/0, x)", "if(x > 0.44, sqrt(-1), 0)"),
            ("if(x > 0.44, 1/0, x)", "if(x > 0.44, sqrt(-1), 0)"),
            ("if(x > 0.9, ln(-x), cos(x))", "0"),
            ("cos(3*x)", "sin(x)"),
        ] {
            let overrides: Vec<String> = [
                format!("initial.displacement=\"{displacement}\""),
                format!("initial.velocity=\"{velocity}\""),
                "mesh.elements=600".to_string(),
            ]
            .into();
            let (_, scene) = crate::scene::load("modal", &overrides).unwrap();
            let disc = Discretisation::new(&scene).unwrap();
            let data = InitialData {
                displacement: Expression::parse("initial.displacement", displacement, false)
                    .unwrap(),
                velocity: Expression::parse("initial.velocity", velocity, false).unwrap(),
                clamped: [false, false],
            };
            let (mut u, mut v) = (vec![0.0; disc.nodes], vec![0.0; disc.nodes]);
            let got = data
                .eval_into(&disc, &mut u, &mut v)
                .map_err(|e| e.to_string());
            let plain = (0..disc.nodes)
                .try_for_each(|i| {
                    let (pu, pv) = (
                        data.displacement.eval(disc.x(i), 0.0)?,
                        data.velocity.eval(disc.x(i), 0.0)?,
                    );
                    assert_eq!(
                        (pu.to_bits(), pv.to_bits()),
                        (u[i].to_bits(), v[i].to_bits())
                    );
                    Ok::<(), SceneError>(())
                })
                .map_err(|e| e.to_string());
            assert_eq!(got, plain, "{displacement} / {velocity}");
        }
    }
}
