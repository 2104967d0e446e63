//! Scene expressions (README, "Expressions"): the grammar table's examples, the cases that
//! used to fail, errors naming field and column, numbers wherever an expression is, and random
//! expression trees against the same tree evaluated directly in Rust.

use proptest::prelude::*;
use viscobar::Scene;
use viscobar::internals::scene::nodal::NodalEvaluator;
use viscobar::scene::Expression;

/// Values computed by one or two correctly rounded operations: they must come out exactly,
/// up to the one rounding of a library function (sqrt is exact, 2π is one multiplication).
const EXACT: f64 = 0.0;

fn eval(text: &str, x: f64, t: f64) -> f64 {
    Expression::parse("load.density", text, true)
        .unwrap_or_else(|e| panic!("{text}: {e}"))
        .eval(x, t)
        .unwrap_or_else(|e| panic!("{text}: {e}"))
}

/// The examples of the README's grammar table, with the values computed by hand there.
#[test]
fn the_grammar_table_examples_give_their_values() {
    let cases: [(&str, f64, f64); 12] = [
        ("1e-2", 0.0, 0.01),
        ("2*x", 0.25, 0.5),
        ("2*pi", 0.0, 2.0 * std::f64::consts::PI),
        ("8/4/2", 0.0, 1.0),
        ("2^3^2", 0.0, 512.0),
        ("-2^2", 0.0, -4.0),
        ("2^-1", 0.0, 0.5),
        ("-0.3*(x<2)", 1.0, -0.3),
        ("if(x<0.5, 1, 2)", 0.75, 2.0),
        ("sqrt(16)", 0.0, 4.0),
        ("max(0,min(1,2-x))", 1.5, 0.5),
        ("step(0) + sign(0) + signum(0)", 0.0, 2.0),
    ];
    for (text, x, expected) in cases {
        let v = eval(text, x, 0.0);
        assert!(
            (v - expected).abs() <= EXACT,
            "{text} at x = {x}: {v} vs {expected}"
        );
    }
}

/// What a new user tried and the former parser refused.
#[test]
fn nested_functions_comparisons_and_sign_work() {
    assert_eq!(eval("max(0,min(1,2-x))", 0.5, 0.0), 1.0);
    assert_eq!(eval("max(0,min(1,2-x))", 3.0, 0.0), 0.0);
    assert_eq!(eval("-0.3*(x<2)", 2.5, 0.0), 0.0);
    assert_eq!(eval("sign(2-x)", 3.0, 0.0), -1.0);
    assert_eq!(eval("min(1,(2-x)/0.05)", 1.99, 0.0), (2.0 - 1.99) / 0.05);
    assert_eq!(
        eval("sin(t*sqrt(2))*cos(2*x)", 0.3, 0.7),
        (0.7 * 2f64.sqrt()).sin() * (2.0 * 0.3f64).cos()
    );
}

/// Errors name the field, quote the text and point at the column, in plain words.
#[test]
fn errors_name_the_field_and_the_column() {
    let err = |field: &str, text: &str, allow_t: bool| match Expression::parse(field, text, allow_t)
    {
        Ok(_) => panic!("{text} accepted"),
        Err(e) => e.to_string(),
    };
    let e = err("initial.displacement", "max(0,min(1,2-x)", false);
    assert!(
        e.contains("`initial.displacement`") && e.contains("column 4"),
        "{e}"
    );
    let e = err("initial.velocity", "2*(x+1))", false);
    assert!(
        e.contains("`initial.velocity`") && e.contains("column 8"),
        "{e}"
    );
    let e = err("initial.displacement", "sin(t)", false);
    assert!(e.contains('t') && e.contains("column 5"), "{e}");
    let e = err("load.density", "foo(x)", true);
    assert!(e.contains("foo") && e.contains("column 1"), "{e}");
    for e in [e, err("load.density", "x = 1", true)] {
        assert!(!e.contains("exmex") && !e.contains("Token"), "{e}");
    }
}

fn scene_with(displacement: &str, velocity: &str) -> String {
    format!(
        "[bar]\nlength = 1.0\nviscosity = 0.0\n[left]\ncondition = \"free\"\n\
         [right]\ncondition = \"free\"\n[initial]\ndisplacement = {displacement}\n\
         velocity = {velocity}\n[mesh]\nelements = 10\n[time]\nstep = 0.1\nend = 0.2\n"
    )
}

