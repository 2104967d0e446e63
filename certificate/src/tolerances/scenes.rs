//! The bar's scene-wide tolerances and those of its closed forms, runs and loads
//! (`tests/energy_and_contact.rs`, `closed_forms.rs`, `episodes.rs`, `diagnostics.rs`,
//! `mass.rs`, `loads.rs`, `roundoff.rs`), each beside the measurement of what it guards.

use super::invalid;
use viscobar::bar::closed_form::{ClosedForm, FallingBar};
use viscobar::output::run_in_memory;
use viscobar::scene::{self, MassVariant, builtin_names};
use viscobar::scheme::RunError;
use viscobar::study::accuracy::error_against;

/// The energy identity's bound for a solver exact to round-off: the run's own (every run checks
/// it at every measured step, `viscobar::scheme::certify`), measured here.
pub use viscobar::scheme::certify::IDENTITY_TOL;
/// An energy increase of an unforced run, relative to `E^{1/2}`, that round-off can make.
pub const ENERGY_RISE_TOL: f64 = 1e-13;
/// Gap negative by round-off only: the exact solver puts an active node on the obstacle up to
/// the rounding of `u^n + z` with |u| <= 1.
pub const GAP_TOL: f64 = 1e-14;
/// Reaction negative by round-off only (reactions of order 10).
pub const REACTION_TOL: f64 = 1e-12;
/// `|gap · reaction|`: round-off in the gap times a reaction of order 10.
pub const COMPLEMENTARITY_TOL: f64 = 1e-12;

/// L2 error bounds at the kinked scenes' own meshes (`tests/closed_forms.rs`): 1.25x the
/// measured L2 error (VERIFICATION.md's convergence table, first row of each scene), so that
/// round-off changes pass and a regression of the contact step (wrong reaction, wrong
/// start-up) fails.
pub const IMPACT_L2_BOUND: f64 = 1.25 * 2.10e-2;
pub const CLAMPED_IMPACT_L2_BOUND: f64 = 1.25 * 1.09e-2;
pub const FALLING_BAR_L2_BOUND: f64 = 1.25 * 2.987e-2;

/// Worst values over every built-in scene (its own solver) of what the scene-wide tolerances
/// of `tests/energy_and_contact.rs` guard: identity residual, energy rise (unforced scenes,
/// relative to `E^{1/2}`), negative gap, negative reaction, `|gap · reaction|`.
pub fn scene_worst() -> Result<[f64; 5], RunError> {
    let mut w = [0.0f64; 5];
    for name in builtin_names() {
        let (_, scene) = scene::load(name, &[])?;
        let (records, _, sim) = run_in_memory(name, &scene)?;
        let sim = sim
            .mechanical()
            .expect("the built-in bar scenes have no [heat]");
        let constrained = !sim.discretisation().constraints.is_empty();
        let e0 = records[0].energy;
        for (i, r) in records.iter().enumerate() {
            w[0] = w[0].max(r.identity_residual);
            if scene.load.density.is_none() && i > 0 {
                w[1] = w[1].max((r.energy - records[i - 1].energy) / e0);
            }
            if constrained {
                w[2] = w[2].max(-r.contact.min_gap);
                w[3] = w[3].max(-r.contact.min_reaction);
                w[4] = w[4].max(r.contact.max_complementarity);
            }
        }
    }
    Ok(w)
}

/// The L2 error of a built-in scene at its own mesh against its closed form.
pub fn l2_at_scene_mesh(name: &str) -> Result<f64, RunError> {
    let (_, base) = scene::load(name, &[])?;
    let exact = viscobar::bar::closed_form::for_scene(name, &base).ok_or_else(|| {
        invalid(
            "scene",
            name.to_string(),
            "a built-in scene with a closed form",
        )
    })?;
    Ok(error_against(&base, exact.as_ref())?.l2)
}

/// Midpoints of the falling bar's energy quadrature ([`falling_bar_quadrature`]).
pub const FALLING_BAR_QUAD_POINTS: usize = 20_000;
/// Step of that quadrature's differences, capped at a quarter of the piece: the closed form is
/// quadratic on each piece, so any step is exact up to round-off `ε|u|/step`.
pub const QUAD_FD_STEP: f64 = 1e-3;

