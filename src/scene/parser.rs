//! The parser of scene expressions ([`crate::scene::expr`]): a small recursive-descent parser
//! from text to the expression tree. The grammar (numbers, `x`, `y`, `t`, constants, `+ - * /`
//! left-associative, `^` right-associative and tighter than unary minus, comparisons loosest,
//! `if`, `step`, the one- and several-argument functions) is README.md's "Expressions" table.
//! Spaces are ignored; nesting is bounded by `MAX_DEPTH`. A parse error names the field, the
//! text and the column (counted in characters from 1), e.g.
//! ``` `initial.displacement` = "max(0,min(1,2-x)": unclosed parenthesis opened at column 4```.

use crate::scene::SceneError;
use crate::scene::expr::{BinOp, CONSTANTS, CmpOp, Expression, FUNC1, Func2, Node};

/// Deepest nesting of parentheses, unary signs and powers accepted (keeps the recursive parser
/// and evaluator far from the stack limit on hostile input).
const MAX_DEPTH: usize = 200;

// ---------------------------------------------------------------------------------------------
// Tokens

#[derive(Clone, Debug, PartialEq)]
enum Tok {
    Num(f64),
    Ident(String),
    Op(&'static str),
    LParen,
    RParen,
    Comma,
    End,
}

#[derive(Clone, Debug)]
struct Token {
    tok: Tok,
    /// Column of the first character, counted in characters from 1.
    col: usize,
}

impl Tok {
    fn describe(&self) -> String {
        match self {
            Tok::Num(_) => "a number".into(),
            Tok::Ident(name) => format!("`{name}`"),
            Tok::Op(op) => format!("`{op}`"),
            Tok::LParen => "`(`".into(),
            Tok::RParen => "`)`".into(),
            Tok::Comma => "`,`".into(),
            Tok::End => "the end of the expression".into(),
        }
    }

    fn starts_operand(&self) -> bool {
        matches!(self, Tok::Num(_) | Tok::Ident(_) | Tok::LParen)
    }
}

fn is_ident_start(c: char) -> bool {
    c.is_alphabetic() || c == '_'
}

fn is_ident_char(c: char) -> bool {
    c.is_alphanumeric() || c == '_'
}

fn tokenize(text: &str) -> Result<Vec<Token>, String> {
    let chars: Vec<char> = text.chars().collect();
    let mut out = Vec::new();
    let mut i = 0;
    while i < chars.len() {
        let c = chars[i];
        let col = i + 1;
        if c.is_whitespace() {
            i += 1;
            continue;
        }
        if c.is_ascii_digit() || (c == '.' && chars.get(i + 1).is_some_and(char::is_ascii_digit)) {
            let start = i;
            while i < chars.len() && chars[i].is_ascii_digit() {
                i += 1;
            }
            if i < chars.len() && chars[i] == '.' {
                i += 1;
                while i < chars.len() && chars[i].is_ascii_digit() {
                    i += 1;
                }
            }
            if i < chars.len() && (chars[i] == 'e' || chars[i] == 'E') {
                let mut k = i + 1;
                if k < chars.len() && (chars[k] == '+' || chars[k] == '-') {
                    k += 1;
                }
                if k < chars.len() && chars[k].is_ascii_digit() {
                    while k < chars.len() && chars[k].is_ascii_digit() {
                        k += 1;
                    }
                    i = k;
                }
            }
            let literal: String = chars[start..i].iter().collect();
            let value = literal
                .parse::<f64>()
                .map_err(|_| format!("`{literal}` at column {col} is not a number"))?;
            out.push(Token {
                tok: Tok::Num(value),
                col,
            });
            if i < chars.len() && is_ident_start(chars[i]) {
                return Err(format!(
                    "missing operator before `{}` at column {} (write `*` to multiply)",
                    chars[i],
                    i + 1
                ));
            }
            if i < chars.len() && chars[i] == '.' {
                return Err(format!(
                    "second decimal point at column {} in the number at column {col}",
                    i + 1
                ));
            }
            continue;
        }
        if is_ident_start(c) {
            let start = i;
            while i < chars.len() && is_ident_char(chars[i]) {
                i += 1;
            }
            out.push(Token {
                tok: Tok::Ident(chars[start..i].iter().collect()),
                col,
            });
            continue;
        }
        let two: Option<&'static str> = match (c, chars.get(i + 1)) {
            ('<', Some('=')) => Some("<="),
            ('>', Some('=')) => Some(">="),
            ('=', Some('=')) => Some("=="),
            ('!', Some('=')) => Some("!="),
            _ => None,
        };
        if let Some(op) = two {
            out.push(Token {
                tok: Tok::Op(op),
                col,
            });
            i += 2;
            continue;
        }
        let tok = match c {
            '+' => Tok::Op("+"),
            '-' => Tok::Op("-"),
            '*' => Tok::Op("*"),
            '/' => Tok::Op("/"),
            '^' => Tok::Op("^"),
            '<' => Tok::Op("<"),
            '>' => Tok::Op(">"),
            '(' => Tok::LParen,
            ')' => Tok::RParen,
            ',' => Tok::Comma,
            '=' => return Err(format!("`=` at column {col}: write `==` to compare")),
            '!' => return Err(format!("`!` at column {col}: write `!=` for \"not equal\"")),
            other => {
                return Err(format!(
                    "unexpected character `{other}` at column {col} (operators are + - * / ^ \
                     < <= > >= == !=)"
                ));
            }
        };
        out.push(Token { tok, col });
        i += 1;
    }
    out.push(Token {
        tok: Tok::End,
        col: chars.len() + 1,
    });
    Ok(out)
}

