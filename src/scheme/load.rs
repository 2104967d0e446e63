//! The load vector `F^n = M_full (l(x_i, t_n))_i` restricted to the unknowns: the load vector
//! of the nodal interpolant of `l`, for either body. It does no more work than the expression
//! needs: none without a load, once for a constant one, `Σ_k f_k(t_n) (M g_k)` for a load that
//! separates into `Σ_k f_k(t) g_k(x)` (the products computed once), and nodal values times the
//! full-mesh mass every step otherwise (on the bar's line, through the vectorised
//! [`NodalEvaluator`]).

use crate::scene::SceneError;
use crate::scene::expr::Expression;
use crate::scene::nodal::NodalEvaluator;
use crate::scheme::body::{Body, FullMassRows};

/// `expr` at `(x, y)`: the bar's `f(x, t)` or the plane's `f(x, y, t)`, whose errors name the
/// point as each body's fields do.
fn eval_at(expr: &Expression, (x, y): (f64, Option<f64>), t: f64) -> Result<f64, SceneError> {
    match y {
        None => expr.eval(x, t),
        Some(y) => expr.eval_xy(x, y, t),
    }
}

/// How `F^n` is produced.
enum Kind {
    None,
    /// `l` independent of `t`: `F` computed once.
    Constant,
    /// `F^n = Σ_k f_k(t_n) V_k`, each `V_k = M (g_k on one component)` computed once (a load
    /// of `t` alone is one term with `g = 1`). A step where a factor is not finite evaluates
    /// the components themselves node by node, so that the error names the node.
    Separable {
        components: Vec<Option<Expression>>,
        terms: Vec<(Expression, Vec<f64>)>,
    },
    /// Nodal values every step, times the full-mesh mass.
    General {
        components: Vec<Option<Nodal>>,
        mass: FullMassRows,
        nodal: Vec<f64>,
    },
}

/// A component's nodal values: vectorised on the bar's line, node by node on the plane.
enum Nodal {
    Line(Box<NodalEvaluator>),
    Points {
        expr: Expression,
        points: Vec<(f64, Option<f64>)>,
    },
}

/// The load term of a run.
pub struct Load {
    kind: Kind,
    /// `F^n` of the last evaluation (empty without a load).
    force: Vec<f64>,
}

impl Load {
    /// No load.
    pub fn none() -> Self {
        Self {
            kind: Kind::None,
            force: Vec::new(),
        }
    }

    /// The load with one expression per component of the body's nodes (`None`: 0); `F^0` is
    /// computed. A load that is 0 everywhere is no load.
    pub fn new(components: Vec<Option<Expression>>, body: &impl Body) -> Result<Self, SceneError> {
        let components: Vec<Option<Expression>> = (components.into_iter())
            .map(|e| e.filter(|e| !is_zero(e)))
            .collect();
        if components.iter().all(Option::is_none) {
            return Ok(Self::none());
        }
        let n = body.unknowns();
        let mut force = vec![0.0; n];
        let (count, per_node) = (body.nodes(), body.components());
        let dofs = count * per_node;
        let on_component = |c: usize, value: &dyn Fn(usize) -> Result<f64, SceneError>| {
            let mut full = vec![0.0; dofs];
            for i in 0..count {
                full[per_node * i + c] = value(i)?;
            }
            Ok::<_, SceneError>(full)
        };
        let exprs = || {
            components
                .iter()
                .enumerate()
                .filter_map(|(c, e)| Some((c, e.as_ref()?)))
        };
        let mut rows = body.full_mass_rows();
        if !exprs().any(|(_, e)| e.depends_on_t()) {
            let mut full = vec![0.0; dofs];
            for (c, e) in exprs() {
                let values = on_component(c, &|i| eval_at(e, body.point(i), 0.0))?;
                for i in 0..count {
                    full[per_node * i + c] = values[per_node * i + c];
                }
            }
            rows(&full, &mut force);
            return Ok(Self {
                kind: Kind::Constant,
                force,
            });
        }
        // Each component separated, or none.
        let mut terms = Vec::new();
        let mut separable = true;
        for (c, e) in exprs() {
            let parts = if e.depends_on_x() || e.depends_on_y() {
                e.separate()
                    .map(|p| p.into_iter().map(|p| (p.time, Some(p.space))).collect())
            } else {
                Some(vec![(e.clone(), None)])
            };
            let Some(parts) = parts else {
                separable = false;
                break;
            };
            for (time, space) in parts {
                let g = on_component(c, &|i| match &space {
                    Some(space) => eval_at(space, body.point(i), 0.0),
                    None => Ok(1.0),
                })?;
                let mut mg = vec![0.0; n];
                rows(&g, &mut mg);
                terms.push((time, mg));
            }
        }
        let kind = if separable {
            Kind::Separable { components, terms }
        } else {
            let nodal = (components.into_iter())
                .map(|e| {
                    e.map(|expr| match body.point(0).1 {
                        None => Nodal::Line(Box::new(NodalEvaluator::new(
                            expr,
                            (0..count).map(|i| body.point(i).0).collect(),
                        ))),
                        Some(_) => Nodal::Points {
                            expr,
                            points: (0..count).map(|i| body.point(i)).collect(),
                        },
                    })
                })
                .collect();
            Kind::General {
                components: nodal,
                mass: rows,
                nodal: vec![0.0; dofs],
            }
        };
        let mut load = Self { kind, force };
        load.update(body, 0)?;
        Ok(load)
    }

