//! Expressions in `x` and `t` from scene files, parsed and evaluated by the `exmex` crate.
//!
//! Besides `x` and `t`, the name `pi` may be used (exmex itself spells the constant `PI` or `π`).

use crate::scene::SceneError;
use exmex::prelude::*;
use exmex::{FloatOpsFactory, MatchLiteral};

/// Numeric literals with an optional exponent (`1e6`, `2.5E-3`): exmex's default matcher reads
/// `1e6` as `1`, Euler's `e`, `6`. An `e` counts as an exponent only after a mantissa and before
/// digits, so `2*e` is still Euler's number.
#[derive(Clone, Debug, Default)]
pub struct ScientificLiteral;

impl MatchLiteral for ScientificLiteral {
    fn is_literal(text: &str) -> Option<&str> {
        let b = text.as_bytes();
        let digits = |mut i: usize| {
            while i < b.len() && b[i].is_ascii_digit() {
                i += 1;
            }
            i
        };
        let int_end = digits(0);
        let mut end = int_end;
        if end < b.len() && b[end] == b'.' {
            end = digits(end + 1);
        }
        if end == 0 || (end == 1 && b[0] == b'.') {
            return None;
        }
        if end < b.len() && (b[end] == b'e' || b[end] == b'E') {
            let mut k = end + 1;
            if k < b.len() && (b[k] == b'+' || b[k] == b'-') {
                k += 1;
            }
            let exp_end = digits(k);
            if exp_end > k {
                end = exp_end;
            }
        }
        Some(&text[..end])
    }
}

type Flat = FlatEx<f64, FloatOpsFactory<f64>, ScientificLiteral>;

/// A parsed expression `f(x, t)`, evaluated with the variables it does not use ignored.
#[derive(Clone, Debug)]
pub struct Expression {
    text: String,
    field: String,
    flat: Flat,
    /// Position in the argument list of each variable exmex found (alphabetical order).
    slots: Vec<Var>,
}

#[derive(Clone, Copy, Debug, PartialEq)]
enum Var {
    X,
    T,
    Pi,
}

impl Expression {
    /// Parses `text` for the scene field `field` (named in every error). `allow_t` is false for
    /// initial data, which may depend on `x` only.
    pub fn parse(field: &str, text: &str, allow_t: bool) -> Result<Self, SceneError> {
        let bad = |reason: String| SceneError::Expression {
            field: field.to_string(),
            text: text.to_string(),
            reason,
        };
        let flat = Flat::parse(text).map_err(|e| bad(e.to_string()))?;
        let slots = flat
            .var_names()
            .iter()
            .map(|name| match name.as_str() {
                "x" => Ok(Var::X),
                "t" if allow_t => Ok(Var::T),
                "pi" => Ok(Var::Pi),
                other => Err(bad(format!(
                    "unknown variable `{other}` (allowed: x{}, pi)",
                    if allow_t { ", t" } else { "" }
                ))),
            })
            .collect::<Result<Vec<_>, _>>()?;
        Ok(Self {
            text: text.to_string(),
            field: field.to_string(),
            flat,
            slots,
        })
    }

    pub fn text(&self) -> &str {
        &self.text
    }

    pub fn depends_on_x(&self) -> bool {
        self.slots.contains(&Var::X)
    }

    pub fn depends_on_t(&self) -> bool {
        self.slots.contains(&Var::T)
    }

    /// `f(x, t)`; an error names the field, the expression and the point when the value is not
    /// a finite number.
    pub fn eval(&self, x: f64, t: f64) -> Result<f64, SceneError> {
        let mut args = [0.0; 3];
        for (a, v) in args.iter_mut().zip(&self.slots) {
            *a = match v {
                Var::X => x,
                Var::T => t,
                Var::Pi => std::f64::consts::PI,
            };
        }
        let value = self.flat.eval(&args[..self.slots.len()]);
        match value {
            Ok(v) if v.is_finite() => Ok(v),
            Ok(v) => Err(SceneError::NonFinite {
                field: self.field.clone(),
                text: self.text.clone(),
                x,
                t,
                value: v,
            }),
            Err(e) => Err(SceneError::Expression {
                field: self.field.clone(),
                text: self.text.clone(),
                reason: e.to_string(),
            }),
        }
    }
}
