//! Symmetric banded matrices of half-bandwidth `P` and their `LDLᵀ` without pivoting, for the
//! symmetric quasi-definite matrices `[[A, B], [Bᵀ, −C]]` (`A`, `C` positive definite) of
//! coupled problems: every symmetric permutation of such a matrix has an `LDLᵀ` with `D`
//! nonsingular (Vanderbei, SIAM J. Optim. 5 (1995) 100–113), so an ordering that keeps the
//! band (the two fields interleaved node by node) is factorised as it stands, once. The signs
//! of `D` give the inertia (as many positive pivots as `A` has rows). Test-only: the
//! independent reference the block factor ([`super::block_tridiag`]) is checked against.

/// A symmetric `n × n` matrix with `A_ij = 0` for `|i − j| > P`: the diagonal and, per row `i`,
/// `lower[i][s − 1] = A_{i, i−s}` for `s = 1..=P` (0 where `i < s`).
#[derive(Clone, Debug, PartialEq)]
pub struct SymBanded<const P: usize> {
    pub diag: Vec<f64>,
    pub lower: Vec<[f64; P]>,
}

impl<const P: usize> SymBanded<P> {
    /// The zero matrix of order `n`.
    pub fn zeros(n: usize) -> Self {
        Self {
            diag: vec![0.0; n],
            lower: vec![[0.0; P]; n],
        }
    }

    pub fn dim(&self) -> usize {
        self.diag.len()
    }

    /// `A_ij` (`0` outside the band).
    pub fn get(&self, i: usize, j: usize) -> f64 {
        let (hi, lo) = (i.max(j), i.min(j));
        match hi - lo {
            0 => self.diag[i],
            s if s <= P => self.lower[hi][s - 1],
            _ => 0.0,
        }
    }

    /// `A_ij += v` and `A_ji += v` (once on the diagonal); `|i − j| <= P`.
    pub fn add(&mut self, i: usize, j: usize, v: f64) {
        let (hi, lo) = (i.max(j), i.min(j));
        match hi - lo {
            0 => self.diag[i] += v,
            s => {
                assert!(s <= P, "entry ({i}, {j}) outside the band {P}");
                self.lower[hi][s - 1] += v;
            }
        }
    }

    /// `y = A x`.
    pub fn mul_into(&self, x: &[f64], y: &mut [f64]) {
        let n = self.dim();
        for i in 0..n {
            let mut s = self.diag[i] * x[i];
            for d in 1..=P.min(i) {
                s += self.lower[i][d - 1] * x[i - d];
            }
            for d in 1..=P.min(n - 1 - i) {
                s += self.lower[i + d][d - 1] * x[i + d];
            }
            y[i] = s;
        }
    }
}

/// A zero or non-finite pivot: the matrix is not quasi-definite (or not finite).
#[derive(Clone, Copy, Debug, PartialEq, thiserror::Error)]
#[error("pivot {pivot} of the banded LDLᵀ at row {row} is zero or not finite")]
pub struct ZeroPivot {
    pub row: usize,
    pub pivot: f64,
}

/// `A = L D Lᵀ`, `L` unit lower triangular with the band of `A`, `D` diagonal (of either sign).
#[derive(Clone, Debug)]
pub struct BandedLdlt<const P: usize> {
    /// `l[i][s − 1] = L_{i, i−s}`.
    l: Vec<[f64; P]>,
    /// The columns of `L` below the diagonal, row by row for the backward solve:
    /// `lt[i][s − 1] = L_{i+s, i}` (0 past the end).
    lt: Vec<[f64; P]>,
    d: Vec<f64>,
    inv_d: Vec<f64>,
}

impl<const P: usize> BandedLdlt<P> {
    /// Factorises `a` row by row (`O(n P²)`): `t_j = A_ij − Σ_k t_k L_jk` (`t_j = L_ij d_j`),
    /// `d_i = A_ii − Σ_j t_j L_ij`.
    pub fn factor(a: &SymBanded<P>) -> Result<Self, ZeroPivot> {
        let n = a.dim();
        let mut l = vec![[0.0; P]; n];
        let mut d = vec![0.0; n];
        for i in 0..n {
            let lo = i.saturating_sub(P);
            let mut t = [0.0; P];
            let mut di = a.diag[i];
            for j in lo..i {
                let mut tj = a.lower[i][i - j - 1];
                for k in lo.max(j.saturating_sub(P))..j {
                    tj -= t[i - k - 1] * l[j][j - k - 1];
                }
                let lij = tj / d[j];
                t[i - j - 1] = tj;
                l[i][i - j - 1] = lij;
                di -= tj * lij;
            }
            if !(di.is_finite() && di != 0.0) {
                return Err(ZeroPivot { row: i, pivot: di });
            }
            d[i] = di;
        }
        let inv_d = d.iter().map(|v| 1.0 / v).collect();
        let mut lt = vec![[0.0; P]; n];
        for (i, row) in lt.iter_mut().enumerate() {
            for (s, v) in row.iter_mut().enumerate() {
                if i + s + 1 < n {
                    *v = l[i + s + 1][s];
                }
            }
        }
        Ok(Self { l, lt, d, inv_d })
    }

