//! Refinement study of the manufactured viscous-contact scene (`viscous-contact`,
//! [`ViscousContact`](viscobar::bar::closed_form::ViscousContact)): errors of the displacement,
//! the reaction and the contact times against the closed form, `dx` and `dt` halved together;
//! and the closed form's self-checks by finite differences. Shared by
//! `tests/viscous_contact.rs`, the tolerance registry and the generated table of
//! VERIFICATION.md; derivation in [docs/viscous-contact.md](../../../docs/viscous-contact.md).

use std::fmt::Write;
use viscobar::bar::closed_form::{self, ClosedForm};
use viscobar::output::run_in_memory;
use viscobar::scene::{self, Scene};
use viscobar::scheme::RunError;
use viscobar::study::accuracy::{error_against, observed_order};
use viscobar::study::converge::contact_time_error;

/// The built-in scene's name.
pub const SCENE: &str = "viscous-contact";

/// Time kept off each end of the contact window for [`Row::reaction_interior`]: a tenth of
/// the window, longer than the discrete contact set's lag at the scene's own mesh (about 4
/// steps, 0.0625, in the table).
pub const INTERIOR_MARGIN: f64 = 0.1;

/// Step of the fourth-order central differences of the self-test ([`pde_residual_worst`]).
pub const FD_STEP: f64 = 1e-2;
/// The fourth-order differences err by `d⁴/90 · f⁽⁶⁾` (`d⁴/30 f⁽⁵⁾` for `f'`); the largest
/// sixth derivative is the free decay's `|h0|/α⁶ · w ≤ 0.2e6 · 2/π` and the window's
/// `Pω⁵/α ~ 1e5`, so about `1e-8 · 2e5 / 90 ≈ 2e-5` per term, three terms; relative to the
/// load where it exceeds 1.
pub const PDE_FD_TOL: f64 = 1e-4;
/// Half-width of the joins' jump test ([`join_slope_worst`]).
pub const JOIN_DELTA: f64 = 1e-9;
/// A bound on the next derivative of `g, g', g'', h, h', h''` near the joins: the third
/// derivative of `h` is at most `(|σ''| + |h''|)/α ≤ (2π²P + 100)/0.1 ≈ 1.2e3`; 1e4 leaves a
/// margin, and a jump of size 1e-4 still fails.
pub const JOIN_SLOPE_BOUND: f64 = 1e4;
/// Midpoints of the energy quadrature ([`energy_quadrature_worst`]).
pub const ENERGY_QUAD_POINTS: usize = 2000;
/// The midpoint rule errs by `Δx²/24` times the integrand's second derivative
/// (`≤ k² · 2 max(u_t², u_x²) ~ 50`: about 1e-6 at `Δx = 5e-4`; measured far below, the
/// integrand being smooth), differences of step 1e-6 by `1e-10` relative; relative to the
/// energy where it exceeds 1.
pub const ENERGY_QUAD_TOL: f64 = 1e-6;

/// `f''` by the fourth-order central stencil of step [`FD_STEP`].
fn second(f: impl Fn(f64) -> f64, y: f64) -> f64 {
    let d = FD_STEP;
    (-f(y + 2.0 * d) + 16.0 * f(y + d) - 30.0 * f(y) + 16.0 * f(y - d) - f(y - 2.0 * d))
        / (12.0 * d * d)
}

/// `f'` by the fourth-order central stencil of step [`FD_STEP`].
fn first(f: impl Fn(f64) -> f64, y: f64) -> f64 {
    let d = FD_STEP;
    (-f(y + 2.0 * d) + 8.0 * f(y + d) - 8.0 * f(y - d) + f(y - 2.0 * d)) / (12.0 * d)
}

/// Deterministic sample points of the self-tests: `(x, t)` from two Weyl sequences over the
/// bar and `[0, 2.5]`.
pub fn sample_points(vc: &closed_form::ViscousContact) -> impl Iterator<Item = (f64, f64)> {
    let l = vc.length;
    (1..3000usize).map(move |i| {
        (
            l * (i as f64 * 0.414_213_562_373_095_1).fract(),
            2.5 * (i as f64 * 0.618_033_988_749_894_9).fract(),
        )
    })
}

