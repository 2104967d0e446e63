//! The plane body's temperature (`[heat]`): uncoupled, the heat balance of a frictional launch
//! at every step, its uniform end temperature, a block on a belt against its closed-form flux
//! and edge temperature, an exchanging floor's decay rate, a sudden edge temperature's range and
//! the heat step's orders; coupled, the orders of a manufactured solution in `u` and `θ` and the
//! identity of a frictional launch. `tests/plane_heat*.rs` assert each against its tolerance
//! ([`crate::tolerances`]); [`markdown`] is VERIFICATION.md's generated table. Derivations:
//! docs/thermal.md, "The plane body".

use std::fmt::Write;
use viscobar::output::run_plane_in_memory;
use viscobar::plane::{PlaneBody, PlaneSimulation};
use viscobar::scheme::{Body, RunError};
use viscobar::{PlaneScene, StepRecord};

/// The frictional launch (`scenes/plane-friction-launch.toml`).
pub const LAUNCH: &str = include_str!("../../scenes/plane-friction-launch.toml");

/// The launch with `[heat]` (`heat` the table's lines) and `overrides`.
pub fn launch_with_heat(heat: &str, overrides: &[&str]) -> PlaneScene {
    let text = format!("{LAUNCH}\n[heat]\n{heat}\n");
    let overrides: Vec<String> = overrides.iter().map(|s| s.to_string()).collect();
    PlaneScene::from_toml(&text, &overrides).expect("a valid scene")
}

/// The records and the simulation of a certified run of `scene`.
pub fn run(scene: &PlaneScene) -> Result<(Vec<StepRecord>, PlaneSimulation), RunError> {
    let (records, _, sim) = run_plane_in_memory("plane-heat", scene)?;
    Ok((records, sim))
}

fn theta(sim: &PlaneSimulation, node: usize) -> f64 {
    let body: &PlaneBody = sim.body();
    body.temperature(sim.displacement(), node)
        .expect("a temperature")
}

/// The heat balance of the launch with `frictional_heating = eta` on its floor: the worst
/// `|Δ(1ᵀMθ) − Σ q|` over the steps, relative to the largest heat content, and `Σ D_f`.
pub fn heat_balance(eta: f64) -> Result<(f64, f64), RunError> {
    let scene = launch_with_heat(
        &format!("coupling = 0\ndiffusivity = 0.1\nbottom = {{ frictional_heating = {eta:?} }}"),
        &[],
    );
    let (records, _) = run(&scene)?;
    let heat = |r: &StepRecord| r.heat.expect("a temperature");
    let largest = (records.iter())
        .map(|r| heat(r).heat_content.abs())
        .fold(0.0, f64::max);
    let (mut before, mut worst, mut total) = (0.0, 0.0f64, 0.0);
    for r in &records {
        let h = heat(r);
        worst = worst.max((h.heat_content - before - h.frictional_heating).abs() / largest);
        before = h.heat_content;
        total += r.friction_dissipation;
    }
    Ok((worst, total))
}

/// The launch, insulated (`κ = 1`), run to `t = 8`: the worst relative deviation of θ from the
/// uniform `Σ D_f / (W H)`, and whether the block has stopped.
pub fn uniform_end() -> Result<(f64, bool), RunError> {
    let scene = launch_with_heat("coupling = 0\ndiffusivity = 1.0", &["time.end=8"]);
    let (records, sim) = run(&scene)?;
    let work: f64 = records.iter().map(|r| r.friction_dissipation).sum();
    let expected = work / (scene.plane.width * scene.plane.height);
    let worst = (0..sim.body().nodes())
        .map(|node| (theta(&sim, node) - expected).abs() / expected)
        .fold(0.0, f64::max);
    let stopped = records.last().is_some_and(|r| r.slip_nodes == 0);
    Ok((worst, stopped))
}

/// The belt's friction coefficient, speed and the diffusivity.
pub const BELT: (f64, f64, f64) = (0.5, 1.0, 1.0);

