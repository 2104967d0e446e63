//! Helpers shared by the integration tests.
#![allow(dead_code)]

use viscobar::Scene;
use viscobar::scene;

/// Loads a built-in scene with overrides.
pub fn builtin(name: &str, overrides: &[&str]) -> Scene {
    let o: Vec<String> = overrides.iter().map(|s| s.to_string()).collect();
    scene::load(name, &o).expect("built-in scene loads").1
}

/// Scales the mesh and the time step of a scene by `2^level` together.
pub fn refined(base: &Scene, level: u32) -> Scene {
    let mut s = base.clone();
    s.mesh.elements = base.mesh.elements << level;
    s.time.step = base.time.step / f64::from(1u32 << level);
    s
}
