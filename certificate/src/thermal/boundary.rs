//! The thermal bar's fixed end temperatures varying in time: a manufactured solution
//! (`docs/thermal.md`, "Manufactured solution with time-varying end temperatures") on a bar
//! clamped at both ends whose prescribed temperatures `θ(0, t) = sin 3t`, `θ(1, t) = ½ cos 2t`
//! move, its self-test (the equations and the data of the scene checked against the closed
//! form by finite differences) and its refinement study. The scheme holds a fixed end at
//! `θ^{n+1/2} = θ_end(t_{n+1/2})`; data taken at another time is an `O(Δt)` shift that the
//! energy identity does not see and the order of this study does (`tests/thermal_boundary.rs`).

use crate::thermal::{Study2, sized, temperatures};
use std::f64::consts::PI;
use viscobar::internals::scene::expr::Expression;
use viscobar::output::run_thermal_in_memory;
use viscobar::scene::{Scene, SceneError};
use viscobar::scheme::RunError;
use viscobar::study::accuracy::observed_order;

/// `α`, `γ`, `κ` of the scene.
pub const PARAMETERS: (f64, f64, f64) = (0.1, 0.5, 0.2);

/// The scene: `u = A(t) sin(πx)`, `θ = a(t)(1 − x) + b(t) x + B(t) sin(πx)` with
/// `A = 0.1 sin 2t`, `a = sin 3t`, `b = ½ cos 2t`, `B = 0.3 cos t`; clamped at both ends, each
/// end held at its temperature; load and source from [`load`] and [`source`].
pub const SCENE: &str = r#"
[bar]
length = 1.0
viscosity = 0.1
[left]
condition = "clamped"
[right]
condition = "clamped"
[initial]
displacement = "0"
velocity = "0.2*sin(pi*x)"
[load]
density = "(0.1*pi^2*sin(2*t) - 0.4*sin(2*t) + 0.02*pi^2*cos(2*t))*sin(pi*x) + 0.5*(0.5*cos(2*t) - sin(3*t)) + 0.15*pi*cos(t)*cos(pi*x)"
[heat]
coupling = 0.5
diffusivity = 0.2
temperature = "0.5*x + 0.3*sin(pi*x)"
source = "3*cos(3*t)*(1 - x) - sin(2*t)*x + (0.06*pi^2*cos(t) - 0.3*sin(t))*sin(pi*x) + 0.1*pi*cos(2*t)*cos(pi*x)"
left = { condition = "temperature", value = "sin(3*t)" }
right = { condition = "temperature", value = "0.5*cos(2*t)" }
[mesh]
elements = 8
[time]
step = 0.1
end = 2.0
"#;

/// `(u, θ)` at `(x, t)`.
pub fn exact(x: f64, t: f64) -> (f64, f64) {
    let s = (PI * x).sin();
    let u = 0.1 * (2.0 * t).sin() * s;
    let theta = (3.0 * t).sin() * (1.0 - x) + 0.5 * (2.0 * t).cos() * x + 0.3 * t.cos() * s;
    (u, theta)
}

/// `l = u_tt − u_xx − α u_xxt + γ θ_x`, derived by hand from [`exact`]
/// (`(A'' + π²A + απ²A') sin πx + γ(b − a) + γπB cos πx`).
pub fn load(x: f64, t: f64) -> f64 {
    let (alpha, gamma, _) = PARAMETERS;
    let (a, a1, a2) = (
        0.1 * (2.0 * t).sin(),
        0.2 * (2.0 * t).cos(),
        -0.4 * (2.0 * t).sin(),
    );
    let (ta, tb, tbb) = ((3.0 * t).sin(), 0.5 * (2.0 * t).cos(), 0.3 * t.cos());
    (a2 + PI * PI * a + alpha * PI * PI * a1) * (PI * x).sin()
        + gamma * (tb - ta)
        + gamma * PI * tbb * (PI * x).cos()
}

/// `q = θ_t − κ θ_xx + γ u_xt`, derived by hand from [`exact`]
/// (`a'(1 − x) + b' x + (B' + κπ²B) sin πx + γπA' cos πx`).
pub fn source(x: f64, t: f64) -> f64 {
    let (_, gamma, kappa) = PARAMETERS;
    let (ta1, tb1) = (3.0 * (3.0 * t).cos(), -(2.0 * t).sin());
    let (tbb, tbb1) = (0.3 * t.cos(), -0.3 * t.sin());
    let a1 = 0.2 * (2.0 * t).cos();
    ta1 * (1.0 - x)
        + tb1 * x
        + (tbb1 + kappa * PI * PI * tbb) * (PI * x).sin()
        + gamma * PI * a1 * (PI * x).cos()
}

/// Step of the fourth-order central differences of the self-test.
pub const FD_STEP: f64 = 1e-2;

fn first(f: impl Fn(f64) -> f64, y: f64) -> f64 {
    let d = FD_STEP;
    (-f(y + 2.0 * d) + 8.0 * f(y + d) - 8.0 * f(y - d) + f(y - 2.0 * d)) / (12.0 * d)
}

