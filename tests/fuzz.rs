//! Fuzzing the input path: no text and no combination of values makes viscobar panic; a scene
//! is either refused with an error or runs with finite diagnostics.
//!
//! CI runs `FUZZ_CASES` cases per property (default 2 000); the long run, at least 1e5 cases:
//!
//!     FUZZ_CASES=100000 cargo test --release --test fuzz

use proptest::prelude::*;
use viscobar::{Scene, Simulation};

fn cases() -> u32 {
    std::env::var("FUZZ_CASES")
        .ok()
        .and_then(|v| v.parse().ok())
        .unwrap_or(2_000)
}

/// Numbers that break naive code: signs, zero, non-finite, extremes, a string.
fn bad_number() -> impl Strategy<Value = String> {
    prop_oneof![
        Just("0"),
        Just("-1"),
        Just("nan"),
        Just("inf"),
        Just("-inf"),
        Just("1e-300"),
        Just("1e300"),
        Just("\"text\""),
        Just("-0.5"),
    ]
    .prop_map(str::to_string)
}

/// Mostly valid positive numbers (so that many scenes run), sometimes a bad one.
fn number() -> impl Strategy<Value = String> {
    prop_oneof![
        12 => (1e-3f64..1.0).prop_map(|v| format!("{v:?}")),
        1 => bad_number(),
    ]
}

fn count() -> impl Strategy<Value = String> {
    prop_oneof![
        12 => (1u64..200).prop_map(|v| v.to_string()),
        1 => prop_oneof![Just("0"), Just("-1"), Just("18446744073709551615"), Just("2.5")]
            .prop_map(str::to_string),
    ]
}

fn expression() -> impl Strategy<Value = String> {
    let good = prop_oneof![
        Just("0"),
        Just("x"),
        Just("sin(t)*x"),
        Just("pi*cos(2*pi*x)"),
        Just("1e6*t"),
        Just("0.3*cos(2*x)"),
        Just("1"),
        Just("0.5*x"),
    ];
    let bad = prop_oneof![
        Just("-1"),
        Just("1/x"),
        Just("1/(t-0.01)"),
        Just("sqrt(x-1)"),
        Just("ln(x)"),
        Just("x^1000"),
        Just("1e308*1e308"),
        Just("(("),
        Just("y"),
        Just(""),
    ];
    prop_oneof![6 => good, 1 => bad].prop_map(str::to_string)
}

/// An end condition with its gap: usually consistent (a gap exactly for signorini), sometimes
/// an unknown condition or a misplaced or bad gap.
fn condition() -> impl Strategy<Value = (String, Option<String>)> {
    prop_oneof![
        8 => (prop_oneof![Just("signorini"), Just("free"), Just("clamped")], number()).prop_map(
            |(c, g)| (c.to_string(), (c == "signorini").then_some(g))
        ),
        1 => (prop_oneof![Just("signorini"), Just("free"), Just("glued")], prop::option::of(bad_number()))
            .prop_map(|(c, g)| (c.to_string(), g)),
    ]
}

fn scene_text() -> impl Strategy<Value = String> {
    (
        (number(), number(), prop_oneof![6 => Just("consistent"), 2 => Just("talk-printed"), 1 => Just("x")]),
        (condition(), condition()),
        (expression(), expression(), prop::option::of(expression())),
        // The end: usually a whole number of steps (scenes whose step does not divide the end
        // are refused), sometimes any number.
        (count(), number(), prop_oneof![8 => (1u32..400).prop_map(Ok), 1 => number().prop_map(Err)], count()),
    )
        .prop_map(|((len, visc, mat), (l, r), (u0, v0, load), (el, dt, end, every))| {
            let end = match (end, dt.parse::<f64>()) {
                (Ok(steps), Ok(step)) => format!("{:?}", f64::from(steps) * step),
                (Ok(steps), Err(_)) => steps.to_string(),
                (Err(text), _) => text,
            };
            let end_block = |name: &str, (c, g): &(String, Option<String>)| {
                let gap = g.as_ref().map(|g| format!("gap = {g}\n")).unwrap_or_default();
                format!("[{name}]\ncondition = \"{c}\"\n{gap}")
            };
            let load = load.map(|d| format!("[load]\ndensity = \"{d}\"\n")).unwrap_or_default();
            format!(
                "[bar]\nlength = {len}\nviscosity = {visc}\nmatrices = \"{mat}\"\n{}{}\
                 [initial]\ndisplacement = \"{u0}\"\nvelocity = \"{v0}\"\n{load}\
                 [mesh]\nelements = {el}\n[time]\nstep = {dt}\nend = {end}\n[output]\nevery = {every}\n",
                end_block("left", &l),
                end_block("right", &r),
            )
        })
}

/// Largest run the fuzzer steps through (keeps each case to microseconds).
const MAX_FUZZ_NODES: u64 = 500;
const MAX_FUZZ_STEPS: usize = 20;

proptest! {
    #![proptest_config(ProptestConfig::with_cases(cases()))]

    #[test]
    fn arbitrary_text_never_panics(text in "\\PC{0,200}") {
        let _ = Scene::from_toml(&text, &[]);
    }

    #[test]
    fn mutated_builtin_scenes_never_panic(pos in 0usize..2000, byte in prop::sample::select(b"=\"[]0.-e9xnaf\n ".to_vec())) {
        let mut text = viscobar::scene::builtin_text("both-ends-forced").unwrap().as_bytes().to_vec();
        let p = pos % text.len();
        text[p] = byte;
        if let Ok(t) = String::from_utf8(text) {
            let _ = Scene::from_toml(&t, &[]);
        }
    }
}

/// At least this share of the random scenes must pass validation and be stepped, or the fuzzer
/// would only be testing the validator.
const MIN_RUN_SHARE: f64 = 0.05;

#[test]
fn random_scenes_are_refused_or_run_finite() {
    let mut runner = proptest::test_runner::TestRunner::new(ProptestConfig::with_cases(cases()));
    let runs = std::cell::Cell::new(0u32);
    runner
        .run(&scene_text(), |text| {
            if let Ok(scene) = Scene::from_toml(&text, &[])
                && scene.mesh.elements < MAX_FUZZ_NODES
                && let Ok(mut sim) = Simulation::new(&scene)
            {
                runs.set(runs.get() + 1);
                for _ in 1..scene.steps().min(MAX_FUZZ_STEPS) {
                    match sim.step() {
                        Ok(r) => {
                            prop_assert!(r.energy.is_finite() && r.identity_residual.is_finite())
                        }
                        Err(_) => break,
                    }
                }
            }
            Ok(())
        })
        .unwrap();
    let share = f64::from(runs.get()) / f64::from(cases());
    println!("{:.1} % of {} random scenes ran", 100.0 * share, cases());
    assert!(
        share >= MIN_RUN_SHARE,
        "only {share:.3} of the random scenes ran"
    );
}
