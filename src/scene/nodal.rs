//! An expression evaluated over a whole array of nodes one operation at a time: each node of
//! the tree becomes one loop over the array, so the interpreter's dispatch is paid once per
//! operation instead of once per operation and node. The array is taken in blocks of
//! [`BLOCK`] nodes, the whole tree over one block before the next, so the intermediate arrays
//! stay in the L1 cache; a number, `x`, `y` or `t` as the right operand of an operation is read
//! in place rather than filled into an array. The buffers are sized at set-up, so an
//! evaluation allocates nothing; the values are those of [`Expression::eval`] bit for bit
//! (the same `f64` operations in the same order at each point).

use crate::scene::SceneError;
use crate::scene::expr::{BinOp, Expression, Func1, Func2, Node, pow};

/// Nodes evaluated together: a few scratch arrays of this many doubles (2 KiB each) stay in
/// the L1 cache, and the walk of the tree per block costs little next to a block's work.
pub const BLOCK: usize = 256;

/// `f(x_i, t)` at fixed nodes `x_i`, for any `t`.
#[derive(Clone, Debug)]
pub struct NodalEvaluator {
    expr: Expression,
    xs: Vec<f64>,
    /// Scratch arrays of one block, one per level of the tree that holds an intermediate result.
    pool: Vec<Vec<f64>>,
}

/// Scratch arrays the evaluation of `node` needs besides its output.
fn scratch(node: &Node) -> usize {
    match node {
        Node::Num(_) | Node::X | Node::Y | Node::T => 0,
        Node::Neg(a) | Node::Call1(_, a) => scratch(a),
        Node::Bin(_, a, b) | Node::Cmp(_, a, b) | Node::Call2(_, a, b) => {
            scratch(a).max(usize::from(leaf(b).is_none()) + scratch(b))
        }
        Node::If(c, a, b) => scratch(c).max(1 + scratch(a)).max(2 + scratch(b)),
    }
}

/// A right operand read in place: a number (`y` is 0 on a bar) or `t`, or `x`.
#[derive(Clone, Copy)]
enum Leaf {
    Scalar(Scalar),
    X,
}

#[derive(Clone, Copy)]
enum Scalar {
    Num(f64),
    T,
}

fn leaf(node: &Node) -> Option<Leaf> {
    match node {
        Node::Num(v) => Some(Leaf::Scalar(Scalar::Num(*v))),
        // A bar expression is evaluated at `y = 0`, as `Expression::eval` does.
        Node::Y => Some(Leaf::Scalar(Scalar::Num(0.0))),
        Node::T => Some(Leaf::Scalar(Scalar::T)),
        Node::X => Some(Leaf::X),
        _ => None,
    }
}

/// The right operand of a binary node over one block.
#[derive(Clone, Copy)]
enum Operand<'a> {
    Scalar(f64),
    Array(&'a [f64]),
}

/// `out[i] = f(out[i], b_i)`.
#[inline(always)]
fn combine(out: &mut [f64], b: Operand<'_>, f: impl Fn(f64, f64) -> f64) {
    match b {
        Operand::Scalar(c) => out.iter_mut().for_each(|o| *o = f(*o, c)),
        Operand::Array(b) => out.iter_mut().zip(b).for_each(|(o, &b)| *o = f(*o, b)),
    }
}