/// Where the falling bar's kink (the front of the impact's wave, speed 1) is at `t`, if on the
/// open bar: with the time folded into the first half period, at `x = τ` or `2L − τ` in
/// contact (`τ` since the impact), at the distance of `s` (since the release) to the nearest
/// multiple of `2L` in flight; none in the free fall.
pub fn falling_bar_kink(fb: &FallingBar, t: f64) -> Option<f64> {
    let (l, p) = (fb.length, fb.period());
    let r = t.rem_euclid(p);
    let tau = (if r > 0.5 * p { p - r } else { r }) - fb.fall_time();
    let x = if tau <= 0.0 {
        return None;
    } else if tau <= 2.0 * l {
        tau.min(2.0 * l - tau)
    } else {
        let s = tau - 2.0 * l;
        (s - 2.0 * l * (s / (2.0 * l)).round()).abs()
    };
    (x > 0.0 && x < l).then_some(x)
}

/// The falling bar's total energy `½∫u_t² + ½∫u_x² + g∫u` (zero) and `∫u` (against
/// [`FallingBar::integral`]) by a midpoint quadrature of differences of the displacement, each
/// cell cut at the kink, at 321 times over two periods: worst errors and their bounds.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct FallingBarQuadrature {
    pub energy_worst: f64,
    /// `g·dx²`: on each piece the integrand `f` is quadratic in `x` with
    /// `|f''| = |u_xt² + u_xx² + g u_xx| ≤ 10g²` (`|u_xx|, |u_xt| ≤ 2g`: two waves of curvature
    /// `g`), so the midpoint rule errs by at most `L dx²/24 · 10g² ≈ 0.4 g² dx² L`; differences
    /// of step `≥ dx/4` (exact on quadratics) add round-off `≈ 4 ε |u| / d · slope · L ≈ 9e-11`.
    /// (The former bound, a kink spoiling a midpoint, `2 slope² dx ≈ 1.6e-4`, was 1e5 times the
    /// measured error.)
    pub energy_tol: f64,
    pub mass_worst: f64,
    /// `dx² g L/12` (midpoint error with `u_xx = 2g`, reached in flight) plus the sum's
    /// round-off, `QUAD_POINTS · ε · L max|u|`, `max|u| ≤ 2a0 + gL²`.
    pub mass_tol: f64,
}

pub fn falling_bar_quadrature(fb: &FallingBar) -> FallingBarQuadrature {
    let (l, g) = (fb.length, fb.gravity);
    let u = |x: f64, t: f64| fb.displacement(x, t);
    let n = FALLING_BAR_QUAD_POINTS;
    let dx = l / n as f64;
    let mut out = FallingBarQuadrature {
        energy_worst: 0.0,
        energy_tol: g * dx * dx,
        mass_worst: 0.0,
        mass_tol: dx * dx * g * l / 12.0 + n as f64 * f64::EPSILON * l * (2.0 * fb.gap + g * l * l),
    };
    for i in 0..=320 {
        let t = 0.05 * i as f64 + 0.0123; // off the phase boundaries, two periods
        // Each cell is cut at the kink (at most one crosses the bar at a time, speed 1), so
        // that u is one quadratic in (x, t) on each piece and on every stencil; the stencils
        // stay inside their piece in x, and in t (the kink moves by the step).
        let kink = falling_bar_kink(fb, t);
        let (mut kinetic, mut elastic, mut mass) = (0.0, 0.0, 0.0);
        for j in 0..n {
            let (a, b) = (j as f64 * dx, (j + 1) as f64 * dx);
            let cuts = match kink {
                Some(k) if a < k && k < b => [[a, k], [k, b]],
                _ => [[a, b], [b, b]],
            };
            for [p, q] in cuts {
                let w = q - p;
                if w <= 0.0 {
                    continue;
                }
                let (x, d) = (0.5 * (p + q), (0.25 * w).min(QUAD_FD_STEP));
                let ut = (u(x, t + d) - u(x, t - d)) / (2.0 * d);
                let ux = (u(x + d, t) - u(x - d, t)) / (2.0 * d);
                kinetic += 0.5 * ut * ut * w;
                elastic += 0.5 * ux * ux * w;
                mass += u(x, t) * w;
            }
        }
        let total = kinetic + elastic + g * mass;
        out.energy_worst = out.energy_worst.max(total.abs());
        out.mass_worst = out.mass_worst.max((mass - fb.integral(t)).abs());
    }
    out
}

