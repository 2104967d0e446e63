//! The plane body's temperature (`[heat]`, γ = 0): the heat friction dissipates enters the
//! body's heat content to round-off at every step; a launched block ends at the uniform
//! temperature of its friction work; a block dragged by a belt against a wall settles to the
//! flux of kinetic friction through its bottom edge (P1 in `y` makes its edge-mean temperature
//! exact); the heat equation converges at order 2 against a manufactured solution; a
//! temperature leaves the mechanics' bits alone; bad `[heat]` keys are refused naming the key.

mod common;

use viscobar::plane::PlaneBody;
use viscobar::{Body, PlaneScene, PlaneSimulation, StepRecord, run_plane_in_memory};

/// The heat-content balance per step, relative to the largest heat content of the run: the
/// content and the step's heat are sums of a few hundred products, the solve backward stable.
const HEAT_BALANCE_TOL: f64 = 1e-13;
/// A uniform or a linear steady temperature, relative to its size: round-off of the steady
/// state the decaying modes have reached (their slowest factor is below 1e-20 at the end).
const STEADY_TEMPERATURE_TOL: f64 = 1e-10;
/// The least observed order of the manufactured solution's nodal error (Q1 nodes and
/// Crank–Nicolson both second order).
const MIN_ORDER: f64 = 1.9;

const LAUNCH: &str = include_str!("../scenes/plane-friction-launch.toml");

fn launch_with_heat(heat: &str, overrides: &[&str]) -> PlaneScene {
    let text = format!("{LAUNCH}\n[heat]\n{heat}\n");
    let overrides: Vec<String> = overrides.iter().map(|s| s.to_string()).collect();
    PlaneScene::from_toml(&text, &overrides).expect("a valid scene")
}

fn run(scene: &PlaneScene) -> (Vec<StepRecord>, PlaneSimulation) {
    let (records, _, sim) = run_plane_in_memory("plane-heat", scene).expect("the run certifies");
    (records, sim)
}

/// At every step (the start-up's half step included) the heat content `1ᵀMθ` grows by the
/// frictional heating, which is `η D_f` exactly (η = 1, and η = ¼, a power of two), and the
/// rest of `D_f` is the obstacle's.
#[test]
fn heat_content_grows_by_the_frictional_heating_at_every_step() {
    for (eta, extra) in [(1.0, ""), (0.25, "bottom = { frictional_heating = 0.25 }")] {
        let scene = launch_with_heat(&format!("coupling = 0\ndiffusivity = 0.1\n{extra}"), &[]);
        let (records, _) = run(&scene);
        let largest = (records.iter())
            .map(|r| r.heat.unwrap().heat_content.abs())
            .fold(0.0, f64::max);
        let largest_work = (records.iter())
            .map(|r| r.friction_dissipation.abs())
            .fold(0.0, f64::max);
        let mut before = 0.0;
        let mut total = 0.0;
        for r in &records {
            let h = r.heat.expect("a temperature");
            assert_eq!(
                h.frictional_heating,
                eta * r.friction_dissipation,
                "step {}",
                r.step
            );
            let rest = (h.frictional_heating + h.obstacle_heating - r.friction_dissipation).abs();
            assert!(rest <= 4.0 * f64::EPSILON * largest_work, "step {}", r.step);
            let gap = (h.heat_content - before - h.frictional_heating).abs();
            assert!(
                gap <= HEAT_BALANCE_TOL * largest,
                "step {}: {gap:e} of {largest:e}",
                r.step
            );
            before = h.heat_content;
            total += r.friction_dissipation;
        }
        assert!(total > 0.2, "the block slides: Σ D_f = {total}");
    }
}

/// Insulated, without a source, once the block has stopped and its temperature has evened
/// out: `θ = η Σ D_f / (W H)` at every node (`θ^0 = 0`; `1ᵀ M 1 = W H`).
#[test]
fn a_launched_block_ends_at_the_uniform_temperature_of_its_friction_work() {
    let scene = launch_with_heat("coupling = 0\ndiffusivity = 1.0", &["time.end=8"]);
    let (records, sim) = run(&scene);
    let work: f64 = records.iter().map(|r| r.friction_dissipation).sum();
    let (w, h) = (scene.plane.width, scene.plane.height);
    let expected = work / (w * h);
    let body: &PlaneBody = sim.body();
    for node in 0..body.nodes() {
        let theta = body.temperature(sim.displacement(), node).unwrap();
        let error = (theta - expected).abs() / expected;
        assert!(
            error <= STEADY_TEMPERATURE_TOL,
            "node {node}: {theta} against {expected}"
        );
    }
    assert_eq!(
        records.last().unwrap().slip_nodes,
        0,
        "the block has stopped"
    );
}

