//! Rannacher's start of the heat step (`docs/thermal.md`, "Non-smooth data: Rannacher's
//! start"): a sudden end temperature, at `t = 0` or midway, keeps `θ` within the data's range
//! (a discrete maximum principle, up to a measured bound) at every step; the implicit steps'
//! numerical dissipation is its own term of the exact identity, `>= 0`, and 0 on the
//! Crank–Nicolson steps; an exchange end's temperature decays at the analytic slowest rate.

use viscobar::Scene;
use viscobar::scene;
use viscobar::scheme::Body;
use viscobar::thermal::ThermalSimulation;

/// How far `θ` may leave the data's range `[0, 1]`: the runs below measure no excursion at
/// all (0 above 1, 0 below 0, at every node and step), so the bound is round-off on values of
/// order 1. Crank–Nicolson from the start left it by 0.648 (`heated-expansion`, x = 0.995).
const MAX_PRINCIPLE_TOL: f64 = 1e-12;

/// The measured rate's relative distance to the analytic slowest rate: the discretisation
/// errs by about `(μ Δx)²/12 + (λ Δt)²/12`, below 1e-4 here; a ringing mode left by the start
/// (Crank–Nicolson from `t = 0`) makes the decay look several times slower.
const DECAY_RATE_TOL: f64 = 1e-3;

/// `θ` at every node of the run's state.
fn temperatures(sim: &ThermalSimulation) -> Vec<f64> {
    let body = sim.body();
    (0..body.nodes())
        .map(|k| body.temperature(sim.displacement(), k).unwrap())
        .collect()
}

/// Steps `scene` to its end; returns how far `θ` left `[0, 1]` at any node and step (above,
/// below), checking every measured identity and the smoothing term's sign on the way, and
/// the steps whose heat step was implicit.
fn excursions(scene: &Scene) -> ([f64; 2], Vec<usize>) {
    let mut sim = ThermalSimulation::new(scene).unwrap();
    let (mut above, mut below) = (0.0f64, 0.0f64);
    let mut implicit = Vec::new();
    for _ in 1..scene.steps() {
        let record = sim.step().unwrap();
        let heat = record.heat.unwrap();
        assert!(heat.smoothing >= 0.0, "step {}: {heat:?}", record.step);
        assert!(
            record.identity_residual <= record.identity_bound,
            "step {}: {} > {}",
            record.step,
            record.identity_residual,
            record.identity_bound
        );
        if sim.body().implicit_step() {
            implicit.push(record.step);
        } else {
            assert_eq!(heat.smoothing, 0.0, "step {}", record.step);
        }
        for theta in temperatures(&sim) {
            above = above.max(theta - 1.0);
            below = below.max(-theta);
        }
    }
    ([above, below], implicit)
}

/// `heated-expansion` at every step (its end raised from 0 to 1 at `t = 0`, `κΔt/Δx² = 100`)
/// stays within `[0, 1]`; so does a bar without coupling whose end temperature is switched on
/// at `t = 0` and off again at `t = 0.5` (a jump within a step, recognised there), over a range
/// of `κΔt/Δx²`.
#[test]
fn a_sudden_end_temperature_keeps_theta_within_the_datas_range() {
    let (_, expansion) = scene::load("heated-expansion", &[]).unwrap();
    let ([above, below], implicit) = excursions(&expansion);
    eprintln!("heated-expansion: above {above:e}, below {below:e}, implicit {implicit:?}");
    assert!(above <= MAX_PRINCIPLE_TOL && below <= MAX_PRINCIPLE_TOL);
    // The start-up and the next two steps (records 1, 2, 3) are implicit, and no other.
    assert_eq!(implicit, vec![2, 3]);
    for diffusivity in [0.01, 0.1, 1.0, 2.0] {
        let text = format!(
            "[bar]\nlength = 1.0\nviscosity = 0.1\n[left]\ncondition = \"clamped\"\n\
             [right]\ncondition = \"clamped\"\n[initial]\ndisplacement = \"0\"\n\
             velocity = \"0\"\n[heat]\ncoupling = 0.0\ndiffusivity = {diffusivity}\n\
             temperature = \"0\"\nleft = {{ condition = \"insulated\" }}\n\
             right = {{ condition = \"temperature\", value = \"1 - (t >= 0.5)\" }}\n\
             [mesh]\nelements = 100\n[time]\nstep = 0.005\nend = 1.0\n"
        );
        let scene = Scene::from_toml(&text, &[]).unwrap();
        let ([above, below], implicit) = excursions(&scene);
        eprintln!("κ = {diffusivity}: above {above:e}, below {below:e}, implicit {implicit:?}");
        assert!(
            above <= MAX_PRINCIPLE_TOL && below <= MAX_PRINCIPLE_TOL,
            "κ = {diffusivity}: above {above:e}, below {below:e}"
        );
        // The jump at t = 0.5 = t_{100}: within the step from t_{99.5} to t_{100.5}, step 100
        // (record 101), and the next.
        assert_eq!(implicit, vec![2, 3, 101, 102], "κ = {diffusivity}");
    }
}