// ---- tests/closed_forms.rs: the closed forms themselves -------------------------------------

/// The closed form is built from polynomials of size ≤ 1: its identities hold to round-off.
pub const FALLING_BAR_ROUNDOFF: f64 = 1e-12;
/// Central differences of step [`FD_STEP`] for `u_t`, `u_x` and `−u_x(0)`; the closed form is
/// piecewise quadratic, so they are exact away from the kinks up to round-off `1e-16/FD_STEP`.
pub const FD_STEP: f64 = 1e-7;
/// Round-off of a difference quotient of step [`FD_STEP`]: a few ulps of `|u| ≤ 1` over it.
pub const FD_ROUNDOFF: f64 = 1e-8;

/// Deterministic sample points in `[0, 1)` (a Weyl sequence), so the checks need no seed.
pub fn weyl(i: usize, a: f64) -> f64 {
    (i as f64 * a).fract()
}

/// The falling bar's identities at 4000 sample points over two periods, each a residual that
/// is round-off only for the weak solution: the characteristic diamond in the interior, the
/// half diamond at the free end and at the free left end in flight, the gap in contact, and
/// the release at rest. Returns the worst `|residual|`, or an error naming the failed check (not
/// a tolerance) if the contact intervals are missing or the contact phases' reaction or gap
/// sign are wrong.
pub fn falling_bar_identities_worst(fb: &FallingBar) -> Result<f64, String> {
    let (l, g, a0) = (fb.length, fb.gravity, fb.gap);
    let p = fb.period();
    let u = |x: f64, t: f64| fb.displacement(x, t);
    let contact = fb
        .contact_intervals(2.0 * p)
        .ok_or("the falling bar gives no contact intervals")?;
    let in_contact = |t: f64| contact.iter().any(|iv| iv[0] <= t && t <= iv[1]);
    let mut worst = 0.0f64;
    for i in 1..4000 {
        // Two periods, so periodicity and the time reversal at T/2 are crossed.
        let t = 2.0 * p * weyl(i, 0.618_033_988_749_894_9);
        let k = 0.5 * l * weyl(i, 0.414_213_562_373_095_1);
        // Interior: the characteristic diamond identity holds exactly for every weak solution of
        // u_tt − u_xx = −g, kinks and impacts included.
        let x = k + (l - 2.0 * k) * weyl(i, 0.732_050_807_568_877_3);
        let diamond = u(x, t + k) + u(x, t - k) - u(x + k, t) - u(x - k, t) + g * k * k;
        worst = worst.max(diamond.abs());
        // Free end x = L: the half diamond (even reflection, u_x(L) = 0).
        let free = u(l, t + k) + u(l, t - k) - 2.0 * u(l - k, t) + g * k * k;
        worst = worst.max(free.abs());
        // Left end: on the obstacle with a positive reaction in contact, above it otherwise,
        // and free (half diamond) in flight.
        let gap = u(0.0, t) + a0;
        if in_contact(t) {
            if fb.reaction(t) < fb.impact_speed() {
                return Err(format!("t {t}: reaction {} in contact", fb.reaction(t)));
            }
            worst = worst.max(gap.abs());
        } else {
            if !(gap > 0.0 && fb.reaction(t) == 0.0) {
                return Err(format!(
                    "t {t}: gap {gap:e}, reaction {} in flight",
                    fb.reaction(t)
                ));
            }
            let kf = k.min(t);
            if !contact.iter().any(|iv| iv[0] < t + kf && t - kf < iv[1]) {
                let half = u(0.0, t + kf) + u(0.0, t - kf) - 2.0 * u(kf, t) + g * kf * kf;
                worst = worst.max(half.abs());
            }
        }
    }
    // Released at rest from u = 0 (u = −g t²/2 until the impact).
    for i in 0..=100 {
        let x = l * i as f64 / 100.0;
        worst = worst.max((u(x, 1e-3) + 0.5 * g * 1e-6).abs());
    }
    Ok(worst)
}

