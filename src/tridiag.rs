//! Symmetric tridiagonal matrices and their LDLᵀ factorisation.
//!
//! nalgebra has no banded solver, so the O(n) kernels the time stepper needs live here: a
//! matrix-vector product, quadratic forms and a factorisation computed once per run and reused
//! for every step.

/// A symmetric tridiagonal matrix: `diag[i] = A[i][i]`, `off[i] = A[i][i+1] = A[i+1][i]`.
#[derive(Clone, Debug, PartialEq)]
pub struct SymTridiag {
    pub diag: Vec<f64>,
    pub off: Vec<f64>,
    /// Row sums `s_i = A_i,i−1 + A_ii + A_i,i+1`, for the difference form of the kernels.
    row_sums: Vec<f64>,
}

impl SymTridiag {
    /// Builds the matrix; `off` must have one entry fewer than `diag` (none for an empty matrix).
    pub fn new(diag: Vec<f64>, off: Vec<f64>) -> Self {
        assert_eq!(
            off.len(),
            diag.len().saturating_sub(1),
            "off-diagonal length"
        );
        let n = diag.len();
        let row_sums = (0..n)
            .map(|i| {
                let left = if i > 0 { off[i - 1] } else { 0.0 };
                let right = if i + 1 < n { off[i] } else { 0.0 };
                left + diag[i] + right
            })
            .collect();
        Self {
            diag,
            off,
            row_sums,
        }
    }

    pub fn dim(&self) -> usize {
        self.diag.len()
    }

    /// `a * self + b * other`, entrywise.
    pub fn combine(a: f64, x: &SymTridiag, b: f64, y: &SymTridiag) -> SymTridiag {
        assert_eq!(x.dim(), y.dim());
        let mix = |p: &[f64], q: &[f64]| p.iter().zip(q).map(|(p, q)| a * p + b * q).collect();
        SymTridiag::new(mix(&x.diag, &y.diag), mix(&x.off, &y.off))
    }

    /// The principal sub-matrix on rows and columns `first..=last`.
    pub fn sub(&self, first: usize, last: usize) -> SymTridiag {
        SymTridiag::new(
            self.diag[first..=last].to_vec(),
            self.off[first..last].to_vec(),
        )
    }

    /// `y = A x`, without allocating, in difference form
    /// `(Ax)_i = s_i x_i + A_i,i−1 (x_{i−1} − x_i) + A_i,i+1 (x_{i+1} − x_i)`: for the stiffness
    /// matrix (`s = 0`) the round-off is relative to the differences of `x`, so a rigid offset
    /// of the bar adds none.
    pub fn mul_into(&self, x: &[f64], y: &mut [f64]) {
        let n = self.dim();
        debug_assert!(x.len() == n && y.len() == n);
        match n {
            0 => {}
            1 => y[0] = self.diag[0] * x[0],
            _ => {
                let (s, e) = (&self.row_sums, &self.off);
                y[0] = s[0] * x[0] + e[0] * (x[1] - x[0]);
                for i in 1..n - 1 {
                    y[i] = s[i] * x[i] + e[i - 1] * (x[i - 1] - x[i]) + e[i] * (x[i + 1] - x[i]);
                }
                y[n - 1] = s[n - 1] * x[n - 1] + e[n - 2] * (x[n - 2] - x[n - 1]);
            }
        }
    }

    /// `A x` as a new vector (set-up and tests only).
    pub fn mul(&self, x: &[f64]) -> Vec<f64> {
        let mut y = vec![0.0; x.len()];
        self.mul_into(x, &mut y);
        y
    }

    /// The quadratic form `xᵀ A x = Σ s_i x_i² − Σ A_i,i+1 (x_{i+1} − x_i)²` (difference form,
    /// exact zero for rigid motions of the stiffness matrix).
    pub fn quad(&self, x: &[f64]) -> f64 {
        let n = self.dim();
        let mut q = 0.0;
        for i in 0..n {
            q += self.row_sums[i] * x[i] * x[i];
        }
        for i in 0..n.saturating_sub(1) {
            let d = x[i + 1] - x[i];
            q -= self.off[i] * d * d;
        }
        q
    }

    /// `(x + y)ᵀ A (x + y)`, in difference form, without forming `x + y`.
    pub fn quad_of_sum(&self, x: &[f64], y: &[f64]) -> f64 {
        let n = self.dim();
        let mut q = 0.0;
        for i in 0..n {
            let v = x[i] + y[i];
            q += self.row_sums[i] * v * v;
        }
        for i in 0..n.saturating_sub(1) {
            let d = (x[i + 1] + y[i + 1]) - (x[i] + y[i]);
            q -= self.off[i] * d * d;
        }
        q
    }

    /// Row sums `s_i` (zero for a matrix that annihilates constants).
    pub fn row_sums(&self) -> &[f64] {
        &self.row_sums
    }

    /// Dense copy (tests and small oracles).
    pub fn to_dense(&self) -> nalgebra::DMatrix<f64> {
        let n = self.dim();
        nalgebra::DMatrix::from_fn(n, n, |i, j| {
            if i == j {
                self.diag[i]
            } else if i + 1 == j {
                self.off[i]
            } else if j + 1 == i {
                self.off[j]
            } else {
                0.0
            }
        })
    }
}

/// `xᵀ y`.
pub fn dot(x: &[f64], y: &[f64]) -> f64 {
    x.iter().zip(y).map(|(a, b)| a * b).sum()
}

