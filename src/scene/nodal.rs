//! An expression evaluated over a whole array of nodes one operation at a time: each node of
//! the tree becomes one loop over the array, so the interpreter's dispatch is paid once per
//! operation instead of once per operation and node. The buffers are sized at set-up, so an
//! evaluation allocates nothing; the values are those of [`Expression::eval`] bit for bit
//! (the same `f64` operations in the same order at each point).

use crate::scene::SceneError;
use crate::scene::expr::{BinOp, Expression, Func2, Node, pow};

/// `f(x_i, t)` at fixed nodes `x_i`, for any `t`.
#[derive(Clone, Debug)]
pub struct NodalEvaluator {
    expr: Expression,
    xs: Vec<f64>,
    /// Scratch arrays, one per level of the tree that holds an intermediate result.
    pool: Vec<Vec<f64>>,
}

/// Scratch arrays the evaluation of `node` needs besides its output.
fn scratch(node: &Node) -> usize {
    match node {
        Node::Num(_) | Node::X | Node::Y | Node::T => 0,
        Node::Neg(a) | Node::Call1(_, a) => scratch(a),
        Node::Bin(_, a, b) | Node::Cmp(_, a, b) | Node::Call2(_, a, b) => {
            scratch(a).max(1 + scratch(b))
        }
        Node::If(c, a, b) => scratch(c).max(1 + scratch(a)).max(2 + scratch(b)),
    }
}

/// `out = node(xs, t)`, using `pool` for intermediate arrays.
fn eval_into(node: &Node, xs: &[f64], t: f64, out: &mut [f64], pool: &mut [Vec<f64>]) {
    match node {
        Node::Num(v) => out.fill(*v),
        Node::X => out.copy_from_slice(xs),
        Node::T => out.fill(t),
        // A bar expression is evaluated at `y = 0`, as `Expression::eval` does.
        Node::Y => out.fill(0.0),
        Node::Neg(a) => {
            eval_into(a, xs, t, out, pool);
            out.iter_mut().for_each(|v| *v = -*v);
        }
        Node::Call1(f, a) => {
            eval_into(a, xs, t, out, pool);
            out.iter_mut().for_each(|v| *v = f.apply(*v));
        }
        Node::Bin(op, a, b) => {
            eval_into(a, xs, t, out, pool);
            let (tmp, rest) = pool.split_first_mut().expect("pool sized by `scratch`");
            eval_into(b, xs, t, tmp, rest);
            let pairs = out.iter_mut().zip(tmp.iter());
            match op {
                BinOp::Add => pairs.for_each(|(o, b)| *o += b),
                BinOp::Sub => pairs.for_each(|(o, b)| *o -= b),
                BinOp::Mul => pairs.for_each(|(o, b)| *o *= b),
                BinOp::Div => pairs.for_each(|(o, b)| *o /= b),
                BinOp::Pow if matches!(**b, Node::Num(e) if e == 2.0) => {
                    out.iter_mut().for_each(|o| *o *= *o)
                }
                BinOp::Pow => pairs.for_each(|(o, b)| *o = pow(*o, *b)),
            }
        }
        Node::Cmp(op, a, b) => {
            eval_into(a, xs, t, out, pool);
            let (tmp, rest) = pool.split_first_mut().expect("pool sized by `scratch`");
            eval_into(b, xs, t, tmp, rest);
            for (o, &b) in out.iter_mut().zip(tmp.iter()) {
                *o = op.apply(*o, b);
            }
        }
        Node::Call2(f, a, b) => {
            eval_into(a, xs, t, out, pool);
            let (tmp, rest) = pool.split_first_mut().expect("pool sized by `scratch`");
            eval_into(b, xs, t, tmp, rest);
            let pairs = out.iter_mut().zip(tmp.iter());
            match f {
                Func2::Min => pairs.for_each(|(o, b)| *o = o.min(*b)),
                Func2::Max => pairs.for_each(|(o, b)| *o = o.max(*b)),
                Func2::Atan2 => pairs.for_each(|(o, b)| *o = o.atan2(*b)),
            }
        }
        Node::If(c, a, b) => {
            eval_into(c, xs, t, out, pool);
            let (then, rest) = pool.split_first_mut().expect("pool sized by `scratch`");
            eval_into(a, xs, t, then, rest);
            let (other, rest) = rest.split_first_mut().expect("pool sized by `scratch`");
            eval_into(b, xs, t, other, rest);
            for ((o, &a), &b) in out.iter_mut().zip(then.iter()).zip(other.iter()) {
                *o = if o.is_nan() {
                    f64::NAN
                } else if *o != 0.0 {
                    a
                } else {
                    b
                };
            }
        }
    }
}

impl NodalEvaluator {
    /// Prepares `expr` for evaluation at the nodes `xs`.
    pub fn new(expr: Expression, xs: Vec<f64>) -> Self {
        let pool = vec![vec![0.0; xs.len()]; scratch(expr.root())];
        Self { expr, xs, pool }
    }

    pub fn expression(&self) -> &Expression {
        &self.expr
    }

    /// `out[i] = f(x_i, t)`; an error names the field, the expression and the first node where
    /// the value is not a finite number (as [`Expression::eval`] would).
    pub fn eval_into(&mut self, t: f64, out: &mut [f64]) -> Result<(), SceneError> {
        eval_into(self.expr.root(), &self.xs, t, out, &mut self.pool);
        match out.iter().position(|v| !v.is_finite()) {
            None => Ok(()),
            Some(i) => self.expr.eval(self.xs[i], t).map(|_| ()),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn every_operation_gives_the_bits_of_the_scalar_evaluation() {
        let xs: Vec<f64> = (0..=40).map(|i| -1.0 + 0.075 * i as f64).collect();
        for text in [
            "sin(x*t)",
            "exp(-(x-t)^2)",
            "if(x < t, atan2(x, t), min(x, -t)) + max(0, min(1, 2 - x))",
            "sign(x) * step(x - 0.5) / (1 + abs(x)) - (x >= 0.2) + (x != t) * cbrt(x)",
            "-x^3 + 2*x*t - floor(3*x) + fract(x) + round(x) + trunc(x) + ceil(x)",
        ] {
            let e = Expression::parse("load.density", text, true).unwrap();
            let mut n = NodalEvaluator::new(e.clone(), xs.clone());
            let mut out = vec![0.0; xs.len()];
            for t in [0.0, 0.3, 1.7] {
                n.eval_into(t, &mut out).unwrap();
                for (&x, &v) in xs.iter().zip(&out) {
                    assert_eq!(
                        v.to_bits(),
                        e.eval(x, t).unwrap().to_bits(),
                        "{text} at ({x}, {t})"
                    );
                }
            }
        }
    }

    #[test]
    fn a_non_finite_value_is_reported_at_its_node() {
        let e = Expression::parse("load.density", "1/(x - t)", true).unwrap();
        let mut n = NodalEvaluator::new(e, vec![0.0, 0.5, 1.0]);
        let mut out = vec![0.0; 3];
        let err = n.eval_into(0.5, &mut out).unwrap_err().to_string();
        assert!(err.contains("load.density") && err.contains("0.5"), "{err}");
    }
}