/// The reaction `−u_x(0)` by a one-sided difference of step [`FD_STEP`] at 321 times over two
/// periods (where the reaction is not 0): the worst `|difference − reaction|` over its bound
/// `g · FD_STEP + FD_ROUNDOFF` (`u` is linear in `x` near 0 within a phase up to `g x²/2`).
pub fn falling_bar_reaction_fd_ratio(fb: &FallingBar) -> f64 {
    let g = fb.gravity;
    let u = |x: f64, t: f64| fb.displacement(x, t);
    let mut worst = 0.0f64;
    for i in 0..=320 {
        let t = 0.05 * i as f64 + 0.0123; // off the phase boundaries, two periods
        if fb.reaction(t) == 0.0 {
            continue;
        }
        let one_sided = -(u(FD_STEP, t) - u(0.0, t)) / FD_STEP;
        worst = worst.max((one_sided - fb.reaction(t)).abs() / (g * FD_STEP + FD_ROUNDOFF));
    }
    worst
}

/// The built-in falling bar's closed form (the scene's own data).
pub fn builtin_falling_bar() -> Result<FallingBar, RunError> {
    let (_, s) = scene::load("falling-bar", &[])?;
    let gravity = s
        .load
        .density
        .as_ref()
        .and_then(|d| d.trim().parse::<f64>().ok())
        .map(|l| -l)
        .ok_or_else(|| {
            invalid(
                "load.density",
                format!("{:?}", s.load.density),
                "a constant",
            )
        })?;
    let gap = s
        .left
        .constant_gap()
        .ok_or_else(|| invalid("left.gap", "none".into(), "a Signorini left end"))?;
    FallingBar::new(s.bar.length, gravity, gap).ok_or_else(|| {
        invalid(
            "falling-bar",
            format!("L {}, g {gravity}, gap {gap}", s.bar.length),
            "a falling bar's data",
        )
    })
}
/// The impact scene's contact times are resolved to a few time steps (the kink is smeared over
/// a few cells).
pub const CONTACT_TIME_TOL: f64 = 0.02;
/// The mean reaction over the contact interval against `v0 = 1`.
pub const MEAN_REACTION_TOL: f64 = 0.02;

/// Impact at 400 elements, `Δt = 0.0025`: contact on `[t1, t1 + 2L] = [0.1, 2.1]` with mean
/// reaction `v0 = 1` (the momentum change `2 v0 L` over `2L`). Returns the number of contact
/// episodes, the worst error of the contact times and the error of the mean reaction.
pub fn impact_contact_errors() -> Result<(usize, f64, f64), RunError> {
    let (_, scene) = scene::load(
        "impact",
        &["mesh.elements=400".into(), "time.step=0.0025".into()],
    )?;
    let (records, summary, _) = run_in_memory("impact", &scene)?;
    // No left contact at all: no episode, infinite errors (the checks fail, nothing panics).
    let intervals = summary
        .contact_intervals
        .get("left")
        .map_or(&[][..], |v| v.as_slice());
    let time_error = intervals
        .first()
        .map_or(f64::INFINITY, |[s, e]| (s - 0.1).abs().max((e - 2.1).abs()));
    let in_contact: Vec<f64> = records
        .iter()
        .filter_map(|r| {
            let end = r.contact.groups[0];
            (end.min_gap <= 1e-12).then_some(end.reaction)
        })
        .collect();
    let mean_error = if in_contact.is_empty() {
        f64::INFINITY
    } else {
        (in_contact.iter().sum::<f64>() / in_contact.len() as f64 - 1.0).abs()
    };
    Ok((intervals.len(), time_error, mean_error))
}

// ---- tests/mass.rs, tests/episodes.rs, tests/diagnostics.rs ------------------------------------

/// `E before − E after` against the summed contact term on `impact` at α = 0 (no load, no
/// viscosity: the identity makes them equal): round-off of a few hundred steps' sums.
pub const DROP_TOL: f64 = 1e-12;