// ---------------------------------------------------------------------------------------------
// Parser

struct Parser<'a> {
    tokens: Vec<Token>,
    pos: usize,
    depth: usize,
    allow_t: bool,
    allow_y: bool,
    /// An edge's gap: the only variable is `s`, read as `x` (the edge's coordinate).
    edge: bool,
    field: &'a str,
    uses_x: bool,
    uses_y: bool,
    uses_t: bool,
}

impl Parser<'_> {
    fn peek(&self) -> &Token {
        &self.tokens[self.pos]
    }

    fn next(&mut self) -> Token {
        let t = self.tokens[self.pos].clone();
        if t.tok != Tok::End {
            self.pos += 1;
        }
        t
    }

    fn is_op(&self, op: &str) -> bool {
        matches!(self.peek().tok, Tok::Op(o) if o == op)
    }

    fn enter(&mut self) -> Result<(), String> {
        self.depth += 1;
        if self.depth > MAX_DEPTH {
            return Err(format!(
                "nested more than {MAX_DEPTH} levels deep at column {}",
                self.peek().col
            ));
        }
        Ok(())
    }

    /// The whole text: one expression, then the end.
    fn parse_all(&mut self) -> Result<Node, String> {
        if self.peek().tok == Tok::End {
            return Err("the expression is empty (write 0 for zero)".into());
        }
        let node = self.expr()?;
        let t = self.peek().clone();
        match t.tok {
            Tok::End => Ok(node),
            Tok::RParen => Err(format!("`)` at column {} has no matching `(`", t.col)),
            _ => Err(self.unexpected_after_operand(&t)),
        }
    }

    fn unexpected_after_operand(&self, t: &Token) -> String {
        if t.tok.starts_operand() {
            format!(
                "missing operator before {} at column {} (write `*` to multiply)",
                t.tok.describe(),
                t.col
            )
        } else {
            format!("unexpected {} at column {}", t.tok.describe(), t.col)
        }
    }

    /// comparison := sum [ cmp-op sum ]
    fn expr(&mut self) -> Result<Node, String> {
        let left = self.sum()?;
        let Some((op, _)) = self.cmp_op() else {
            return Ok(left);
        };
        self.next();
        let right = self.sum()?;
        if let Some((_, col)) = self.cmp_op() {
            return Err(format!(
                "a second comparison at column {col}: comparisons cannot be chained; \
                 write e.g. (a < b)*(b < c)"
            ));
        }
        Ok(Node::Cmp(op, Box::new(left), Box::new(right)))
    }

    fn cmp_op(&self) -> Option<(CmpOp, usize)> {
        let t = self.peek();
        let op = match t.tok {
            Tok::Op("<") => CmpOp::Lt,
            Tok::Op("<=") => CmpOp::Le,
            Tok::Op(">") => CmpOp::Gt,
            Tok::Op(">=") => CmpOp::Ge,
            Tok::Op("==") => CmpOp::Eq,
            Tok::Op("!=") => CmpOp::Ne,
            _ => return None,
        };
        Some((op, t.col))
    }

    /// sum := product { (+|-) product }, left-associative
    fn sum(&mut self) -> Result<Node, String> {
        let mut left = self.product()?;
        loop {
            let op = if self.is_op("+") {
                BinOp::Add
            } else if self.is_op("-") {
                BinOp::Sub
            } else {
                return Ok(left);
            };
            self.next();
            let right = self.product()?;
            left = Node::Bin(op, Box::new(left), Box::new(right));
        }
    }

    /// product := unary { (*|/) unary }, left-associative
    fn product(&mut self) -> Result<Node, String> {
        let mut left = self.unary()?;
        loop {
            let op = if self.is_op("*") {
                BinOp::Mul
            } else if self.is_op("/") {
                BinOp::Div
            } else {
                return Ok(left);
            };
            self.next();
            let right = self.unary()?;
            left = Node::Bin(op, Box::new(left), Box::new(right));
        }
    }

    /// unary := (-|+) unary | power
    fn unary(&mut self) -> Result<Node, String> {
        self.enter()?;
        let node = if self.is_op("-") {
            self.next();
            Node::Neg(Box::new(self.unary()?))
        } else if self.is_op("+") {
            self.next();
            self.unary()?
        } else {
            self.power()?
        };
        self.depth -= 1;
        Ok(node)
    }

    /// power := primary [ ^ unary ], so right-associative and `2^-1` allowed
    fn power(&mut self) -> Result<Node, String> {
        let base = self.primary()?;
        if self.is_op("^") {
            self.next();
            let exponent = self.unary()?;
            return Ok(Node::Bin(BinOp::Pow, Box::new(base), Box::new(exponent)));
        }
        Ok(base)
    }

    /// primary := number | variable | constant | function ( args ) | ( expr )
    fn primary(&mut self) -> Result<Node, String> {
        let t = self.next();
        match t.tok {
            Tok::Num(v) => Ok(Node::Num(v)),
            Tok::LParen => {
                self.enter()?;
                let inner = self.expr()?;
                self.close(t.col, None)?;
                self.depth -= 1;
                Ok(inner)
            }
            Tok::Ident(name) => {
                if self.peek().tok == Tok::LParen {
                    let open = self.next().col;
                    self.call(&name, t.col, open)
                } else {
                    self.name(&name, t.col)
                }
            }
            other => Err(format!(
                "expected a number, a variable, a function or `(` at column {}, found {}",
                t.col,
                other.describe()
            )),
        }
    }

    /// Expects the `)` that closes the parenthesis opened at column `open`.
    fn close(&mut self, open: usize, function: Option<&str>) -> Result<(), String> {
        let t = self.peek().clone();
        match t.tok {
            Tok::RParen => {
                self.next();
                Ok(())
            }
            Tok::End => Err(match function {
                Some(f) => format!("unclosed parenthesis of `{f}(` opened at column {open}"),
                None => format!("unclosed parenthesis opened at column {open}"),
            }),
            Tok::Comma if function.is_none() => Err(format!(
                "`,` at column {} outside a function's argument list",
                t.col
            )),
            _ => Err(self.unexpected_after_operand(&t)),
        }
    }

    fn name(&mut self, name: &str, col: usize) -> Result<Node, String> {
        match name {
            "s" if self.edge => {
                self.uses_x = true;
                return Ok(Node::X);
            }
            "x" if !self.edge => {
                self.uses_x = true;
                return Ok(Node::X);
            }
            "y" if self.allow_y => {
                self.uses_y = true;
                return Ok(Node::Y);
            }
            "t" if self.allow_t => {
                self.uses_t = true;
                return Ok(Node::T);
            }
            _ => {}
        }
        if let Some((_, v)) = CONSTANTS.iter().find(|(n, _)| *n == name) {
            return Ok(Node::Num(*v));
        }
        if FUNC1.iter().any(|(n, _)| *n == name) || is_multi(name) {
            return Err(format!(
                "`{name}` at column {col} is a function: write {name}(...)"
            ));
        }
        let vars = match (self.allow_y, self.allow_t) {
            _ if self.edge => "s",
            (false, false) => "x",
            (false, true) => "x, t",
            (true, false) => "x, y",
            (true, true) => "x, y, t",
        };
        let mut msg = format!(
            "unknown variable `{name}` at column {col} (allowed: {vars}, constants pi, e, tau)"
        );
        if name == "t" {
            let only = if self.allow_y { "x and y" } else { "x" };
            msg.push_str(&format!("; `{}` may depend on {only} only", self.field));
        } else if matches!(name, "inf" | "infinity" | "nan" | "NaN") {
            msg.push_str("; a value must be a finite number");
        }
        Err(msg)
    }

    /// Arguments of `name(` (the parenthesis at column `open`), separated by commas.
    fn call(&mut self, name: &str, col: usize, open: usize) -> Result<Node, String> {
        self.enter()?;
        let mut args = Vec::new();
        if self.peek().tok == Tok::RParen {
            self.next();
        } else {
            loop {
                args.push(self.expr()?);
                if self.peek().tok == Tok::Comma {
                    self.next();
                    continue;
                }
                self.close(open, Some(name))?;
                break;
            }
        }
        self.depth -= 1;
        let n = args.len();
        let count = |wanted: &str| {
            format!(
                "`{name}` at column {col} takes {wanted}, got {n} argument{}",
                if n == 1 { "" } else { "s" }
            )
        };
        if let Some((_, f)) = FUNC1.iter().find(|(n, _)| *n == name) {
            if n != 1 {
                return Err(count("1 argument"));
            }
            let a = args.pop().expect("one argument");
            return Ok(Node::Call1(*f, Box::new(a)));
        }
        match name {
            "min" | "max" => {
                if n < 2 {
                    return Err(count("2 or more arguments"));
                }
                let f = if name == "min" {
                    Func2::Min
                } else {
                    Func2::Max
                };
                let mut it = args.into_iter();
                let first = it.next().expect("two arguments");
                Ok(it.fold(first, |acc, a| Node::Call2(f, Box::new(acc), Box::new(a))))
            }
            "atan2" => {
                if n != 2 {
                    return Err(count("2 arguments (y, x)"));
                }
                let b = args.pop().expect("two arguments");
                let a = args.pop().expect("two arguments");
                Ok(Node::Call2(Func2::Atan2, Box::new(a), Box::new(b)))
            }
            "if" => {
                if n != 3 {
                    return Err(count(
                        "3 arguments (condition, value if true, value if false)",
                    ));
                }
                let b = args.pop().expect("three arguments");
                let a = args.pop().expect("three arguments");
                let c = args.pop().expect("three arguments");
                Ok(Node::If(Box::new(c), Box::new(a), Box::new(b)))
            }
            _ => {
                let names: Vec<&str> = FUNC1.iter().map(|(n, _)| *n).collect();
                Err(format!(
                    "unknown function `{name}` at column {col} (functions: {}, min, max, atan2, if)",
                    names.join(", ")
                ))
            }
        }
    }
}

