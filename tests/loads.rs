//! The load vector `F^n = M (l(x_i, t_n))_i` through the fast paths against the plain
//! evaluation: random sums of products of a function of `t` and a function of `x` (split once
//! into `Σ_k f_k(t) M g_k`) to round-off, and random non-separable loads (evaluated over the
//! node array, with the block kernels' `sin`, `cos`, `exp`) to round-off.

mod common;
use proptest::prelude::*;
use viscobar::Simulation;
use viscobar::scene::Expression;

// Defined beside its measurement in the tolerance registry (`viscobar-certificate verify
// --tolerances`), which measures the separation on fixed loads; the properties below draw more.
use viscobar_certificate::tolerances::{SEPARATION_TOL, load_vectors, separation_error};

/// A load's text and the text of its magnitude: the same tree with every factor's absolute
/// value and every difference a sum, the scale of its round-off.
type Pair = (String, String);

/// `(text, text)` for a factor that is not negative.
fn same(text: String) -> Pair {
    (text.clone(), text)
}

fn factor(var: &'static str) -> impl Strategy<Value = Pair> {
    prop_oneof![
        (0.5f64..3.0).prop_map(|c| same(format!("{c}"))),
        Just((var.to_string(), format!("abs({var})"))),
        (0.5f64..3.0)
            .prop_map(move |c| (format!("sin({c}*{var})"), format!("abs(sin({c}*{var}))"))),
        (0.5f64..3.0)
            .prop_map(move |c| (format!("cos({c}*{var})"), format!("abs(cos({c}*{var}))"))),
        (0.5f64..3.0).prop_map(move |c| same(format!("exp(-{c}*{var})"))),
        (0.5f64..3.0).prop_map(move |c| {
            let f = format!("(1 + {var}^2)/({c} + {var})");
            (f.clone(), format!("abs({f})"))
        }),
    ]
}

/// Random trees of sums, differences, products and quotients (by a factor of one variable)
/// over factors of `x` and of `t`, with their magnitudes: they always separate, though not
/// always within the term limit.
fn separable_pair() -> impl Strategy<Value = Pair> {
    let leaf = prop_oneof![factor("x"), factor("t")];
    leaf.prop_recursive(4, 16, 2, |inner| {
        prop_oneof![
            (inner.clone(), inner.clone()).prop_map(|(a, b)| (
                format!("({} + {})", a.0, b.0),
                format!("({} + {})", a.1, b.1)
            )),
            (inner.clone(), inner.clone()).prop_map(|(a, b)| (
                format!("({} - {})", a.0, b.0),
                format!("({} + {})", a.1, b.1)
            )),
            (inner.clone(), inner.clone()).prop_map(|(a, b)| (
                format!("({})*({})", a.0, b.0),
                format!("({})*({})", a.1, b.1)
            )),
            (inner.clone(), factor("t")).prop_map(|(a, b)| (
                format!("({})/(2 + {})", a.0, b.0),
                format!("({})/abs(2 + {})", a.1, b.0)
            )),
            (inner.clone(), factor("x")).prop_map(|(a, b)| (
                format!("({})/(2 + {})", a.0, b.0),
                format!("({})/abs(2 + {})", a.1, b.0)
            )),
            inner.prop_map(|a| (format!("-({})", a.0), a.1)),
        ]
    })
}

fn separable() -> impl Strategy<Value = String> {
    separable_pair().prop_map(|p| p.0)
}

/// A separable tree with a non-separable part mixed in, and its magnitude.
fn non_separable() -> impl Strategy<Value = Pair> {
    let mixed = prop_oneof![
        (0.5f64..3.0).prop_map(|c| (format!("sin({c}*x*t)"), format!("abs(sin({c}*x*t))"))),
        Just(same("exp(-(x - t)^2)".to_string())),
        Just(("min(x, t)".to_string(), "abs(min(x, t))".to_string())),
        Just(("if(x < t, 1, -1)".to_string(), "1".to_string())),
    ];
    (separable_pair(), mixed).prop_map(|(a, m)| {
        (
            format!("{} + ({})*{}", a.0, a.0, m.0),
            format!("{} + ({})*{}", a.1, a.1, m.1),
        )
    })
}