/// The mass study's rows on `impact` at α = 0: the worst `|energy drop − contact term|`.
pub fn drop_worst(rows: &[crate::bar::mass_study::MassRow]) -> f64 {
    rows.iter()
        .filter(|r| r.scene == "impact" && r.alpha == 0.0)
        .map(|r| (r.energy_drop - r.contact_dissipation).abs())
        .fold(0.0, f64::max)
}

/// [`drop_worst`] of a fresh mass study (a few seconds).
pub fn mass_study_drop_worst() -> Result<f64, RunError> {
    use crate::bar::mass_study::{MassStudyError, mass_study};
    let rows = mass_study().map_err(|e| match e {
        MassStudyError::Run(r) => r,
        other => invalid(
            "mass study",
            other.to_string(),
            "a complete contact episode",
        ),
    })?;
    Ok(drop_worst(&rows))
}

/// The redistributed mass's massless end after the start-up, relative to the bar's largest
/// first step: `z = C⁻¹(C w) = w` up to the solve's round-off, a few ε κ(C) with κ(C) about
/// 10 here.
pub const START_TOL: f64 = 1e-14;

/// `one-end` (at rest in the shape `0.3 cos 2x`) with each mass variant: `(variant, |u¹₀ − u⁰₀|,
/// max_i |u¹_i − u⁰_i|)`, the first step of the left end and of the bar.
pub fn start_up_motion() -> Result<Vec<(MassVariant, f64, f64)>, RunError> {
    let mut out = Vec::new();
    for mass in MassVariant::ALL {
        let (_, scene) = scene::load("one-end", &[format!("bar.mass={}", mass.name())])?;
        let sim = viscobar::bar::Simulation::new(&scene)?;
        let (u0, _) = sim.initial_state();
        let u1 = sim.displacement();
        let moved = (u1[0] - u0[0]).abs();
        let scale = u1
            .iter()
            .zip(&u0)
            .fold(0.0f64, |m, (a, b)| m.max((a - b).abs()));
        out.push((mass, moved, scale));
    }
    Ok(out)
}

/// The release time of `impact` (exact 2.1) at Δx = 0.01, 0.005, 0.0025 (Δt = Δx): the
/// contact-time error is 0.02 on the coarsest of them (VERIFICATION.md), a quarter more.
pub const RELEASE_TOL: f64 = 0.025;
/// The meshes of `tests/episodes.rs`'s impact check.
pub const RELEASE_ELEMENTS: [u64; 3] = [100, 200, 400];

/// The release time's error of an `impact` contact episode, `|end − 2.1|`.
pub fn release_error(e: &viscobar::output::ContactEpisode) -> f64 {
    (e.end - 2.1).abs()
}

/// [`release_error`] of each of `impact`'s left-end contact episodes at [`RELEASE_ELEMENTS`].
pub fn release_errors() -> Result<Vec<f64>, RunError> {
    let mut out = Vec::new();
    for elements in RELEASE_ELEMENTS {
        let (_, scene) = scene::load(
            "impact",
            &[
                format!("mesh.elements={elements}"),
                format!("time.step={}", 1.0 / elements as f64),
            ],
        )?;
        let (_, summary, _) = run_in_memory("impact", &scene)?;
        for e in summary.contact_episodes.get("left").into_iter().flatten() {
            out.push(release_error(e));
        }
    }
    Ok(out)
}

/// A measured energy after unmeasured steps is computed from `u^{n−1} = u^n − w` rather than
/// carried over: it differs from the every-step value by round-off in `E`, relative to
/// `max(E, 1)`.
pub const ENERGY_ROUNDOFF_TOL: f64 = 1e-13;
/// The thinning of `tests/diagnostics.rs` (`output.diagnostics_every`).
pub const THINNING: u64 = 7;

/// `|E_every − E_thinned| / max(E_every, 1)`, the quantity [`ENERGY_ROUNDOFF_TOL`] bounds.
pub fn thinned_energy_error(every: f64, thinned: f64) -> f64 {
    (every - thinned).abs() / every.max(1.0)
}

