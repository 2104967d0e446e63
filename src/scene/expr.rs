//! Expressions in `x`, `y` and `t` from scene files: the tree ([`Expression`]) and its
//! evaluation by a tree walk in `f64` (no allocation per evaluation). The grammar and the
//! parser are in [`crate::scene::parser`].
//!
//! Every operation is the `std` `f64` method: `^` is `f64::powf`, `min`/`max` are
//! `f64::min`/`f64::max`, `atan2(y, x)` is `y.atan2(x)`, `ln` and `log` are `f64::ln`. Chains of
//! `+ - * /` are evaluated left to right.

use crate::scene::SceneError;

/// A parsed expression `f(x, y, t)` (an edge's gap: `f(s, t)`).
#[derive(Clone, Debug)]
pub struct Expression {
    pub(super) text: String,
    pub(super) field: String,
    pub(super) root: Node,
    pub(super) uses_x: bool,
    pub(super) uses_y: bool,
    pub(super) uses_t: bool,
    /// An edge's gap: `x` is the edge's coordinate `s` (named so in errors).
    pub(super) edge: bool,
}

#[derive(Clone, Debug)]
pub(super) enum Node {
    Num(f64),
    X,
    /// `y`: plane scenes only.
    Y,
    T,
    Neg(Box<Node>),
    Bin(BinOp, Box<Node>, Box<Node>),
    Cmp(CmpOp, Box<Node>, Box<Node>),
    Call1(Func1, Box<Node>),
    Call2(Func2, Box<Node>, Box<Node>),
    If(Box<Node>, Box<Node>, Box<Node>),
}

#[derive(Clone, Copy, Debug, PartialEq)]
pub(super) enum BinOp {
    Add,
    Sub,
    Mul,
    Div,
    Pow,
}

#[derive(Clone, Copy, Debug, PartialEq)]
pub(super) enum CmpOp {
    Lt,
    Le,
    Gt,
    Ge,
    Eq,
    Ne,
}

#[derive(Clone, Copy, Debug, PartialEq)]
pub(super) enum Func1 {
    Sin,
    Cos,
    Tan,
    Asin,
    Acos,
    Atan,
    Sinh,
    Cosh,
    Tanh,
    Asinh,
    Acosh,
    Atanh,
    Exp,
    Ln,
    Log2,
    Log10,
    Sqrt,
    Cbrt,
    Abs,
    Sign,
    Signum,
    Floor,
    Ceil,
    Round,
    Trunc,
    Fract,
    Step,
}

#[derive(Clone, Copy, Debug, PartialEq)]
pub(super) enum Func2 {
    Min,
    Max,
    Atan2,
}

pub(super) const FUNC1: &[(&str, Func1)] = &[
    ("sin", Func1::Sin),
    ("cos", Func1::Cos),
    ("tan", Func1::Tan),
    ("asin", Func1::Asin),
    ("acos", Func1::Acos),
    ("atan", Func1::Atan),
    ("sinh", Func1::Sinh),
    ("cosh", Func1::Cosh),
    ("tanh", Func1::Tanh),
    ("asinh", Func1::Asinh),
    ("acosh", Func1::Acosh),
    ("atanh", Func1::Atanh),
    ("exp", Func1::Exp),
    ("ln", Func1::Ln),
    ("log", Func1::Ln),
    ("log2", Func1::Log2),
    ("log10", Func1::Log10),
    ("sqrt", Func1::Sqrt),
    ("cbrt", Func1::Cbrt),
    ("abs", Func1::Abs),
    ("sign", Func1::Sign),
    ("signum", Func1::Signum),
    ("floor", Func1::Floor),
    ("ceil", Func1::Ceil),
    ("round", Func1::Round),
    ("trunc", Func1::Trunc),
    ("fract", Func1::Fract),
    ("step", Func1::Step),
];