/// A plain number is accepted where an expression is: in TOML and through `--set`.
#[test]
fn a_number_is_an_expression() {
    let scene = Scene::from_toml(&scene_with("0.1", "-1"), &[]).unwrap();
    assert_eq!(eval(&scene.initial.displacement, 0.3, 0.0), 0.1);
    assert_eq!(eval(&scene.initial.velocity, 0.3, 0.0), -1.0);
    let set = ["initial.displacement=0.25".to_string()];
    let scene = Scene::from_toml(&scene_with("\"x\"", "0"), &set).unwrap();
    assert_eq!(eval(&scene.initial.displacement, 0.3, 0.0), 0.25);

    let out = std::env::temp_dir().join(format!("viscobar-expr-{}", std::process::id()));
    let o = std::process::Command::new(env!("CARGO_BIN_EXE_viscobar"))
        .args([
            "run",
            "impact",
            "--set",
            "initial.displacement=0.1",
            "--out",
        ])
        .arg(&out)
        .output()
        .unwrap();
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let _ = std::fs::remove_dir_all(&out);
}

/// A random expression tree, its text and its value by a direct Rust evaluation of the same
/// operations in the same order.
#[derive(Clone, Debug)]
enum Tree {
    X,
    T,
    Num(u8),
    Add(Box<Tree>, Box<Tree>),
    Sub(Box<Tree>, Box<Tree>),
    Mul(Box<Tree>, Box<Tree>),
    Div(Box<Tree>, Box<Tree>),
    Neg(Box<Tree>),
    Sin(Box<Tree>),
    Exp(Box<Tree>),
    Square(Box<Tree>),
    Min(Box<Tree>, Box<Tree>),
    Max(Box<Tree>, Box<Tree>),
    Less(Box<Tree>, Box<Tree>),
    If(Box<Tree>, Box<Tree>, Box<Tree>),
}

impl Tree {
    fn text(&self) -> String {
        use Tree::*;
        match self {
            X => "x".into(),
            T => "t".into(),
            Num(n) => format!("{n}"),
            Add(a, b) => format!("({} + {})", a.text(), b.text()),
            Sub(a, b) => format!("({} - {})", a.text(), b.text()),
            Mul(a, b) => format!("({} * {})", a.text(), b.text()),
            Div(a, b) => format!("({} / {})", a.text(), b.text()),
            Neg(a) => format!("(-{})", a.text()),
            Sin(a) => format!("sin({})", a.text()),
            Exp(a) => format!("exp({})", a.text()),
            Square(a) => format!("({})^2", a.text()),
            Min(a, b) => format!("min({}, {})", a.text(), b.text()),
            Max(a, b) => format!("max({},{})", a.text(), b.text()),
            Less(a, b) => format!("({} < {})", a.text(), b.text()),
            If(c, a, b) => format!("if({}, {}, {})", c.text(), a.text(), b.text()),
        }
    }

    fn value(&self, x: f64, t: f64) -> f64 {
        use Tree::*;
        match self {
            X => x,
            T => t,
            Num(n) => f64::from(*n),
            Add(a, b) => a.value(x, t) + b.value(x, t),
            Sub(a, b) => a.value(x, t) - b.value(x, t),
            Mul(a, b) => a.value(x, t) * b.value(x, t),
            Div(a, b) => a.value(x, t) / b.value(x, t),
            Neg(a) => -a.value(x, t),
            Sin(a) => a.value(x, t).sin(),
            Exp(a) => a.value(x, t).exp(),
            Square(a) => {
                let a = a.value(x, t);
                a * a
            }
            Min(a, b) => a.value(x, t).min(b.value(x, t)),
            Max(a, b) => a.value(x, t).max(b.value(x, t)),
            // A comparison or condition on NaN is NaN (README, "Expressions"), not false.
            Less(a, b) => {
                let (a, b) = (a.value(x, t), b.value(x, t));
                if a.is_nan() || b.is_nan() {
                    f64::NAN
                } else {
                    f64::from(u8::from(a < b))
                }
            }
            If(c, a, b) => {
                let c = c.value(x, t);
                if c.is_nan() {
                    f64::NAN
                } else if c != 0.0 {
                    a.value(x, t)
                } else {
                    b.value(x, t)
                }
            }
        }
    }

