//! The mass variants of `[bar] mass` (consistent, redistributed, lumped) for a study: a scene
//! with another variant, validated; a run with it; the `--mass` list of `viscobar converge`.
//! The derivation of the variants is in `docs/mass-variants.md`; their measured behaviour in
//! VERIFICATION.md ("Mass variants").

use crate::output::BarSimulation;
use crate::output::summary::Summary;
use crate::scene::{MassVariant, Scene, SceneError};
use crate::scheme::{RunError, StepRecord};

/// The scene with `bar.mass = mass`, validated (the refusals of [`Scene::validate`] apply: a
/// redistributed mass with an obstacle, with the talk's printed matrices, on too short a bar).
/// What `--set bar.mass=<variant>` does on the command line.
pub fn with_mass(scene: &Scene, mass: MassVariant) -> Result<Scene, SceneError> {
    let mut s = scene.clone();
    s.bar.mass = mass;
    s.validate()?;
    Ok(s)
}

/// Parses a comma-separated list of mass variants (`consistent,redistributed,lumped`), for a
/// `--mass` option; the error names the option, the bad item and the allowed values.
pub fn parse_mass_list(list: &str) -> Result<Vec<MassVariant>, SceneError> {
    list.split(',')
        .map(|item| {
            MassVariant::parse(item).ok_or_else(|| SceneError::Invalid {
                field: "--mass".into(),
                value: format!("\"{}\"", item.trim()),
                allowed: format!(
                    "a comma-separated list of {}",
                    MassVariant::ALL.map(MassVariant::name).join(", ")
                ),
            })
        })
        .collect()
}

/// Runs `scene` with mass variant `mass` (its solver, in memory): the records, the summary and
/// the finished simulation, as [`crate::output::run_in_memory`].
pub fn run_with_mass(
    name: &str,
    scene: &Scene,
    mass: MassVariant,
) -> Result<(Vec<StepRecord>, Summary, BarSimulation), RunError> {
    crate::output::run_in_memory(name, &with_mass(scene, mass)?)
}