/// The slowest rate of `θ_t = κ θ_xx` on `[0, 1]`, insulated at 1, exchanging at 0
/// (`κ θ_x = h θ`): `κ μ²`, `μ tan μ = h/κ` on `(0, π/2)`, by bisection.
fn slowest_exchange_rate(kappa: f64, h: f64) -> f64 {
    let f = |m: f64| m * m.tan() - h / kappa;
    let (mut a, mut b) = (1e-9, std::f64::consts::FRAC_PI_2 - 1e-12);
    for _ in 0..200 {
        let m = 0.5 * (a + b);
        if f(m) > 0.0 { b = m } else { a = m }
    }
    let mu = 0.5 * (a + b);
    assert!(
        f(mu).abs() <= 1e-9 * h / kappa,
        "the root solves its equation"
    );
    kappa * mu * mu
}

/// A bar at rest on its obstacle (gap 0: in contact throughout), at temperature 1, the
/// obstacle at 0, exchanging through `h = 8` (`κ = 2`, `κΔt/Δx² = 100`): the largest `|θ|`
/// decays between `t = 4` and `t = 5` at the analytic slowest rate.
#[test]
fn an_exchange_end_decays_at_the_slowest_rate() {
    let (kappa, h) = (2.0, 8.0);
    let text = format!(
        "[bar]\nlength = 1.0\nviscosity = 0.1\n[left]\ncondition = \"signorini\"\ngap = 0.0\n\
         [right]\ncondition = \"clamped\"\n[initial]\ndisplacement = \"0\"\nvelocity = \"0\"\n\
         [heat]\ncoupling = 0.0\ndiffusivity = {kappa}\ntemperature = \"1\"\n\
         left = {{ condition = \"exchange\", coefficient = {h}, obstacle = \"0\" }}\n\
         right = {{ condition = \"insulated\" }}\n\
         [mesh]\nelements = 100\n[time]\nstep = 0.005\nend = 5.0\n"
    );
    let scene = Scene::from_toml(&text, &[]).unwrap();
    let mut sim = ThermalSimulation::new(&scene).unwrap();
    let largest = |sim: &ThermalSimulation| {
        temperatures(sim)
            .into_iter()
            .map(f64::abs)
            .fold(0.0, f64::max)
    };
    let mut at_four = None;
    for step in 1..scene.steps() {
        sim.step().unwrap();
        if step + 1 == 800 {
            at_four = Some(largest(&sim));
        }
    }
    let rate = (at_four.unwrap() / largest(&sim)).ln() / 1.0;
    let exact = slowest_exchange_rate(kappa, h);
    eprintln!("measured decay rate {rate}, analytic {exact}");
    assert!(
        (rate - exact).abs() <= DECAY_RATE_TOL * exact,
        "rate {rate} against {exact}"
    );
}