/// A block (1 × 0.5, `ρ g = 1`) on a belt moving at `−v` under it, dragged against a
/// frictionless wall at its left edge, its top held at θ = 0.
pub fn belt_scene() -> PlaneScene {
    let (mu, v, kappa) = BELT;
    let text = format!(
        r#"
[plane]
width = 1.0
height = 0.5
lambda = 100.0
mu = 100.0
viscosity = 0.05

[edges]
left = {{ condition = "signorini", gap = 0 }}
bottom = {{ condition = "signorini", gap = 0, friction = {mu}, velocity = "-{v}" }}

[load]
density = ["0", "-1"]

[mesh]
nx = 8
ny = 4

[time]
step = 0.01
end = 6.0

[heat]
coupling = 0
diffusivity = {kappa}
top = {{ condition = "temperature", value = 0 }}
"#
    );
    PlaneScene::from_toml(&text, &[]).expect("a valid scene")
}

/// The belt at its end: `p` (the frictional nodes' mean pressure, `|Σ r_T| / (μ W)`), the
/// relative deviation of the frictional heat flux from `μ p v`, of the bottom's edge-mean
/// temperature from `flux H / κ`, and whether a frictional node sticks.
pub fn belt() -> Result<[f64; 4], RunError> {
    let (mu, v, kappa) = BELT;
    let scene = belt_scene();
    let (records, sim) = run(&scene)?;
    let last = records.last().expect("a step");
    let (w, h, dt) = (scene.plane.width, scene.plane.height, scene.time.step);
    let flux = last.heat.expect("a temperature").frictional_heating / dt / w;
    let tangential: f64 = last
        .contact
        .groups
        .iter()
        .map(|g| g.tangential_reaction)
        .sum();
    let p = tangential.abs() / (mu * w);
    let [nx, _] = sim.body().lattice();
    let hx = w / (nx - 1) as f64;
    let mean: f64 = (0..nx)
        .map(|i| {
            let weight = if i == 0 || i == nx - 1 { hx / 2.0 } else { hx };
            weight * theta(&sim, i) / w
        })
        .sum();
    let expected = flux * h / kappa;
    Ok([
        p,
        (flux - mu * p * v).abs() / (mu * p * v),
        (mean - expected).abs() / expected,
        last.stick_nodes as f64,
    ])
}

/// The manufactured solution's levels `(cells per side, Δt)`.
pub const MANUFACTURED_LEVELS: [(u64, f64); 3] = [(4, 0.04), (8, 0.02), (16, 0.01)];

/// `θ = (1 + t) sin πx sin πy` on the unit square, held at 0 on every edge, with its source:
/// the nodal error at the last half step, per level of [`MANUFACTURED_LEVELS`].
pub fn manufactured_errors() -> Result<Vec<f64>, RunError> {
    let kappa = 0.5;
    let mut errors = Vec::new();
    for (n, dt) in MANUFACTURED_LEVELS {
        let text = format!(
            r#"
[plane]
width = 1.0
height = 1.0
lambda = 1.0
mu = 1.0

[mesh]
nx = {n}
ny = {n}

[time]
step = {dt}
end = 0.4

[heat]
coupling = 0
diffusivity = {kappa}
temperature = "sin(pi*x)*sin(pi*y)"
source = "sin(pi*x)*sin(pi*y)*(1 + 2*pi*pi*{kappa}*(1 + t))"
left = {{ condition = "temperature", value = 0 }}
right = {{ condition = "temperature", value = 0 }}
bottom = {{ condition = "temperature", value = 0 }}
top = {{ condition = "temperature", value = 0 }}
"#
        );
        let scene = PlaneScene::from_toml(&text, &[]).expect("a valid scene");
        let (_, sim) = run(&scene)?;
        // The state at t_N holds θ^{N−1/2}.
        let t = 0.4 - dt / 2.0;
        let pi = std::f64::consts::PI;
        let error = (0..sim.body().nodes())
            .map(|node| {
                let (x, y) = sim.body().point(node);
                let exact = (1.0 + t) * (pi * x).sin() * (pi * y.unwrap_or(0.0)).sin();
                (theta(&sim, node) - exact).abs()
            })
            .fold(0.0, f64::max);
        errors.push(error);
    }
    Ok(errors)
}