/// A block (1 × 0.5, ρ g = 1) on a belt moving at `v = −1` under it, dragged against a
/// frictionless wall at its left edge, its top held at θ = 0: at rest, every frictional bottom
/// node slips at `v`, and the heat `η μ p |v|` per unit length of edge flows to the top (`p`
/// the mean contact pressure of the frictional nodes, `|Σ r_T| / (μ W)` by Coulomb's law; the
/// corner's tangent is the wall's normal, so it carries no friction). Its edge-mean
/// (trapezoidal) bottom temperature is then `η μ p |v| H / κ`, exactly.
#[test]
fn a_block_on_a_belt_settles_to_the_flux_of_kinetic_friction() {
    let (mu, v, kappa) = (0.5, 1.0, 1.0);
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
    let scene = PlaneScene::from_toml(&text, &[]).unwrap();
    let (records, sim) = run(&scene);
    let last = records.last().unwrap();
    let (w, h, dt) = (scene.plane.width, scene.plane.height, scene.time.step);
    assert_eq!(last.stick_nodes, 0);
    // The heat the step's friction puts in, per unit time and length of edge: η μ p |v|.
    let flux = last.heat.unwrap().frictional_heating / dt / w;
    let tangential: f64 = last
        .contact
        .groups
        .iter()
        .map(|g| g.tangential_reaction)
        .sum();
    let p = tangential.abs() / (mu * w);
    assert!(p > 0.4 * h, "pressed by its weight: p = {p}");
    assert!(
        (flux - mu * p * v).abs() <= STEADY_TEMPERATURE_TOL * mu * p * v,
        "flux {flux} against η μ p v = {}",
        mu * p * v
    );
    let body: &PlaneBody = sim.body();
    let [nx, _] = body.lattice();
    let hx = w / (nx - 1) as f64;
    let mut mean = 0.0;
    for i in 0..nx {
        let weight = if i == 0 || i == nx - 1 { hx / 2.0 } else { hx };
        mean += weight * body.temperature(sim.displacement(), i).unwrap() / w;
    }
    let expected = flux * h / kappa;
    assert!(
        (mean - expected).abs() <= STEADY_TEMPERATURE_TOL * expected,
        "edge mean {mean} against {expected}"
    );
}

/// `θ = (1 + t) sin πx sin πy` on the unit square, held at 0 on every edge, with its source
/// `q = θ_t − κ Δθ`: the nodal error at the last half step falls at order 2 as `h` and `Δt`
/// halve together.
#[test]
fn the_heat_step_converges_at_order_two() {
    let kappa = 0.5;
    let mut errors = Vec::new();
    for (n, dt) in [(4, 0.04), (8, 0.02), (16, 0.01)] {
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
        let scene = PlaneScene::from_toml(&text, &[]).unwrap();
        let (_, sim) = run(&scene);
        // The state at t_N holds θ^{N−1/2}.
        let t = 0.4 - dt / 2.0;
        let body: &PlaneBody = sim.body();
        let pi = std::f64::consts::PI;
        let error = (0..body.nodes())
            .map(|node| {
                let (x, y) = body.point(node);
                let exact = (1.0 + t) * (pi * x).sin() * (pi * y.unwrap()).sin();
                (body.temperature(sim.displacement(), node).unwrap() - exact).abs()
            })
            .fold(0.0, f64::max);
        errors.push(error);
    }
    for pair in errors.windows(2) {
        let order = (pair[0] / pair[1]).log2();
        assert!(order >= MIN_ORDER, "errors {errors:?}: order {order}");
    }
}

/// A temperature (γ = 0) leaves the mechanics as they are, bit for bit.
#[test]
fn a_temperature_leaves_the_mechanics_bits_alone() {
    let plain = PlaneScene::from_toml(LAUNCH, &[]).unwrap();
    let heated = launch_with_heat("coupling = 0\ndiffusivity = 0.3", &[]);
    let (a, sim_a) = run(&plain);
    let (b, sim_b) = run(&heated);
    assert_eq!(sim_a.displacement(), sim_b.displacement());
    for (ra, rb) in a.iter().zip(&b) {
        assert_eq!(ra.friction_dissipation, rb.friction_dissipation);
        assert_eq!(ra.contact, rb.contact);
        assert_eq!(ra.work, rb.work);
    }
}

