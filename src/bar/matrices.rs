//! P1 mass and stiffness matrices on the uniform mesh of [0, L] with `J + 2` nodes, and the mass
//! variants of `[bar] mass` (consistent, redistributed, lumped; see [`mass_matrix`]).
//!
//! The talk (Petrov & Schatzman, Lisboa 2009, "Numerical scheme" slide) prints
//! `M_ii = 2Δx/3`, `M_i,i±1 = Δx/3`, `R_00 = R_J+1,J+1 = 2/Δx`. Those entries are not the P1
//! matrices: they give the bar a total mass `1ᵀM1 → 4L/3` and tie both ends to the ground
//! (`R·1 ≠ 0`). The consistent matrices are the default; the printed ones are kept as
//! [`MatrixVariant::TalkPrinted`] so that the tests can show what is wrong with them.

use crate::linalg::tridiag::SymTridiag;
pub use crate::scene::{MassVariant, MatrixVariant};

/// Mass matrix on `nodes = J + 2` nodes with spacing `dx`.
pub fn mass(variant: MatrixVariant, nodes: usize, dx: f64) -> SymTridiag {
    assert!(nodes >= 2);
    let (end, inner, off) = match variant {
        MatrixVariant::Consistent => (dx / 3.0, 2.0 * dx / 3.0, dx / 6.0),
        MatrixVariant::TalkPrinted => (2.0 * dx / 3.0, 2.0 * dx / 3.0, dx / 3.0),
    };
    banded(nodes, end, inner, off)
}

/// Why [`mass_matrix`] cannot build a variant: the bar is too short for redistribution.
#[derive(Clone, Copy, Debug, PartialEq, Eq, thiserror::Error)]
#[error(
    "a redistributed mass at {ends} signorini end(s) needs at least {least} elements, not {elements}"
)]
pub struct TooFewElements {
    pub ends: usize,
    pub least: usize,
    pub elements: usize,
}

/// The mass matrix of variant `mass` on `nodes = J + 2` nodes with spacing `dx` (consistent
/// matrices underneath), where `massless = [left, right]` says which ends are Signorini ends
/// (only [`MassVariant::Redistributed`] reads it).
///
/// - `Consistent`: [`mass`]`(Consistent, …)`.
/// - `Lumped`: the row sums on the diagonal, `diag(Δx/2, Δx, …, Δx, Δx/2)`, no off-diagonal.
/// - `Redistributed` (Khenous, Laborde & Renard, Eur. J. Mech. A/Solids 27 (2008) 918–932; in
///   1D Dabaghi, Petrov, Pousin & Renard, ESAIM: M2AN 48 (2014) 1147–1169): at a Signorini end
///   node row and column are zeroed, and the mass removed (`2Δx/3`, centred `Δx/4` inside the
///   end element) is put on the two nearest nodes' diagonals, `+7Δx/6` and `−Δx/2`, so that the
///   total mass `1ᵀM1` and the first moment `xᵀM1` are both kept. Row sums from the left end:
///   `(0, 2Δx, Δx/2, Δx, …)`. GetFEM's 1D demo (`demo_dynamic_contact_1D.py`) instead adds the
///   end's `M00 + M10` to `M11` and loses `Δx/6` of mass. `M` stays symmetric positive
///   semidefinite with kernel exactly the massless nodes for `J + 1 >=`
///   [`REDISTRIBUTED_MIN_ELEMENTS_ONE_END`](crate::scene::REDISTRIBUTED_MIN_ELEMENTS_ONE_END)
///   elements (one end) or
///   [`REDISTRIBUTED_MIN_ELEMENTS_TWO_ENDS`](crate::scene::REDISTRIBUTED_MIN_ELEMENTS_TWO_ENDS)
///   (two); fewer are refused. Derivation and proof: `docs/mass-variants.md`.
pub fn mass_matrix(
    mass_variant: MassVariant,
    massless: [bool; 2],
    nodes: usize,
    dx: f64,
) -> Result<SymTridiag, TooFewElements> {
    assert!(nodes >= 2);
    match mass_variant {
        MassVariant::Consistent => Ok(mass(MatrixVariant::Consistent, nodes, dx)),
        MassVariant::Lumped => Ok(banded(nodes, dx / 2.0, dx, 0.0)),
        MassVariant::Redistributed => {
            let ends = massless.iter().filter(|m| **m).count();
            let least = match ends {
                0 => 0,
                1 => crate::scene::REDISTRIBUTED_MIN_ELEMENTS_ONE_END as usize,
                _ => crate::scene::REDISTRIBUTED_MIN_ELEMENTS_TWO_ENDS as usize,
            };
            let elements = nodes - 1;
            if elements < least {
                return Err(TooFewElements {
                    ends,
                    least,
                    elements,
                });
            }
            let mut m = mass(MatrixVariant::Consistent, nodes, dx);
            let (mut diag, mut off) = (std::mem::take(&mut m.diag), std::mem::take(&mut m.off));
            let n = nodes - 1;
            // (end node, its neighbour, the next node, the off-diagonal entry to the end)
            for (end, near, next, edge) in [(0, 1, 2, 0), (n, n - 1, n - 2, n - 1)]
                .into_iter()
                .zip(massless)
                .filter_map(|(e, m)| m.then_some(e))
            {
                diag[end] = 0.0;
                off[edge] = 0.0;
                // 2Δx/3 + 7Δx/6 and 2Δx/3 − Δx/2, each rounded once.
                diag[near] = 11.0 * dx / 6.0;
                diag[next] = dx / 6.0;
            }
            Ok(SymTridiag::new(diag, off))
        }
    }
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