/// The closed form against its problem, by differences of the displacement alone: the worst
/// of `|u_tt − u_xx − α u_xxt − l| / max(|l|, 1)`, `|s(0, t) − σ(t)|` and `|s(L, t)|` over
/// [`sample_points`] whose stencils do not straddle `t = 0, t1, t2` (the third time
/// derivative jumps there).
pub fn pde_residual_worst(vc: &closed_form::ViscousContact) -> f64 {
    let (l, a) = (vc.length, vc.alpha);
    let u = |x: f64, t: f64| vc.displacement(x, t);
    let mut worst = 0.0f64;
    for (x, t) in sample_points(vc) {
        let reach = 2.0 * FD_STEP;
        if [0.0, vc.t1, vc.t2]
            .iter()
            .any(|&tb| (t - tb).abs() <= reach)
        {
            continue;
        }
        let utt = second(|s| u(x, s), t);
        // x-differences reach past the bar: u is the same analytic function of x there.
        let uxx = |s: f64| second(|y| u(y, s), x);
        let residual = utt - uxx(t) - a * first(uxx, t) - vc.load(x, t);
        worst = worst.max(residual.abs() / vc.load(x, t).abs().max(1.0));
        let ux = |y: f64, s: f64| first(|z| u(z, s), y);
        let s0 = ux(0.0, t) + a * first(|s| ux(0.0, s), t);
        let sl = ux(l, t) + a * first(|s| ux(l, s), t);
        worst = worst.max((s0 - vc.stress(t)[0]).abs()).max(sl.abs());
    }
    worst
}

/// The joins at `t1`, `t2`: the worst of `|f(tb + δ) − f(tb − δ)| / (2δ)` over
/// `f = g, g', g'', h, h', h''` (δ = [`JOIN_DELTA`]) and of `|left − right| / d` for one-sided
/// second differences of `u` in time (step `d = 1e-3`) at `x = 0, L/2, L`: bounded by the next
/// derivative for a `C²` join, by a jump / δ otherwise.
pub fn join_slope_worst(vc: &closed_form::ViscousContact) -> f64 {
    let mut worst = 0.0f64;
    for tb in [vc.t1, vc.t2] {
        let (lo, hi) = (tb - JOIN_DELTA, tb + JOIN_DELTA);
        let pairs = vc.rigid(lo).into_iter().zip(vc.rigid(hi)).chain(
            vc.amplitude_rates(lo)
                .into_iter()
                .zip(vc.amplitude_rates(hi)),
        );
        for (a, b) in pairs {
            worst = worst.max((a - b).abs() / (2.0 * JOIN_DELTA));
        }
        let d = 1e-3;
        for x in [0.0, 0.5 * vc.length, vc.length] {
            let u = |t: f64| vc.displacement(x, t);
            let one_sided = |s: f64| {
                (2.0 * u(tb) - 5.0 * u(tb + s) + 4.0 * u(tb + 2.0 * s) - u(tb + 3.0 * s)) / (s * s)
            };
            worst = worst.max((one_sided(-d) - one_sided(d)).abs() / d);
        }
    }
    worst
}

/// The closed form's energy against a midpoint quadrature of central differences (step 1e-6)
/// at 50 times: the worst `|quadrature − E| / max(E, 1)`.
pub fn energy_quadrature_worst(vc: &closed_form::ViscousContact) -> f64 {
    let dx = vc.length / ENERGY_QUAD_POINTS as f64;
    let d = 1e-6;
    let u = |x: f64, t: f64| vc.displacement(x, t);
    let mut worst = 0.0f64;
    for i in 0..50 {
        let t = 0.05 * i as f64 + 0.0123;
        let e: f64 = (0..ENERGY_QUAD_POINTS)
            .map(|j| {
                let x = (j as f64 + 0.5) * dx;
                let ut = (u(x, t + d) - u(x, t - d)) / (2.0 * d);
                let ux = (u(x + d, t) - u(x - d, t)) / (2.0 * d);
                0.5 * (ut * ut + ux * ux) * dx
            })
            .sum();
        let exact = vc.energy(t).expect("derived");
        worst = worst.max((e - exact).abs() / exact.max(1.0));
    }
    worst
}

/// Errors at the scene's own mesh (`tests/viscous_contact.rs`, [`crate::tolerances`]):
/// 1.25x those measured (VERIFICATION.md's viscous-contact table, first row), so that
/// round-off changes pass and a wrong reaction or load fails.
pub const L2_BOUND: f64 = 1.25 * 1.196e-3;
pub const REACTION_INTERIOR_BOUND: f64 = 1.25 * 2.587e-3;

