//! Every scene the parser accepts keeps the certificate. Whole scenes are drawn over the schema
//! (bar: ends free, clamped or Signorini with fixed, moving or oscillating gaps, an obstacle, the
//! mass and matrix variants, loads, `[heat]` with every end condition, each solver; plane: edges
//! free, clamped or Signorini with fixed, varying and moving gaps, friction as a number or a
//! field of `s`, sliding obstacles, both integration rules, tilted loads, each solver), small
//! and short. Each draw is refused naming a key with nothing written, or runs certified at
//! every step (the run checks its identity against its bound itself, the solvers their audits)
//! with finite records, contact consistent with the reactions and files free of NaN and
//! infinity. Over the same draws the metamorphic relations: the mirrored bar and plane, a
//! friction zero at every node against no key, `coupling = 0` against no `[heat]`, a moving
//! obstacle and a belt (a sliding obstacle) against their Galilean twins.
//!
//! `cargo test` draws `SCENE_CASES` scenes of each body (default 150) from the fixed seed; the
//! soak: `SCENE_CASES=1000 cargo test --release --test scene_property` (2000 scenes), or other
//! seeds with `bash scripts/proptest-seeds.sh FIRST LAST`.

mod scenes;

use proptest::prelude::*;
use proptest::test_runner::{Config, TestCaseError, TestRunner};
use scenes::{BarDraw, PlaneDraw, bar_draw, plane_draw};
use viscobar::scene::{AnyScene, load_any};
use viscobar::scheme::{CONTACT_GAP_TOL, RunError, StepRecord};
use viscobar::{BarSimulation, PlaneScene, Scene};

fn cases() -> u32 {
    std::env::var("SCENE_CASES")
        .ok()
        .and_then(|v| v.parse().ok())
        .unwrap_or(150)
}

/// Mirrored and Galilean twins agree to this, relative to the compared quantity's largest
/// magnitude over the run: the two runs add the same terms in another order (sums over the
/// nodes reversed, `u + ct` rounded), so a few thousand ulps after some tens of steps of a
/// scheme that does not amplify perturbations.
const TWIN_TOL: f64 = 1e-10;
/// `friction = 0` against no friction key: Lemke's answer against block pivoting's on the same
/// step problems, each exact to round-off (the tangential rows carry zero reactions).
const FRICTIONLESS_TOL: f64 = 1e-10;
/// A closed body's heat content against its frictional heating, per step, relative to the
/// largest content: sums of a few hundred products and a backward-stable solve.
const CLOSED_BODY_HEAT_TOL: f64 = 1e-12;

/// The plane's condensed exact solver takes `z` from a second solve with the reactions, without
/// writing an active node onto its bound: its gap is that solve's forward error, measured up to
/// 3e-12 at `λ/μ = 1000`, `Δt = 0.1` (above the 1e-12 of "in contact"); three decades more.
const PLANE_ACTIVE_GAP_TOL: f64 = 1e-9;

/// What a draw did.
enum Outcome {
    /// Refused at load or set-up, the message naming a key.
    Refused,
    /// OSQP stopped at a step with an error naming it (a documented limit of the iterative
    /// solver: its ADMM or its Tresca fixed point not converging, its audit refusing an
    /// answer), nothing written. Never accepted of the exact and penalty solvers.
    Stopped,
    /// Ran, certified: its records and its final displacement.
    Ran(Vec<StepRecord>, Vec<f64>),
}

fn scene_file(text: &str) -> tempfile_path::Path {
    tempfile_path::write(text)
}

/// A small self-cleaning temporary file (no extra crate).
mod tempfile_path {
    use std::sync::atomic::{AtomicUsize, Ordering};
    static NEXT: AtomicUsize = AtomicUsize::new(0);
    pub struct Path(pub std::path::PathBuf);
    impl Drop for Path {
        fn drop(&mut self) {
            let _ = std::fs::remove_dir_all(&self.0);
        }
    }
    impl Path {
        pub fn file(&self) -> std::path::PathBuf {
            self.0.join("scene.toml")
        }
        pub fn out(&self) -> std::path::PathBuf {
            self.0.join("out")
        }
    }
    pub fn write(text: &str) -> Path {
        let n = NEXT.fetch_add(1, Ordering::Relaxed);
        let dir = std::env::temp_dir().join(format!("viscobar-scene-{}-{n}", std::process::id()));
        let _ = std::fs::remove_dir_all(&dir);
        std::fs::create_dir_all(&dir).expect("temp dir");
        std::fs::write(dir.join("scene.toml"), text).expect("scene file");
        Path(dir)
    }
}

