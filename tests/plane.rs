//! The plane body (issue 20): the energy identity at every step, the bar as an exact special
//! case, and the observed order of the manufactured solution. Run in release (the sparse
//! factorisation is ~150x slower in debug).

use viscobar::Scene;
use viscobar::plane::PlaneSimulation;
use viscobar::plane::closed_form::Manufactured;
use viscobar::plane::run::run_plane_in_memory;
use viscobar::scene::plane::{
    Body, EdgeCondition, EdgeSpec, Edges, PLANE_BUILTIN, PlaneInitial, PlaneLoad, PlaneMesh,
    PlaneOutput, PlaneScene, Vector,
};
use viscobar::scene::{Condition, load_any};

/// The bar's `IDENTITY_TOL` (tests/energy_and_contact.rs): the identity is exact algebra, only
/// round-off remains, relative to the largest of its terms.
const IDENTITY_TOL: f64 = 1e-12;
/// The bar as a special case: the two schemes are the same equations (each plane x-equation
/// is the bar's times `∫ψ_j dy`), solved by different factorisations: round-off only.
const BAR_CASE_TOL: f64 = 1e-12;
/// Observed order of the manufactured solution: 2 (Q1 in L2, the scheme in time) ± this.
const ORDER_TOL: f64 = 0.15;

fn plane_scene(name: &str) -> PlaneScene {
    match load_any(name, &[]).unwrap().1 {
        viscobar::scene::AnyScene::Plane(s) => *s,
        viscobar::scene::AnyScene::Bar(_) => panic!("{name} is a bar scene"),
    }
}

#[test]
fn energy_identity_holds_at_every_step_of_every_builtin_plane_scene_and_the_manufactured_one() {
    let mut scenes: Vec<(String, PlaneScene)> = PLANE_BUILTIN
        .iter()
        .map(|(n, _)| (n.to_string(), plane_scene(n)))
        .collect();
    // Forced, viscous, λ ≠ 0, clamped, graded: every term of the identity is non-zero.
    scenes.push((
        "manufactured".into(),
        Manufactured::default().scene(16, 8, 3.0, 0.0625, 1.0),
    ));
    for (name, scene) in &scenes {
        let (records, summary, _) = run_plane_in_memory(name, scene).unwrap();
        assert_eq!(records.len(), scene.steps());
        for r in &records[1..] {
            assert!(
                r.identity_residual <= IDENTITY_TOL,
                "{name} step {}: {:e}",
                r.step,
                r.identity_residual
            );
        }
        assert!(summary.max_identity_residual <= IDENTITY_TOL);
        // Without load the energy never rises (viscous term ≥ 0), with it the work is seen.
        if scene.load.density.is_none() || name == "plane-strip" {
            assert!(summary.max_energy_rise.unwrap() <= 1e-13, "{name}");
        } else {
            assert!(records.iter().any(|r| r.work != 0.0), "{name}");
        }
        if scene.plane.viscosity > 0.0 {
            assert!(
                records[1..].iter().all(|r| r.viscous_dissipation > 0.0),
                "{name}"
            );
        }
    }
}

/// The plane scene of a bar scene: `λ = 0`, `μ = ½`, `ρ = 1`, data `(f, 0)`, the bar's end
/// conditions on the left and right edges, free top and bottom, `ny` rows graded by `grading`.
fn plane_of_bar(bar: &Scene, height: f64, ny: u64, grading: f64) -> PlaneScene {
    let edge = |c: Condition| EdgeSpec {
        condition: match c {
            Condition::Free => EdgeCondition::Free,
            Condition::Clamped => EdgeCondition::Clamped,
            Condition::Signorini => panic!("no contact on the plane yet"),
        },
    };
    let free = EdgeSpec::default();
    let pair = |s: &str| Vector([s.to_string(), "0".into()]);
    PlaneScene {
        description: None,
        plane: Body {
            width: bar.bar.length,
            height,
            lambda: 0.0,
            mu: 0.5,
            density: 1.0,
            viscosity: bar.bar.viscosity,
        },
        edges: Edges {
            left: edge(bar.left.condition),
            right: edge(bar.right.condition),
            bottom: free,
            top: free,
        },
        initial: PlaneInitial {
            displacement: pair(&bar.initial.displacement),
            velocity: pair(&bar.initial.velocity),
        },
        load: PlaneLoad {
            density: bar.load.density.as_deref().map(pair),
        },
        mesh: PlaneMesh {
            nx: bar.mesh.elements,
            ny,
            y_grading: grading,
        },
        time: bar.time.clone(),
        output: PlaneOutput::default(),
    }
}