    /// The value and a bound on how far the node-array evaluation may be from it: its `sin`
    /// and `exp` are within `vecmath::MAX_ULPS` of `std`'s, and every later operation adds
    /// the propagated difference and at most one rounding of either (`ε|v|`, `ε` = 2⁻⁵²).
    /// `None` where the difference could flip a comparison or a condition.
    fn roundoff(&self, x: f64, t: f64) -> Option<(f64, f64)> {
        use Tree::*;
        let eps = f64::EPSILON;
        let kernel = vecmath::MAX_ULPS as f64 + 1.0;
        // A rounding of either evaluation once the operands differ.
        let round = |d: f64, v: f64| {
            if d > 0.0 {
                d * (1.0 + eps) + eps * v.abs()
            } else {
                0.0
            }
        };
        let v = self.value(x, t);
        let d = match self {
            X | T | Num(_) => 0.0,
            Neg(a) => a.roundoff(x, t)?.1,
            Add(a, b) | Sub(a, b) => round(a.roundoff(x, t)?.1 + b.roundoff(x, t)?.1, v),
            Mul(a, b) => {
                let ((a, da), (b, db)) = (a.roundoff(x, t)?, b.roundoff(x, t)?);
                round(b.abs() * da + a.abs() * db + da * db, v)
            }
            Div(a, b) => {
                let ((_, da), (b, db)) = (a.roundoff(x, t)?, b.roundoff(x, t)?);
                if b.abs() <= db {
                    return None;
                }
                round((da + v.abs() * db) / (b.abs() - db), v)
            }
            Square(a) => {
                let (a, da) = a.roundoff(x, t)?;
                round(2.0 * a.abs() * da + da * da, v)
            }
            // Lipschitz 1, then the kernel's ulps (and `std`'s rounding) of the result.
            Sin(a) => {
                let da = a.roundoff(x, t)?.1;
                da * (1.0 + eps) + kernel * eps * (v.abs() + da)
            }
            Exp(a) => {
                let (a, da) = a.roundoff(x, t)?;
                let top = (a + da).exp();
                top * da * (1.0 + eps) + kernel * eps * top
            }
            Min(a, b) | Max(a, b) => a.roundoff(x, t)?.1.max(b.roundoff(x, t)?.1),
            Less(a, b) => {
                let ((a, da), (b, db)) = (a.roundoff(x, t)?, b.roundoff(x, t)?);
                if da + db > 0.0 && ((a - b).abs() <= da + db || a.is_nan() || b.is_nan()) {
                    return None;
                }
                0.0
            }
            If(c, a, b) => {
                let (c, dc) = c.roundoff(x, t)?;
                if dc > 0.0 && (c.abs() <= dc || c.is_nan()) {
                    return None;
                }
                if c != 0.0 && !c.is_nan() {
                    a.roundoff(x, t)?.1
                } else {
                    b.roundoff(x, t)?.1
                }
            }
        };
        Some((v, d))
    }
}

fn tree() -> impl Strategy<Value = Tree> {
    let leaf = prop_oneof![Just(Tree::X), Just(Tree::T), (0u8..10).prop_map(Tree::Num)];
    leaf.prop_recursive(5, 40, 3, |inner| {
        let b = || inner.clone().prop_map(Box::new);
        prop_oneof![
            (b(), b()).prop_map(|(a, c)| Tree::Add(a, c)),
            (b(), b()).prop_map(|(a, c)| Tree::Sub(a, c)),
            (b(), b()).prop_map(|(a, c)| Tree::Mul(a, c)),
            (b(), b()).prop_map(|(a, c)| Tree::Div(a, c)),
            b().prop_map(Tree::Neg),
            b().prop_map(Tree::Sin),
            b().prop_map(Tree::Exp),
            b().prop_map(Tree::Square),
            (b(), b()).prop_map(|(a, c)| Tree::Min(a, c)),
            (b(), b()).prop_map(|(a, c)| Tree::Max(a, c)),
            (b(), b()).prop_map(|(a, c)| Tree::Less(a, c)),
            (b(), b(), b()).prop_map(|(c, a, d)| Tree::If(c, a, d)),
        ]
    })
}

proptest! {
    /// The parser evaluates a fully parenthesised tree with the same operations in the same
    /// order, hence the same bits (a division by zero gives an error, not a value).
    #[test]
    fn random_trees_evaluate_like_rust(tree in tree(), x in -2.0f64..2.0, t in 0.0f64..3.0) {
        let expected = tree.value(x, t);
        let parsed = Expression::parse("load.density", &tree.text(), true).unwrap();
        match parsed.eval(x, t) {
            Ok(v) => prop_assert_eq!(v.to_bits(), expected.to_bits(), "{}", tree.text()),
            Err(_) => prop_assert!(!expected.is_finite(), "{} = {} refused", tree.text(), expected),
        }
    }
}