fn second(f: impl Fn(f64) -> f64, y: f64) -> f64 {
    let d = FD_STEP;
    (-f(y + 2.0 * d) + 16.0 * f(y + d) - 30.0 * f(y) + 16.0 * f(y - d) - f(y - 2.0 * d))
        / (12.0 * d * d)
}

/// The worst residuals, over a grid of `(x, t)` in `[0, 1] × [0, 2]`, of the closed form
/// against the scene's own data: `[equations, data]`. Equations: both PDEs by differences of
/// [`exact`] alone, against the scene's load and source expressions, relative to
/// `max(|l|, |q|, 1)`; data: `|θ(0, t) − value_left|`, `|θ(1, t) − value_right|`,
/// `|u(0, t)|`, `|u(1, t)|` and the initial displacement, velocity (by differences) and
/// temperature against the scene's, and [`load`], [`source`] against the scene's.
pub fn self_test() -> Result<[f64; 2], SceneError> {
    let scene = Scene::from_toml(SCENE, &[])?;
    let heat = scene.heat.as_ref().expect("a thermal scene");
    let parse = |field: &str, text: &Option<String>| {
        Expression::parse(field, text.as_deref().expect("set"), true)
    };
    let l = parse("load.density", &scene.load.density)?;
    let q = parse("heat.source", &heat.source)?;
    let left = parse("heat.left.value", &heat.left.value)?;
    let right = parse("heat.right.value", &heat.right.value)?;
    let u0 = Expression::parse("initial.displacement", &scene.initial.displacement, false)?;
    let v0 = Expression::parse("initial.velocity", &scene.initial.velocity, false)?;
    let th0 = Expression::parse("heat.temperature", &heat.temperature, false)?;
    let (alpha, gamma, kappa) = PARAMETERS;
    let u = |x: f64, t: f64| exact(x, t).0;
    let th = |x: f64, t: f64| exact(x, t).1;
    let (mut equations, mut data) = (0.0f64, 0.0f64);
    for i in 0..=40 {
        for n in 0..=40 {
            let (x, t) = (i as f64 / 40.0, 2.0 * n as f64 / 40.0);
            let (lx, qx) = (l.eval(x, t)?, q.eval(x, t)?);
            let uxx = |s: f64| second(|y| u(y, s), x);
            let residual_u = second(|s| u(x, s), t) - uxx(t) - alpha * first(uxx, t)
                + gamma * first(|y| th(y, t), x)
                - lx;
            let uxt = first(|s| first(|y| u(y, s), x), t);
            let residual_q =
                first(|s| th(x, s), t) - kappa * second(|y| th(y, t), x) + gamma * uxt - qx;
            let scale = lx.abs().max(qx.abs()).max(1.0);
            equations = equations.max(residual_u.abs().max(residual_q.abs()) / scale);
            let misfits = [
                th(0.0, t) - left.eval(0.0, t)?,
                th(1.0, t) - right.eval(0.0, t)?,
                u(0.0, t),
                u(1.0, t),
                u(x, 0.0) - u0.eval(x, 0.0)?,
                first(|s| u(x, s), 0.0) - v0.eval(x, 0.0)?,
                th(x, 0.0) - th0.eval(x, 0.0)?,
                load(x, t) - lx,
                source(x, t) - qx,
            ];
            data = misfits.iter().fold(data, |m, v| m.max(v.abs()));
        }
    }
    Ok([equations, data])
}

/// The study's levels (`J`, `Δt = 1/J`) to `t = 2`.
pub const ELEMENTS: [u64; 4] = [32, 64, 128, 256];

/// Per level: `J`, the max nodal errors of `u^N` and of `θ^{N−1/2}` (the fixed ends
/// included); and the observed orders of both (least squares over the levels).
pub fn study() -> Result<Study2<(u64, f64, f64)>, RunError> {
    let mut rows = Vec::new();
    for elements in ELEMENTS {
        let dt = 1.0 / elements as f64;
        let scene = sized(SCENE, elements, dt, 2.0)?;
        let (_, _, sim) = run_thermal_in_memory("thermal-boundary", &scene)?;
        let (t, dx) = (sim.time(), 1.0 / elements as f64);
        let (mut eu, mut et) = (0.0f64, 0.0f64);
        let dofs = sim.displacement_dofs();
        for (i, (u, th)) in dofs.iter().zip(temperatures(&sim)).enumerate() {
            let x = i as f64 * dx;
            eu = eu.max((u - exact(x, t).0).abs());
            et = et.max((th - exact(x, t - 0.5 * dt).1).abs());
        }
        rows.push((elements, eu, et));
    }
    let h: Vec<f64> = rows.iter().map(|r| 1.0 / r.0 as f64).collect();
    let eu: Vec<f64> = rows.iter().map(|r| r.1).collect();
    let et: Vec<f64> = rows.iter().map(|r| r.2).collect();
    Ok((rows, observed_order(&h, &eu), observed_order(&h, &et)))
}