/// Bad `[heat]` keys on the plane: exit 2 naming the key, nothing written.
#[test]
fn bad_heat_keys_are_refused_naming_the_key() {
    let dir = common::fresh_dir("plane-heat", "refused");
    std::fs::create_dir_all(&dir).unwrap();
    let scene = dir.join("scene.toml");
    std::fs::write(
        &scene,
        format!("{LAUNCH}\n[heat]\ncoupling = 0\ndiffusivity = 0.1\n"),
    )
    .unwrap();
    let out = dir.join("out");
    common::assert_each_refused(
        scene.to_str().unwrap(),
        &[
            ("coupling", &["heat.coupling=0.5"], "heat.coupling"),
            ("diffusivity", &["heat.diffusivity=0"], "heat.diffusivity"),
            (
                "heating out of range",
                &["heat.bottom.frictional_heating=1.5"],
                "heat.bottom.frictional_heating",
            ),
            (
                "heating without friction",
                &["heat.top.frictional_heating=0.5"],
                "heat.top.frictional_heating",
            ),
            (
                "exchange on a free edge",
                &["heat.top.condition=\"exchange\"", "heat.top.coefficient=1"],
                "heat.top.condition",
            ),
            ("osqp", &["solver.method=\"osqp\""], "solver.method"),
        ],
        &out,
    );
    let _ = std::fs::remove_dir_all(&dir);
}

/// The slowest decay rate of an exchange edge, relative to the analytic one: the Q1 and
/// Crank–Nicolson errors of the slowest mode at 32 cells over the height and `Δt = 0.005`.
const DECAY_RATE_TOL: f64 = 2e-3;

/// A block resting on a floor that takes its heat, `−κ ∂θ/∂n = h θ` while in contact
/// (insulated elsewhere, `θ^0 = 1`): uniform in `x`, its temperature is the bar's exchange
/// problem in `y`, whose slowest mode decays at `κμ²`, `μ tan μH = h/κ`; the exchange term of
/// the identity is the heat the floor takes.
#[test]
fn an_exchanging_floor_takes_the_heat_at_the_slowest_rate() {
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
    let scene = PlaneScene::from_toml(&text, &[]).unwrap();
    let (records, _) = run(&scene);
    // μ tan μH = h/κ on (0, π/(2H)), by bisection.
    let f = |m: f64| m * (m * height).tan() - h / kappa;
    let (mut a, mut b) = (1e-9, std::f64::consts::PI / (2.0 * height) - 1e-9);
    for _ in 0..200 {
        let m = 0.5 * (a + b);
        if f(m) < 0.0 { a = m } else { b = m }
    }
    let mu = 0.5 * (a + b);
    assert!(f(mu).abs() < 1e-9, "the root");
    let rate = kappa * mu * mu;
    let content = |t: f64| {
        let r = records.iter().find(|r| (r.time - t).abs() < 1e-9).unwrap();
        r.heat.unwrap().heat_content
    };
    let observed = (content(0.6) / content(1.0)).ln() / 0.4;
    assert!(
        (observed - rate).abs() <= DECAY_RATE_TOL * rate,
        "decay rate {observed} against κμ² = {rate}"
    );
    assert!(
        records
            .iter()
            .skip(1)
            .all(|r| r.heat.unwrap().exchange > 0.0)
    );
}

/// An edge held at 1 from `t = 0` on a body at 0, square cells, `κΔt/h²` = 0.5, 5 and 100 (the
/// bar's range): the implicit start keeps θ within the data's range [0, 1] at every node and
/// step. (The step resolves the body's slowest mode, `κΔt/W² <= 0.04`: Crank–Nicolson
/// alternates the sign of every mode with `κλΔt > 2`, so a step longer than the whole body's
/// diffusion time rings whatever the start.)
#[test]
fn a_sudden_edge_temperature_keeps_theta_within_the_datas_range() {
    for kappa in [0.005, 0.05, 1.0] {
        let text = format!(
            r#"
[plane]
width = 1.0
height = 0.1
lambda = 1.0
mu = 1.0

[mesh]
nx = 50
ny = 5

[time]
step = 0.04
end = 1.0

[heat]
coupling = 0
diffusivity = {kappa}
left = {{ condition = "temperature", value = "1" }}
"#
        );
        let scene = PlaneScene::from_toml(&text, &[]).unwrap();
        let mut sim = PlaneSimulation::new(&scene).unwrap();
        for _ in 1..scene.steps() {
            sim.step().unwrap();
            let body: &PlaneBody = sim.body();
            for node in 0..body.nodes() {
                let theta = body.temperature(sim.displacement(), node).unwrap();
                assert!(
                    (-MAX_PRINCIPLE_TOL..=1.0 + MAX_PRINCIPLE_TOL).contains(&theta),
                    "κ = {kappa}, node {node}: θ = {theta}"
                );
            }
        }
    }
}

/// The excursion allowed outside the data's range: round-off of the steps' sums.
const MAX_PRINCIPLE_TOL: f64 = 1e-12;