/// A refusal's message names a key (in backquotes) and the run writes nothing.
fn check_refusal(message: &str, text: &str) -> Result<(), TestCaseError> {
    prop_assert!(
        message.contains('`'),
        "a refusal names no key: {message}\n{text}"
    );
    Ok(())
}

/// Every field of every record finite (the contact extents are NaN by definition when nothing
/// is in contact), the identity within its bound at every measured step, the contact state
/// consistent with the reactions.
fn check_records(
    records: &[StepRecord],
    (groups, exact, plane): (usize, bool, bool),
    text: &str,
) -> Result<(), TestCaseError> {
    for r in records {
        let fields = [
            r.energy,
            r.work,
            r.viscous_dissipation,
            r.contact_dissipation,
            r.identity_residual,
            r.obstacle_work,
            r.friction_dissipation,
            r.sliding_work,
            r.contact.total_reaction,
            r.contact.min_gap,
            r.contact.min_reaction,
            r.contact.max_complementarity,
        ];
        prop_assert!(
            fields.iter().all(|v| v.is_finite()),
            "step {}: {r:?}\n{text}",
            r.step
        );
        if r.measured {
            prop_assert!(
                r.identity_residual <= r.identity_bound,
                "step {}\n{text}",
                r.step
            );
        }
        for g in &r.contact.groups[..groups] {
            // In contact exactly where the extent is set.
            prop_assert_eq!(g.contact_nodes > 0, g.extent[0].is_finite(), "{}", text);
            // An exact solver's reaction is positive only on constraints it puts on their
            // obstacle: a group that pushes has a constraint in contact (the bar's solvers
            // write an active node onto its bound), or within the plane's active-gap
            // tolerance of it.
            if exact && g.reaction > 0.0 {
                prop_assert!(
                    g.contact_nodes > 0 || (plane && g.min_gap <= PLANE_ACTIVE_GAP_TOL),
                    "step {}: {g:?}\n{text}",
                    r.step
                );
            }
        }
        if exact && !plane && r.contact.contact_nodes == 0 {
            prop_assert!(r.contact.min_gap > CONTACT_GAP_TOL || r.contact.total_reaction == 0.0);
        }
    }
    Ok(())
}

/// The written files hold no NaN or infinity (empty cells stand for "none").
fn check_files(out: &std::path::Path, text: &str) -> Result<(), TestCaseError> {
    for entry in std::fs::read_dir(out).expect("output folder") {
        let path = entry.expect("entry").path();
        if path.is_file() {
            let body = std::fs::read_to_string(&path).unwrap_or_default();
            let lower = body.to_ascii_lowercase();
            prop_assert!(
                !lower.contains("nan") && !lower.contains("inf"),
                "{} holds a non-finite number\n{text}",
                path.display()
            );
        }
    }
    Ok(())
}

