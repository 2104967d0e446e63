//! P1 mass and stiffness matrices on the uniform mesh of [0, L] with `J + 2` nodes.
//!
//! The talk (Petrov & Schatzman, Lisboa 2009, "Numerical scheme" slide) prints
//! `M_ii = 2Δx/3`, `M_i,i±1 = Δx/3`, `R_00 = R_J+1,J+1 = 2/Δx`. Those entries are not the P1
//! matrices: they give the bar a total mass `1ᵀM1 → 4L/3` and tie both ends to the ground
//! (`R·1 ≠ 0`). The consistent matrices are the default; the printed ones are kept as
//! [`MatrixVariant::TalkPrinted`] so that the tests can show what is wrong with them.

use crate::linalg::tridiag::SymTridiag;
pub use crate::scene::MatrixVariant;

/// Mass matrix on `nodes = J + 2` nodes with spacing `dx`.
pub fn mass(variant: MatrixVariant, nodes: usize, dx: f64) -> SymTridiag {
    assert!(nodes >= 2);
    let (end, inner, off) = match variant {
        MatrixVariant::Consistent => (dx / 3.0, 2.0 * dx / 3.0, dx / 6.0),
        MatrixVariant::TalkPrinted => (2.0 * dx / 3.0, 2.0 * dx / 3.0, dx / 3.0),
    };
    banded(nodes, end, inner, off)
}

/// Stiffness matrix `R_ij = ∫ w_i' w_j' dx` on `nodes = J + 2` nodes with spacing `dx`.
pub fn stiffness(variant: MatrixVariant, nodes: usize, dx: f64) -> SymTridiag {
    assert!(nodes >= 2);
    // 1/dx is rounded once and every entry is an exact multiple of it, so R·1 = 0 holds
    // bitwise for the consistent matrix (rigid motions store no elastic energy).
    let k = 1.0 / dx;
    let (end, inner, off) = match variant {
        MatrixVariant::Consistent => (k, 2.0 * k, -k),
        MatrixVariant::TalkPrinted => (2.0 * k, 2.0 * k, -k),
    };
    banded(nodes, end, inner, off)
}

fn banded(nodes: usize, end: f64, inner: f64, off: f64) -> SymTridiag {
    let mut diag = vec![inner; nodes];
    diag[0] = end;
    diag[nodes - 1] = end;
    SymTridiag::new(diag, vec![off; nodes - 1])
}
