//! `A = L D Lᵀ` of a symmetric positive definite tridiagonal matrix by Thomas' algorithm: the
//! pivots `d_i` and multipliers `l_i` computed once, then each solve a forward and a back
//! substitution. Also the factorisations of `A` with a few rows changed, each from scratch,
//! that the exact and penalty solvers need. The per-step solve runs the optimised twin
//! [`super::ldlt_fast`].

use crate::linalg::tridiag::SymTridiag;

/// `A = L D Lᵀ`, `L` unit lower bidiagonal: `d_0 = A_00`, and for `i >= 1`
/// `l_{i−1} = A_{i,i−1}/d_{i−1}`, `d_i = A_ii − l_{i−1} A_{i,i−1}`. Gaussian elimination without
/// pivoting on a positive definite matrix: backward stable (Higham, *Accuracy and Stability of
/// Numerical Algorithms*, 2nd ed., Thm 9.3 and §9.5).
#[derive(Clone, Debug)]
pub struct Ldlt {
    d: Vec<f64>,
    l: Vec<f64>,
}

/// How [`Ldlt::factor_with_rows_changed`] changes the rows (and columns) of its nodes.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum RowChange {
    /// Replaced by identity ones: the exact solver's active set, `z_j = lo_j`.
    Identity,
    /// This added to the diagonal entry: the penalty solver's contact spring `1/ε`.
    AddToDiagonal(f64),
}

/// The matrix was not numerically positive definite: pivot `index` came out as `pivot`.
#[derive(Clone, Copy, Debug, PartialEq, thiserror::Error)]
#[error("matrix is not positive definite: pivot {index} is {pivot:e}")]
pub struct NotPositiveDefinite {
    pub index: usize,
    pub pivot: f64,
}

/// `pivot` if it is positive and finite, else the error naming row `index`.
pub(crate) fn checked_pivot(index: usize, pivot: f64) -> Result<f64, NotPositiveDefinite> {
    if pivot > 0.0 && pivot.is_finite() {
        Ok(pivot)
    } else {
        Err(NotPositiveDefinite { index, pivot })
    }
}

/// The diagonal and the off-diagonal of `a` with the rows and columns of `nodes` changed by
/// `change`, as functions of the row (the matrix the modified factorisations factor).
pub(crate) fn changed_entries<'a>(
    a: &'a SymTridiag,
    nodes: &'a [usize],
    change: RowChange,
) -> (impl Fn(usize) -> f64 + 'a, impl Fn(usize) -> f64 + 'a) {
    let changed = move |i: usize| nodes.contains(&i);
    let diag = move |i: usize| match change {
        _ if !changed(i) => a.diag[i],
        RowChange::Identity => 1.0,
        RowChange::AddToDiagonal(s) => a.diag[i] + s,
    };
    let off = move |i: usize| match change {
        RowChange::Identity if changed(i) || changed(i + 1) => 0.0,
        _ => a.off[i],
    };
    (diag, off)
}

impl Ldlt {
    pub fn factor(a: &SymTridiag) -> Result<Self, NotPositiveDefinite> {
        Self::factor_by(a.dim(), |i| a.diag[i], |i| a.off[i])
    }

    /// The factorisation of `a` with the rows and columns of `nodes` replaced by identity ones.
    pub fn factor_with_identity_rows(
        a: &SymTridiag,
        nodes: &[usize],
    ) -> Result<Self, NotPositiveDefinite> {
        Self::factor_with_rows_changed(a, nodes, RowChange::Identity)
    }

    /// The factorisation of `a` with the rows of `nodes` changed by `change`.
    pub fn factor_with_rows_changed(
        a: &SymTridiag,
        nodes: &[usize],
        change: RowChange,
    ) -> Result<Self, NotPositiveDefinite> {
        let (diag, off) = changed_entries(a, nodes, change);
        Self::factor_by(a.dim(), diag, off)
    }

    /// The factorisation of the matrix with diagonal `a(i)` and off-diagonal `e(i) = A_i,i+1`.
    fn factor_by(
        n: usize,
        a: impl Fn(usize) -> f64,
        e: impl Fn(usize) -> f64,
    ) -> Result<Self, NotPositiveDefinite> {
        let mut d = Vec::with_capacity(n);
        let mut l = Vec::with_capacity(n.saturating_sub(1));
        for i in 0..n {
            let pivot = if i == 0 {
                a(0)
            } else {
                let li = e(i - 1) / d[i - 1];
                l.push(li);
                a(i) - li * e(i - 1)
            };
            d.push(checked_pivot(i, pivot)?);
        }
        Ok(Self { d, l })
    }

    pub fn dim(&self) -> usize {
        self.d.len()
    }

    /// Overwrites `x` (holding `b`) with `A⁻¹ b`: `L y = b` forward, then `D Lᵀ x = y` back.
    pub fn solve_in_place(&self, x: &mut [f64]) {
        let n = self.dim();
        assert_eq!(x.len(), n, "right-hand side length");
        for i in 1..n {
            x[i] -= self.l[i - 1] * x[i - 1];
        }
        for i in (0..n).rev() {
            x[i] /= self.d[i];
            if i + 1 < n {
                x[i] -= self.l[i] * x[i + 1];
            }
        }
    }

    /// `x = A⁻¹ b`.
    pub fn solve_into(&self, b: &[f64], x: &mut [f64]) {
        x.copy_from_slice(b);
        self.solve_in_place(x);
    }

    /// `A⁻¹ e_j` as a new vector (set-up only).
    pub fn column_of_inverse(&self, j: usize) -> Vec<f64> {
        let mut c = vec![0.0; self.dim()];
        c[j] = 1.0;
        self.solve_in_place(&mut c);
        c
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The factorisation of a changed matrix is the factorisation of that matrix written out.
    #[test]
    fn changed_rows_factor_the_changed_matrix() {
        let n = 9;
        let a = SymTridiag::new(
            (0..n).map(|i| 3.0 + (i as f64).sin()).collect(),
            (0..n - 1).map(|i| (i as f64 * 1.3).cos()).collect(),
        );
        let bits = |f: &Ldlt| {
            let (d, l) = (f.d.iter(), f.l.iter());
            d.chain(l).map(|x| x.to_bits()).collect::<Vec<_>>()
        };
        let nodes = [0, 4, n - 1];
        let (mut di, mut off) = (a.diag.clone(), a.off.clone());
        for &c in &nodes {
            di[c] = 1.0;
            if c > 0 {
                off[c - 1] = 0.0;
            }
            if c + 1 < n {
                off[c] = 0.0;
            }
        }
        let written = Ldlt::factor(&SymTridiag::new(di, off)).unwrap();
        let changed = Ldlt::factor_with_identity_rows(&a, &nodes).unwrap();
        assert_eq!(bits(&changed), bits(&written));
        let mut ds = a.diag.clone();
        ds[2] += 7.5;
        let written = Ldlt::factor(&SymTridiag::new(ds, a.off.clone())).unwrap();
        let shifted =
            Ldlt::factor_with_rows_changed(&a, &[2], RowChange::AddToDiagonal(7.5)).unwrap();
        assert_eq!(bits(&shifted), bits(&written));
    }

    /// A matrix that is not positive definite is refused, naming the row whose pivot failed.
    #[test]
    fn an_indefinite_matrix_is_refused_at_its_pivot() {
        let a = SymTridiag::new(vec![1.0, 1.0, 1.0], vec![0.5, 1.0]);
        let err = Ldlt::factor(&a).unwrap_err();
        assert_eq!(err.index, 2);
        assert!(err.pivot <= 0.0);
    }
}
