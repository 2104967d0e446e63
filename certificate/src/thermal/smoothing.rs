//! Rannacher's start of the thermal bar's heat step (`docs/thermal.md`, "Non-smooth data"):
//! how far `θ` leaves the data's range after a sudden end temperature, which steps were
//! implicit, and an exchange end's decay rate against the analytic slowest one
//! (`tests/thermal_smoothing.rs` asserts them against [`crate::tolerances`]).

use viscobar::Scene;
use viscobar::scene;
use viscobar::scheme::{Body, RunError};
use viscobar::thermal::ThermalSimulation;

/// `θ` at every node of the run's state.
fn temperatures(sim: &ThermalSimulation) -> Vec<f64> {
    let body = sim.body();
    (0..body.nodes())
        .map(|k| body.temperature(sim.displacement(), k).unwrap_or(f64::NAN))
        .collect()
}

/// A run's excursions out of `[0, 1]` and its implicit steps.
#[derive(Clone, Debug, Default)]
pub struct Excursions {
    /// How far `θ` left `[0, 1]` at any node and step: above 1, below 0.
    pub above: f64,
    pub below: f64,
    /// The records whose heat step was implicit Euler.
    pub implicit: Vec<usize>,
    /// Every smoothing term `>= 0`, 0 on every Crank–Nicolson step, and every identity within
    /// its bound.
    pub consistent: bool,
}

/// Steps `scene` to its end and measures its [`Excursions`].
pub fn excursions(scene: &Scene) -> Result<Excursions, RunError> {
    let mut sim = ThermalSimulation::new(scene)?;
    let mut e = Excursions {
        consistent: true,
        ..Default::default()
    };
    for _ in 1..scene.steps() {
        let record = sim.step()?;
        let heat = record.heat.unwrap_or_default();
        e.consistent &= heat.smoothing >= 0.0 && record.identity_residual <= record.identity_bound;
        if sim.body().implicit_step() {
            e.implicit.push(record.step);
        } else {
            e.consistent &= heat.smoothing == 0.0;
        }
        for theta in temperatures(&sim) {
            e.above = e.above.max(theta - 1.0);
            e.below = e.below.max(-theta);
        }
    }
    Ok(e)
}

/// The diffusivities of the switched end: `κΔt/Δx²` from 0.5 to 100 (100 elements, `Δt =
/// 0.005`).
pub const SWITCHED_DIFFUSIVITIES: [f64; 4] = [0.01, 0.1, 1.0, 2.0];

/// A bar without coupling whose right end temperature is switched on at `t = 0` and off at
/// `t = 0.5` (a jump within a step).
pub fn switched_end(diffusivity: f64) -> Result<Scene, RunError> {
    let text = format!(
        "[bar]\nlength = 1.0\nviscosity = 0.1\n[left]\ncondition = \"clamped\"\n\
         [right]\ncondition = \"clamped\"\n[initial]\ndisplacement = \"0\"\n\
         velocity = \"0\"\n[heat]\ncoupling = 0.0\ndiffusivity = {diffusivity}\n\
         temperature = \"0\"\nleft = {{ condition = \"insulated\" }}\n\
         right = {{ condition = \"temperature\", value = \"1 - (t >= 0.5)\" }}\n\
         [mesh]\nelements = 100\n[time]\nstep = 0.005\nend = 1.0\n"
    );
    Ok(Scene::from_toml(&text, &[])?)
}

/// The largest excursion out of `[0, 1]` over `heated-expansion` and the switched ends.
pub fn max_principle_worst() -> Result<f64, RunError> {
    let (_, expansion) = scene::load("heated-expansion", &[])?;
    let mut scenes = vec![expansion];
    for kappa in SWITCHED_DIFFUSIVITIES {
        scenes.push(switched_end(kappa)?);
    }
    let mut worst = 0.0f64;
    for s in &scenes {
        let e = excursions(s)?;
        worst = worst.max(e.above).max(e.below);
    }
    Ok(worst)
}

