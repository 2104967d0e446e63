//! # viscobar-certificate: the certificate of [`viscobar`], in folders by topic
//!
//! - [`verify`]: VERIFICATION.md's generated tables, with the bar's matrices, scenes, closed forms;
//! - [`bar`]: the stiff case matrix, the rigid mode's round-off, mass variants, viscous contact;
//! - [`plane`]: the plane body, its contact, symmetry, locking, moving obstacles (both bodies);
//! - [`friction`]: plane friction and its rigid-limit closed forms; [`thermal`]: the thermal bar;
//!   [`plane_heat`]: the plane body's temperature;
//! - [`solvers`]: the step solvers' agreement, the dense brute-force oracle, contact at scale;
//! - [`tolerances`]: the registry, every tolerance of the tests against the worst value it guards;
//! - [`performance`]: error against run time, the READMEs' benches and peak memory.
//!
//! A member crate of the viscobar workspace, beside the library and not part of its API: it
//! imports `viscobar`, and the integration tests of `viscobar` import it (a dev-dependency),
//! so that a test and the registry share one constant. Its commands:
//! `cargo run --release -p viscobar-certificate -- --help`.

pub mod bar;
pub mod friction;
pub mod performance;
pub mod plane;
pub mod plane_heat;
pub mod solvers;
pub mod thermal;
pub mod tolerances;
pub mod verify;

/// The workspace's root folder (the `viscobar` package): the base of the paths the certificate
/// reads and names (`tests/`, `target/criterion/`).
pub fn workspace_root() -> &'static std::path::Path {
    let certificate = std::path::Path::new(env!("CARGO_MANIFEST_DIR"));
    certificate.parent().unwrap_or(certificate)
}
