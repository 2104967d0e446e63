//! The step matrix `C` of a body with its factorisation, as the step solvers and their audit
//! use it: products, solves and the magnitudes their round-off floors are measured in. One
//! trait, [`SpdSystem`], so that a solver is written once for every body; the bar supplies the
//! tridiagonal [`TridiagSystem`], the plane body the sparse [`SparseSystem`].

use crate::linalg::cholesky::{FactorError, SparseCholesky};
use crate::linalg::kernels::ldlt::NotPositiveDefinite;
use crate::linalg::kernels::ldlt_fast::TwistedLdlt;
use crate::linalg::sparse::Pattern;
use crate::linalg::tridiag::SymTridiag;

/// A symmetric positive definite matrix `C`, factorised once.
pub trait SpdSystem {
    /// `n`.
    fn dim(&self) -> usize;
    /// `y = C x`.
    fn mul_into(&self, x: &[f64], y: &mut [f64]);
    /// `x ← C⁻¹ x`; allocates nothing.
    fn solve_in_place(&mut self, x: &mut [f64]);
    /// `X ← C⁻¹ X` for `ncols` right-hand sides stored one after the other (set-up only).
    fn solve_columns_in_place(&mut self, x: &mut [f64], ncols: usize) {
        let n = self.dim();
        for column in x.chunks_exact_mut(n.max(1)).take(ncols) {
            self.solve_in_place(column);
        }
    }
    /// `C⁻¹ e_j` as a new vector (set-up only).
    fn column_of_inverse(&mut self, j: usize) -> Vec<f64> {
        let mut c = vec![0.0; self.dim()];
        c[j] = 1.0;
        self.solve_in_place(&mut c);
        c
    }
    /// `‖C‖∞`.
    fn inf_norm(&self) -> f64;
    /// `C_ii`.
    fn diagonal(&self, i: usize) -> f64;
    /// `(|C||x|)_i`: the magnitudes the row `(C x)_i` is summed from.
    fn abs_row_product(&self, i: usize, x: &[f64]) -> f64;
    /// The round-off of a residual `C z − b − r` recomputed from a backward-stable solve's `z`,
    /// in ulps of `|C||z| + |b| + |r|` (a row's products and sums, the solve's backward error).
    fn roundoff_ulps(&self) -> f64;
    /// The upper triangle of `C` in compressed columns (OSQP's `P`).
    fn upper_triangle(&self) -> Csc;
}

/// A sparse matrix in compressed sparse columns: column `j` holds rows
/// `indices[indptr[j]..indptr[j + 1]]` (ascending) with values `data[…]`.
#[derive(Clone, Debug, PartialEq)]
pub struct Csc {
    pub nrows: usize,
    pub ncols: usize,
    pub indptr: Vec<usize>,
    pub indices: Vec<usize>,
    pub data: Vec<f64>,
}

/// Hager's estimate (1984; Higham, *Accuracy and Stability of Numerical Algorithms*, ch. 15)
/// of `‖C⁻¹‖_1`, which equals `‖C⁻¹‖_∞` for symmetric `C`: a lower bound, exact or within a
/// small factor in practice; at most five pairs of solves, once per run.
pub fn inverse_norm_estimate(system: &mut impl SpdSystem) -> f64 {
    hager_norm_estimate(system.dim(), |x| system.solve_in_place(x))
}

/// Hager's estimate of `‖A‖_1` for a symmetric `A` of order `n` given as `apply: x ← A x`
/// ([`inverse_norm_estimate`] with `A = C⁻¹`); at most five pairs of applications.
pub fn hager_norm_estimate(n: usize, mut apply: impl FnMut(&mut [f64])) -> f64 {
    if n == 0 {
        return 0.0;
    }
    let mut x = vec![1.0 / n as f64; n];
    let mut y = vec![0.0; n];
    let mut w = vec![0.0; n];
    let mut estimate = 0.0;
    for _ in 0..5 {
        y.copy_from_slice(&x);
        apply(&mut y);
        estimate = y.iter().map(|v| v.abs()).sum::<f64>();
        for (wi, yi) in w.iter_mut().zip(&y) {
            *wi = if *yi >= 0.0 { 1.0 } else { -1.0 };
        }
        apply(&mut w);
        let (j, wmax) = w.iter().enumerate().fold((0, 0.0f64), |(jm, m), (i, v)| {
            if v.abs() > m { (i, v.abs()) } else { (jm, m) }
        });
        let wx: f64 = w.iter().zip(&x).map(|(a, b)| a * b).sum();
        if wmax <= wx {
            break;
        }
        x.fill(0.0);
        x[j] = 1.0;
    }
    estimate
}

/// The bar's step matrix: tridiagonal, with the factorisation the bar's step solves with
/// (the twin [`TwistedLdlt`], so that every solver of a bar solves with the same bits).
#[derive(Clone, Debug)]
pub struct TridiagSystem {
    pub matrix: SymTridiag,
    pub factor: TwistedLdlt,
}

impl TridiagSystem {
    pub fn new(matrix: &SymTridiag) -> Result<Self, NotPositiveDefinite> {
        Ok(Self {
            factor: TwistedLdlt::factor(matrix)?,
            matrix: matrix.clone(),
        })
    }
}