/// The coupled manufactured solution's levels `(cells along x, Δt)` (`nx × nx/2` cells graded
/// by 1.5, to [`COUPLED_END`]).
pub const COUPLED_LEVELS: [(u64, f64); 3] = [(32, 0.0125), (64, 0.00625), (128, 0.003125)];
/// End time of the coupled manufactured runs.
pub const COUPLED_END: f64 = 0.5;

/// [`viscobar::plane::closed_form::Coupled`] (`γ = 0.8`): the nodal errors of `u` at `t_N`
/// and of `θ` at `t_N − Δt/2`, per level of [`COUPLED_LEVELS`].
pub fn coupled_manufactured_errors() -> Result<Vec<(f64, f64)>, RunError> {
    let c = viscobar::plane::closed_form::Coupled::default();
    let mut errors = Vec::new();
    for (nx, dt) in COUPLED_LEVELS {
        let scene = c.scene(nx, nx / 2, 1.5, dt, COUPLED_END);
        let (_, sim) = run(&scene)?;
        let t = sim.time();
        let d = sim.discretisation();
        let u_error = (d.free.iter().zip(sim.displacement()))
            .map(|(&dof, u)| {
                let (x, y) = d.grid.point(dof / 2);
                (u - c.mechanics.displacement(x, y, t)[dof % 2]).abs()
            })
            .fold(0.0, f64::max);
        let theta_error = (0..d.grid.nodes())
            .map(|node| {
                let (x, y) = d.grid.point(node);
                (theta(&sim, node) - c.temperature(x, y, t - dt / 2.0)).abs()
            })
            .fold(0.0, f64::max);
        errors.push((u_error, theta_error));
    }
    Ok(errors)
}

/// The launch with a coupled temperature (`γ = coupling`, `κ = 0.2`, `θ^0 = 1 + y`), every step
/// measured.
pub fn coupled_launch(coupling: f64) -> PlaneScene {
    launch_with_heat(
        &format!("coupling = {coupling:?}\ndiffusivity = 0.2\ntemperature = \"1 + y\""),
        &["output.diagnostics_every=1"],
    )
}

/// The coupled launch's (`γ = 0.5`) worst identity residual over its steps and the bound.
pub fn coupled_launch_identity() -> Result<(f64, f64), RunError> {
    let (records, _) = run(&coupled_launch(0.5))?;
    Ok(records[1..].iter().fold((0.0f64, 0.0f64), |(r, b), rec| {
        (r.max(rec.identity_residual), b.max(rec.identity_bound))
    }))
}

/// The thermal bar of the strip comparison: clamped at both ends, `α = 1`, `θ^0 = 0`, the right
/// end's temperature ramped to 1 by `t = 0.05` (smooth data: Crank–Nicolson from the start, and
/// no thermal stress in the Taylor step), `γ = 0.5`.
pub const STRIP_BAR: &str = r#"
[bar]
length = 1.0
viscosity = 1.0

[left]
condition = "clamped"

[right]
condition = "clamped"

[heat]
coupling = 0.5
diffusivity = 0.5
temperature = "0"
right = { condition = "temperature", value = "min(1, 20*t)" }

[mesh]
elements = 40

[time]
step = 0.01
end = 1.5
"#;

/// [`STRIP_BAR`] as a plane strip: one row of cells of height `H = 0.1`, `λ = 0`, `μ = ½`,
/// `ρ = 1`, between frictionless obstacles below and above at gap 0. While `θ >= 0` the thermal
/// stress `−γθ` presses both edges onto their obstacles, `u_y = 0`, and every plane equation of
/// `u_x` and `θ`, uniform in `y`, is the bar's times `H` (a thermal stress at the start would
/// push the Taylor step through the obstacles, and its projection mixes `u_x` and `u_y`).
pub const STRIP_PLANE: &str = r#"
[plane]
width = 1.0
height = 0.1
lambda = 0.0
mu = 0.5
viscosity = 1.0

[edges]
left = { condition = "clamped" }
right = { condition = "clamped" }
bottom = { condition = "signorini", gap = 0 }
top = { condition = "signorini", gap = 0 }

