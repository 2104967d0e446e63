//! An expression evaluated over a whole array of nodes one operation at a time: each node of
//! the tree becomes one loop over the array, so the interpreter's dispatch is paid once per
//! operation instead of once per operation and node. The array is taken in blocks of
//! [`BLOCK`] nodes, the whole expression over one block before the next, so the intermediate
//! arrays stay in the L1 cache.
//!
//! [`NodalEvaluator`] compiles the tree once at set-up into a `Program`, a flat list of
//! loops: constant subtrees folded, subtrees of `t` alone evaluated once per call as scalars,
//! `x` and scalars read in place, a sign or square fused into the loop before it. The
//! set-up's [`eval_block`] walks the tree per block. Buffers are sized at set-up, so an
//! evaluation allocates nothing. [`eval_block`] gives the values of [`Expression::eval`] bit
//! for bit (the same `f64` operations in the same order at each point); so does the program,
//! except that it takes `sin`, `cos` and `exp` from [`vecmath`] (vectorised, within
//! [`vecmath::MAX_ULPS`] of `std`'s), so its values match to round-off, and the same bits at
//! any block split.

use crate::scene::SceneError;
use crate::scene::expr::{BinOp, CmpOp, Expression, Func1, Func2, Node, pow};
use crate::scene::vecmath;

/// Nodes evaluated together: a few scratch arrays of this many doubles (2 KiB each) stay in
/// the L1 cache, and the walk of the tree per block costs little next to a block's work.
pub const BLOCK: usize = 256;

/// `f(x_i, t)` at fixed nodes `x_i`, for any `t`.
#[derive(Clone, Debug)]
pub struct NodalEvaluator {
    expr: Expression,
    xs: Vec<f64>,
    /// Boxed: a simulation's load holds it beside smaller variants.
    compiled: Box<Compiled>,
}

/// A [`Program`] and its buffers.
#[derive(Clone, Debug)]
struct Compiled {
    program: Program,
    /// The program's scratch arrays, `stride` doubles each.
    scratch: Vec<f64>,
    stride: usize,
    /// Values of the program's subtrees of `t` alone at the current call.
    params: Vec<f64>,
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
    /// Prepares `expr` for evaluation at the nodes `xs`: compiles it into a `Program` once.
    pub fn new(expr: Expression, xs: Vec<f64>) -> Self {
        let program = Program::compile(expr.root());
        let stride = xs.len().clamp(1, BLOCK);
        Self {
            compiled: Box::new(Compiled {
                scratch: vec![0.0; program.regs * stride],
                params: vec![0.0; program.params.len()],
                program,
                stride,
            }),
            expr,
            xs,
        }
    }

    pub fn expression(&self) -> &Expression {
        &self.expr
    }

    /// `out[i] = f(x_i, t)`; an error names the field, the expression and the first node where
    /// the value is not a finite number (as [`Expression::eval`] would).
    pub fn eval_into(&mut self, t: f64, out: &mut [f64]) -> Result<(), SceneError> {
        // Subtrees of `t` alone: once per call, the bits of the tree walk at any node.
        let c = &mut *self.compiled;
        for (p, node) in c.params.iter_mut().zip(&c.program.params) {
            *p = node.eval(0.0, 0.0, t);
        }
        for (start, (xs, out)) in (0..)
            .step_by(BLOCK)
            .zip(self.xs.chunks(BLOCK).zip(out.chunks_mut(BLOCK)))
        {
            c.program.run(xs, &c.params, out, &mut c.scratch, c.stride);
            // `|` rather than `any`: no early exit, so the check vectorises.
            if out.iter().fold(false, |bad, v| bad | !v.is_finite()) {
                // The plain evaluation decides: its error, or its value where the round-off of
                // the block's `sin`, `cos`, `exp` alone overflowed.
                for (i, o) in out.iter_mut().enumerate() {
                    if !o.is_finite() {
                        *o = self.expr.eval(self.xs[start + i], t)?;
                    }
                }
            }
        }
        Ok(())
    }
}

