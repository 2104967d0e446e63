//! The thermal bar's coupled step matrix with its factorisation, as the step solvers see it
//! ([`SpdSystem`]): vectors in the body's block layout `[u | θ]`, the matrix and its banded
//! `LDLᵀ` in the interleaved order (a gather before and a scatter after each solve). The
//! matrix `[[C, −γ/2 G], [−γ/2 Gᵀ, −H]]` is symmetric quasi-definite, not positive definite;
//! what the condensed solver needs holds all the same: `E A⁻¹ Eᵀ` on displacement unknowns is
//! the inverse's block `(C + γ²/4 G H⁻¹ Gᵀ)⁻¹`, positive definite, so the contact step stays
//! an exact convex LCP. Factorised once per exchange state.

use crate::linalg::banded::{BandedLdlt, SymBanded, ZeroPivot};
use crate::linalg::system::{Csc, SpdSystem};
use crate::thermal::matrices::BAND;

/// The coupled step matrix and its factor, in the block layout.
#[derive(Clone, Debug)]
pub struct CoupledSystem {
    matrix: SymBanded<BAND>,
    factor: BandedLdlt<BAND>,
    /// Interleaved position → block index, and back.
    order: Vec<usize>,
    position: Vec<usize>,
    /// The interleaved right-hand side of a solve.
    scratch: Vec<f64>,
}

impl CoupledSystem {
    /// Factorises `matrix` (interleaved as `order` says: position `k` holds block index
    /// `order[k]`).
    pub fn new(matrix: SymBanded<BAND>, order: Vec<usize>) -> Result<Self, ZeroPivot> {
        let factor = BandedLdlt::factor(&matrix)?;
        let mut position = vec![0; order.len()];
        for (k, &b) in order.iter().enumerate() {
            position[b] = k;
        }
        Ok(Self {
            scratch: vec![0.0; order.len()],
            matrix,
            factor,
            order,
            position,
        })
    }

    /// The factor's inertia: (positive, negative) pivots.
    pub fn inertia(&self) -> (usize, usize) {
        self.factor.inertia()
    }

    /// `A_ij` in the block layout.
    pub fn entry(&self, i: usize, j: usize) -> f64 {
        self.matrix.get(self.position[i], self.position[j])
    }
}

impl SpdSystem for CoupledSystem {
    fn dim(&self) -> usize {
        self.order.len()
    }

    fn mul_into(&self, x: &[f64], y: &mut [f64]) {
        let (a, order) = (&self.matrix, &self.order);
        let n = order.len();
        for (k, &bi) in order.iter().enumerate() {
            let mut s = a.diag[k] * x[bi];
            for d in 1..=BAND.min(k) {
                s += a.lower[k][d - 1] * x[order[k - d]];
            }
            for d in 1..=BAND.min(n - 1 - k) {
                s += a.lower[k + d][d - 1] * x[order[k + d]];
            }
            y[bi] = s;
        }
    }

    fn solve_in_place(&mut self, x: &mut [f64]) {
        for (s, &bi) in self.scratch.iter_mut().zip(&self.order) {
            *s = x[bi];
        }
        self.factor.solve_in_place(&mut self.scratch);
        for (s, &bi) in self.scratch.iter().zip(&self.order) {
            x[bi] = *s;
        }
    }

    fn inf_norm(&self) -> f64 {
        self.matrix.inf_norm()
    }

    fn diagonal(&self, i: usize) -> f64 {
        self.matrix.diag[self.position[i]]
    }

    fn abs_row_product(&self, i: usize, x: &[f64]) -> f64 {
        let order = &self.order;
        (self.matrix).abs_row_sum(self.position[i], |k| x[order[k]].abs())
    }

    /// A row of `A z` is at most seven products and six additions, then `− b_i − r_i` two
    /// more (about 9 ulps of `|A||z| + |b| + |r|` exactly rounded); the banded `LDLᵀ` of a
    /// quasi-definite matrix is backward stable with a growth bounded by the blocks'
    /// conditioning (Gill, Saunders & Shinnerl, SIAM J. Matrix Anal. Appl. 17 (1996)), which
    /// the thermal bar's well-scaled blocks keep small: 64 leaves a margin of about three over
    /// the tridiagonal bar's 32 · 7/3.
    fn roundoff_ulps(&self) -> f64 {
        64.0
    }

    /// The upper triangle in the block layout. The matrix is quasi-definite, not positive
    /// semidefinite: it is not a convex QP's `P` (OSQP on the thermal bar takes the reduced
    /// problem, `crate::thermal::osqp`).
    fn upper_triangle(&self) -> Csc {
        let n = self.order.len();
        let mut columns: Vec<Vec<(usize, f64)>> = vec![Vec::new(); n];
        for k in 0..n {
            for d in 0..=BAND.min(k) {
                let v = if d == 0 {
                    self.matrix.diag[k]
                } else {
                    self.matrix.lower[k][d - 1]
                };
                if v != 0.0 || d == 0 {
                    let (i, j) = (self.order[k], self.order[k - d]);
                    let (r, c) = (i.min(j), i.max(j));
                    columns[c].push((r, v));
                }
            }
        }
        let (mut indptr, mut indices, mut data) = (vec![0], Vec::new(), Vec::new());
        for mut col in columns {
            col.sort_by_key(|&(r, _)| r);
            for (r, v) in col {
                indices.push(r);
                data.push(v);
            }
            indptr.push(indices.len());
        }
        Csc {
            nrows: n,
            ncols: n,
            indptr,
            indices,
            data,
        }
    }
}
