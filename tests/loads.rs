//! The load vector `F^n = M (l(x_i, t_n))_i` through the fast paths against the plain
//! evaluation: random sums of products of a function of `t` and a function of `x` (split once
//! into `Σ_k f_k(t) M g_k`) to round-off, and random non-separable loads (evaluated over the
//! node array) bit for bit.

mod common;
use proptest::prelude::*;
use viscobar::Simulation;
use viscobar::scene::Expression;

// Defined beside its measurement in the tolerance registry (`verify --tolerances`), which
// measures the separation on fixed loads; the properties below draw more.
use viscobar::study::tolerances::{SEPARATION_TOL, load_vectors, separation_error};

fn factor(var: &'static str) -> impl Strategy<Value = String> {
    prop_oneof![
        (0.5f64..3.0).prop_map(|c| format!("{c}")),
        Just(var.to_string()),
        (0.5f64..3.0).prop_map(move |c| format!("sin({c}*{var})")),
        (0.5f64..3.0).prop_map(move |c| format!("cos({c}*{var})")),
        (0.5f64..3.0).prop_map(move |c| format!("exp(-{c}*{var})")),
        (0.5f64..3.0).prop_map(move |c| format!("(1 + {var}^2)/({c} + {var})")),
    ]
}

/// Random trees of sums, differences, products and quotients (by a factor of one variable)
/// over factors of `x` and of `t`: they always separate, though not always within the term limit.
fn separable() -> impl Strategy<Value = String> {
    let leaf = prop_oneof![factor("x"), factor("t")];
    leaf.prop_recursive(4, 16, 2, |inner| {
        prop_oneof![
            (inner.clone(), inner.clone()).prop_map(|(a, b)| format!("({a} + {b})")),
            (inner.clone(), inner.clone()).prop_map(|(a, b)| format!("({a} - {b})")),
            (inner.clone(), inner.clone()).prop_map(|(a, b)| format!("({a})*({b})")),
            (inner.clone(), factor("t")).prop_map(|(a, b)| format!("({a})/(2 + {b})")),
            (inner.clone(), factor("x")).prop_map(|(a, b)| format!("({a})/(2 + {b})")),
            inner.prop_map(|a| format!("-({a})")),
        ]
    })
}

/// A separable tree with a non-separable part mixed in.
fn non_separable() -> impl Strategy<Value = String> {
    let mixed = prop_oneof![
        (0.5f64..3.0).prop_map(|c| format!("sin({c}*x*t)")),
        Just("exp(-(x - t)^2)".to_string()),
        Just("min(x, t)".to_string()),
        Just("if(x < t, 1, -1)".to_string()),
    ];
    (separable(), mixed).prop_map(|(a, m)| format!("{a} + ({a})*{m}"))
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
    fn non_separable_loads_match_the_plain_evaluation_bitwise(text in non_separable(), n in 0usize..80) {
        let [fast, plain, _] = load_vectors(&text, n).unwrap();
        let expr = Expression::parse("load.density", &text, true).unwrap();
        prop_assert!(expr.separate().is_none(), "{text} separated");
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
struct Counting;

thread_local! {
    static ALLOCATIONS: std::cell::Cell<usize> = const { std::cell::Cell::new(0) };
}

unsafe impl std::alloc::GlobalAlloc for Counting {
    unsafe fn alloc(&self, layout: std::alloc::Layout) -> *mut u8 {
        let _ = ALLOCATIONS.try_with(|c| c.set(c.get() + 1));
        unsafe { std::alloc::System.alloc(layout) }
    }
    unsafe fn dealloc(&self, ptr: *mut u8, layout: std::alloc::Layout) {
        unsafe { std::alloc::System.dealloc(ptr, layout) }
    }
    unsafe fn realloc(&self, ptr: *mut u8, layout: std::alloc::Layout, new_size: usize) -> *mut u8 {
        let _ = ALLOCATIONS.try_with(|c| c.set(c.get() + 1));
        unsafe { std::alloc::System.realloc(ptr, layout, new_size) }
    }
}

#[global_allocator]
static GLOBAL: Counting = Counting;

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
        let before = ALLOCATIONS.with(std::cell::Cell::get);
        for _ in 0..20 {
            sim.step().unwrap();
        }
        let count = ALLOCATIONS.with(std::cell::Cell::get) - before;
        assert_eq!(count, 0, "{text}: {count} allocations in 20 steps");
    }
}