// ---------------------------------------------------------------------------------------------
// The compiled form

/// Where an operand is read over one block: the instruction's own output array (in place),
/// a higher scratch array, `x`, a constant, or a subtree of `t` alone evaluated once per call.
#[derive(Clone, Copy, Debug, PartialEq)]
enum Src {
    Dst,
    Reg(usize),
    X,
    Const(f64),
    Param(usize),
}

#[derive(Clone, Copy, Debug)]
enum Fn2 {
    Bin(BinOp),
    Cmp(CmpOp),
    Call(Func2),
}

/// A sign or a square applied in the loop of the [`Instr::Binary`] before it (one pass over
/// the block instead of two or three, e.g. `-(x - t)^2`).
#[derive(Clone, Copy, Debug, PartialEq)]
enum Post {
    None,
    Neg,
    Square,
    /// `−(v²)`.
    NegSquare,
}

#[derive(Clone, Copy, Debug)]
enum Fn1 {
    Neg,
    /// `a^2` as one product, as [`pow`] computes it.
    Square,
    Call(Func1),
}

/// One loop over a block. Array 0 is the output; array `r > 0` is scratch array `r − 1`. An
/// instruction writing array `d` reads only `d` itself and arrays above it (the compiler hands
/// out arrays as a stack), so the borrows split at `d`.
#[derive(Clone, Copy, Debug)]
enum Instr {
    /// `d = a`.
    Load { dst: usize, a: Src },
    /// `d = post(f(a, b))`.
    Binary {
        f: Fn2,
        dst: usize,
        a: Src,
        b: Src,
        post: Post,
    },
    /// `d = f(d)`.
    Unary { f: Fn1, dst: usize },
    /// `d = if(d, a, b)`.
    If { dst: usize, a: Src, b: Src },
}

/// An expression compiled once at set-up into a flat list of loops over a block: no walk of
/// the tree per block, constant subtrees folded, subtrees of `t` alone evaluated once per
/// call as scalars, `x` and scalars read in place. Every point sees the same `f64` operations
/// in the same order as [`Node::eval`], so the values are its bits, but for `sin`, `cos` and
/// `exp` from [`vecmath`] (within [`vecmath::MAX_ULPS`]).
#[derive(Clone, Debug)]
struct Program {
    code: Vec<Instr>,
    /// The subtrees of `t` alone, by parameter index.
    params: Vec<Node>,
    /// Scratch arrays needed besides the output.
    regs: usize,
}

impl Program {
    fn compile(root: &Node) -> Self {
        let mut p = Program {
            code: Vec::new(),
            params: Vec::new(),
            regs: 0,
        };
        p.emit(root, 0);
        p
    }

    /// `node` as an operand read in place, when it needs no array of its own.
    fn leaf(&mut self, node: &Node) -> Option<Src> {
        match node {
            Node::X => return Some(Src::X),
            // A bar expression is evaluated at `y = 0`, as `Expression::eval` does.
            Node::Y => return Some(Src::Const(0.0)),
            _ => {}
        }
        // `uses` counts `y` as `x`, so a subtree reading `y` is never hoisted.
        match node.uses() {
            (true, _) => None,
            (false, false) => Some(Src::Const(node.eval(0.0, 0.0, 0.0))),
            (false, true) => {
                self.params.push(node.clone());
                Some(Src::Param(self.params.len() - 1))
            }
        }
    }

