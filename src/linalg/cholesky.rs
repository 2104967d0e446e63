//! The sparse Cholesky factorisation `A = LLᵀ` of the plane body's symmetric positive definite
//! matrices (faer 0.24, supernodal, AMD fill-reducing ordering), and `A = LDLᵀ` of its
//! symmetric quasi-definite ones (`[[P, G], [Gᵀ, −N]]`, `P`, `N` positive definite: an `LDLᵀ`
//! exists for every ordering, Vanderbei 1995), through faer's low-level
//! API: the symbolic analysis once per pattern, the numeric factorisation once per matrix, and
//! solves with a work space kept for the run, so that a solve allocates nothing (faer's
//! high-level `Llt` allocates on every solve: `docs/sparse-cholesky.md`).

use crate::linalg::sparse::Pattern;
use faer::dyn_stack::{MemBuffer, MemStack};
use faer::linalg::cholesky::ldlt::factor::{LdltError, LdltRegularization};
use faer::linalg::cholesky::llt::factor::LltRegularization;
use faer::sparse::linalg::cholesky::{
    CholeskySymbolicParams, LdltRef, LltRef, SymbolicCholesky, SymmetricOrdering,
    factorize_symbolic_cholesky,
};
use faer::sparse::{SparseColMatRef, SymbolicSparseColMatRef};
use faer::{Conj, MatMut, Par, Side};

