//! The contact normals of the plane body's Signorini edges (its contact set): one
//! per node of a Signorini edge that is not clamped, `n = σ e_c` its outward normal.

use crate::plane::mesh::Grid;
use crate::scene::SceneError;
use crate::scene::expr::Expression;
use crate::scene::plane::EDGE_NAMES;
use crate::scheme::contact::{GapMotion, MovingGap};

/// One contact normal.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Normal {
    /// 0 left, 1 right, 2 bottom, 3 top ([`EDGE_NAMES`]).
    pub edge: usize,
    /// The mesh node.
    pub node: usize,
    /// The unknown of the normal component.
    pub unknown: usize,
    /// `σ = ±1`: `n = σ e_c`.
    pub sign: f64,
    /// The edge coordinate `s` of the node.
    pub s: f64,
    /// `g(s)`.
    pub gap: f64,
    /// The node's trapezoid share of the edge, `∫ ψ ds` (half of each adjacent segment).
    pub weight: f64,
}

/// The contact normals of the grid `g` with unknowns `index` and the edges' gaps; `u0_full` the initial displacement at
/// every degree of freedom. Errors: a non-finite gap, a negative gap at a clamped node, an
/// initial displacement beyond the obstacle (bad input, naming the field).
pub fn normals(
    g: &Grid,
    index: &[Option<usize>],
    gaps: &[Option<Expression>; 4],
    u0_full: &[f64],
) -> Result<Vec<Normal>, SceneError> {
    let mut out = Vec::new();
    for (edge, expr) in gaps.iter().enumerate() {
        let Some(expr) = expr else { continue };
        let along_y = edge < 2;
        let count = if along_y { g.ny + 1 } else { g.nx + 1 };
        let coords: &[f64] = if along_y { &g.ys } else { &g.xs };
        for k in 0..count {
            let node = match edge {
                0 => g.node(0, k),
                1 => g.node(g.nx, k),
                2 => g.node(k, 0),
                _ => g.node(k, g.ny),
            };
            let c = usize::from(!along_y);
            let sign = if edge % 2 == 0 { -1.0 } else { 1.0 };
            let s = coords[k];
            let gap = expr.eval(s, 0.0)?;
            let field = format!("edges.{}.gap", EDGE_NAMES[edge]);
            let Some(unknown) = index[2 * node + c] else {
                if gap < 0.0 {
                    return Err(SceneError::Invalid {
                        field,
                        value: format!("{gap} at s = {s}"),
                        allowed: "a clamped node (u = 0) of a Signorini edge needs a gap >= 0"
                            .into(),
                    });
                }
                continue;
            };
            let un = sign * u0_full[2 * node + c];
            if un > gap {
                // `+ 0.0`: a zero component times σ = −1 is −0, printed "-0".
                return Err(SceneError::Invalid {
                    field: "initial.displacement".into(),
                    value: format!("u·n = {} at node {node} (s = {s})", un + 0.0),
                    allowed: format!(
                        "the initial state must be admissible: u·n <= {} (`{field}` at t = 0)",
                        gap + 0.0
                    ),
                });
            }
            let lo = if k > 0 {
                coords[k] - coords[k - 1]
            } else {
                0.0
            };
            let hi = if k + 1 < count {
                coords[k + 1] - coords[k]
            } else {
                0.0
            };
            out.push(Normal {
                edge,
                node,
                unknown,
                sign,
                s,
                gap,
                weight: 0.5 * (lo + hi),
            });
        }
    }
    Ok(out)
}

/// The moving obstacles of the edges whose gap depends on `t`: normal `k` of such an edge
/// (in the order of [`normals`], which is the contact set's) gets `g(s_k, t)` at each step.
/// `None` when no edge's obstacle moves.
pub fn edge_motion(gaps: &[Option<Expression>; 4], normals: &[Normal]) -> Option<GapMotion> {
    let mut laws = Vec::new();
    let mut law_of_edge = [None; 4];
    for (edge, g) in gaps.iter().enumerate() {
        if let Some(g) = g.as_ref().filter(|g| g.depends_on_t()) {
            law_of_edge[edge] = Some(laws.len());
            laws.push(g.clone());
        }
    }
    let moving = (normals.iter().enumerate())
        .filter_map(|(k, nk)| {
            Some(MovingGap {
                constraint: k,
                law: law_of_edge[nk.edge]?,
                s: nk.s,
                cap: f64::INFINITY,
            })
        })
        .collect();
    GapMotion::new(laws, moving)
}