/// A clamped–free bar, viscous, under a load varying in x and t.
const CLAMPED_BAR: &str = r#"
[bar]
length = 1.5
viscosity = 0.02
[left]
condition = "clamped"
[right]
condition = "free"
[initial]
displacement = "0.1*sin(pi*x/3)"
velocity = "0.05*x"
[load]
density = "sin(3*t)*(1 + x)"
[mesh]
elements = 48
[time]
step = 0.02
end = 3.0
"#;

/// Max over steps of `max |ux(x_i, y_j) − u_i|` and `max |uy|`, and `max |u|` of the bar.
fn bar_case_deviation(bar: &Scene) -> (f64, f64, f64) {
    let plane = plane_of_bar(bar, 0.3, 3, 4.0);
    let mut b = viscobar::Simulation::new(bar).unwrap();
    let mut p = PlaneSimulation::new(&plane).unwrap();
    let grid = p.discretisation().grid.clone();
    let (mut dev_x, mut dev_y, mut scale) = (0.0f64, 0.0f64, 0.0f64);
    let mut compare = |b: &viscobar::Simulation, p: &PlaneSimulation| {
        let (ub, up) = (b.displacement(), p.displacement());
        assert_eq!(ub.len(), grid.nx + 1);
        for node in 0..grid.nodes() {
            let (i, _) = grid.position(node);
            dev_x = dev_x.max((up[2 * node] - ub[i]).abs());
            dev_y = dev_y.max(up[2 * node + 1].abs());
        }
        scale = scale.max(ub.iter().fold(0.0f64, |a, v| a.max(v.abs())));
    };
    compare(&b, &p);
    for _ in 1..bar.steps() {
        b.step().unwrap();
        p.step().unwrap();
        compare(&b, &p);
    }
    (dev_x, dev_y, scale)
}

#[test]
fn the_bar_is_an_exact_special_case_of_the_plane_body() {
    let (_, modal) = viscobar::scene::load("modal", &[]).unwrap();
    let clamped = Scene::from_toml(CLAMPED_BAR, &[]).unwrap();
    for (name, bar) in [("modal", &modal), ("clamped", &clamped)] {
        let (dev_x, dev_y, scale) = bar_case_deviation(bar);
        assert!(scale > 0.05, "{name}: the bar moves ({scale})");
        assert!(dev_x <= BAR_CASE_TOL * scale, "{name}: ux off by {dev_x:e}");
        assert!(dev_y <= BAR_CASE_TOL * scale, "{name}: uy = {dev_y:e}");
    }
}

/// `‖u_h(T) − I_h u(T)‖_{L2} = sqrt(eᵀ M e)` of the manufactured solution with `nx × nx/2`
/// cells graded by 1.5, `Δt = h/2`, up to `T = 0.5`.
fn manufactured_error(nx: u64) -> (f64, f64) {
    let m = Manufactured::default();
    let h = m.width / nx as f64;
    let scene = m.scene(nx, nx / 2, 1.5, h / 2.0, 0.5);
    let mut sim = PlaneSimulation::new(&scene).unwrap();
    for _ in 1..scene.steps() {
        sim.step().unwrap();
    }
    let d = sim.discretisation();
    let t = sim.time();
    let e: Vec<f64> = d
        .free
        .iter()
        .zip(sim.unknowns())
        .map(|(&dof, u)| {
            let (x, y) = d.grid.point(dof / 2);
            u - m.displacement(x, y, t)[dof % 2]
        })
        .collect();
    (h, d.pattern.quad(&d.mass, &e).sqrt())
}

#[test]
fn manufactured_solution_converges_at_order_two_with_dt_proportional_to_h() {
    let levels: Vec<(f64, f64)> = [16, 32, 64, 128].map(manufactured_error).into();
    // Least-squares slope of log error against log h.
    let pts: Vec<(f64, f64)> = levels.iter().map(|(h, e)| (h.ln(), e.ln())).collect();
    let n = pts.len() as f64;
    let (mx, my) = (
        pts.iter().map(|p| p.0).sum::<f64>() / n,
        pts.iter().map(|p| p.1).sum::<f64>() / n,
    );
    let slope = pts.iter().map(|p| (p.0 - mx) * (p.1 - my)).sum::<f64>()
        / pts.iter().map(|p| (p.0 - mx).powi(2)).sum::<f64>();
    assert!(
        (slope - 2.0).abs() <= ORDER_TOL,
        "order {slope}: {levels:?}"
    );
}