[mesh]
nx = 40
ny = 1

[time]
step = 0.01
end = 1.5

[heat]
coupling = 0.5
diffusivity = 0.5
temperature = "0"
right = { condition = "temperature", value = "min(1, 20*t)" }
"#;

/// The coupled strip against the thermal bar, step by step: the largest difference of `u_x`
/// (bottom and top nodes) from the bar's `u` and of `θ` from the bar's, each relative to its
/// field's largest value over the run; and the least `θ` seen (it must stay positive for the
/// strip's edges to stay in contact).
pub fn coupled_strip_against_bar() -> Result<(f64, f64, f64), RunError> {
    use viscobar::thermal::ThermalSimulation;
    let bar_scene = viscobar::Scene::from_toml(STRIP_BAR, &[])?;
    let plane_scene = PlaneScene::from_toml(STRIP_PLANE, &[])?;
    let mut bar = ThermalSimulation::new(&bar_scene)?;
    let mut plane = PlaneSimulation::new(&plane_scene)?;
    let (mut du, mut dt, mut u_scale, mut t_scale) = (0.0f64, 0.0f64, 0.0f64, 0.0f64);
    let mut least = f64::INFINITY;
    for step in 1..bar_scene.steps() {
        if step > 1 {
            bar.step()?;
            plane.step()?;
        }
        let (b, p) = (bar.body(), plane.body());
        let [nx, _] = p.lattice();
        for i in 0..nx {
            let ub = b.unknown_of(i).map_or(0.0, |k| bar.displacement()[k]);
            let tb = b.temperature(bar.displacement(), i).expect("a temperature");
            u_scale = u_scale.max(ub.abs());
            t_scale = t_scale.max(tb.abs());
            least = least.min(tb);
            for node in [i, i + nx] {
                let up = p
                    .unknown_of(2 * node)
                    .map_or(0.0, |k| plane.displacement()[k]);
                du = du.max((up - ub).abs());
                dt = dt.max((theta(&plane, node) - tb).abs());
            }
        }
    }
    Ok((du / u_scale, dt / t_scale, least))
}

/// The built-in `plane-brake` (`η < 1` at its floor) over every step: the largest
/// `|Σ (1 − η) d − (1 − η)/η Σ η d|` (heat to the belt against the body's share) and the
/// largest excess of the heat content over the frictional heating so far (the top, held at 0,
/// only lets heat out), each relative to the largest frictional heating so far.
pub fn brake_heat_sums() -> Result<(f64, f64), RunError> {
    let text = viscobar::scene::plane_builtin_text("plane-brake").expect("a built-in scene");
    let scene = PlaneScene::from_toml(text, &[])?;
    let eta = (scene.heat.as_ref())
        .and_then(|h| h.bottom.frictional_heating)
        .expect("the brake's floor has its share η");
    let (records, _) = run(&scene)?;
    let (mut heating, mut to_obstacle) = (0.0, 0.0);
    let (mut share, mut excess, mut largest) = (0.0f64, 0.0f64, 0.0f64);
    for r in &records {
        let h = r.heat.expect("a temperature");
        heating += h.frictional_heating;
        to_obstacle += h.obstacle_heating;
        largest = largest.max(heating);
        share = share.max((to_obstacle - (1.0 - eta) / eta * heating).abs());
        excess = excess.max(h.heat_content - heating);
    }
    Ok((share / largest, excess / largest))
}

/// The observed orders between successive levels.
pub fn orders(errors: &[f64]) -> Vec<f64> {
    errors.windows(2).map(|p| (p[0] / p[1]).log2()).collect()
}

