//! Symmetric tridiagonal matrices: the matrix type, its products and quadratic forms (in
//! difference form, exact for rigid motions), and the interior coefficients of a uniform mesh.
//! nalgebra has no banded solver; the factorisation is in [`super::kernels::ldlt`].

/// A symmetric tridiagonal matrix: `diag[i] = A[i][i]`, `off[i] = A[i][i+1] = A[i+1][i]`.
#[derive(Clone, Debug, PartialEq)]
pub struct SymTridiag {
    pub diag: Vec<f64>,
    pub off: Vec<f64>,
    /// Row sums `s_i = A_i,i−1 + A_ii + A_i,i+1`, for the difference form of the kernels.
    row_sums: Vec<f64>,
}

/// `s_i = (A_i,i−1 + A_ii) + A_i,i+1` with absent neighbours 0 (`0.0 + d` and `… + 0.0` kept:
/// they turn a −0 into +0), the interior in one branch-free pass.
fn row_sums(diag: &[f64], off: &[f64]) -> Vec<f64> {
    let n = diag.len();
    let mut s = Vec::with_capacity(n);
    if n >= 2 {
        s.push(0.0);
        s.extend((off.windows(2).zip(&diag[1..n - 1])).map(|(lr, d)| (lr[0] + d) + lr[1]));
    }
    s.resize(n, 0.0);
    set_end_sums(diag, off, &mut s);
    s
}

/// The row sums of the end rows into `s` (the formula of [`row_sums`]; one neighbour each, none
/// when `n = 1`).
fn set_end_sums(diag: &[f64], off: &[f64], s: &mut [f64]) {
    let n = diag.len();
    match n {
        0 => {}
        1 => s[0] = (0.0 + diag[0]) + 0.0,
        _ => {
            s[0] = (0.0 + diag[0]) + off[0];
            s[n - 1] = (off[n - 2] + diag[n - 1]) + 0.0;
        }
    }
}

impl SymTridiag {
    /// Builds the matrix; `off` must have one entry fewer than `diag` (none for an empty matrix).
    pub fn new(diag: Vec<f64>, off: Vec<f64>) -> Self {
        assert_eq!(
            off.len(),
            diag.len().saturating_sub(1),
            "off-diagonal length"
        );
        let row_sums = row_sums(&diag, &off);
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

    /// `‖A‖∞`, the largest absolute row sum.
    pub fn inf_norm(&self) -> f64 {
        let n = self.dim();
        (0..n)
            .map(|i| {
                let left = if i > 0 { self.off[i - 1].abs() } else { 0.0 };
                let right = if i + 1 < n { self.off[i].abs() } else { 0.0 };
                left + self.diag[i].abs() + right
            })
            .fold(0.0, f64::max)
    }

    /// The principal sub-matrix on rows and columns `first..=last`.
    pub fn sub(&self, first: usize, last: usize) -> SymTridiag {
        SymTridiag::new(
            self.diag[first..=last].to_vec(),
            self.off[first..last].to_vec(),
        )
    }

    /// [`SymTridiag::sub`], reusing this matrix's storage, row sums included: an interior row
    /// of the sub-matrix keeps both neighbours, so its sum has the same bits; only the two end
    /// rows are summed again (no J-sized vector allocated and filled at set-up).
    pub fn into_sub(self, first: usize, last: usize) -> SymTridiag {
        let (mut diag, mut off, mut s) = (self.diag, self.off, self.row_sums);
        diag.truncate(last + 1);
        diag.drain(..first);
        off.truncate(last);
        off.drain(..first);
        s.truncate(last + 1);
        s.drain(..first);
        set_end_sums(&diag, &off, &mut s);
        SymTridiag {
            diag,
            off,
            row_sums: s,
        }
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
                // The interior through zipped windows: no bounds checks, the same expression.
                for (((yi, si), ei), xi) in (y[1..n - 1].iter_mut())
                    .zip(&s[1..n - 1])
                    .zip(e.windows(2))
                    .zip(x.windows(3))
                {
                    *yi = si * xi[1] + ei[0] * (xi[0] - xi[1]) + ei[1] * (xi[2] - xi[1]);
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
        for (s, xi) in self.row_sums.iter().zip(&x[..n]) {
            q += s * xi * xi;
        }
        // The same sum in the same order, through windows (no bounds checks).
        for (e, w) in self.off.iter().zip(x[..n].windows(2)) {
            let d = w[1] - w[0];
            q -= e * d * d;
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

/// The interior coefficients of a symmetric tridiagonal matrix whose interior rows (`1..n−1`)
/// are all alike (the uniform mesh): the row sum `s` and the off-diagonal `e`, read by the
/// optimised twins of the bar's kernels as two numbers instead of two streams.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Uniform {
    pub s: f64,
    pub e: f64,
}

impl SymTridiag {
    /// The interior coefficients as two numbers, when every interior row sum and every
    /// off-diagonal entry are bitwise equal (the uniform mesh).
    pub fn uniform(&self) -> Option<Uniform> {
        let n = self.dim();
        let e = *self.off.first()?;
        let s = if n > 2 { self.row_sums[1] } else { 0.0 };
        let same = |v: &[f64], x: f64| v.iter().all(|y| y.to_bits() == x.to_bits());
        (same(&self.off, e) && same(&self.row_sums[1..n - 1], s)).then_some(Uniform { s, e })
    }
}

/// Normwise backward error of an approximate solution `x` of `A x = b`, in units of ε:
/// `‖b − A x‖∞ / ((‖A‖∞ ‖x‖∞ + ‖b‖∞) ε)`, the smallest relative perturbation of `A` and `b`
/// that `x` solves exactly (Rigal and Gaches; Higham, *Accuracy and Stability*, Thm 7.1).
pub fn backward_error(a: &SymTridiag, x: &[f64], b: &[f64]) -> f64 {
    let max_abs = |v: &[f64]| v.iter().fold(0.0f64, |m, w| m.max(w.abs()));
    let residual = (a.mul(x).iter().zip(b)).fold(0.0f64, |m, (p, q)| m.max((p - q).abs()));
    let scale = a.inf_norm() * max_abs(x) + max_abs(b);
    if scale == 0.0 {
        0.0
    } else {
        residual / scale / f64::EPSILON
    }
}

/// `xᵀ y`.
pub fn dot(x: &[f64], y: &[f64]) -> f64 {
    x.iter().zip(y).map(|(a, b)| a * b).sum()
}

#[cfg(test)]
mod tests {
    use super::*;

    /// `into_sub` keeps the interior row sums it had: every entry of the result, row sums
    /// included, has the bits `sub` computes afresh (signed zeros too).
    #[test]
    fn into_sub_has_the_bits_of_sub() {
        let bits = |v: &[f64]| v.iter().map(|x| x.to_bits()).collect::<Vec<_>>();
        for n in 1..8 {
            let diag: Vec<f64> = (0..n).map(|i| [0.3, -0.0, 1.0 / 3.0, 7.5][i % 4]).collect();
            let off: Vec<f64> = (1..n).map(|i| [-0.0, 0.1, -2.0 / 7.0][i % 3]).collect();
            let a = SymTridiag::new(diag, off);
            for first in 0..n {
                for last in first..n {
                    let (want, got) = (a.sub(first, last), a.clone().into_sub(first, last));
                    assert_eq!(bits(&got.diag), bits(&want.diag));
                    assert_eq!(bits(&got.off), bits(&want.off));
                    assert_eq!(
                        bits(got.row_sums()),
                        bits(want.row_sums()),
                        "{n} {first}..={last}"
                    );
                }
            }
        }
    }
}
