//! Separation of a load `l(x, t)` into `Σ_k f_k(t) g_k(x)`, found in the expression's tree once
//! at set-up, so that a step costs `K` scalar evaluations and `K` multiply-adds per node
//! (`F^n = Σ_k f_k(t_n) M g_k`, the `M g_k` computed once).
//!
//! The split is algebra on the tree, not a list of known loads: a subtree free of `x` is a time
//! factor, a subtree free of `t` a space factor; sums and differences concatenate their terms,
//! products multiply them out, and a quotient by a factor of one variable divides that
//! variable's factors. Anything else that mixes `x` and `t` (`sin(x*t)`, `exp(-(x-t)^2)`,
//! `min(x, t)`) does not separate.

use crate::scene::expr::{BinOp, Expression, Node};

/// Most terms a separated load may have; a product of two long sums past this is evaluated
/// node by node instead (its `K` passes would cost more than one evaluation of the tree).
pub const MAX_TERMS: usize = 8;

/// One term `f(t) g(x)` of a separated load.
#[derive(Clone, Debug)]
pub struct SeparatedTerm {
    /// `f`, depending on `t` only (or constant).
    pub time: Expression,
    /// `g`, depending on `x` only (or constant).
    pub space: Expression,
}

/// A factor of a term: `None` is 1 (no operation spent on it).
type Factor = Option<Node>;

impl Node {
    /// Whether the tree reads `x` and `t` (a bar expression; see `Node::Y` below).
    pub(super) fn uses(&self) -> (bool, bool) {
        match self {
            Node::Num(_) => (false, false),
            Node::X => (true, false),
            Node::T => (false, true),
            // The plane's `y` counts as both, so that a tree reading it never separates.
            Node::Y => (true, true),
            Node::Neg(a) | Node::Call1(_, a) => a.uses(),
            Node::Bin(_, a, b) | Node::Cmp(_, a, b) | Node::Call2(_, a, b) => {
                let (p, q) = (a.uses(), b.uses());
                (p.0 || q.0, p.1 || q.1)
            }
            Node::If(c, a, b) => {
                let (p, q, r) = (c.uses(), a.uses(), b.uses());
                (p.0 || q.0 || r.0, p.1 || q.1 || r.1)
            }
        }
    }
}

fn times(a: Factor, b: Factor) -> Factor {
    match (a, b) {
        (None, f) | (f, None) => f,
        (Some(a), Some(b)) => Some(Node::Bin(BinOp::Mul, Box::new(a), Box::new(b))),
    }
}

fn negate(f: Factor) -> Factor {
    Some(match f {
        None => Node::Num(-1.0),
        Some(n) => Node::Neg(Box::new(n)),
    })
}

fn divide(a: Factor, b: &Node) -> Factor {
    Some(Node::Bin(
        BinOp::Div,
        Box::new(a.unwrap_or(Node::Num(1.0))),
        Box::new(b.clone()),
    ))
}

/// The terms `(f, g)` of `node`, or `None` when it does not separate within [`MAX_TERMS`].
fn split(node: &Node) -> Option<Vec<(Factor, Factor)>> {
    let (uses_x, uses_t) = node.uses();
    if !uses_x {
        return Some(vec![(Some(node.clone()), None)]);
    }
    if !uses_t {
        return Some(vec![(None, Some(node.clone()))]);
    }
    let terms = match node {
        Node::Neg(a) => split(a)?.into_iter().map(|(f, g)| (negate(f), g)).collect(),
        Node::Bin(BinOp::Add, a, b) => {
            let mut t = split(a)?;
            t.extend(split(b)?);
            t
        }
        Node::Bin(BinOp::Sub, a, b) => {
            let mut t = split(a)?;
            t.extend(split(b)?.into_iter().map(|(f, g)| (negate(f), g)));
            t
        }
        Node::Bin(BinOp::Mul, a, b) => {
            let (p, q) = (split(a)?, split(b)?);
            if p.len() * q.len() > MAX_TERMS {
                return None;
            }
            let mut t = Vec::with_capacity(p.len() * q.len());
            for (fa, ga) in &p {
                for (fb, gb) in &q {
                    t.push((times(fa.clone(), fb.clone()), times(ga.clone(), gb.clone())));
                }
            }
            t
        }
        Node::Bin(BinOp::Div, a, b) => {
            let (b_x, b_t) = b.uses();
            let p = split(a)?;
            match (b_x, b_t) {
                (false, _) => p.into_iter().map(|(f, g)| (divide(f, b), g)).collect(),
                (true, false) => p.into_iter().map(|(f, g)| (f, divide(g, b))).collect(),
                (true, true) => return None,
            }
        }
        _ => return None,
    };
    (terms.len() <= MAX_TERMS).then_some(terms)
}