pub(super) const CONSTANTS: &[(&str, f64)] = &[
    ("pi", std::f64::consts::PI),
    ("PI", std::f64::consts::PI),
    ("π", std::f64::consts::PI),
    ("e", std::f64::consts::E),
    ("E", std::f64::consts::E),
    ("tau", std::f64::consts::TAU),
    ("TAU", std::f64::consts::TAU),
    ("τ", std::f64::consts::TAU),
];

impl Func1 {
    pub(super) fn apply(self, a: f64) -> f64 {
        match self {
            Func1::Sin => a.sin(),
            Func1::Cos => a.cos(),
            Func1::Tan => a.tan(),
            Func1::Asin => a.asin(),
            Func1::Acos => a.acos(),
            Func1::Atan => a.atan(),
            Func1::Sinh => a.sinh(),
            Func1::Cosh => a.cosh(),
            Func1::Tanh => a.tanh(),
            Func1::Asinh => a.asinh(),
            Func1::Acosh => a.acosh(),
            Func1::Atanh => a.atanh(),
            Func1::Exp => a.exp(),
            Func1::Ln => a.ln(),
            Func1::Log2 => a.log2(),
            Func1::Log10 => a.log10(),
            Func1::Sqrt => a.sqrt(),
            Func1::Cbrt => a.cbrt(),
            Func1::Abs => a.abs(),
            Func1::Sign => {
                if a > 0.0 {
                    1.0
                } else if a < 0.0 {
                    -1.0
                } else if a == 0.0 {
                    0.0
                } else {
                    f64::NAN
                }
            }
            Func1::Signum => a.signum(),
            Func1::Floor => a.floor(),
            Func1::Ceil => a.ceil(),
            Func1::Round => a.round(),
            Func1::Trunc => a.trunc(),
            Func1::Fract => a.fract(),
            Func1::Step => {
                if a.is_nan() {
                    f64::NAN
                } else if a >= 0.0 {
                    1.0
                } else {
                    0.0
                }
            }
        }
    }
}

/// `a^b`, with the square as one correctly rounded product (the commonest power in loads and
/// data, and several times cheaper than `powf`).
pub(super) fn pow(a: f64, b: f64) -> f64 {
    if b == 2.0 { a * a } else { a.powf(b) }
}

impl CmpOp {
    /// `1` or `0`, and NaN when either side is NaN (never read as false).
    pub(super) fn apply(self, a: f64, b: f64) -> f64 {
        if a.is_nan() || b.is_nan() {
            return f64::NAN;
        }
        truth(match self {
            CmpOp::Lt => a < b,
            CmpOp::Le => a <= b,
            CmpOp::Gt => a > b,
            CmpOp::Ge => a >= b,
            CmpOp::Eq => a == b,
            CmpOp::Ne => a != b,
        })
    }
}

pub(super) fn truth(b: bool) -> f64 {
    if b { 1.0 } else { 0.0 }
}

impl Node {
    pub(super) fn eval(&self, x: f64, y: f64, t: f64) -> f64 {
        match self {
            Node::Num(v) => *v,
            Node::X => x,
            Node::Y => y,
            Node::T => t,
            Node::Neg(a) => -a.eval(x, y, t),
            Node::Bin(op, a, b) => {
                let (a, b) = (a.eval(x, y, t), b.eval(x, y, t));
                match op {
                    BinOp::Add => a + b,
                    BinOp::Sub => a - b,
                    BinOp::Mul => a * b,
                    BinOp::Div => a / b,
                    BinOp::Pow => pow(a, b),
                }
            }
            Node::Cmp(op, a, b) => op.apply(a.eval(x, y, t), b.eval(x, y, t)),
            Node::Call1(f, a) => f.apply(a.eval(x, y, t)),
            Node::Call2(f, a, b) => {
                let (a, b) = (a.eval(x, y, t), b.eval(x, y, t));
                match f {
                    Func2::Min => a.min(b),
                    Func2::Max => a.max(b),
                    Func2::Atan2 => a.atan2(b),
                }
            }
            Node::If(c, a, b) => {
                let c = c.eval(x, y, t);
                if c.is_nan() {
                    f64::NAN
                } else if c != 0.0 {
                    a.eval(x, y, t)
                } else {
                    b.eval(x, y, t)
                }
            }
        }
    }
}