/// A block resting on a floor that takes its heat (`κ = 1`, `h = 2`, `H = 0.5`, `θ^0 = 1`):
/// the decay rate of its heat content between `t = 0.6` and `t = 1` against `κμ²`,
/// `μ tan μH = h/κ` (bisection), relative; and whether every step gave heat to the floor.
pub fn exchange_decay() -> Result<(f64, bool), RunError> {
    let (kappa, h, height) = (1.0, 2.0, 0.5);
    let text = format!(
        r#"
[plane]
width = 0.25
height = {height}
lambda = 100.0
mu = 100.0
viscosity = 0.5

[edges]
bottom = {{ condition = "signorini", gap = 0 }}

[load]
density = ["0", "-1"]

[mesh]
nx = 2
ny = 32

[time]
step = 0.005
end = 1.0

[heat]
coupling = 0
diffusivity = {kappa}
temperature = "1"
bottom = {{ condition = "exchange", coefficient = {h}, obstacle = "0" }}
"#
    );
    let scene = PlaneScene::from_toml(&text, &[]).expect("a valid scene");
    let (records, _) = run(&scene)?;
    let f = |m: f64| m * (m * height).tan() - h / kappa;
    let (mut a, mut b) = (1e-9, std::f64::consts::PI / (2.0 * height) - 1e-9);
    for _ in 0..200 {
        let m = 0.5 * (a + b);
        if f(m) < 0.0 {
            a = m;
        } else {
            b = m;
        }
    }
    let mu = 0.5 * (a + b);
    assert!(f(mu).abs() < 1e-9, "the bisection found the root");
    let rate = kappa * mu * mu;
    let content = |t: f64| {
        (records.iter())
            .find(|r| (r.time - t).abs() < 1e-9)
            .map_or(f64::NAN, |r| r.heat.expect("a temperature").heat_content)
    };
    let observed = (content(0.6) / content(1.0)).ln() / 0.4;
    let exchanging = (records.iter().skip(1)).all(|r| r.heat.is_some_and(|h| h.exchange > 0.0));
    Ok(((observed - rate).abs() / rate, exchanging))
}

/// A strip 1 × 0.1 of 50 × 5 square cells at rest, `Δt = 0.04` to `t = 1`, with `[heat]` of
/// diffusivity `kappa` and the further lines `heat` (`κΔt/h² = 100 κ`).
fn strip(kappa: f64, heat: &str) -> PlaneScene {
    let text = format!(
        "[plane]\nwidth = 1.0\nheight = 0.1\nlambda = 1.0\nmu = 1.0\n\n[mesh]\nnx = 50\nny = 5\n\n\
         [time]\nstep = 0.04\nend = 1.0\n\n[heat]\ncoupling = 0\ndiffusivity = {kappa}\n{heat}\n"
    );
    PlaneScene::from_toml(&text, &[]).expect("a valid scene")
}

/// The diffusivities of the sudden edge temperature: `κΔt/h²` = 0.5, 5 and 100.
pub const SUDDEN_DIFFUSIVITIES: [f64; 3] = [0.005, 0.05, 1.0];

/// An edge held at 1 from `t = 0` on a body at 0 (square cells, `Δt = 0.04`): the largest
/// excursion of θ outside [0, 1] over every node and step, for each of
/// [`SUDDEN_DIFFUSIVITIES`].
pub fn sudden_edge_excursion() -> Result<f64, RunError> {
    let mut worst = 0.0f64;
    for kappa in SUDDEN_DIFFUSIVITIES {
        let scene = strip(
            kappa,
            "left = { condition = \"temperature\", value = \"1\" }",
        );
        let mut sim = PlaneSimulation::new(&scene)?;
        for _ in 1..scene.steps() {
            sim.step()?;
            for node in 0..sim.body().nodes() {
                let t = theta(&sim, node);
                worst = worst.max(-t).max(t - 1.0);
            }
        }
    }
    Ok(worst)
}