/// [`thinned_energy_error`] over every built-in scene's measured steps, thinned by
/// [`THINNING`] against every step.
pub fn thinned_energy_worst() -> Result<f64, RunError> {
    use viscobar::bar::Simulation;
    let mut worst = 0.0f64;
    for name in builtin_names() {
        let (_, every) = scene::load(name, &[])?;
        let (_, thinned) = scene::load(name, &[format!("output.diagnostics_every={THINNING}")])?;
        let (mut a, mut b) = (Simulation::new(&every)?, Simulation::new(&thinned)?);
        for _ in 1..every.steps() {
            let (ra, rb) = (a.step()?, b.step()?);
            if rb.measured {
                worst = worst.max(thinned_energy_error(ra.energy, rb.energy));
            }
        }
    }
    Ok(worst)
}

// ---- tests/loads.rs ---------------------------------------------------------------------------

/// The separated load path against the plain one, relative to `Σ_k |f_k| M|g_k| + M|l|`: the
/// split regroups at most `MAX_TERMS` = 8 terms, each combined by at most a few roundings along
/// the sums and products of the tree (the regrouped sum may cancel where the tree did not).
pub const SEPARATION_TOL: f64 = 64.0 * f64::EPSILON;
/// Elements of the loads' comparison (`modal` with `Δt = Δx`).
pub const LOAD_ELEMENTS: u64 = 40;
/// Separable loads of the registry's measurement: the talk's two and sums, products and
/// quotients of the generator's factors (`tests/loads.rs` draws more at random).
pub const SEPARABLE_LOADS: [&str; 6] = [
    "sin(t*sqrt(2))*cos(2*x)",
    "-0.5 + 0.8*sin(3*t)*cos(pi*x/2)",
    "(sin(1.3*x) + exp(-0.7*t))*(cos(2.1*t) - x)",
    "((1 + x^2)/(1.5 + x))/(2 + cos(0.9*t)) - sin(2.5*t)*exp(-1.1*x)",
    "(t - sin(0.6*x))*(x + cos(1.7*t)) + 2.2*(1 + t^2)/(0.8 + t)",
    "-((exp(-2*x) - t)*(sin(0.5*t) + x)) + cos(2.9*x)",
];

/// The load vector at step `n` of `modal` with load `text` ([`LOAD_ELEMENTS`]): the
/// simulation's (separated where it can) and the plain `M l(x, t)`, and the scale
/// `Σ_k |f_k(t)| M|g_k| + M|l|` of the separation's round-off.
pub fn load_vectors(text: &str, n: usize) -> Result<[Vec<f64>; 3], RunError> {
    use viscobar::bar::matrices::{MatrixVariant, mass};
    use viscobar::scene::Expression;
    let (_, scene) = scene::load(
        "modal",
        &[
            format!("load.density=\"{text}\""),
            format!("mesh.elements={LOAD_ELEMENTS}"),
            format!("time.step={}", 1.0 / LOAD_ELEMENTS as f64),
        ],
    )?;
    let mut sim = viscobar::bar::Simulation::new(&scene)?;
    let disc = sim.discretisation().clone();
    let t = n as f64 * disc.dt;
    let fast = sim.load_vector(n)?.to_vec();
    let expr = Expression::parse("load.density", text, true)?;
    let eval = |e: &Expression, x: f64, t: f64| -> Result<f64, RunError> { Ok(e.eval(x, t)?) };
    let m = mass(MatrixVariant::Consistent, disc.nodes, disc.dx);
    let xs: Vec<f64> = (0..disc.nodes).map(|i| disc.x(i)).collect();
    let l = xs
        .iter()
        .map(|&x| eval(&expr, x, t))
        .collect::<Result<Vec<f64>, RunError>>()?;
    let plain = m.mul(&l);
    let mut scale = m.mul(&l.iter().map(|v| v.abs()).collect::<Vec<_>>());
    for term in expr.separate().unwrap_or_default() {
        let f = eval(&term.time, 0.0, t)?.abs();
        let g = xs
            .iter()
            .map(|&x| eval(&term.space, x, 0.0).map(f64::abs))
            .collect::<Result<Vec<f64>, RunError>>()?;
        for (s, mg) in scale.iter_mut().zip(m.mul(&g)) {
            *s += f * mg;
        }
    }
    Ok([fast, plain, scale])
}