/// The slowest rate of `θ_t = κ θ_xx` on `[0, 1]`, insulated at 1, exchanging at 0
/// (`κ θ_x = h θ`): `κ μ²`, `μ tan μ = h/κ` on `(0, π/2)`, by bisection.
pub fn slowest_exchange_rate(kappa: f64, h: f64) -> f64 {
    let f = |m: f64| m * m.tan() - h / kappa;
    let (mut a, mut b) = (1e-9, std::f64::consts::FRAC_PI_2 - 1e-12);
    for _ in 0..200 {
        let m = 0.5 * (a + b);
        if f(m) > 0.0 {
            b = m;
        } else {
            a = m;
        }
    }
    let mu = 0.5 * (a + b);
    assert!(
        f(mu).abs() <= 1e-9 * h / kappa,
        "the root solves its equation"
    );
    kappa * mu * mu
}

/// A bar at rest on its obstacle (gap 0: in contact throughout), at temperature 1, the
/// obstacle at 0, exchanging through `h = 8` (`κ = 2`, `κΔt/Δx² = 100`): the decay rate of the
/// largest `|θ|` between `t = 4` and `t = 5`, and the analytic slowest rate.
pub fn exchange_decay_rate() -> Result<(f64, f64), RunError> {
    let (kappa, h) = (2.0, 8.0);
    let text = format!(
        "[bar]\nlength = 1.0\nviscosity = 0.1\n[left]\ncondition = \"signorini\"\ngap = 0.0\n\
         [right]\ncondition = \"clamped\"\n[initial]\ndisplacement = \"0\"\nvelocity = \"0\"\n\
         [heat]\ncoupling = 0.0\ndiffusivity = {kappa}\ntemperature = \"1\"\n\
         left = {{ condition = \"exchange\", coefficient = {h}, obstacle = \"0\" }}\n\
         right = {{ condition = \"insulated\" }}\n\
         [mesh]\nelements = 100\n[time]\nstep = 0.005\nend = 5.0\n"
    );
    let scene = Scene::from_toml(&text, &[])?;
    let mut sim = ThermalSimulation::new(&scene)?;
    let largest = |sim: &ThermalSimulation| {
        temperatures(sim)
            .into_iter()
            .map(f64::abs)
            .fold(0.0, f64::max)
    };
    let mut at_four = f64::NAN;
    for step in 1..scene.steps() {
        sim.step()?;
        if step + 1 == 800 {
            at_four = largest(&sim);
        }
    }
    let rate = (at_four / largest(&sim)).ln() / 1.0;
    Ok((rate, slowest_exchange_rate(kappa, h)))
}

/// A bar at 0 left of `x = 0.503` and 1 right of it (a jump inside an element), insulated,
/// `κΔt/Δx² = 100`: the largest decrease of `θ` from a node to the next along `x` over every
/// step (the exact solution stays nondecreasing), and the implicit steps.
pub fn initial_jump_monotonicity() -> Result<(f64, Vec<usize>), RunError> {
    let text = "[bar]\nlength = 1.0\nviscosity = 0.1\n[left]\ncondition = \"clamped\"\n\
                [right]\ncondition = \"clamped\"\n[initial]\ndisplacement = \"0\"\n\
                velocity = \"0\"\n[heat]\ncoupling = 0.0\ndiffusivity = 2.0\n\
                temperature = \"x > 0.503\"\n\
                [mesh]\nelements = 100\n[time]\nstep = 0.005\nend = 1.0\n";
    let scene = Scene::from_toml(text, &[])?;
    let mut sim = ThermalSimulation::new(&scene)?;
    let (mut worst, mut implicit) = (0.0f64, Vec::new());
    for _ in 1..scene.steps() {
        let record = sim.step()?;
        if sim.body().implicit_step() {
            implicit.push(record.step);
        }
        let theta = temperatures(&sim);
        worst = (theta.windows(2)).fold(worst, |m, w| m.max(w[0] - w[1]));
    }
    Ok((worst, implicit))
}