impl SpdSystem for TridiagSystem {
    fn dim(&self) -> usize {
        self.matrix.dim()
    }

    fn mul_into(&self, x: &[f64], y: &mut [f64]) {
        self.matrix.mul_into(x, y);
    }

    fn solve_in_place(&mut self, x: &mut [f64]) {
        self.factor.solve_in_place(x);
    }

    fn column_of_inverse(&mut self, j: usize) -> Vec<f64> {
        self.factor.column_of_inverse(j)
    }

    fn inf_norm(&self) -> f64 {
        self.matrix.inf_norm()
    }

    fn diagonal(&self, i: usize) -> f64 {
        self.matrix.diag[i]
    }

    fn abs_row_product(&self, i: usize, x: &[f64]) -> f64 {
        let c = &self.matrix;
        let left = i.checked_sub(1).map_or(0.0, |h| (c.off[h] * x[h]).abs());
        let right = c.off.get(i).map_or(0.0, |o| (o * x[i + 1]).abs());
        (c.diag[i] * x[i]).abs() + left + right
    }

    /// A row of `C z` is three products and two additions, then `− b_i − r_i` two more, so an
    /// exactly rounded answer leaves up to about 6 ulps of `|C||z| + |b| + |r|`, and a
    /// backward-stable tridiagonal solve about 4 more (`|L||D||Lᵀ| = |C|` for SPD tridiagonal
    /// matrices); 32 gives a margin of three.
    fn roundoff_ulps(&self) -> f64 {
        32.0
    }

    /// Column `j` holds `C[j−1][j]` (for `j > 0`) and `C[j][j]`.
    fn upper_triangle(&self) -> Csc {
        let c = &self.matrix;
        let n = c.dim();
        let mut indptr = Vec::with_capacity(n + 1);
        let mut indices = Vec::with_capacity(2 * n);
        let mut data = Vec::with_capacity(2 * n);
        indptr.push(0);
        for j in 0..n {
            if j > 0 {
                indices.push(j - 1);
                data.push(c.off[j - 1]);
            }
            indices.push(j);
            data.push(c.diag[j]);
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

/// The plane body's step matrix: values on a symmetric CSR pattern, with its sparse Cholesky
/// factorisation.
pub struct SparseSystem {
    pub pattern: Pattern,
    pub values: Vec<f64>,
    pub factor: SparseCholesky,
}

impl SparseSystem {
    /// Factorises the matrix `values` on `pattern`; `matrix` names it in errors.
    pub fn new(
        pattern: &Pattern,
        values: &[f64],
        matrix: &'static str,
    ) -> Result<Self, FactorError> {
        Ok(Self {
            factor: SparseCholesky::new(pattern, values, matrix)?,
            pattern: pattern.clone(),
            values: values.to_vec(),
        })
    }
}

impl SpdSystem for SparseSystem {
    fn dim(&self) -> usize {
        self.pattern.n
    }

    fn mul_into(&self, x: &[f64], y: &mut [f64]) {
        self.pattern.mul_into(&self.values, x, y);
    }

    fn solve_in_place(&mut self, x: &mut [f64]) {
        self.factor.solve_in_place(x);
    }

    fn solve_columns_in_place(&mut self, x: &mut [f64], ncols: usize) {
        self.factor.solve_columns_in_place(x, ncols);
    }

    fn inf_norm(&self) -> f64 {
        let p = &self.pattern;
        (0..p.n)
            .map(|r| {
                (p.row_ptr[r]..p.row_ptr[r + 1])
                    .map(|k| self.values[k].abs())
                    .sum()
            })
            .fold(0.0f64, f64::max)
    }

    fn diagonal(&self, i: usize) -> f64 {
        self.values[self.pattern.position(i, i)]
    }

    fn abs_row_product(&self, i: usize, x: &[f64]) -> f64 {
        let p = &self.pattern;
        (p.row_ptr[i]..p.row_ptr[i + 1])
            .map(|k| (self.values[k] * x[p.cols[k]]).abs())
            .sum()
    }

    /// A row of `C z` sums 18 products (about 18 ulps of `|C||z|`), the sparse solve that
    /// produced `z` adds its backward error (below 16 ulps, [`SparseCholesky`]), `− b + r`
    /// two more; 64 leaves a margin of about two.
    fn roundoff_ulps(&self) -> f64 {
        64.0
    }

    /// Column `j` of the upper triangle is row `j`'s columns `<= j` (the pattern is symmetric).
    fn upper_triangle(&self) -> Csc {
        let p = &self.pattern;
        let (mut indptr, mut indices, mut data) = (vec![0], Vec::new(), Vec::new());
        for r in 0..p.n {
            let range = p.row_ptr[r]..p.row_ptr[r + 1];
            for (&col, &v) in p.cols[range.clone()].iter().zip(&self.values[range]) {
                if col <= r {
                    indices.push(col);
                    data.push(v);
                }
            }
            indptr.push(indices.len());
        }
        Csc {
            nrows: p.n,
            ncols: p.n,
            indptr,
            indices,
            data,
        }
    }
}