/// Runs a scene text as the command line would: loaded from a file, set up, run in memory and
/// written to a folder.
fn run_text(text: &str, write: bool) -> Result<Outcome, TestCaseError> {
    let tmp = scene_file(text);
    let path = tmp.file();
    let scene = match load_any(path.to_str().expect("utf-8 path"), &[]) {
        Ok((_, scene)) => scene,
        Err(e) => {
            check_refusal(&e.to_string(), text)?;
            return Ok(Outcome::Refused);
        }
    };
    let out = tmp.out();
    let ran = match &scene {
        AnyScene::Bar(s) => run_bar(s, text),
        AnyScene::Plane(s) => run_plane(s, text),
    };
    let (records, u, groups, exact) = match ran {
        Ok(r) => r,
        Err(RunError::Scene(e)) => {
            check_refusal(&e.to_string(), text)?;
            let written = match &scene {
                AnyScene::Bar(s) => viscobar::run_to_dir("draw", s, &out, false),
                AnyScene::Plane(s) => viscobar::output::run_plane_to_dir("draw", s, &out, false),
            };
            prop_assert!(matches!(written, Err(RunError::Scene(_))), "{}", text);
            prop_assert!(
                !out.exists(),
                "a refused scene wrote {}\n{text}",
                out.display()
            );
            return Ok(Outcome::Refused);
        }
        Err(e @ RunError::Step { .. }) if e.to_string().contains("solver `osqp`") => {
            let written = match &scene {
                AnyScene::Bar(s) => viscobar::run_to_dir("draw", s, &out, false),
                AnyScene::Plane(s) => viscobar::output::run_plane_to_dir("draw", s, &out, false),
            };
            prop_assert!(written.is_err() && !out.exists(), "{}", text);
            return Ok(Outcome::Stopped);
        }
        Err(e) => return Err(TestCaseError::fail(format!("{e}\n{text}"))),
    };
    let plane = matches!(scene, AnyScene::Plane(_));
    check_records(&records, (groups, exact, plane), text)?;
    if write {
        let summary = match &scene {
            AnyScene::Bar(s) => viscobar::run_to_dir("draw", s, &out, false),
            AnyScene::Plane(s) => viscobar::output::run_plane_to_dir("draw", s, &out, false),
        };
        let summary = summary.map_err(|e| TestCaseError::fail(format!("{e}\n{text}")))?;
        prop_assert!(summary.certificate.certified, "{}", text);
        prop_assert_eq!(
            summary.certificate.measured_steps,
            records.iter().filter(|r| r.measured).count()
        );
        check_files(&out, text)?;
    }
    Ok(Outcome::Ran(records, u))
}

/// The records, the final displacement, the number of contact groups and whether the solver
/// is exact.
type Ran = (Vec<StepRecord>, Vec<f64>, usize, bool);

fn run_bar(s: &Scene, _text: &str) -> Result<Ran, RunError> {
    let exact = s.solver.method == viscobar::SolverMethod::Exact;
    // `run_in_memory` runs a scene with `[heat]` with its temperature, as `run_to_dir` does.
    let (records, _, sim) = viscobar::run_in_memory("draw", s)?;
    assert_eq!(sim.thermal().is_some(), s.heat.is_some());
    match sim {
        BarSimulation::Thermal(sim) => {
            let groups = sim.contact().groups().len();
            // The displacement block of `[u | θ]`.
            let n_u = sim.body().bar().discretisation().unknowns();
            Ok((records, sim.state().u[..n_u].to_vec(), groups, exact))
        }
        BarSimulation::Mechanical(sim) => {
            let groups = sim.contact().groups().len();
            Ok((records, sim.state().u.to_vec(), groups, exact))
        }
    }
}

fn run_plane(s: &PlaneScene, _text: &str) -> Result<Ran, RunError> {
    let exact = s.solver.method == viscobar::SolverMethod::Exact;
    let (records, _, sim) = viscobar::output::run_plane_in_memory("draw", s)?;
    let groups = sim.contact().groups().len();
    Ok((records, sim.state().u.to_vec(), groups, exact))
}

fn max_abs(v: impl IntoIterator<Item = f64>) -> f64 {
    v.into_iter().fold(0.0, |m, x| m.max(x.abs()))
}

/// `a` and `b` agree to `tol` relative to their largest magnitude.
fn close(a: &[f64], b: &[f64], tol: f64) -> bool {
    let scale = max_abs(a.iter().chain(b).copied()).max(f64::MIN_POSITIVE);
    a.len() == b.len() && a.iter().zip(b).all(|(x, y)| (x - y).abs() <= tol * scale)
}

fn energies(r: &[StepRecord]) -> Vec<f64> {
    r.iter().map(|r| r.energy).collect()
}