/// A factorisation that could not be made.
#[derive(Debug, thiserror::Error)]
pub enum FactorError {
    #[error("the matrix {matrix} is not positive definite (pivot {index} of the ordered matrix)")]
    NotPositiveDefinite { matrix: &'static str, index: usize },
    #[error("the matrix {matrix} has a zero pivot ({index} of the ordered matrix)")]
    ZeroPivot { matrix: &'static str, index: usize },
    #[error("the symbolic analysis of {matrix} failed: {reason}")]
    Symbolic {
        matrix: &'static str,
        reason: String,
    },
}

/// `A = LLᵀ` for matrices on one [`Pattern`]: [`SparseCholesky::factor`] replaces the numeric
/// factor (same pattern, no new analysis), [`SparseCholesky::solve_in_place`] solves.
/// [`SparseCholesky::quasi_definite`] factorises `A = LDLᵀ` instead, without pivoting.
pub struct SparseCholesky {
    symbolic: SymbolicCholesky<usize>,
    /// `LDLᵀ` (a quasi-definite matrix) rather than `LLᵀ`.
    ldlt: bool,
    values: Vec<f64>,
    /// Work space of a solve, kept for the run.
    solve_buffer: MemBuffer,
    /// Work space of [`SparseCholesky::refactor`], made on its first call.
    factor_buffer: Option<MemBuffer>,
    n: usize,
}

impl SparseCholesky {
    /// The symbolic analysis of `pattern` (AMD ordering) and the factorisation of the matrix
    /// with values `a` on it; `matrix` names it in errors.
    pub fn new(pattern: &Pattern, a: &[f64], matrix: &'static str) -> Result<Self, FactorError> {
        Self::with_kind(pattern, a, matrix, false)
    }

    /// `A = LDLᵀ` of the symmetric quasi-definite matrix with values `a` on `pattern` (AMD
    /// ordering, no pivoting: `D` holds the signs of `A`'s two blocks).
    pub fn quasi_definite(
        pattern: &Pattern,
        a: &[f64],
        matrix: &'static str,
    ) -> Result<Self, FactorError> {
        Self::with_kind(pattern, a, matrix, true)
    }

    fn with_kind(
        pattern: &Pattern,
        a: &[f64],
        matrix: &'static str,
        ldlt: bool,
    ) -> Result<Self, FactorError> {
        let symbolic = factorize_symbolic_cholesky(
            Self::structure(pattern),
            Side::Lower,
            SymmetricOrdering::Amd,
            CholeskySymbolicParams::default(),
        )
        .map_err(|e| FactorError::Symbolic {
            matrix,
            reason: format!("{e:?}"),
        })?;
        let solve_buffer = MemBuffer::new(symbolic.solve_in_place_scratch::<f64>(1, Par::Seq));
        let values = vec![0.0; symbolic.len_val()];
        let mut this = Self {
            symbolic,
            ldlt,
            values,
            solve_buffer,
            factor_buffer: None,
            n: pattern.n,
        };
        this.factor(pattern, a, matrix)?;
        Ok(this)
    }

    fn structure(pattern: &Pattern) -> SymbolicSparseColMatRef<'_, usize> {
        // Symmetric: the CSR rows are the CSC columns.
        SymbolicSparseColMatRef::new_checked(
            pattern.n,
            pattern.n,
            &pattern.row_ptr,
            None,
            &pattern.cols,
        )
    }

    /// Factorises the matrix with values `a` on the analysed pattern (the lower triangle is
    /// read). Allocates its work space (once per matrix, not per step).
    pub fn factor(
        &mut self,
        pattern: &Pattern,
        a: &[f64],
        matrix: &'static str,
    ) -> Result<(), FactorError> {
        let mut buffer = MemBuffer::new(self.factor_scratch());
        self.factor_with(pattern, a, matrix, &mut buffer)
    }

    /// [`SparseCholesky::factor`] with its work space kept (made on the first call): a matrix
    /// that changes from step to step (the sparse penalty solver's `C + D/ε`) is refactorised
    /// without allocating; the symbolic analysis is the pattern's, made once.
    pub fn refactor(
        &mut self,
        pattern: &Pattern,
        a: &[f64],
        matrix: &'static str,
    ) -> Result<(), FactorError> {
        let mut buffer = match self.factor_buffer.take() {
            Some(b) => b,
            None => MemBuffer::new(self.factor_scratch()),
        };
        let result = self.factor_with(pattern, a, matrix, &mut buffer);
        self.factor_buffer = Some(buffer);
        result
    }

    fn factor_scratch(&self) -> faer::dyn_stack::StackReq {
        if self.ldlt {
            self.symbolic
                .factorize_numeric_ldlt_scratch::<f64>(Par::Seq, Default::default())
        } else {
            self.symbolic
                .factorize_numeric_llt_scratch::<f64>(Par::Seq, Default::default())
        }
    }

    fn factor_with(
        &mut self,
        pattern: &Pattern,
        a: &[f64],
        matrix: &'static str,
        buffer: &mut MemBuffer,
    ) -> Result<(), FactorError> {
        let a = SparseColMatRef::new(Self::structure(pattern), a);
        if self.ldlt {
            self.symbolic
                .factorize_numeric_ldlt(
                    &mut self.values,
                    a,
                    Side::Lower,
                    LdltRegularization::default(),
                    Par::Seq,
                    MemStack::new(buffer),
                    Default::default(),
                )
                .map_err(|LdltError::ZeroPivot { index }| FactorError::ZeroPivot {
                    matrix,
                    index,
                })?;
            return Ok(());
        }
        self.symbolic
            .factorize_numeric_llt(
                &mut self.values,
                a,
                Side::Lower,
                LltRegularization::default(),
                Par::Seq,
                MemStack::new(buffer),
                Default::default(),
            )
            .map_err(|e| match e {
                faer::linalg::cholesky::llt::factor::LltError::NonPositivePivot { index } => {
                    FactorError::NotPositiveDefinite { matrix, index }
                }
            })?;
        Ok(())
    }

    /// `x ← A⁻¹ x`; allocates nothing.
    pub fn solve_in_place(&mut self, x: &mut [f64]) {
        assert_eq!(x.len(), self.n, "right-hand side of the wrong length");
        let rhs = MatMut::from_column_major_slice_mut(x, self.n, 1);
        let stack = MemStack::new(&mut self.solve_buffer);
        solve_factored((&self.symbolic, &self.values, self.ldlt), rhs, stack);
    }

    /// `X ← A⁻¹ X` for `ncols` right-hand sides stored column after column in `x` (one pass
    /// over the factor for all of them). Allocates its work space: for set-up, not per step.
    pub fn solve_columns_in_place(&mut self, x: &mut [f64], ncols: usize) {
        assert_eq!(
            x.len(),
            self.n * ncols,
            "right-hand sides of the wrong length"
        );
        let mut buffer =
            MemBuffer::new(self.symbolic.solve_in_place_scratch::<f64>(ncols, Par::Seq));
        let rhs = MatMut::from_column_major_slice_mut(x, self.n, ncols);
        let stack = MemStack::new(&mut buffer);
        solve_factored((&self.symbolic, &self.values, self.ldlt), rhs, stack);
    }

    /// Stored values of the factor (`≈ nnz(L)`, supernodal blocks included).
    pub fn factor_len(&self) -> usize {
        self.values.len()
    }

    /// Unknowns.
    pub fn dim(&self) -> usize {
        self.n
    }
}

/// `X ← A⁻¹ X` by the factor `(symbolic, values)`, `LDLᵀ` when `ldlt`, else `LLᵀ`.
fn solve_factored(
    (symbolic, values, ldlt): (&SymbolicCholesky<usize>, &[f64], bool),
    rhs: MatMut<'_, f64>,
    stack: &mut MemStack,
) {
    if ldlt {
        LdltRef::new(symbolic, values).solve_in_place_with_conj(Conj::No, rhs, Par::Seq, stack);
    } else {
        LltRef::new(symbolic, values).solve_in_place_with_conj(Conj::No, rhs, Par::Seq, stack);
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::plane::matrices::{Material, assemble};
    use crate::plane::mesh::Grid;

    /// Normwise backward error `‖b − Ax‖∞ / (‖A‖∞ ‖x‖∞ + ‖b‖∞)` in units of ε: Cholesky is
    /// backward stable with `|ΔA| ≤ γ_{c·n_L}|L||Lᵀ|` (Higham, Thm 10.3); on these well
    /// conditioned, diagonally dominant-ish matrices the measured error is below one ε.
    const BACKWARD_ULPS: f64 = 16.0;

    #[test]
    fn solves_the_step_matrix_backward_stably() {
        let grid = Grid::new(2.0, 1.0, 12, 6, 2.0);
        let m = assemble(
            &grid,
            Material {
                lambda: 1.0,
                mu: 0.5,
                density: 1.0,
            },
        );
        let (dt, alpha) = (0.05, 0.02);
        let c: Vec<f64> = m
            .mass
            .iter()
            .zip(&m.stiffness)
            .map(|(mm, k)| mm / (dt * dt) + (0.5 + alpha / (2.0 * dt)) * k)
            .collect();
        let mut chol = SparseCholesky::new(&m.pattern, &c, "C").unwrap();
        let b: Vec<f64> = (0..m.pattern.n)
            .map(|i| ((i * 7919) % 13) as f64 - 6.0)
            .collect();
        let mut x = b.clone();
        chol.solve_in_place(&mut x);
        let mut ax = vec![0.0; x.len()];
        m.pattern.mul_into(&c, &x, &mut ax);
        let inf = |v: &[f64]| v.iter().fold(0.0f64, |a, x| a.max(x.abs()));
        let norm_a = (0..m.pattern.n)
            .map(|r| {
                (m.pattern.row_ptr[r]..m.pattern.row_ptr[r + 1])
                    .map(|k| c[k].abs())
                    .sum()
            })
            .fold(0.0f64, f64::max);
        let r: Vec<f64> = b.iter().zip(&ax).map(|(b, a)| b - a).collect();
        let backward = inf(&r) / ((norm_a * inf(&x) + inf(&b)) * f64::EPSILON);
        assert!(backward <= BACKWARD_ULPS, "{backward}");
        // −C is negative definite: refused, naming the matrix.
        let minus: Vec<f64> = c.iter().map(|v| -v).collect();
        match SparseCholesky::new(&m.pattern, &minus, "-C") {
            Err(FactorError::NotPositiveDefinite { matrix: "-C", .. }) => {}
            Err(e) => panic!("{e}"),
            Ok(_) => panic!("-C factorised"),
        }
    }
}