/// Round-off of a load evaluated with the block kernels against the plain evaluation, per
/// operation of its text and of the mass product, relative to the magnitude `M|l|`: to first
/// order each `sin`, `cos`, `exp` is `vecmath::MAX_ULPS` ulps apart and each later operation
/// adds at most one rounding of either side (`ε` relative), and no quotient amplifies (the
/// denominators `2 + g` exceed `|g|`).
fn roundoff_tol(text: &str) -> f64 {
    let ops = text.chars().filter(|c| "+-*/^(".contains(*c)).count() + 4;
    ops as f64 * (viscobar::internals::scene::vecmath::MAX_ULPS as f64 + 1.0) * f64::EPSILON
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(64))]

    #[test]
    fn separated_loads_match_the_plain_evaluation(text in separable(), n in 0usize..80) {
        let v = load_vectors(&text, n).unwrap();
        let error = separation_error(&v);
        prop_assert!(error <= SEPARATION_TOL, "{text} at step {n}: {error:e} of the scale");
    }

    #[test]
    fn non_separable_loads_match_the_plain_evaluation_to_roundoff(
        (text, magnitude) in non_separable(),
        n in 0usize..80,
    ) {
        let [fast, plain, _] = load_vectors(&text, n).unwrap();
        let expr = Expression::parse("load.density", &text, true).unwrap();
        prop_assert!(expr.separate().is_none(), "{text} separated");
        // `M|l|` of the magnitude's tree (it separates or not, either way the plain values).
        let [_, scale, _] = load_vectors(&magnitude, n).unwrap();
        let tol = roundoff_tol(&text);
        for i in 0..fast.len() {
            let d = (fast[i] - plain[i]).abs();
            prop_assert!(d <= tol * scale[i], "{} at node {}: {:e} > {:e}", text, i, d, tol * scale[i]);
        }
    }

    /// Without `sin`, `cos`, `exp` the node-array evaluation gives the plain bits.
    #[test]
    fn non_separable_loads_without_transcendentals_match_bitwise(n in 0usize..80, c in 0.5f64..3.0) {
        let text = format!("(1 + x^2)/({c} + t) + (x - t)*min(x, t) - if(x < t, x, {c})");
        let [fast, plain, _] = load_vectors(&text, n).unwrap();
        for i in 0..fast.len() {
            prop_assert_eq!(fast[i].to_bits(), plain[i].to_bits(), "{} at node {}", text, i);
        }
    }
}

#[test]
fn the_talk_loads_take_the_separated_path() {
    for text in ["sin(t*sqrt(2))*cos(2*x)", "-0.5 + 0.8*sin(3*t)*cos(pi*x/2)"] {
        let e = Expression::parse("load.density", text, true).unwrap();
        assert!(e.separate().is_some(), "{text}");
        let error = separation_error(&load_vectors(text, 17).unwrap());
        assert!(error <= SEPARATION_TOL, "{text}: {error:e}");
    }
}

#[test]
fn a_load_that_is_not_finite_is_named_with_its_node() {
    // Separable, infinite at x = 0.5 from t = 0 on: the error names the field and the point.
    let scene = common::builtin(
        "modal",
        &["load.density=\"cos(t)/(x - 0.5)\"", "mesh.elements=4"],
    );
    let err = match Simulation::new(&scene) {
        Err(e) => e.to_string(),
        Ok(mut sim) => sim.load_vector(0).unwrap_err().to_string(),
    };
    assert!(err.contains("load.density") && err.contains("0.5"), "{err}");
}

/// Counts the allocations of this thread (tests/no_alloc.rs runs the built-in scenes, whose
/// loads all separate; this one watches the node-array path).
#[global_allocator]
static GLOBAL: common::alloc::Counting = common::alloc::Counting;

#[test]
fn steps_with_a_load_that_does_not_separate_do_not_allocate() {
    for text in [
        "0.1*sin(x*t)*exp(-(x-t)^2)",
        "if(x < t, atan2(x, t), min(x, -t)) + (t*t + 1)^x",
    ] {
        // Several blocks of the node-array evaluator and a partial one.
        let scene = common::builtin(
            "both-ends",
            &[&format!("load.density=\"{text}\""), "mesh.elements=700"],
        );
        let mut sim = Simulation::new(&scene).unwrap();
        sim.step().unwrap(); // warm-up outside the count
        let before = common::alloc::allocations();
        for _ in 0..20 {
            sim.step().unwrap();
        }
        let count = common::alloc::allocations() - before;
        assert_eq!(count, 0, "{text}: {count} allocations in 20 steps");
    }
}
