//! The plane body's temperature (`[heat]`, γ = 0): the heat friction dissipates enters the
//! body's heat content to round-off at every step; a launched block ends at the uniform
//! temperature of its friction work; a block dragged by a belt against a wall settles to the
//! flux of kinetic friction through its bottom edge (P1 in `y` makes its edge-mean temperature
//! exact); the heat equation converges at order 2 against a manufactured solution; a
//! temperature leaves the mechanics' bits alone; bad `[heat]` keys are refused naming the key.

mod common;

use viscobar::{Body, PlaneScene, StepRecord};
use viscobar_certificate::plane_heat::{
    self, LAUNCH, belt, exchange_decay, launch_with_heat, manufactured_errors, orders,
    sudden_edge_excursion, uniform_end,
};
use viscobar_certificate::tolerances::{
    HEAT_BALANCE_TOL, PLANE_DECAY_RATE_TOL, PLANE_MAX_PRINCIPLE_TOL, PLANE_MONOTONE_TOL,
    STEADY_TEMPERATURE_TOL,
};

/// The observed orders of the manufactured solution's nodal error (Q1 nodes and
/// Crank–Nicolson both second order; VERIFICATION.md gives the measured orders).
const PLANE_HEAT_ORDER_BAND: (f64, f64) = (1.9, 2.1);

fn run(scene: &PlaneScene) -> (Vec<StepRecord>, viscobar::PlaneSimulation) {
    plane_heat::run(scene).expect("the run certifies")
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
    let (deviation, stopped) = uniform_end().unwrap();
    assert!(stopped, "the block has stopped");
    assert!(deviation <= STEADY_TEMPERATURE_TOL, "{deviation:e}");
}

/// A block (1 × 0.5, ρ g = 1) on a belt moving at `v = −1` under it, dragged against a
/// frictionless wall at its left edge, its top held at θ = 0: at rest, every frictional bottom
/// node slips at `v`, and the heat `η μ p |v|` per unit length of edge flows to the top (`p`
/// the mean contact pressure of the frictional nodes, `|Σ r_T| / (μ W)` by Coulomb's law; the
/// corner's tangent is the wall's normal, so it carries no friction). Its edge-mean
/// (trapezoidal) bottom temperature is then `η μ p |v| H / κ`, exactly.
#[test]
fn a_block_on_a_belt_settles_to_the_flux_of_kinetic_friction() {
    let [p, flux, mean, sticking] = belt().unwrap();
    assert_eq!(sticking, 0.0, "every frictional node slips");
    assert!(p > 0.4 * 0.5, "pressed by its weight: p = {p}");
    assert!(
        flux <= STEADY_TEMPERATURE_TOL,
        "flux against μ p v: {flux:e}"
    );
    assert!(
        mean <= STEADY_TEMPERATURE_TOL,
        "edge mean against flux H / κ: {mean:e}"
    );
}

/// `θ = (1 + t) sin πx sin πy` on the unit square, held at 0 on every edge, with its source
/// `q = θ_t − κ Δθ`: the nodal error at the last half step falls at order 2 as `h` and `Δt`
/// halve together.
#[test]
fn the_heat_step_converges_at_order_two() {
    let errors = manufactured_errors().unwrap();
    for order in orders(&errors) {
        let (low, high) = PLANE_HEAT_ORDER_BAND;
        assert!(
            (low..=high).contains(&order),
            "errors {errors:?}: order {order}"
        );
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
            ("coupling", &["heat.coupling=-0.5"], "heat.coupling"),
            (
                "coupled osqp",
                &["heat.coupling=0.5", "solver.method=\"osqp\""],
                "solver.method",
            ),
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

/// A block resting on a floor that takes its heat, `−κ ∂θ/∂n = h θ` while in contact
/// (insulated elsewhere, `θ^0 = 1`): uniform in `x`, its temperature is the bar's exchange
/// problem in `y`, whose slowest mode decays at `κμ²`, `μ tan μH = h/κ`; the exchange term of
/// the identity is the heat the floor takes.
#[test]
fn an_exchanging_floor_takes_the_heat_at_the_slowest_rate() {
    let (error, exchanging) = exchange_decay().unwrap();
    assert!(exchanging, "every step gives heat to the floor");
    assert!(error <= PLANE_DECAY_RATE_TOL, "decay rate off by {error:e}");
}

/// An edge held at 1 from `t = 0` on a body at 0, square cells, `κΔt/h²` = 0.5, 5 and 100 (the
/// bar's range): the implicit start keeps θ within the data's range [0, 1] at every node and
/// step. (The step resolves the body's slowest mode, `κΔt/W² <= 0.04`: Crank–Nicolson
/// alternates the sign of every mode with `κλΔt > 2`, so a step longer than the whole body's
/// diffusion time rings whatever the start.)
#[test]
fn a_sudden_edge_temperature_keeps_theta_within_the_datas_range() {
    let excursion = sudden_edge_excursion().unwrap();
    assert!(excursion <= PLANE_MAX_PRINCIPLE_TOL, "{excursion:e}");
}

/// The profile file of a plane scene with `[heat]` gains `theta`, the run's temperature at each
/// written node.
#[test]
fn the_profile_file_gains_theta() {
    let dir = common::fresh_dir("plane-heat", "profile");
    let scene = launch_with_heat(
        "coupling = 0\ndiffusivity = 0.3",
        &["output.every=300", "time.end=3"],
    );
    viscobar::output::run_plane_to_dir("profile", &scene, &dir, false).unwrap();
    let text = std::fs::read_to_string(dir.join("displacement.csv")).unwrap();
    let mut lines = text.lines();
    let header: Vec<&str> = lines.next().unwrap().split(',').collect();
    assert_eq!(header.last(), Some(&"theta"), "{header:?}");
    let (_, sim) = run(&scene);
    let body = sim.body();
    let last: Vec<&str> = text.lines().rev().take(body.nodes()).collect();
    let nodes = viscobar::internals::output::profiles::written_nodes(body.lattice(), 1);
    for (line, &node) in last.iter().rev().zip(&nodes) {
        let theta: f64 = line.rsplit(',').next().unwrap().parse().unwrap();
        let expected = body.temperature(sim.displacement(), node).unwrap();
        assert!(
            (theta - expected).abs() <= 1e-15 * expected.abs().max(1.0),
            "{theta} against {expected}"
        );
    }
    let _ = std::fs::remove_dir_all(&dir);
}

/// An initial temperature that jumps inside a cell starts implicitly: θ stays nondecreasing in
/// `x` at every step, as the exact solution does (a Crank–Nicolson start rings).
#[test]
fn an_initial_jump_starts_implicitly_and_keeps_theta_monotone() {
    let decrease = plane_heat::initial_jump_monotonicity().unwrap();
    assert!(decrease <= PLANE_MONOTONE_TOL, "{decrease:e}");
}