/// A twisted factorisation of a symmetric positive definite tridiagonal matrix ("burn at both
/// ends"): `L D Lᵀ` from the top for rows `0..m`, `U D Uᵀ` from the bottom for rows `m+1..n`,
/// joined at the twist row `m = n/2`. Computed once per run. A solve runs the two elimination
/// chains (top-down and bottom-up) interleaved in one loop, so the processor overlaps two
/// dependent multiply-subtract chains instead of waiting on one: about half the latency of the
/// plain `L D Lᵀ` sweep, with the same number of operations and no fused multiply-add (results
/// do not depend on target-cpu flags).
#[derive(Clone, Debug)]
pub struct Ldlt {
    /// Multipliers: `l[i] = e_i / d_i` for `i < m` (top chain) and `l[i] = e_{i−1} / d_i` for
    /// `i > m` (bottom chain); unused at `m`.
    l: Vec<f64>,
    /// `1 / d_i`, with `d_m = γ_m` the twist pivot.
    inv_d: Vec<f64>,
    /// Off-diagonal of `A`, needed by the outward sweeps.
    off: Vec<f64>,
    twist: usize,
}

/// The matrix was not numerically positive definite: pivot `index` came out as `pivot`.
#[derive(Clone, Copy, Debug, PartialEq, thiserror::Error)]
#[error("matrix is not positive definite: pivot {index} is {pivot:e}")]
pub struct NotPositiveDefinite {
    pub index: usize,
    pub pivot: f64,
}

impl Ldlt {
    pub fn factor(a: &SymTridiag) -> Result<Self, NotPositiveDefinite> {
        let n = a.dim();
        let twist = n / 2;
        let mut l = vec![0.0; n];
        let mut inv_d = vec![0.0; n];
        let check = |index: usize, pivot: f64| {
            if pivot > 0.0 && pivot.is_finite() {
                Ok(pivot)
            } else {
                Err(NotPositiveDefinite { index, pivot })
            }
        };
        let (d, e) = (&a.diag, &a.off);
        let mut top = 0.0;
        for i in 0..twist {
            let p = if i == 0 {
                d[0]
            } else {
                d[i] - e[i - 1] * l[i - 1]
            };
            top = check(i, p)?;
            inv_d[i] = 1.0 / top;
            l[i] = e[i] / top;
        }
        let mut bottom = 0.0;
        for i in (twist + 1..n).rev() {
            let p = if i == n - 1 {
                d[i]
            } else {
                d[i] - e[i] * l[i + 1]
            };
            bottom = check(i, p)?;
            inv_d[i] = 1.0 / bottom;
            l[i] = e[i - 1] / bottom;
        }
        if n > 0 {
            let mut g = d[twist];
            if twist > 0 {
                g -= e[twist - 1] * l[twist - 1];
            }
            if twist + 1 < n {
                g -= e[twist] * l[twist + 1];
            }
            inv_d[twist] = 1.0 / check(twist, g)?;
        }
        let _ = (top, bottom);
        Ok(Self {
            l,
            inv_d,
            off: e.clone(),
            twist,
        })
    }

    pub fn dim(&self) -> usize {
        self.inv_d.len()
    }

    /// Overwrites `b` with `A⁻¹ b`: the two chains eliminate towards the twist row together,
    /// then substitute outwards together.
    pub fn solve_in_place(&self, b: &mut [f64]) {
        let n = self.dim();
        debug_assert_eq!(b.len(), n);
        if n == 0 {
            return;
        }
        let m = self.twist;
        let (l, inv_d, e) = (&self.l[..n], &self.inv_d[..n], &self.off[..]);
        // Inward: top rows 1..m (each uses the row above), bottom rows n−2..m+1 (the row below).
        let top_len = m; // rows 0..m
        let bottom_len = n - 1 - m; // rows m+1..n
        let common = top_len.min(bottom_len);
        for k in 1..common {
            let (i, j) = (k, n - 1 - k);
            b[i] -= l[i - 1] * b[i - 1];
            b[j] -= l[j + 1] * b[j + 1];
        }
        for i in common.max(1)..top_len {
            b[i] -= l[i - 1] * b[i - 1];
        }
        for k in common.max(1)..bottom_len {
            let j = n - 1 - k;
            b[j] -= l[j + 1] * b[j + 1];
        }
        // Twist row.
        let mut xm = b[m];
        if m > 0 {
            xm -= l[m - 1] * b[m - 1];
        }
        if m + 1 < n {
            xm -= l[m + 1] * b[m + 1];
        }
        b[m] = xm * inv_d[m];
        // Outward: x_i = (y_i − e_i x_{i+1}) / d_i above, (y_j − e_{j−1} x_{j−1}) / d_j below.
        for k in 1..=common {
            let (i, j) = (m - k, m + k);
            b[i] = (b[i] - e[i] * b[i + 1]) * inv_d[i];
            b[j] = (b[j] - e[j - 1] * b[j - 1]) * inv_d[j];
        }
        for k in common + 1..=top_len {
            let i = m - k;
            b[i] = (b[i] - e[i] * b[i + 1]) * inv_d[i];
        }
        for k in common + 1..=bottom_len {
            let j = m + k;
            b[j] = (b[j] - e[j - 1] * b[j - 1]) * inv_d[j];
        }
    }

    /// `A⁻¹ e_j` as a new vector (set-up only).
    pub fn column_of_inverse(&self, j: usize) -> Vec<f64> {
        let mut c = vec![0.0; self.dim()];
        c[j] = 1.0;
        self.solve_in_place(&mut c);
        c
    }
}