    /// Emits the loops that leave `node` in array `dst`, using arrays above it.
    fn emit(&mut self, node: &Node, dst: usize) {
        self.regs = self.regs.max(dst);
        if let Some(a) = self.leaf(node) {
            self.code.push(Instr::Load { dst, a });
            return;
        }
        let unary = |p: &mut Self, a: &Node, f: Fn1| {
            p.emit(a, dst);
            if let Some(Instr::Binary { dst: d, post, .. }) = p.code.last_mut()
                && *d == dst
            {
                let fused = match (*post, f) {
                    (Post::None, Fn1::Neg) => Some(Post::Neg),
                    (Post::None, Fn1::Square) => Some(Post::Square),
                    (Post::Square, Fn1::Neg) => Some(Post::NegSquare),
                    _ => None,
                };
                if let Some(fused) = fused {
                    *post = fused;
                    return;
                }
            }
            p.code.push(Instr::Unary { f, dst });
        };
        match node {
            Node::Neg(a) => unary(self, a, Fn1::Neg),
            Node::Call1(f, a) => unary(self, a, Fn1::Call(*f)),
            Node::Bin(BinOp::Pow, a, b)
                if b.uses() == (false, false) && b.eval(0.0, 0.0, 0.0) == 2.0 =>
            {
                unary(self, a, Fn1::Square)
            }
            Node::Bin(op, a, b) => self.binary(Fn2::Bin(*op), a, b, dst),
            Node::Cmp(op, a, b) => self.binary(Fn2::Cmp(*op), a, b, dst),
            Node::Call2(f, a, b) => self.binary(Fn2::Call(*f), a, b, dst),
            Node::If(c, a, b) => {
                self.emit(c, dst);
                let a = self.operand(a, dst + 1);
                let b = self.operand(b, dst + 2);
                self.code.push(Instr::If { dst, a, b });
            }
            Node::Num(_) | Node::X | Node::Y | Node::T => unreachable!("leaves are loaded"),
        }
    }

    /// `node` in place, or computed into array `reg`.
    fn operand(&mut self, node: &Node, reg: usize) -> Src {
        self.leaf(node).unwrap_or_else(|| {
            self.emit(node, reg);
            Src::Reg(reg)
        })
    }

    fn binary(&mut self, f: Fn2, a: &Node, b: &Node, dst: usize) {
        let (la, lb) = (self.leaf(a), self.leaf(b));
        let (a, b) = match (la, lb) {
            (Some(a), Some(b)) => (a, b),
            (None, Some(b)) => {
                self.emit(a, dst);
                (Src::Dst, b)
            }
            (Some(a), None) => {
                self.emit(b, dst);
                (a, Src::Dst)
            }
            (None, None) => {
                self.emit(a, dst);
                self.emit(b, dst + 1);
                (Src::Dst, Src::Reg(dst + 1))
            }
        };
        self.code.push(Instr::Binary {
            f,
            dst,
            a,
            b,
            post: Post::None,
        });
    }

    /// Runs the program over one block `xs` into `out`, with `scratch` holding [`Program::regs`]
    /// arrays of `stride >= xs.len()` doubles.
    fn run(&self, xs: &[f64], params: &[f64], out: &mut [f64], scratch: &mut [f64], stride: usize) {
        let n = xs.len();
        for ins in &self.code {
            let dst = match *ins {
                Instr::Load { dst, .. }
                | Instr::Binary { dst, .. }
                | Instr::Unary { dst, .. }
                | Instr::If { dst, .. } => dst,
            };
            // The output array and the arrays above it (array `r` at `(r − dst − 1) stride`).
            let (d, above): (&mut [f64], &[f64]) = if dst == 0 {
                (&mut *out, &*scratch)
            } else {
                let (d, above) = scratch[(dst - 1) * stride..].split_at_mut(stride);
                (d, above)
            };
            let d = &mut d[..n];
            let val = |s: Src| match s {
                Src::Dst => Val::Dst,
                Src::Reg(r) => Val::Array(&above[(r - dst - 1) * stride..][..n]),
                Src::X => Val::Array(xs),
                Src::Const(c) => Val::Scalar(c),
                Src::Param(p) => Val::Scalar(params[p]),
            };
            match *ins {
                Instr::Load { a, .. } => match val(a) {
                    Val::Dst => {}
                    Val::Array(a) => d.copy_from_slice(a),
                    Val::Scalar(c) => d.fill(c),
                },
                Instr::Binary { f, a, b, post, .. } => {
                    let (a, b) = (val(a), val(b));
                    match post {
                        Post::None => binary(f, d, a, b, |v| v),
                        Post::Neg => binary(f, d, a, b, |v| -v),
                        Post::Square => binary(f, d, a, b, |v| v * v),
                        Post::NegSquare => binary(f, d, a, b, |v| -(v * v)),
                    }
                }
                Instr::Unary { f, .. } => unary(f, d),
                Instr::If { a, b, .. } => {
                    let (a, b) = (val(a), val(b));
                    for (i, o) in d.iter_mut().enumerate() {
                        let at = |v: &Val<'_>| match v {
                            Val::Dst => unreachable!("branches are not the condition's array"),
                            Val::Array(a) => a[i],
                            Val::Scalar(c) => *c,
                        };
                        *o = if o.is_nan() {
                            f64::NAN
                        } else if *o != 0.0 {
                            at(&a)
                        } else {
                            at(&b)
                        };
                    }
                }
            }
        }
    }
}

