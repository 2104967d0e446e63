//! Helpers shared by the integration tests.
#![allow(dead_code)]

use proptest::prelude::*;
use viscobar::Scene;
use viscobar::linalg::tridiag::SymTridiag;
use viscobar::scene;

/// Loads a built-in scene with overrides.
pub fn builtin(name: &str, overrides: &[&str]) -> Scene {
    let o: Vec<String> = overrides.iter().map(|s| s.to_string()).collect();
    scene::load(name, &o).expect("built-in scene loads").1
}

/// Smallest diagonal-dominance margin of [`spd_tridiag`]: keeps the condition number below
/// about 1e4 for the sizes the tests draw.
pub const MIN_MARGIN: f64 = 0.05;

/// Random SPD tridiagonal matrices of size `2..=max_n`: diagonally dominant by a random margin
/// of at least [`MIN_MARGIN`], off-diagonals of either sign (the step matrix C is not an
/// M-matrix when the mass term dominates).
pub fn spd_tridiag(max_n: usize) -> impl Strategy<Value = SymTridiag> {
    (2usize..=max_n).prop_flat_map(|n| {
        (
            prop::collection::vec(-1.0f64..1.0, n - 1),
            prop::collection::vec(MIN_MARGIN..3.0, n),
        )
            .prop_map(move |(off, margin)| {
                let diag = (0..n)
                    .map(|i| {
                        let l = if i > 0 { off[i - 1].abs() } else { 0.0 };
                        let r = if i + 1 < n { off[i].abs() } else { 0.0 };
                        l + r + margin[i]
                    })
                    .collect();
                SymTridiag::new(diag, off)
            })
    })
}