/// VERIFICATION.md's table of the plane body's temperature.
pub fn markdown() -> Result<String, RunError> {
    let (balance_one, work) = heat_balance(1.0)?;
    let (balance_quarter, _) = heat_balance(0.25)?;
    let (uniform, stopped) = uniform_end()?;
    let [p, flux, mean, sticking] = belt()?;
    let errors = manufactured_errors()?;
    let heat_orders = orders(&errors);
    let (decay, _) = exchange_decay()?;
    let excursion = sudden_edge_excursion()?;
    let coupled = coupled_manufactured_errors()?;
    let (coupled_u, coupled_theta): (Vec<f64>, Vec<f64>) = coupled.iter().copied().unzip();
    let (residual, bound) = coupled_launch_identity()?;
    let (strip_u, strip_theta, _) = coupled_strip_against_bar()?;
    let mut s = String::new();
    let _ = writeln!(s, "| check | measured |\n|---|---|");
    let _ = writeln!(
        s,
        "| launch (`η = 1`, `η = ¼`): worst `|Δ(1ᵀMθ) − Σ q|` per step / largest heat content | {balance_one:.1e}, {balance_quarter:.1e} (Σ D_f = {work:.4e}) |"
    );
    let _ = writeln!(
        s,
        "| launch to `t = 8`, insulated: worst relative deviation from `Σ D_f / (W H)` (block stopped: {stopped}) | {uniform:.1e} |"
    );
    let _ = writeln!(
        s,
        "| belt: `p` of the frictional nodes; flux against `μ p v`; edge-mean bottom θ against `flux H / κ` (relative; sticking nodes {sticking}) | p = {p:.6}; {flux:.1e}; {mean:.1e} |"
    );
    let levels: Vec<String> = (MANUFACTURED_LEVELS.iter().zip(&errors))
        .map(|((n, dt), e)| format!("{n} × {n}, Δt = {dt}: {e:.3e}"))
        .collect();
    let heat_orders: Vec<String> = heat_orders.iter().map(|o| format!("{o:.2}")).collect();
    let _ = writeln!(
        s,
        "| manufactured θ: nodal error per level; observed orders | {}; {} |",
        levels.join(", "),
        heat_orders.join(", ")
    );
    let _ = writeln!(
        s,
        "| exchanging floor: decay rate against `κμ²`, relative | {decay:.1e} |"
    );
    let _ = writeln!(
        s,
        "| sudden edge temperature, `κΔt/h²` = 0.5, 5, 100: largest excursion outside [0, 1] | {excursion:.1e} |"
    );
    let levels: Vec<String> = (COUPLED_LEVELS.iter().zip(&coupled))
        .map(|((n, dt), (u, t))| format!("{n} × {}, Δt = {dt}: {u:.3e}, {t:.3e}", n / 2))
        .collect();
    let show = |o: Vec<f64>| {
        o.iter()
            .map(|o| format!("{o:.2}"))
            .collect::<Vec<_>>()
            .join(", ")
    };
    let _ = writeln!(
        s,
        "| coupled manufactured (`γ = 0.8`): nodal errors of `u` and `θ` per level; observed orders in `u`; in `θ` | {}; {}; {} |",
        levels.join("; "),
        show(orders(&coupled_u)),
        show(orders(&coupled_theta))
    );
    let _ = writeln!(
        s,
        "| coupled launch (`γ = 0.5`, Lemke through the coupled system): worst identity residual per step (bound) | {residual:.1e} ({bound:.1e}) |"
    );
    let _ = writeln!(
        s,
        "| coupled strip (one row of cells, `λ = 0`, `μ = ½`, held in `y` by its obstacles) against the thermal bar: largest difference of `u`, of `θ`, over every node and step, relative | {strip_u:.1e}, {strip_theta:.1e} |"
    );
    Ok(s)
}

/// A body at 0 left of `x = 0.503` and 1 right of it (a jump inside a cell), insulated,
/// `κΔt/h² = 100`: the largest decrease of `θ` from a node to the next along `x`, over every
/// row and step (the exact solution stays nondecreasing in `x`).
pub fn initial_jump_monotonicity() -> Result<f64, RunError> {
    let scene = strip(1.0, "temperature = \"x > 0.503\"");
    let mut sim = PlaneSimulation::new(&scene)?;
    let [nx, ny] = sim.body().lattice();
    let mut worst = 0.0f64;
    for _ in 1..scene.steps() {
        sim.step()?;
        for j in 0..ny {
            for i in 1..nx {
                let (a, b) = (theta(&sim, j * nx + i - 1), theta(&sim, j * nx + i));
                worst = worst.max(a - b);
            }
        }
    }
    Ok(worst)
}