/// An operand over one block.
#[derive(Clone, Copy)]
enum Val<'a> {
    /// The output array itself.
    Dst,
    Array(&'a [f64]),
    Scalar(f64),
}

/// `d = f(a, b)`, one loop per kind of operand (so each loop vectorises where `f` does).
#[inline(always)]
fn zip2(d: &mut [f64], a: Val<'_>, b: Val<'_>, f: impl Fn(f64, f64) -> f64) {
    use Val::*;
    match (a, b) {
        (Dst, Dst) => d.iter_mut().for_each(|o| *o = f(*o, *o)),
        (Dst, Array(b)) => d.iter_mut().zip(b).for_each(|(o, &b)| *o = f(*o, b)),
        (Dst, Scalar(c)) => d.iter_mut().for_each(|o| *o = f(*o, c)),
        (Array(a), Dst) => d.iter_mut().zip(a).for_each(|(o, &a)| *o = f(a, *o)),
        (Scalar(c), Dst) => d.iter_mut().for_each(|o| *o = f(c, *o)),
        (Array(a), Array(b)) => d
            .iter_mut()
            .zip(a.iter().zip(b))
            .for_each(|(o, (&a, &b))| *o = f(a, b)),
        (Array(a), Scalar(c)) => d.iter_mut().zip(a).for_each(|(o, &a)| *o = f(a, c)),
        (Scalar(c), Array(b)) => d.iter_mut().zip(b).for_each(|(o, &b)| *o = f(c, b)),
        (Scalar(a), Scalar(b)) => d.fill(f(a, b)),
    }
}

/// `d = post(f(a, b))`.
#[inline(always)]
fn binary(f: Fn2, d: &mut [f64], a: Val<'_>, b: Val<'_>, post: impl Fn(f64) -> f64 + Copy) {
    match f {
        Fn2::Bin(BinOp::Add) => zip2(d, a, b, |a, b| post(a + b)),
        Fn2::Bin(BinOp::Sub) => zip2(d, a, b, |a, b| post(a - b)),
        Fn2::Bin(BinOp::Mul) => zip2(d, a, b, |a, b| post(a * b)),
        Fn2::Bin(BinOp::Div) => zip2(d, a, b, |a, b| post(a / b)),
        Fn2::Bin(BinOp::Pow) => zip2(d, a, b, |a, b| post(pow(a, b))),
        Fn2::Cmp(op) => zip2(d, a, b, |a, b| post(op.apply(a, b))),
        Fn2::Call(Func2::Min) => zip2(d, a, b, |a, b| post(a.min(b))),
        Fn2::Call(Func2::Max) => zip2(d, a, b, |a, b| post(a.max(b))),
        Fn2::Call(Func2::Atan2) => zip2(d, a, b, |a, b| post(a.atan2(b))),
    }
}

