//! The per-step path allocates nothing: a counting global allocator watches `Simulation::step`
//! on every built-in scene. The count is per thread, so the test harness's own threads (which
//! may allocate while the test runs) are not counted.

mod common;

use common::alloc::allocations;

#[global_allocator]
static GLOBAL: common::alloc::Counting = common::alloc::Counting;

#[test]
fn steps_do_not_allocate() {
    // The built-in scenes, and `impact` with its obstacle approaching (moving gaps).
    let moving = ["left.gap=\"0.1 - 0.5*t\"".to_string()];
    let runs = (viscobar::scene::builtin_names()
        .into_iter()
        .map(|n| (n, &[][..])))
    .chain([("impact", &moving[..])]);
    for (name, overrides) in runs {
        let (_, scene) = viscobar::scene::load(name, overrides).unwrap();
        let mut sim = viscobar::Simulation::new(&scene).unwrap();
        sim.step().unwrap(); // warm-up outside the count
        let before = allocations();
        for _ in 0..100 {
            sim.step().unwrap();
        }
        let allocations = allocations() - before;
        assert_eq!(
            allocations, 0,
            "{name}: {allocations} allocations in 100 steps"
        );
    }
}

#[test]
fn plane_steps_do_not_allocate() {
    use viscobar::scene::plane::PLANE_BUILTIN;
    use viscobar::scene::{AnyScene, load_any};
    // The built-in plane scenes (no load, constant load, Signorini edges whose contact sets
    // grow and shrink within the counted steps) and a time-dependent load.
    let mut scenes = Vec::new();
    for (name, _) in PLANE_BUILTIN {
        let AnyScene::Plane(scene) = load_any(name, &[]).unwrap().1 else {
            panic!("{name} is a plane scene");
        };
        scenes.push((name.to_string(), *scene));
    }
    // A floor rising into the block (a moving obstacle: its gaps evaluated every step).
    let AnyScene::Plane(rising) = load_any(
        "plane-tilted-drop",
        &["edges.bottom.gap=\"0.05 - 0.3*t\"".into()],
    )
    .unwrap()
    .1
    else {
        panic!("a plane scene");
    };
    scenes.push(("rising floor".into(), *rising));
    scenes.push((
        "manufactured".into(),
        viscobar::plane::closed_form::Manufactured::default().scene(8, 4, 2.0, 0.125, 20.0),
    ));
    for (name, scene) in scenes {
        let mut sim = viscobar::plane::PlaneSimulation::new(&scene).unwrap();
        sim.step().unwrap(); // warm-up outside the count
        let before = allocations();
        let mut touched = 0;
        for _ in 0..100 {
            touched += sim.step().unwrap().contact.contact_nodes;
        }
        let allocations = allocations() - before;
        assert!(
            sim.contact().is_empty() || touched > 0,
            "{name}: the counted steps have contact"
        );
        assert_eq!(
            allocations, 0,
            "{name}: {allocations} allocations in 100 plane steps"
        );
    }
}

/// The plane body's heat steps (the frictional launch with frictional heating, a source and the
/// top held at a temperature varying in time; uncoupled, and coupled with `γ = 0.5`) allocate
/// nothing once each step's factors are made: the implicit start's, then Crank–Nicolson's at
/// the third step (coupled: with each state's step solver).
#[test]
fn plane_heat_steps_do_not_allocate() {
    for coupling in ["0", "0.5"] {
        let text = format!(
            "{}\n[heat]\ncoupling = {coupling}\ndiffusivity = 0.2\nsource = \"x*t\"\n\
             bottom = {{ frictional_heating = 0.5 }}\n\
             top = {{ condition = \"temperature\", value = \"1 + t\" }}\n",
            include_str!("../scenes/plane-friction-launch.toml")
        );
        let scene = viscobar::PlaneScene::from_toml(&text, &[]).unwrap();
        let mut sim = viscobar::plane::PlaneSimulation::new(&scene).unwrap();
        for _ in 0..3 {
            sim.step().unwrap();
        }
        let before = allocations();
        let mut heating = 0.0;
        for _ in 0..100 {
            heating += sim.step().unwrap().heat.unwrap().frictional_heating;
        }
        let allocations = allocations() - before;
        assert!(heating > 0.0, "the counted steps heat the body");
        assert_eq!(
            allocations, 0,
            "{allocations} allocations in 100 plane heat steps, coupling {coupling}"
        );
    }
}

/// The thermal bar's steps (coupled, with contact and the exchange switching on; uncoupled;
/// a source, a fixed temperature varying in time and a load) allocate nothing either.
#[test]
fn thermal_steps_do_not_allocate() {
    let mut scenes: Vec<(String, viscobar::Scene)> = Vec::new();
    for name in viscobar::scene::thermal_builtin_names() {
        let (_, scene) = viscobar::scene::load(name, &[]).unwrap();
        scenes.push((name.to_string(), scene));
    }
    for (name, sets) in [
        ("thermal-impact", &["heat.coupling=0"][..]),
        (
            "heated-expansion",
            &[
                "heat.source=\"x*sin(t)\"",
                "heat.right.value=\"1 + t\"",
                "load.density=\"cos(t)\"",
                "left.gap=0.0005",
            ][..],
        ),
    ] {
        let sets: Vec<String> = sets.iter().map(|s| s.to_string()).collect();
        let (_, scene) = viscobar::scene::load(name, &sets).unwrap();
        scenes.push((format!("{name} {sets:?}"), scene));
    }
    for (name, scene) in scenes {
        let mut sim = viscobar::thermal::ThermalSimulation::new(&scene).unwrap();
        // Warm-up outside the count, up to the first contact.
        while sim.step().unwrap().contact.contact_nodes == 0 && sim.step_index() < 1000 {}
        let before = allocations();
        let mut touched = 0;
        for _ in 0..100 {
            touched += sim.step().unwrap().contact.contact_nodes;
        }
        let allocations = allocations() - before;
        assert!(touched > 0, "{name}: the counted steps have contact");
        assert_eq!(
            allocations, 0,
            "{name}: {allocations} allocations in 100 thermal steps"
        );
    }
}