    pub fn dim(&self) -> usize {
        self.d.len()
    }

    /// The positive and the negative pivots: the inertia of `A` (Sylvester).
    pub fn inertia(&self) -> (usize, usize) {
        let positive = self.d.iter().filter(|v| **v > 0.0).count();
        (positive, self.d.len() - positive)
    }

    /// `x ← A⁻¹ x`: `L y = x`, `y ← D⁻¹ y`, `Lᵀ x = y`, each sweep carrying the last `P`
    /// values (the band of `L` is 0 where it leaves the matrix). Allocates nothing.
    pub fn solve_in_place(&self, x: &mut [f64]) {
        let n = self.dim();
        let x = &mut x[..n];
        let mut w = [0.0; P];
        for (xi, li) in x.iter_mut().zip(&self.l) {
            // The term of the value just computed last: the sweep's dependency chain is one
            // multiply and one subtraction per row.
            let mut s = *xi;
            for d in (0..P).rev() {
                s -= li[d] * w[d];
            }
            w = std::array::from_fn(|d| if d == 0 { s } else { w[d - 1] });
            *xi = s;
        }
        let mut w = [0.0; P];
        for ((xi, li), inv) in x.iter_mut().zip(&self.lt).zip(&self.inv_d).rev() {
            let mut s = *xi * inv;
            for d in (0..P).rev() {
                s -= li[d] * w[d];
            }
            w = std::array::from_fn(|d| if d == 0 { s } else { w[d - 1] });
            *xi = s;
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A quasi-definite matrix interleaving an SPD tridiagonal block `A` (even rows) and a
    /// negative definite one `−C` (odd rows), coupled by a band `B`: the factor exists, its
    /// inertia is that of the blocks, and the solve reproduces a chosen solution to round-off.
    #[test]
    fn quasi_definite_interleaved_matrices_factor_and_solve() {
        for n in [1usize, 2, 3, 7, 40] {
            let mut a = SymBanded::<3>::zeros(2 * n);
            for i in 0..n {
                a.add(2 * i, 2 * i, 4.0 + (i as f64).sin());
                a.add(2 * i + 1, 2 * i + 1, -(3.0 + (i as f64).cos()));
                a.add(2 * i, 2 * i + 1, 0.7);
                if i + 1 < n {
                    a.add(2 * i, 2 * i + 2, -1.0);
                    a.add(2 * i + 1, 2 * i + 3, 0.9);
                    a.add(2 * i, 2 * i + 3, -0.5);
                    a.add(2 * i + 1, 2 * i + 2, 0.4);
                }
            }
            let f = BandedLdlt::factor(&a).unwrap();
            assert_eq!(f.inertia(), (n, n));
            let x: Vec<f64> = (0..2 * n).map(|i| (0.3 * i as f64).cos()).collect();
            let mut b = vec![0.0; 2 * n];
            a.mul_into(&x, &mut b);
            f.solve_in_place(&mut b);
            let err = x
                .iter()
                .zip(&b)
                .map(|(p, q)| (p - q).abs())
                .fold(0.0, f64::max);
            // Round-off: these blocks are well conditioned (κ below 100), so a backward-stable
            // solve leaves at most about 100 n ε.
            assert!(
                err <= 100.0 * (2 * n) as f64 * f64::EPSILON,
                "n {n}: {err:e}"
            );
            for i in 0..2 * n {
                for j in 0..2 * n {
                    assert_eq!(a.get(i, j), a.get(j, i));
                }
            }
        }
    }

    #[test]
    fn a_singular_matrix_is_refused() {
        let a = SymBanded::<1>::zeros(3);
        assert_eq!(BandedLdlt::factor(&a).unwrap_err().row, 0);
    }
}
