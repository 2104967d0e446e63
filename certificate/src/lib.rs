//! # viscobar-certificate: the certificate of [`viscobar`]: the studies that recompute the generated tables of
//! VERIFICATION.md ([`verify`]), the tolerance registry that measures every tolerance of the
//! tests against the worst value it guards ([`tolerances`]), the stiff and extreme case matrix
//! ([`stiff`], [`stiff_runs`]), the step solvers' agreement ([`agreement`]) with the dense
//! brute-force [`oracle`], the rigid mode's round-off ([`roundoff`]), the mass variants side by
//! side ([`mass_study`]), the plane body's checks ([`plane_checks`], [`plane_contact`],
//! [`plane_symmetry`], [`locking`], [`moving`]), its friction ([`friction`], [`friction_rigid`]),
//! the manufactured viscous contact ([`viscous_contact`]), error against run time ([`timings`]);
//! the measured blocks of the READMEs ([`bench_table`], [`bench_compare`], [`peak_memory`]).
//!
//! A member crate of the viscobar workspace, beside the library and not part of its API: it
//! imports `viscobar`, and the integration tests of `viscobar` import it (a dev-dependency),
//! so that a test and the registry share one constant. Its commands:
//! `cargo run --release -p viscobar-certificate -- --help`.

pub mod agreement;
pub mod bench_compare;
pub mod bench_table;
pub mod friction;
pub mod friction_rigid;
pub mod locking;
pub mod mass_study;
pub mod moving;
pub mod oracle;
pub mod peak_memory;
pub mod plane_checks;
pub mod plane_contact;
pub mod plane_symmetry;
pub mod roundoff;
pub mod scale;
pub mod stiff;
pub mod stiff_runs;
pub mod thermal;
pub mod thermal_boundary;
pub mod timings;
pub mod tolerances;
pub mod verify;
pub mod viscous_contact;

/// The workspace's root folder (the `viscobar` package): the base of the paths the certificate
/// reads and names (`tests/`, `target/criterion/`).
pub fn workspace_root() -> &'static std::path::Path {
    let certificate = std::path::Path::new(env!("CARGO_MANIFEST_DIR"));
    certificate.parent().unwrap_or(certificate)
}
