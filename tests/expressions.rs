//! Scene expressions (README, "Expressions"): the grammar table's examples, the cases that
//! used to fail, errors naming field and column, numbers wherever an expression is, and random
//! expression trees against the same tree evaluated directly in Rust.

use proptest::prelude::*;
use viscobar::Scene;
use viscobar::scene::Expression;
use viscobar::scene::nodal::NodalEvaluator;

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
    let n = 3 * viscobar::scene::nodal::BLOCK + 41;
    (0..n).map(|i| -2.0 + 4.0 * i as f64 / n as f64).collect()
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(128))]

    /// The compiled node-array evaluation (subtrees of `t` hoisted, constants folded, signs
    /// and squares fused into loops) gives the bits of the same tree evaluated in Rust at every
    /// node, or the scalar evaluation's error at the first node where the value is not finite.
    #[test]
    fn random_trees_over_the_node_array_evaluate_like_rust(tree in tree(), t in 0.0f64..3.0) {
        let parsed = Expression::parse("load.density", &tree.text(), true).unwrap();
        let xs = nodes();
        let mut nodal = NodalEvaluator::new(parsed.clone(), xs.clone());
        let mut out = vec![0.0; xs.len()];
        let first_bad = xs.iter().position(|&x| !tree.value(x, t).is_finite());
        match (nodal.eval_into(t, &mut out), first_bad) {
            (Ok(()), None) => {
                for (&x, &v) in xs.iter().zip(&out) {
                    prop_assert_eq!(v.to_bits(), tree.value(x, t).to_bits(), "{} at {}", tree.text(), x);
                }
            }
            (Err(e), Some(i)) => prop_assert_eq!(
                e.to_string(),
                parsed.eval(xs[i], t).unwrap_err().to_string()
            ),
            (r, bad) => prop_assert!(false, "{}: {:?} with the first non-finite node {:?}", tree.text(), r, bad),
        }
    }
}
