//! The library used on its own, without the command line: a scene built in code is validated
//! by every public constructor, which returns the error a scene file would give.

use viscobar::bar::Discretisation;
use viscobar::scene::{Condition, EndSpec, builtin_text};
use viscobar::{RunError, Scene, SceneError, Simulation};

fn impact() -> Scene {
    Scene::from_toml(builtin_text("impact").unwrap(), &[]).unwrap()
}

/// The field a scene error names, whatever its kind.
fn field_of(e: &RunError) -> String {
    match e {
        RunError::Scene(SceneError::Invalid { field, .. }) => field.clone(),
        other => panic!("expected a scene error naming a field, got {other}"),
    }
}

#[test]
fn zero_elements_built_in_code_is_a_scene_error_not_a_panic() {
    let mut scene = impact();
    scene.mesh.elements = 0;
    let e = Simulation::new(&scene)
        .err()
        .expect("zero elements must be refused");
    assert_eq!(field_of(&e), "mesh.elements");
    assert_eq!(e.exit_code(), 2);
    let e = Discretisation::new(&scene).err().unwrap();
    assert!(e.to_string().contains("mesh.elements"), "{e}");
}

/// A change that makes a scene invalid.
type Spoil = fn(&mut Scene);

#[test]
fn bad_fields_built_in_code_are_named() {
    let cases: [(&str, Spoil); 4] = [
        ("time.step", |s| s.time.step = -0.01),
        ("bar.viscosity", |s| s.bar.viscosity = f64::NAN),
        ("bar.length", |s| s.bar.length = 0.0),
        ("left.gap", |s| {
            s.left = EndSpec::new(Condition::Signorini, Some(f64::INFINITY))
        }),
    ];
    for (field, spoil) in cases {
        let mut scene = impact();
        spoil(&mut scene);
        let e = Simulation::new(&scene).err().expect(field);
        assert_eq!(field_of(&e), field);
    }
}

/// `with_solver` validates too: the solver is built for a valid scene, then the scene changed.
#[test]
fn with_solver_validates_its_scene() {
    let scene = impact();
    let disc = Discretisation::new(&scene).unwrap();
    let solver = viscobar::internals::bar::body::make_solver(&scene, &disc).unwrap();
    let mut bad = scene.clone();
    bad.time.end = f64::NAN;
    let e = Simulation::with_solver(&bad, disc, solver).err().unwrap();
    assert_eq!(field_of(&e), "time.end");
}

/// A solver's settings are checked by the solver itself, not only by the scene: the error
/// names the `[solver]` key.
#[test]
fn osqp_settings_are_validated_by_the_solver() {
    use viscobar::internals::linalg::SymTridiag;
    use viscobar::internals::step::Osqp;
    use viscobar::step::{OsqpSettings, SetupError};
    let c = SymTridiag::new(vec![2.0; 4], vec![-1.0; 3]);
    let cases = [
        (
            "eps_abs",
            OsqpSettings {
                eps_abs: f64::NAN,
                ..Default::default()
            },
        ),
        (
            "eps_rel",
            OsqpSettings {
                eps_rel: -1.0,
                ..Default::default()
            },
        ),
        (
            "eps_abs",
            OsqpSettings {
                eps_abs: 0.0,
                eps_rel: 0.0,
                ..Default::default()
            },
        ),
        (
            "max_iter",
            OsqpSettings {
                max_iter: 0,
                ..Default::default()
            },
        ),
        (
            "adaptive_rho_interval",
            OsqpSettings {
                adaptive_rho_interval: 0,
                ..Default::default()
            },
        ),
    ];
    for (field, settings) in cases {
        match Osqp::new(&c, &[0], settings) {
            Err(SetupError::Settings(e)) => assert_eq!(e.field, field),
            Err(other) => panic!("{field}: expected a settings error, got {other}"),
            Ok(_) => panic!("{field}: bad settings accepted"),
        }
    }
    assert!(Osqp::new(&c, &[0], OsqpSettings::default()).is_ok());
}