/// `max_i |fast_i − plain_i| / scale_i` of [`load_vectors`] (0 where both are 0).
pub fn separation_error([fast, plain, scale]: &[Vec<f64>; 3]) -> f64 {
    (0..fast.len())
        .map(|i| {
            let d = (fast[i] - plain[i]).abs();
            if d == 0.0 { 0.0 } else { d / scale[i] }
        })
        .fold(0.0, f64::max)
}

/// [`separation_error`] over [`SEPARABLE_LOADS`] at steps 0, 17, 79.
pub fn separation_worst() -> Result<f64, RunError> {
    let mut worst = 0.0f64;
    for text in SEPARABLE_LOADS {
        for n in [0usize, 17, 79] {
            worst = worst.max(separation_error(&load_vectors(text, n)?));
        }
    }
    Ok(worst)
}

// ---- tests/roundoff.rs ------------------------------------------------------------------------

/// Drift allowed for the increment form on the rigid mode (`verify::rigid_drift`): a few
/// hundred ulps of the final displacement (about 3), i.e. round-off that grows no faster than
/// the number of steps.
pub const INCREMENT_DRIFT_TOL: f64 = 1e-9;

// ---- tests/energy_and_contact.rs ---------------------------------------------------------------

/// Round-off of the solves for the bar resting on the obstacle (condition number of C about 3
/// at dt ~ dx): `u` of size 0.25, reactions of size dx.
pub const RESTING_TOL: f64 = 1e-12;

/// The bar resting on a flat obstacle under a uniform load (`distributed` with `u0 = −0.25`,
/// gap 0.25, load −1): the worst `|u + 0.25|` and `|r − M·1|` at the end, and whether every
/// node was in contact at every step.
pub fn resting_bar_worst() -> Result<(f64, bool), RunError> {
    let (_, scene) = scene::load(
        "distributed",
        &[
            "initial.velocity=\"0\"".into(),
            "initial.displacement=\"-0.25\"".into(),
            "obstacle.gap=0.25".into(),
            "load.density=\"-1\"".into(),
        ],
    )?;
    let (records, _, sim) = run_in_memory("resting", &scene)?;
    let sim = sim.mechanical().expect("a scene without [heat]");
    let disc = sim.discretisation();
    let m_one = disc.mass.mul(&vec![1.0; disc.unknowns()]);
    let mut worst = 0.0f64;
    for u in sim.displacement() {
        worst = worst.max((u + 0.25).abs());
    }
    for (r, m) in sim.reactions().iter().zip(&m_one) {
        worst = worst.max((r - m).abs());
    }
    let all_in_contact = records
        .iter()
        .all(|r| r.contact.contact_nodes == disc.nodes);
    Ok((worst, all_in_contact))
}

/// `(E^{1/2} − 1/8)/dx` on clamped-impact: first order (the kink of `u0` at `x = 1`), 15 %
/// over the value that the start-up makes at every level (`start_energy_errors`).
pub const START_ENERGY_ERROR_PER_DX: f64 = 0.25;

/// Clamped-impact at 400 and 800 elements with `Δt = Δx`: per level, `(E^{1/2} − 1/8, dx,
/// E_final / E^{1/2} − 1)`.
pub fn start_energy_errors() -> Result<Vec<(f64, f64, f64)>, RunError> {
    let mut out = Vec::new();
    for elements in [400u64, 800] {
        let dt = 1.0 / elements as f64;
        let (_, scene) = scene::load(
            "clamped-impact",
            &[
                format!("mesh.elements={elements}"),
                format!("time.step={dt}"),
            ],
        )?;
        let (records, _, _) = run_in_memory("clamped-impact", &scene)?;
        let e0 = records[0].energy;
        let e_final = records.last().map_or(e0, |r| r.energy);
        out.push((e0 - 0.125, scene.dx(), e_final / e0 - 1.0));
    }
    Ok(out)
}