/// Evaluates `b`, the right operand of a binary node, over the block `xs`: in place when it is
/// a leaf, else into the first scratch array of `pool`. Calls `then` with it and the rest of
/// the pool.
#[inline(always)]
fn with_operand<R>(
    b: &Node,
    xs: &[f64],
    t: f64,
    pool: &mut [Vec<f64>],
    then: impl FnOnce(Operand<'_>) -> R,
) -> R {
    match leaf(b) {
        Some(Leaf::Scalar(Scalar::Num(v))) => then(Operand::Scalar(v)),
        Some(Leaf::Scalar(Scalar::T)) => then(Operand::Scalar(t)),
        Some(Leaf::X) => then(Operand::Array(xs)),
        None => {
            let (tmp, rest) = pool.split_first_mut().expect("pool sized by `scratch`");
            let tmp = &mut tmp[..xs.len()];
            eval_into(b, xs, t, tmp, rest);
            then(Operand::Array(tmp))
        }
    }
}

/// `out[i] = f(out[i])`, choosing the function once for the block (the same function
/// [`Func1::apply`] calls, named for the common ones).
fn apply1(f: Func1, out: &mut [f64]) {
    let map = |out: &mut [f64], g: fn(f64) -> f64| out.iter_mut().for_each(|v| *v = g(*v));
    match f {
        Func1::Sin => map(out, f64::sin),
        Func1::Cos => map(out, f64::cos),
        Func1::Exp => map(out, f64::exp),
        Func1::Sqrt => map(out, f64::sqrt),
        Func1::Abs => map(out, f64::abs),
        Func1::Tanh => map(out, f64::tanh),
        Func1::Ln => map(out, f64::ln),
        _ => out.iter_mut().for_each(|v| *v = f.apply(*v)),
    }
}

/// `out = node(xs, t)` over one block, using `pool` for intermediate arrays.
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
            apply1(*f, out);
        }
        Node::Bin(op, a, b) => {
            eval_into(a, xs, t, out, pool);
            if *op == BinOp::Pow && matches!(**b, Node::Num(e) if e == 2.0) {
                out.iter_mut().for_each(|o| *o *= *o);
                return;
            }
            with_operand(b, xs, t, pool, |b| match op {
                BinOp::Add => combine(out, b, |a, b| a + b),
                BinOp::Sub => combine(out, b, |a, b| a - b),
                BinOp::Mul => combine(out, b, |a, b| a * b),
                BinOp::Div => combine(out, b, |a, b| a / b),
                BinOp::Pow => combine(out, b, pow),
            });
        }
        Node::Cmp(op, a, b) => {
            eval_into(a, xs, t, out, pool);
            with_operand(b, xs, t, pool, |b| combine(out, b, |a, b| op.apply(a, b)));
        }
        Node::Call2(f, a, b) => {
            eval_into(a, xs, t, out, pool);
            with_operand(b, xs, t, pool, |b| match f {
                Func2::Min => combine(out, b, f64::min),
                Func2::Max => combine(out, b, f64::max),
                Func2::Atan2 => combine(out, b, f64::atan2),
            });
        }
        Node::If(c, a, b) => {
            eval_into(c, xs, t, out, pool);
            let (then, rest) = pool.split_first_mut().expect("pool sized by `scratch`");
            let then = &mut then[..xs.len()];
            eval_into(a, xs, t, then, rest);
            let (other, rest) = rest.split_first_mut().expect("pool sized by `scratch`");
            let other = &mut other[..xs.len()];
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

/// Scratch arrays for [`eval_block`] of `expr`.
pub fn block_pool(expr: &Expression) -> Vec<Vec<f64>> {
    vec![vec![0.0; BLOCK]; scratch(expr.root())]
}

/// `out[i] = f(xs[i], t)` for at most [`BLOCK`] points with the scratch arrays of
/// [`block_pool`], the bits of [`Expression::eval`], non-finite values left in `out` unchecked.
pub fn eval_block(expr: &Expression, xs: &[f64], t: f64, out: &mut [f64], pool: &mut [Vec<f64>]) {
    debug_assert!(xs.len() <= BLOCK && out.len() == xs.len());
    eval_into(expr.root(), xs, t, out, pool);
}

impl NodalEvaluator {
    /// Prepares `expr` for evaluation at the nodes `xs`.
    pub fn new(expr: Expression, xs: Vec<f64>) -> Self {
        let pool = vec![vec![0.0; xs.len().min(BLOCK)]; scratch(expr.root())];
        Self { expr, xs, pool }
    }

    pub fn expression(&self) -> &Expression {
        &self.expr
    }

    /// `out[i] = f(x_i, t)`; an error names the field, the expression and the first node where
    /// the value is not a finite number (as [`Expression::eval`] would).
    pub fn eval_into(&mut self, t: f64, out: &mut [f64]) -> Result<(), SceneError> {
        let root = self.expr.root();
        for (start, (xs, out)) in (0..)
            .step_by(BLOCK)
            .zip(self.xs.chunks(BLOCK).zip(out.chunks_mut(BLOCK)))
        {
            eval_into(root, xs, t, out, &mut self.pool);
            if let Some(i) = out.iter().position(|v| !v.is_finite()) {
                return self.expr.eval(self.xs[start + i], t).map(|_| ());
            }
        }
        Ok(())
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
    fn blocks_and_operands_in_place_give_the_bits_of_the_scalar_evaluation() {
        // Several blocks and a partial one; leaves on either side of every kind of node.
        let xs: Vec<f64> = (0..3 * BLOCK + 37)
            .map(|i| -2.0 + 0.005 * i as f64)
            .collect();
        for text in [
            "0.1*sin(x*t)*exp(-(x-t)^2)",
            "x - t + (x / 3) ^ 3 - 2 ^ x + (t - x) * 3 - (x < t) + (t >= x) + min(x, 0.5)",
            "atan2(t, x) + max(-x, t) + if(x, t, x - t) + (1 - x)/(x*x + t + 1)",
            "-(x^2) + (x*x + 1)^t + 2^2 + t^x",
        ] {
            let e = Expression::parse("load.density", text, true).unwrap();
            let mut n = NodalEvaluator::new(e.clone(), xs.clone());
            let mut out = vec![0.0; xs.len()];
            for t in [0.25, 1.7] {
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