/// A run's records and its final displacement.
type Trajectory = (Vec<StepRecord>, Vec<f64>);

/// A twin of a draw run: `None` when OSQP stopped on it; refused, it fails the draw (a twin
/// of a scene that ran is as valid as it).
fn twin(text: &str, of: &str) -> Result<Option<Trajectory>, TestCaseError> {
    match run_text(text, false)? {
        Outcome::Ran(records, u) => Ok(Some((records, u))),
        Outcome::Stopped => Ok(None),
        Outcome::Refused => Err(TestCaseError::fail(format!(
            "a twin was refused:\n{text}\nof\n{of}"
        ))),
    }
}

/// The bar's relations over one draw.
fn bar_relations(d: &BarDraw, records: &[StepRecord], u: &[f64]) -> Result<(), TestCaseError> {
    let text = d.toml();
    // Mirrored: x → L − x, the ends swapped; energies the same, the displacement reversed.
    // (With a thermal coupling the stress's `−γθ` turns with `θ_x` under the mirror while `u`
    // does not: no such symmetry.)
    if d.heat.as_ref().is_none_or(|h| h.coupling == 0.0) {
        let Some((mirrored, um)) = twin(&d.mirrored().toml(), &text)? else {
            return Ok(());
        };
        let (e, em) = (energies(records), energies(&mirrored));
        prop_assert!(close(&e, &em, TWIN_TOL), "mirror\n{text}");
        let reversed: Vec<f64> = um.iter().rev().copied().collect();
        prop_assert!(close(u, &reversed, TWIN_TOL), "mirror: u\n{text}");
    }
    // coupling = 0 against no [heat]: the mechanics bit for bit.
    if let Some(plain) = d.without_heat_if_uncoupled() {
        let Some((p, up)) = twin(&plain.toml(), &text)? else {
            return Ok(());
        };
        let mech = |r: &StepRecord| {
            [
                r.work,
                r.viscous_dissipation,
                r.contact_dissipation,
                r.contact.total_reaction,
            ]
        };
        for (a, b) in records.iter().zip(&p) {
            prop_assert_eq!(
                mech(a).map(f64::to_bits),
                mech(b).map(f64::to_bits),
                "{}",
                text
            );
        }
        prop_assert_eq!(u, &up[..], "coupling = 0: u\n{}", text);
    }
    // A moving obstacle against its Galilean twin: gaps a + c t with velocity v against fixed
    // gaps a with velocity v + c, so that u_fixed = u_moving + c t.
    if let Some((moving, fixed, shift)) = d.galilean_twins() {
        let (Some((_, um)), Some((_, uf))) =
            (twin(&moving.toml(), &text)?, twin(&fixed.toml(), &text)?)
        else {
            return Ok(());
        };
        let shifted: Vec<f64> = um.iter().map(|x| x + shift).collect();
        prop_assert!(close(&shifted, &uf, TWIN_TOL), "Galilean twins\n{text}");
    }
    Ok(())
}