/// Nodes spanning three blocks of the node-array evaluator and a partial one.
fn nodes() -> Vec<f64> {
    let n = 3 * viscobar::internals::scene::nodal::BLOCK + 41;
    (0..n).map(|i| -2.0 + 4.0 * i as f64 / n as f64).collect()
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(128))]

    /// The compiled node-array evaluation (subtrees of `t` hoisted, constants folded, signs
    /// and squares fused into loops, `sin` and `exp` from `vecmath`) gives the values of the
    /// same tree evaluated in Rust at every node within the round-off bound of
    /// [`Tree::roundoff`] (bit for bit without `sin` and `exp`), or the scalar evaluation's
    /// error at the first node where the value is not finite.
    #[test]
    fn random_trees_over_the_node_array_evaluate_like_rust(tree in tree(), t in 0.0f64..3.0) {
        let parsed = Expression::parse("load.density", &tree.text(), true).unwrap();
        let xs = nodes();
        let mut nodal = NodalEvaluator::new(parsed.clone(), xs.clone());
        let mut out = vec![0.0; xs.len()];
        let first_bad = xs.iter().position(|&x| !tree.value(x, t).is_finite());
        match (nodal.eval_into(t, &mut out), first_bad) {
            (Ok(()), None) => {
                let text = tree.text();
                let transcendental = text.contains("sin") || text.contains("exp");
                for (&x, &v) in xs.iter().zip(&out) {
                    let plain = tree.value(x, t);
                    if !transcendental {
                        prop_assert_eq!(v.to_bits(), plain.to_bits(), "{} at {}", text, x);
                    } else if let Some((_, bound)) = tree.roundoff(x, t) {
                        prop_assert!((v - plain).abs() <= bound, "{} at {}: {} vs {}, bound {:e}", text, x, v, plain, bound);
                    }
                }
            }
            (Err(e), Some(i)) => prop_assert_eq!(
                e.to_string(),
                parsed.eval(xs[i], t).unwrap_err().to_string()
            ),
            (r, bad) => prop_assert!(false, "{}: {:?} with the first non-finite node {:?}", tree.text(), r, bad),
        }
        // Another split into blocks (the nodes from the 17th on): the same bits.
        let mut shifted = NodalEvaluator::new(parsed.clone(), xs[17..].to_vec());
        let mut other = vec![0.0; xs.len() - 17];
        if shifted.eval_into(t, &mut other).is_ok() && nodal.eval_into(t, &mut out).is_ok() {
            for (i, v) in other.iter().enumerate() {
                prop_assert_eq!(v.to_bits(), out[17 + i].to_bits(), "{} at {}", tree.text(), xs[17 + i]);
            }
        }
    }
}

// ---------------------------------------------------------------------------------------------
// The block kernels of the compiled loads (src/scene/vecmath.rs) against `std`

use viscobar::internals::scene::vecmath;

/// Seeded arguments (SplitMix64), the same on every run.
struct Seeded(u64);

impl Seeded {
    fn next(&mut self) -> u64 {
        self.0 = self.0.wrapping_add(0x9e37_79b9_7f4a_7c15);
        let mut z = self.0;
        z = (z ^ (z >> 30)).wrapping_mul(0xbf58_476d_1ce4_e5b9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94d0_49bb_1331_11eb);
        z ^ (z >> 31)
    }

    /// Uniform in `[lo, hi)`.
    fn uniform(&mut self, lo: f64, hi: f64) -> f64 {
        lo + (hi - lo) * ((self.next() >> 11) as f64 / (1u64 << 53) as f64)
    }

    /// `±2^e·m` with `e` uniform in `[lo, hi)`: every scale alike.
    fn log_uniform(&mut self, lo: f64, hi: f64) -> f64 {
        let v = self.uniform(lo, hi).exp2() * self.uniform(1.0, 2.0);
        if self.next() & 1 == 0 { v } else { -v }
    }
}

/// Distance in units in the last place between two finite values of the same sign, or
/// `u64::MAX` when they differ in sign or finiteness (zeros of either sign are 0 apart).
fn ulps(a: f64, b: f64) -> u64 {
    let key = |v: f64| {
        let bits = v.to_bits() as i64;
        if bits < 0 { i64::MIN - bits } else { bits }
    };
    if a.is_nan() && b.is_nan() {
        0
    } else if a.is_finite() != b.is_finite()
        || (a.is_infinite() && a != b)
        || a.is_nan()
        || b.is_nan()
    {
        u64::MAX
    } else {
        key(a).abs_diff(key(b))
    }
}

/// The largest distance of `kernel` from `std` over `args`, through blocks of varied length.
fn worst_ulps(args: &[f64], kernel: fn(&mut [f64]), reference: fn(f64) -> f64) -> (u64, f64) {
    let mut v = args.to_vec();
    for (k, block) in v.chunks_mut(251).enumerate() {
        let (a, b) = block.split_at_mut(k % block.len().max(1));
        kernel(a);
        kernel(b);
    }
    args.iter()
        .zip(&v)
        .map(|(&x, &y)| (ulps(y, reference(x)), x))
        .fold((0, f64::NAN), |w, d| if d.0 > w.0 { d } else { w })
}