fn unary(f: Fn1, d: &mut [f64]) {
    match f {
        Fn1::Neg => d.iter_mut().for_each(|v| *v = -*v),
        Fn1::Square => d.iter_mut().for_each(|v| *v *= *v),
        // `std`'s are one call per value, not vectorised: about 45 instructions each.
        Fn1::Call(Func1::Sin) => vecmath::sin(d),
        Fn1::Call(Func1::Cos) => vecmath::cos(d),
        Fn1::Call(Func1::Exp) => vecmath::exp(d),
        Fn1::Call(f) => apply1(f, d),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The bits of the scalar evaluation without `sin`, `cos`, `exp`; with them, its value
    /// within a few roundings of the terms (all of size below 16 here), each operation after a
    /// kernel's `vecmath::MAX_ULPS` rounding at most one ulp apart.
    fn assert_matches(text: &str, v: f64, e: f64, x: f64, t: f64) {
        if ["sin", "cos", "exp"].iter().any(|f| text.contains(f)) {
            let tol = 16.0 * 8.0 * f64::EPSILON;
            assert!((v - e).abs() <= tol, "{text} at ({x}, {t}): {v} vs {e}");
        } else {
            assert_eq!(v.to_bits(), e.to_bits(), "{text} at ({x}, {t})");
        }
    }

    #[test]
    fn every_operation_gives_the_value_of_the_scalar_evaluation() {
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
                    assert_matches(text, v, e.eval(x, t).unwrap(), x, t);
                }
            }
        }
    }

    #[test]
    fn blocks_and_operands_in_place_give_the_value_of_the_scalar_evaluation() {
        // Several blocks and a partial one; leaves on either side of every kind of node.
        let xs: Vec<f64> = (0..3 * BLOCK + 37)
            .map(|i| -2.0 + 0.005 * i as f64)
            .collect();
        for text in [
            "0.1*sin(x*t)*exp(-(x-t)^2)",
            "x - t + (x / 3) ^ 3 - 2 ^ x + (t - x) * 3 - (x < t) + (t >= x) + min(x, 0.5)",
            "atan2(t, x) + max(-x, t) + if(x, t, x - t) + (1 - x)/(x*x + t + 1)",
            "-(x^2) + (x*x + 1)^t + 2^2 + t^x",
            // Hoisted and folded subtrees, fused signs and squares, leaves alone.
            "x^(1+1) + if(t < 1, x, -x) * (t*t + 1) - (x*x + t)^(2*t)",
            "exp(-(x - t)^2) - (x*t)^2 + -(x + t) + sin(t)*x + cos(2*t)",
            "t",
            "2",
            "x",
        ] {
            let e = Expression::parse("load.density", text, true).unwrap();
            let mut n = NodalEvaluator::new(e.clone(), xs.clone());
            let mut out = vec![0.0; xs.len()];
            for t in [0.25, 1.7] {
                n.eval_into(t, &mut out).unwrap();
                for (&x, &v) in xs.iter().zip(&out) {
                    assert_matches(text, v, e.eval(x, t).unwrap(), x, t);
                }
            }
        }
    }

    #[test]
    fn the_mixed_load_compiles_to_six_loops_with_t_read_once_per_call() {
        let e = Expression::parse("load.density", "0.1*sin(x*t)*exp(-(x-t)^2)", true).unwrap();
        let p = Program::compile(e.root());
        // x*t, sin, 0.1*·, −(x − t)², exp, the product; one scratch array.
        assert_eq!(p.code.len(), 6, "{:?}", p.code);
        assert_eq!((p.params.len(), p.regs), (2, 1));
    }

    #[test]
    fn a_non_finite_value_is_reported_at_its_node() {
        let e = Expression::parse("load.density", "1/(x - t)", true).unwrap();
        let mut n = NodalEvaluator::new(e, vec![0.0, 0.5, 1.0]);
        let mut out = vec![0.0; 3];
        let err = n.eval_into(0.5, &mut out).unwrap_err().to_string();
        assert!(err.contains("load.density") && err.contains("0.5"), "{err}");
        // A hoisted subtree of `t` that is infinite makes the value infinite at every node.
        let e = Expression::parse("load.density", "x + 1/(t - 0.5)", true).unwrap();
        let mut n = NodalEvaluator::new(e.clone(), vec![0.0, 0.5, 1.0]);
        let err = n.eval_into(0.5, &mut out).unwrap_err().to_string();
        assert_eq!(err, e.eval(0.0, 0.5).unwrap_err().to_string());
    }
}