/// The plane's relations over one draw: the mirrored scene (`x → W − x`) has the same energies
/// and friction dissipation; a belt matches its Galilean twin; a friction zero at every node
/// matches no friction key.
fn plane_relations(d: &PlaneDraw, records: &[StepRecord], u: &[f64]) -> Result<(), TestCaseError> {
    let text = d.toml();
    // The mirror for the solvers exact to round-off (OSQP's answers differ by its tolerance).
    let mirrored = match d.solver {
        "osqp" => None,
        _ => twin(&d.mirrored().toml(), &text)?,
    };
    if let Some((mirrored, _)) = mirrored {
        let (e, em) = (energies(records), energies(&mirrored));
        prop_assert!(close(&e, &em, TWIN_TOL), "mirror\n{text}");
        // D_f against the energy's scale: a sticking node's D_f is rounding noise.
        let scale = max_abs(e.iter().copied());
        for (a, b) in records.iter().zip(&mirrored) {
            let diff = (a.friction_dissipation - b.friction_dissipation).abs();
            prop_assert!(
                diff <= TWIN_TOL * scale,
                "mirror: D_f, step {}\n{text}",
                a.step
            );
        }
    }
    // A belt against its Galilean twin: frictional bottom and top obstacles sliding at `c`
    // against fixed ones with the velocity lowered by `c`, so that u_fixed = u_belt − c t along
    // x (every unknown is free: x components at even indices).
    if let Some((belt, fixed, shift)) = d.belt_twins()
        && let (Some((_, ub)), Some((_, uf))) =
            (twin(&belt.toml(), &text)?, twin(&fixed.toml(), &text)?)
    {
        let shifted: Vec<f64> = (ub.iter().enumerate())
            .map(|(i, x)| if i % 2 == 0 { x - shift } else { *x })
            .collect();
        prop_assert!(close(&shifted, &uf, TWIN_TOL), "belt twins\n{}", text);
    }
    // An uncoupled temperature leaves the mechanics' bits; an insulated body without a source
    // gains heat only by friction, to round-off at every step.
    if let Some(plain) = d.without_heat_if_uncoupled()
        && let Some((_, up)) = twin(&plain.toml(), &text)?
    {
        prop_assert_eq!(u, &up[..], "[heat] moved the mechanics\n{}", text);
    }
    if d.heat_is_closed() {
        let content = |r: &StepRecord| r.heat.map_or(0.0, |h| h.heat_content);
        let largest = max_abs(records.iter().map(content));
        let mut before = d.initial_heat_content();
        for r in records {
            let h = r.heat.unwrap();
            let gap = (h.heat_content - before - h.frictional_heating).abs();
            prop_assert!(
                gap <= CLOSED_BODY_HEAT_TOL * largest.max(f64::MIN_POSITIVE),
                "heat balance, step {}: {gap:e}\n{text}",
                r.step
            );
            before = h.heat_content;
        }
    }
    let Some(plain) = d.without_zero_friction() else {
        return Ok(());
    };
    let Some((p, up)) = twin(&plain.toml(), &text)? else {
        return Ok(());
    };
    prop_assert!(
        close(&energies(records), &energies(&p), FRICTIONLESS_TOL),
        "{}",
        text
    );
    prop_assert!(close(u, &up, FRICTIONLESS_TOL), "friction = 0: u\n{}", text);
    Ok(())
}

fn runner() -> TestRunner {
    TestRunner::new(Config {
        cases: cases(),
        failure_persistence: None,
        ..Config::default()
    })
}

/// Runs `cases()` draws of `strategy`, each through [`run_text`] and, when it ran, `relations`;
/// returns how many ran, were refused and stopped.
fn soak<D: std::fmt::Debug>(
    strategy: impl Strategy<Value = D>,
    toml: impl Fn(&D) -> String,
    relations: impl Fn(&D, &[StepRecord], &[f64]) -> Result<(), TestCaseError>,
) -> [usize; 3] {
    let counts = std::cell::Cell::new([0; 3]);
    let bump = |k: usize| {
        let mut c = counts.get();
        c[k] += 1;
        counts.set(c);
    };
    runner()
        .run(&strategy, |d| {
            match run_text(&toml(&d), true)? {
                Outcome::Ran(records, u) => {
                    bump(0);
                    relations(&d, &records, &u)?;
                }
                Outcome::Refused => bump(1),
                Outcome::Stopped => bump(2),
            }
            Ok(())
        })
        .unwrap();
    let [ran, refused, stopped] = counts.get();
    eprintln!("{ran} ran certified, {refused} refused naming a key, {stopped} stopped (osqp)");
    // The strategies mostly draw valid scenes: a test whose draws were all refused or stopped
    // would check nothing.
    assert!(
        ran > refused + stopped,
        "{ran} ran, {refused} refused, {stopped} stopped"
    );
    counts.get()
}

#[test]
fn every_bar_scene_the_parser_accepts_keeps_the_certificate() {
    soak(bar_draw(), BarDraw::toml, bar_relations);
}

#[test]
fn every_plane_scene_the_parser_accepts_keeps_the_certificate() {
    soak(plane_draw(), PlaneDraw::toml, plane_relations);
}