impl Expression {
    /// An expression for `field` with the tree `root` (a part of a parsed expression, whose
    /// `text` it keeps for messages).
    pub(super) fn from_root(field: &str, text: &str, root: Node) -> Self {
        let (uses_x, uses_t) = root.uses();
        Self {
            text: text.to_string(),
            field: field.to_string(),
            root,
            uses_x,
            // Parts come from separating a bar load, which never reads `y`.
            uses_y: false,
            uses_t,
            edge: false,
        }
    }

    pub(super) fn root(&self) -> &Node {
        &self.root
    }

    pub(super) fn field(&self) -> &str {
        &self.field
    }

    pub fn text(&self) -> &str {
        &self.text
    }

    pub fn depends_on_x(&self) -> bool {
        self.uses_x
    }

    pub fn depends_on_y(&self) -> bool {
        self.uses_y
    }

    pub fn depends_on_t(&self) -> bool {
        self.uses_t
    }

    /// `f(x, t)`; an error names the field, the expression and the point when the value is not
    /// a finite number.
    pub fn eval(&self, x: f64, t: f64) -> Result<f64, SceneError> {
        let v = self.root.eval(x, 0.0, t);
        if v.is_finite() {
            Ok(v)
        } else if self.edge {
            Err(SceneError::NonFiniteEdge {
                field: self.field.clone(),
                text: self.text.clone(),
                s: x,
                t,
                value: v,
            })
        } else {
            Err(SceneError::NonFinite {
                field: self.field.clone(),
                text: self.text.clone(),
                x,
                t,
                value: v,
            })
        }
    }

    /// `f(x, y, t)` of an expression parsed with [`Expression::parse_plane`]; an error names
    /// the field, the expression and the point when the value is not a finite number.
    pub fn eval_xy(&self, x: f64, y: f64, t: f64) -> Result<f64, SceneError> {
        let v = self.root.eval(x, y, t);
        if v.is_finite() {
            Ok(v)
        } else {
            Err(SceneError::NonFinitePlane {
                field: self.field.clone(),
                text: self.text.clone(),
                x,
                y,
                t,
                value: v,
            })
        }
    }
}

/// The text of a number given where an expression may be: `{:?}` of the `f64`, which reads back
/// to the same bits (`0.1` stays `0.1`, `1e-7` stays `1e-7`); shared by every expression field
/// so that `displacement = 0.1`, `--set initial.displacement=0.1` and `gap = 0.1` agree.
pub fn number_text(v: f64) -> String {
    format!("{v:?}")
}

/// Serde: an expression field given as a string (the expression) or as a number (TOML integer
/// or float, kept as [`number_text`]). A non-finite float is kept as `inf`/`NaN`, which the
/// expression parser then refuses with the field's name.
pub(crate) fn number_or_expression<'de, D: serde::Deserializer<'de>>(
    d: D,
) -> Result<String, D::Error> {
    struct Visitor;
    impl serde::de::Visitor<'_> for Visitor {
        type Value = String;
        fn expecting(&self, f: &mut std::fmt::Formatter) -> std::fmt::Result {
            f.write_str("a number or an expression in quotes, e.g. 0.1 or \"0.3*cos(2*x)\"")
        }
        fn visit_str<E: serde::de::Error>(self, v: &str) -> Result<String, E> {
            Ok(v.to_string())
        }
        fn visit_string<E: serde::de::Error>(self, v: String) -> Result<String, E> {
            Ok(v)
        }
        fn visit_i64<E: serde::de::Error>(self, v: i64) -> Result<String, E> {
            Ok(number_text(v as f64))
        }
        fn visit_u64<E: serde::de::Error>(self, v: u64) -> Result<String, E> {
            Ok(number_text(v as f64))
        }
        fn visit_f64<E: serde::de::Error>(self, v: f64) -> Result<String, E> {
            Ok(number_text(v))
        }
    }
    d.deserialize_any(Visitor)
}