    /// `F^n` of the last [`Load::update`] (`None` without a load).
    pub fn force(&self) -> Option<&[f64]> {
        match self.kind {
            Kind::None => None,
            _ => Some(&self.force),
        }
    }

    /// Evaluates `F^n` at `t_n = n Δt`; allocates nothing (but to report a non-finite load).
    pub fn update(&mut self, body: &impl Body, n: usize) -> Result<(), SceneError> {
        let t = n as f64 * body.dt();
        let force = &mut self.force;
        match &mut self.kind {
            Kind::None | Kind::Constant => {}
            Kind::Separable { components, terms } => {
                let mut finite = true;
                for (k, (f, mg)) in terms.iter().enumerate() {
                    let Ok(fk) = f.eval(0.0, t) else {
                        finite = false;
                        break;
                    };
                    if k == 0 {
                        force.iter_mut().zip(mg).for_each(|(o, g)| *o = fk * g);
                    } else {
                        force.iter_mut().zip(mg).for_each(|(o, g)| *o += fk * g);
                    }
                }
                if !finite {
                    // Off the hot path: name the node where `l` itself is not finite, or (a
                    // factor overflowing while the product does not) take `M l` directly.
                    let per_node = body.components();
                    let mut full = vec![0.0; body.nodes() * per_node];
                    for (c, e) in components.iter().enumerate() {
                        let Some(e) = e else { continue };
                        for i in 0..body.nodes() {
                            full[per_node * i + c] = eval_at(e, body.point(i), t)?;
                        }
                    }
                    (body.full_mass_rows())(&full, force);
                }
            }
            Kind::General {
                components,
                mass,
                nodal,
            } => {
                let k = body.components();
                for (c, e) in components.iter_mut().enumerate() {
                    match e {
                        None => {}
                        Some(Nodal::Line(eval)) => eval.eval_into(t, nodal)?,
                        Some(Nodal::Points { expr, points }) => {
                            for (i, &p) in points.iter().enumerate() {
                                nodal[k * i + c] = eval_at(expr, p, t)?;
                            }
                        }
                    }
                }
                mass(nodal, force);
            }
        }
        Ok(())
    }
}

/// Whether `e` is the constant 0 (written `0`, `0.0`, `-0`…): no load at all.
fn is_zero(e: &Expression) -> bool {
    !(e.depends_on_x() || e.depends_on_y() || e.depends_on_t())
        && e.eval_xy(0.0, 0.0, 0.0).is_ok_and(|v| v == 0.0)
}