fn is_multi(name: &str) -> bool {
    matches!(name, "min" | "max" | "atan2" | "if")
}

impl Expression {
    /// Parses `text` for the scene field `field` (named in every error). `allow_t` is false for
    /// initial data and gaps, which may depend on `x` only.
    pub fn parse(field: &str, text: &str, allow_t: bool) -> Result<Self, SceneError> {
        Self::parse_with(field, text, allow_t, false)
    }

    /// [`Expression::parse`] for a plane scene: `y` is a variable too (see [`Expression::eval_xy`]).
    pub fn parse_plane(field: &str, text: &str, allow_t: bool) -> Result<Self, SceneError> {
        Self::parse_with(field, text, allow_t, true)
    }

    /// An edge's gap of a plane scene: an expression in the edge's coordinate `s` only (`x`
    /// along the bottom and top, `y` along the left and right edge), evaluated by
    /// [`Expression::eval`] with `s` in place of `x`.
    pub fn parse_edge(field: &str, text: &str) -> Result<Self, SceneError> {
        Self::parse_full(field, text, false, false, true)
    }

    fn parse_with(
        field: &str,
        text: &str,
        allow_t: bool,
        allow_y: bool,
    ) -> Result<Self, SceneError> {
        Self::parse_full(field, text, allow_t, allow_y, false)
    }

    fn parse_full(
        field: &str,
        text: &str,
        allow_t: bool,
        allow_y: bool,
        edge: bool,
    ) -> Result<Self, SceneError> {
        let bad = |reason: String| SceneError::Expression {
            field: field.to_string(),
            text: text.to_string(),
            reason,
        };
        let tokens = tokenize(text).map_err(bad)?;
        let mut parser = Parser {
            tokens,
            pos: 0,
            depth: 0,
            allow_t,
            allow_y,
            edge,
            field,
            uses_x: false,
            uses_y: false,
            uses_t: false,
        };
        let root = parser.parse_all().map_err(bad)?;
        Ok(Self {
            text: text.to_string(),
            field: field.to_string(),
            root,
            uses_x: parser.uses_x,
            uses_y: parser.uses_y,
            uses_t: parser.uses_t,
        })
    }
}