/// One level of the study.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Row {
    pub elements: u64,
    pub dt: f64,
    pub dx: f64,
    /// `max_n ‖u_h(t_n) − u(·, t_n)‖_{L2}` (trapezoidal rule on the nodes).
    pub l2: f64,
    /// `max_n |r^{n+1} − (−s(0, t_n))|`: the reaction of the step centred at `t_n` (the scheme's
    /// equation is centred there) against the closed form's.
    pub reaction: f64,
    /// The same on `[t1 + m, t2 − m]`, `m` = [`INTERIOR_MARGIN`]: away from the landing and the
    /// take-off, where the discrete contact set differs from the exact one for a few steps.
    pub reaction_interior: f64,
    /// [`contact_time_error`] of the left end's episodes against `[t1, t2]`.
    pub contact_times: f64,
}

/// The closed form of the scene (a built-in one always has it).
pub fn closed_form(scene: &Scene) -> closed_form::ViscousContact {
    let exact = closed_form::for_scene(SCENE, scene).expect("viscous-contact has its closed form");
    let [t1, t2] = closed_form::VISCOUS_CONTACT_WINDOW;
    checked_against(
        closed_form::ViscousContact {
            length: scene.bar.length,
            alpha: scene.bar.viscosity,
            gap: scene.left.constant_gap().expect("Signorini left end"),
            t1,
            t2,
            pulse: closed_form::VISCOUS_CONTACT_PULSE,
            initial_amplitude: closed_form::VISCOUS_CONTACT_INITIAL_AMPLITUDE,
        },
        exact.as_ref(),
    )
}

/// `form`, after checking it is the closed form `other` (same displacement at a few points).
fn checked_against(
    form: closed_form::ViscousContact,
    other: &dyn ClosedForm,
) -> closed_form::ViscousContact {
    for (x, t) in [(0.3, 0.2), (0.7, 1.1), (1.0, 2.0)] {
        assert_eq!(form.displacement(x, t), other.displacement(x, t));
    }
    form
}

/// One level: the scene refined `level` times (dx and dt halved together).
pub fn row(base: &Scene, level: u32) -> Result<Row, RunError> {
    let exact = closed_form(base);
    let scene = base.refined(level);
    let l2 = error_against(&scene, &exact)?.l2;
    let (records, summary, _) = run_in_memory(SCENE, &scene)?;
    let dt = scene.time.step;
    let (mut reaction, mut reaction_interior) = (0.0f64, 0.0f64);
    for r in &records {
        let t_n = (r.step - 1) as f64 * dt;
        let e = (r.contact.groups[0].reaction - exact.reaction(t_n)).abs();
        reaction = reaction.max(e);
        if t_n >= exact.t1 + INTERIOR_MARGIN && t_n <= exact.t2 - INTERIOR_MARGIN {
            reaction_interior = reaction_interior.max(e);
        }
    }
    let discrete = summary
        .contact_intervals
        .get("left")
        .cloned()
        .unwrap_or_default();
    let window = exact.contact_intervals(scene.time.end).expect("one window");
    Ok(Row {
        elements: scene.mesh.elements,
        dt,
        dx: scene.dx(),
        l2,
        reaction,
        reaction_interior,
        contact_times: contact_time_error(&window, &discrete).expect("one window"),
    })
}

/// Levels `0..levels` of the built-in scene.
pub fn study(levels: u32) -> Result<Vec<Row>, RunError> {
    let (_, base) = scene::load(SCENE, &[])?;
    (0..levels).map(|l| row(&base, l)).collect()
}

/// Observed orders (least squares over all rows) of the displacement, the reaction (all
/// steps, then the window's interior) and the contact times.
pub fn orders(rows: &[Row]) -> [f64; 4] {
    let h: Vec<f64> = rows.iter().map(|r| r.dx).collect();
    let of = |f: fn(&Row) -> f64| observed_order(&h, &rows.iter().map(f).collect::<Vec<_>>());
    [
        of(|r| r.l2),
        of(|r| r.reaction),
        of(|r| r.reaction_interior),
        of(|r| r.contact_times),
    ]
}

/// The table of VERIFICATION.md.
pub fn markdown(rows: &[Row]) -> String {
    let mut md = String::from(
        "| elements | dt | L2 error (max over t) | reaction error (all steps) | reaction error (window interior) | contact time error |\n|---|---|---|---|---|---|\n",
    );
    for r in rows {
        let _ = writeln!(
            md,
            "| {} | {} | {:.3e} | {:.3e} | {:.3e} | {:.3e} |",
            r.elements, r.dt, r.l2, r.reaction, r.reaction_interior, r.contact_times
        );
    }
    let [p, q, qi, c] = orders(rows);
    let _ = writeln!(
        md,
        "| observed order | | {p:.3} | {q:.3} | {qi:.3} | {c:.3} |"
    );
    md
}