impl Expression {
    /// `Some` terms `f_k(t) g_k(x)` whose sum is this expression, when it depends on both `x`
    /// and `t` and separates within `MAX_TERMS` terms; the sum equals the expression up to
    /// the rounding of the regrouped operations.
    pub fn separate(&self) -> Option<Vec<SeparatedTerm>> {
        if !(self.depends_on_x() && self.depends_on_t()) {
            return None;
        }
        let part = |f: Factor| {
            Expression::from_root(self.field(), self.text(), f.unwrap_or(Node::Num(1.0)))
        };
        Some(
            split(self.root())?
                .into_iter()
                .map(|(f, g)| SeparatedTerm {
                    time: part(f),
                    space: part(g),
                })
                .collect(),
        )
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The regrouped sum against the tree: a few roundings of values of order 10.
    const REGROUPING_TOL: f64 = 1e-13;

    fn terms(text: &str) -> Option<usize> {
        Expression::parse("load.density", text, true)
            .unwrap()
            .separate()
            .map(|t| t.len())
    }

    #[test]
    fn the_talk_loads_separate_and_mixed_ones_do_not() {
        assert_eq!(terms("sin(t*sqrt(2))*cos(2*x)"), Some(1));
        assert_eq!(terms("-0.5 + 0.8*sin(3*t)*cos(pi*x/2)"), Some(2));
        assert_eq!(terms("(x + t)*(x - t)"), Some(4));
        assert_eq!(terms("x/(1 + t^2)"), Some(1));
        assert_eq!(terms("sin(x*t)"), None);
        assert_eq!(terms("exp(-(x-t)^2)"), None);
        assert_eq!(terms("x/(x + t)"), None);
        // No separation is needed for a load of one variable.
        assert_eq!(terms("sin(t)"), None);
        assert_eq!(terms("x"), None);
    }

    #[test]
    fn a_product_of_long_sums_is_not_expanded_past_the_limit() {
        // 3 x 3 = 9 terms > MAX_TERMS; 2 x 3 = 6 are kept.
        assert_eq!(terms("(x + t + 1)*(x + t + 2)"), None);
        assert_eq!(terms("(x + t)*(x + t + 2)"), Some(6));
    }

    #[test]
    fn the_terms_sum_to_the_expression() {
        for text in [
            "sin(t*sqrt(2))*cos(2*x)",
            "-0.5 + 0.8*sin(3*t)*cos(pi*x/2)",
            "-(x - 2*t)*(3 + x*t)/(1 + t)",
            "(x^2 - t)/(2 + cos(x))",
        ] {
            let e = Expression::parse("load.density", text, true).unwrap();
            let parts = e.separate().unwrap();
            for i in 0..=10 {
                for j in 0..=10 {
                    let (x, t) = (0.3 * i as f64, 0.7 * j as f64);
                    let sum: f64 = parts
                        .iter()
                        .map(|p| p.time.eval(0.0, t).unwrap() * p.space.eval(x, 0.0).unwrap())
                        .sum();
                    let want = e.eval(x, t).unwrap();
                    assert!(
                        (sum - want).abs() <= REGROUPING_TOL * (1.0 + want.abs()),
                        "{text} at ({x}, {t}): {sum} against {want}"
                    );
                }
            }
        }
    }
}
