//! Coulomb friction on the plane body's Signorini edges: the frictional node of each normal of
//! an edge with `friction = μ(s)` where `μ(s) > 0` (each node its own `μ`), its tangent `t` the
//! edge's direction of increasing `s` (`+e_y` along left and right, `+e_x` along bottom and
//! top); the step solver that has the law
//! is [`crate::step::algorithm`]'s choice for [`crate::step::Shape::PlaneFriction`]. A corner
//! shared with another Signorini edge carries that edge's normal on its tangential component
//! and no friction. An edge's obstacle may slide along `t` ([`sliding_obstacles`]).

use crate::plane::normals::Normal;
use crate::scene::friction::friction_at;
use crate::scene::{Expression, SceneError};
use crate::scheme::Slide;
use crate::step::Friction;

/// The frictional nodes of the normals `normals` (in the contact set's order) with the edges'
/// coefficients `mu` (`[left, right, bottom, top]`, expressions in `s`, `None`: frictionless),
/// each evaluated at its node's `s` and checked there ([`friction_at`]); `index` maps a degree
/// of freedom of the mesh to its unknown.
pub fn frictional_nodes(
    normals: &[Normal],
    index: &[Option<usize>],
    mu: &[Option<Expression>; 4],
) -> Result<Friction, SceneError> {
    let mut friction = Friction::default();
    for (k, nk) in normals.iter().enumerate() {
        let Some(field) = &mu[nk.edge] else { continue };
        let coefficient = friction_at(field, nk.edge, nk.s)?;
        if coefficient == 0.0 {
            continue;
        }
        // Left and right edges: normal x, tangent y; bottom and top: normal y, tangent x.
        let component = usize::from(nk.edge < 2);
        let Some(tangent) = index[2 * nk.node + component] else {
            continue;
        };
        if normals.iter().any(|other| other.unknown == tangent) {
            continue;
        }
        friction.normals.push(k);
        friction.tangents.push(tangent);
        friction.coefficients.push(coefficient);
    }
    Ok(friction)
}

/// The obstacles of the edges with a `velocity` (`[left, right, bottom, top]`, speeds along the
/// edge's tangent) under the frictional nodes of `friction`, with time step `dt`; `None` when
/// no edge's obstacle slides.
pub fn sliding_obstacles(
    velocities: &[Option<Expression>; 4],
    normals: &[Normal],
    friction: &Friction,
    dt: f64,
) -> Result<Option<Slide>, SceneError> {
    let mut laws = Vec::new();
    let mut law_of_edge = [None; 4];
    for (edge, v) in velocities.iter().enumerate() {
        if let Some(v) = v {
            law_of_edge[edge] = Some(laws.len());
            laws.push(v.clone());
        }
    }
    let law_of_node = (friction.normals.iter())
        .map(|&k| law_of_edge[normals[k].edge])
        .collect();
    Slide::new(laws, law_of_node, dt)
}