type Kernel = (&'static str, fn(&mut [f64]), fn(f64) -> f64);
const KERNELS: [Kernel; 3] = [
    ("sin", vecmath::sin, f64::sin),
    ("cos", vecmath::cos, f64::cos),
    ("exp", vecmath::exp, f64::exp),
];

/// Arguments by range: name, count, generator.
fn ranges(name: &str) -> Vec<(&'static str, Vec<f64>)> {
    let mut g = Seeded(0x5eed_0017);
    let mut draw = |n: usize, f: &mut dyn FnMut(&mut Seeded) -> f64| -> Vec<f64> {
        (0..n).map(|_| f(&mut g)).collect()
    };
    let pio2 = std::f64::consts::FRAC_PI_2;
    let mut v = vec![
        (
            "tiny",
            draw(200_000, &mut |g| g.log_uniform(-1074.0, -20.0)),
        ),
        ("small", draw(200_000, &mut |g| g.log_uniform(-20.0, 2.0))),
    ];
    if name == "exp" {
        v.push((
            "[-745, 710]",
            draw(1_000_000, &mut |g| g.uniform(-745.0, 710.0)),
        ));
        v.push((
            "[-30, 30]",
            draw(1_000_000, &mut |g| g.uniform(-30.0, 30.0)),
        ));
        v.push((
            "subnormal results",
            draw(200_000, &mut |g| g.uniform(-745.2, -700.0)),
        ));
        v.push((
            "zero results",
            draw(200_000, &mut |g| g.uniform(-1e5, -740.0)),
        ));
        v.push((
            "overflow edge",
            draw(200_000, &mut |g| g.uniform(705.0, 710.0)),
        ));
    } else {
        v.push(("[-pi, pi]", draw(1_000_000, &mut |g| g.uniform(-3.2, 3.2))));
        v.push(("up to 1e5", draw(1_000_000, &mut |g| g.uniform(-1e5, 1e5))));
        v.push(("up to 2e6", draw(200_000, &mut |g| g.uniform(-2e6, 2e6))));
        // The nearest doubles to multiples of π/2 and their neighbours: the reduction's
        // cancellation at its worst.
        v.push((
            "near k pi/2",
            draw(400_000, &mut |g| {
                let k = (g.next() % 1_000_000) as f64 * if g.next() & 1 == 0 { 1.0 } else { -1.0 };
                let m = k * pio2;
                let steps = (g.next() % 41) as i64 - 20;
                f64::from_bits((m.to_bits() as i64 + steps) as u64)
            }),
        ));
    }
    v
}

/// Every kernel within `vecmath::MAX_ULPS` of `std` over millions of arguments (≈ 4.6 M per
/// function), whatever the block split.
#[test]
fn the_block_kernels_are_within_their_ulp_bound_of_std() {
    for (name, kernel, reference) in KERNELS {
        for (range, args) in ranges(name) {
            let (worst, at) = worst_ulps(&args, kernel, reference);
            println!("{name} over {range}: {worst} ulp (at {at:e})");
            assert!(
                worst <= vecmath::MAX_ULPS,
                "{name} over {range}: {worst} ulp at {at:e}"
            );
        }
    }
}

/// Special values: `std`'s results, sign of zero included.
#[test]
fn the_block_kernels_treat_special_values_as_std() {
    let specials = [
        0.0,
        -0.0,
        f64::NAN,
        -f64::NAN,
        f64::INFINITY,
        f64::NEG_INFINITY,
        f64::MIN_POSITIVE,
        -f64::MIN_POSITIVE,
        5e-324,
        -5e-324,
        f64::MAX,
        f64::MIN,
        1e300,
        -745.2,
        -745.1,
        -708.5,
        709.78,
        709.79,
        1.6e6,
        1.7e6,
        -1.6e6,
        1e22,
        -745.9,
        -746.0,
        -746.000_001,
        -1e308,
    ];
    for (name, kernel, reference) in KERNELS {
        let mut v = specials.to_vec();
        kernel(&mut v);
        for (&x, &y) in specials.iter().zip(&v) {
            let r = reference(x);
            // Zeros (with their sign), infinities and NaN exactly; others within the bound.
            let same = if r == 0.0 || !r.is_finite() {
                y.to_bits() == r.to_bits() || (y.is_nan() && r.is_nan())
            } else {
                ulps(y, r) <= vecmath::MAX_ULPS
            };
            assert!(same, "{name}({x:e}) = {y:e}, std {r:e}");
        }
    }
}
