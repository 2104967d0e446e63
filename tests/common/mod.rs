//! Helpers shared by the integration tests.
#![allow(dead_code)]

pub mod alloc;
pub mod snapshot;

use proptest::prelude::*;
use viscobar::Scene;
use viscobar::internals::linalg::tridiag::SymTridiag;
use viscobar::scene;
use viscobar_certificate::solvers::agreement::{MAX_MARGIN, diagonally_dominant};

// ---- tolerances shared by several test files -----------------------------------------------

/// Scene-wide round-off tolerances, defined beside their measurement in the tolerance registry
/// (`viscobar-certificate verify --tolerances`).
#[allow(unused_imports)] // each test file uses some of them
pub use viscobar_certificate::tolerances::{
    COMPLEMENTARITY_TOL, ENERGY_RISE_TOL, GAP_TOL, IDENTITY_TOL, REACTION_TOL,
};
/// The scheme is second order in (dx, dt) for smooth solutions (the card asks for 2 ± 0.15).
pub const MODAL_ORDER: f64 = 2.0;
/// Allowed distance of a smooth solution's observed order from [`MODAL_ORDER`] (the card's 0.15).
pub const MODAL_ORDER_TOL: f64 = 0.15;
/// Observed L2 order of a kinked (non-smooth) solution: the study measured 0.68-0.69 on five
/// levels; ±0.12 around it, wide enough for a three-level estimate and narrow enough to fail if
/// the contact handling degrades to first order in the kink position (order 1/2).
pub const KINK_ORDER_BAND: (f64, f64) = (0.56, 0.80);

/// Loads a built-in scene with overrides.
pub fn builtin(name: &str, overrides: &[&str]) -> Scene {
    let o: Vec<String> = overrides.iter().map(|s| s.to_string()).collect();
    scene::load(name, &o).expect("built-in scene loads").1
}

/// Smallest diagonal-dominance margin of [`spd_tridiag`] (shared with the agreement study's
/// random problems).
pub use viscobar_certificate::solvers::agreement::MIN_MARGIN;

/// Random SPD tridiagonal matrices of size `2..=max_n`: diagonally dominant by a random margin
/// of at least [`MIN_MARGIN`], off-diagonals of either sign (the step matrix C is not an
/// M-matrix when the mass term dominates).
pub fn spd_tridiag(max_n: usize) -> impl Strategy<Value = SymTridiag> {
    (2usize..=max_n).prop_flat_map(|n| {
        (
            prop::collection::vec(-1.0f64..1.0, n - 1),
            prop::collection::vec(MIN_MARGIN..MAX_MARGIN, n),
        )
            .prop_map(|(off, margin)| diagonally_dominant(off, &margin))
    })
}

/// The KKT residual, its per-case round-off bound and the tests' seeded data stream, defined
/// beside their measurement in the tolerance registry (`viscobar-certificate verify --tolerances`).
#[allow(unused_imports)] // each test file uses some of them
pub use viscobar_certificate::tolerances::{kkt, kkt_ratio, stream};

// ---- the `viscobar` binary ------------------------------------------------------------------

/// Runs the `viscobar` binary built for the tests with `args`.
pub fn viscobar(args: &[&str]) -> std::process::Output {
    std::process::Command::new(env!("CARGO_BIN_EXE_viscobar"))
        .args(args)
        .output()
        .expect("binary runs")
}

/// `viscobar-{group}-{pid}-{name}` in the temporary folder, removed if a run left it (not
/// created: a run must create its own output folder).
pub fn fresh_dir(group: &str, name: &str) -> std::path::PathBuf {
    let d = std::env::temp_dir().join(format!("viscobar-{group}-{}-{name}", std::process::id()));
    let _ = std::fs::remove_dir_all(&d);
    d
}

/// The width and height in a PNG's IHDR chunk.
pub fn png_size(bytes: &[u8]) -> (u32, u32) {
    assert_eq!(&bytes[..8], b"\x89PNG\r\n\x1a\n", "PNG signature");
    assert_eq!(&bytes[12..16], b"IHDR");
    let be = |b: &[u8]| u32::from_be_bytes(b.try_into().unwrap());
    (be(&bytes[16..20]), be(&bytes[20..24]))
}

/// `viscobar run SCENE --out OUT --set …` for each case `(what, settings, text)`: exit code 2,
/// a message containing `text`, and no output folder.
pub fn assert_each_refused(scene: &str, cases: &[(&str, &[&str], &str)], out: &std::path::Path) {
    for (what, sets, needle) in cases {
        let _ = std::fs::remove_dir_all(out);
        let mut args = vec!["run", scene, "--out", out.to_str().unwrap()];
        for s in *sets {
            args.extend(["--set", s]);
        }
        let o = viscobar(&args);
        let stderr = String::from_utf8_lossy(&o.stderr);
        assert_eq!(o.status.code(), Some(2), "{what}: {stderr}");
        assert!(stderr.contains(needle), "{what}: {stderr}");
        assert!(!out.exists(), "{what}: wrote {}", out.display());
    }
}

/// Rounds `x` to `digits` significant digits of `scale` (the largest magnitude of the same
/// quantity): to a multiple of `10^(e − digits + 1)`, `10^e` the order of `scale`, printed in
/// decimal so the snapshot shows the rounded value; `−0` becomes `0`. The plane, friction and
/// thermal snapshots use it.
pub fn round_to_digits(x: f64, scale: f64, digits: i32) -> f64 {
    if x == 0.0 || scale == 0.0 {
        return x;
    }
    let exponent = scale.abs().log10().floor() as i32 - (digits - 1);
    let q = 10f64.powi(exponent);
    let decimals = (-exponent).max(0) as usize;
    let r: f64 = format!("{:.*}", decimals, (x / q).round() * q)
        .parse()
        .unwrap();
    r + 0.0
}

// ---- the audits' bounds at their edges (tests/audit_bounds/) ----------

/// `‖a‖∞` of a dense matrix: the largest row sum of magnitudes.
pub fn inf_norm(a: &nalgebra::DMatrix<f64>) -> f64 {
    a.row_iter()
        .map(|row| row.iter().map(|v| v.abs()).sum::<f64>())
        .fold(0.0, f64::max)
}

/// `‖v‖∞`.
pub fn amax(v: &[f64]) -> f64 {
    v.iter().fold(0.0, |m, x| m.max(x.abs()))
}

/// A checked value over its tolerance, as the audits report it (0 for a value of 0).
pub fn ratio(value: f64, tolerance: f64) -> f64 {
    if value == 0.0 { 0.0 } else { value / tolerance }
}
