//! Symmetric tridiagonal matrices and their LDLᵀ factorisation.
//!
//! nalgebra has no banded solver, so the O(n) kernels the time stepper needs live here: a
//! matrix-vector product, quadratic forms and a factorisation computed once per run and reused
//! for every step.

use std::sync::Arc;

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

    /// [`SymTridiag::sub`], reusing this matrix's storage.
    pub fn into_sub(self, first: usize, last: usize) -> SymTridiag {
        let (mut diag, mut off) = (self.diag, self.off);
        drop(self.row_sums);
        diag.truncate(last + 1);
        diag.drain(..first);
        off.truncate(last);
        off.drain(..first);
        SymTridiag::new(diag, off)
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

/// The interior rows (`1..n−1`) of a symmetric tridiagonal matrix as the per-step kernels read
/// them: the row sum `s_i` and the off-diagonals `e_{i−1}`, `e_i`. [`Rows`] reads them from the
/// matrix; [`Uniform`] holds the two numbers of a uniform mesh, so the kernels stream no
/// coefficient vectors (same values, same bits).
///
/// Quadratic forms over the interior are accumulated as `Σ ws_i x_i²` and `Σ we_i (Δx_i)²` and
/// scaled at the end: per row (`ws = s`, `we = e`, scales 1) or, on a uniform mesh, as plain
/// sums scaled once by `s` and `e` (half the multiplications).
pub trait Interior: Copy {
    fn s(self, i: usize) -> f64;
    /// `A_{i,i+1}`.
    fn e(self, i: usize) -> f64;
    /// Weights inside the sums, and the factors applied to the finished sums.
    fn ws(self, i: usize) -> f64;
    fn we(self, i: usize) -> f64;
    fn scale_s(self) -> f64;
    fn scale_e(self) -> f64;
}

/// Interior coefficients read row by row.
#[derive(Clone, Copy, Debug)]
pub struct Rows<'a> {
    s: &'a [f64],
    e: &'a [f64],
}

/// Interior coefficients that are the same on every interior row.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Uniform {
    s: f64,
    e: f64,
}

impl Interior for Rows<'_> {
    #[inline(always)]
    fn s(self, i: usize) -> f64 {
        self.s[i]
    }
    #[inline(always)]
    fn e(self, i: usize) -> f64 {
        self.e[i]
    }
    #[inline(always)]
    fn ws(self, i: usize) -> f64 {
        self.s[i]
    }
    #[inline(always)]
    fn we(self, i: usize) -> f64 {
        self.e[i]
    }
    fn scale_s(self) -> f64 {
        1.0
    }
    fn scale_e(self) -> f64 {
        1.0
    }
}

impl Interior for Uniform {
    #[inline(always)]
    fn s(self, _: usize) -> f64 {
        self.s
    }
    #[inline(always)]
    fn e(self, _: usize) -> f64 {
        self.e
    }
    #[inline(always)]
    fn ws(self, _: usize) -> f64 {
        1.0
    }
    #[inline(always)]
    fn we(self, _: usize) -> f64 {
        1.0
    }
    fn scale_s(self) -> f64 {
        self.s
    }
    fn scale_e(self) -> f64 {
        self.e
    }
}

impl SymTridiag {
    /// The interior coefficients, row by row.
    pub fn rows(&self) -> Rows<'_> {
        Rows {
            s: &self.row_sums,
            e: &self.off,
        }
    }

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

/// `u += z`, returning the new `max_i |u_i|` (four running maxima, so the loop vectorises;
/// the maximum is exact, so the order does not change the bits).
#[inline(never)]
pub fn add_in_place(u: &mut [f64], z: &[f64]) -> f64 {
    let mut m = [0.0f64; 4];
    let (mut uc, mut zc) = (u.chunks_exact_mut(4), z.chunks_exact(4));
    for (u4, z4) in (&mut uc).zip(&mut zc) {
        for k in 0..4 {
            u4[k] += z4[k];
            m[k] = m[k].max(u4[k].abs());
        }
    }
    for (ui, zi) in uc.into_remainder().iter_mut().zip(zc.remainder()) {
        *ui += zi;
        m[0] = m[0].max(ui.abs());
    }
    max4(m)
}

/// The largest of four running maxima.
pub(crate) fn max4(m: [f64; 4]) -> f64 {
    m[0].max(m[1]).max(m[2].max(m[3]))
}

/// `xᵀ y`.
pub fn dot(x: &[f64], y: &[f64]) -> f64 {
    x.iter().zip(y).map(|(a, b)| a * b).sum()
}

/// A twisted factorisation of a symmetric positive definite tridiagonal matrix ("burn at both
/// ends"): `L D Lᵀ` from the top for rows `0..m`, `U D Uᵀ` from the bottom for rows `m+1..n`,
/// joined at the twist row `m = n/2`. Computed once per run. A solve runs the two elimination
/// chains (top-down and bottom-up) interleaved in one loop, so the processor overlaps two
/// dependent chains instead of waiting on one: about half the latency of the plain `L D Lᵀ`
/// sweep, with the same number of operations and no fused multiply-add (results do not depend
/// on target-cpu flags).
///
/// Each link of either chain is one multiply and one subtract: the inward sweep stores
/// `y_i / d_i` beside the chain (off the critical path), so the outward sweep is
/// `x_i = y_i/d_i − l_i x_{i±1}` with the same multipliers `l_i = e_i/d_i`.
#[derive(Clone, Debug)]
pub struct Ldlt {
    /// `(l_i, 1/d_i)` in the order the inward sweep visits the rows: `top[i]` for rows
    /// `i = 0..m` (`l_i = e_i/d_i`), `bottom[k]` for rows `j = n−1−k > m` (`l_j = e_{j−1}/d_j`).
    /// Shared (see [`Ldlt::share_halves`]): a half is stored once however many factorisations
    /// have it bitwise.
    top: Arc<Vec<[f64; 2]>>,
    bottom: Arc<Vec<[f64; 2]>>,
    /// `1/γ_m`, the twist pivot.
    inv_twist: f64,
    n: usize,
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
        Self::factor_by(a.dim(), |i| a.diag[i], |i| a.off[i])
    }

    /// The factorisation of `a` with the rows and columns of `nodes` replaced by identity ones
    /// (the same entries the factorisation of that modified matrix reads, without copying it).
    pub fn factor_with_identity_rows(
        a: &SymTridiag,
        nodes: &[usize],
    ) -> Result<Self, NotPositiveDefinite> {
        let identity = |i: usize| nodes.contains(&i);
        Self::factor_by(
            a.dim(),
            |i| if identity(i) { 1.0 } else { a.diag[i] },
            |i| {
                if identity(i) || identity(i + 1) {
                    0.0
                } else {
                    a.off[i]
                }
            },
        )
    }

    /// Makes each half that is bitwise equal to a half of `other` share its storage (a
    /// factorisation with identity rows at one end differs from the plain one in one half).
    pub fn share_halves(&mut self, other: &Ldlt) {
        let same = |a: &[[f64; 2]], b: &[[f64; 2]]| {
            a.len() == b.len()
                && a.iter().zip(b).all(|(x, y)| {
                    x[0].to_bits() == y[0].to_bits() && x[1].to_bits() == y[1].to_bits()
                })
        };
        for mine in [&mut self.top, &mut self.bottom] {
            for theirs in [&other.top, &other.bottom] {
                if !Arc::ptr_eq(mine, theirs) && same(mine, theirs) {
                    *mine = Arc::clone(theirs);
                }
            }
        }
    }

    /// The factorisation of the matrix with diagonal `d(i)` and off-diagonal `e(i) = A_i,i+1`.
    fn factor_by(
        n: usize,
        d: impl Fn(usize) -> f64,
        e: impl Fn(usize) -> f64,
    ) -> Result<Self, NotPositiveDefinite> {
        let twist = n / 2;
        let check = |index: usize, pivot: f64| {
            if pivot > 0.0 && pivot.is_finite() {
                Ok(pivot)
            } else {
                Err(NotPositiveDefinite { index, pivot })
            }
        };
        let mut top = Vec::with_capacity(twist);
        let mut l_prev = 0.0;
        for i in 0..twist {
            let p = if i == 0 {
                d(0)
            } else {
                d(i) - e(i - 1) * l_prev
            };
            let p = check(i, p)?;
            l_prev = e(i) / p;
            top.push([l_prev, 1.0 / p]);
        }
        let mut bottom = Vec::with_capacity(n.saturating_sub(twist + 1));
        let mut l_next = 0.0;
        for i in (twist + 1..n).rev() {
            let p = if i == n - 1 {
                d(i)
            } else {
                d(i) - e(i) * l_next
            };
            let p = check(i, p)?;
            l_next = e(i - 1) / p;
            bottom.push([l_next, 1.0 / p]);
        }
        let mut inv_twist = 0.0;
        if n > 0 {
            let mut g = d(twist);
            if twist > 0 {
                g -= e(twist - 1) * l_prev;
            }
            if twist + 1 < n {
                g -= e(twist) * l_next;
            }
            inv_twist = 1.0 / check(twist, g)?;
        }
        Ok(Self {
            top: Arc::new(top),
            bottom: Arc::new(bottom),
            inv_twist,
            n,
        })
    }

    pub fn dim(&self) -> usize {
        self.n
    }

    /// Overwrites `b` with `A⁻¹ b`: the two chains eliminate towards the twist row together,
    /// then substitute outwards together.
    pub fn solve_in_place(&self, b: &mut [f64]) {
        let n = self.dim();
        assert_eq!(b.len(), n, "right-hand side length");
        if n == 0 {
            return;
        }
        let (top_f, bottom_f) = (&self.top[..], &self.bottom[..]);
        let m = top_f.len();
        let (upper, rest) = b.split_at_mut(m);
        let (mid, lower) = rest.split_at_mut(1);
        // Inward: y_i = b_i − l_{i−1} y_{i−1} (top), y_j = b_j − l_{j+1} y_{j+1} (bottom);
        // b keeps y/d.
        let (mut yt, mut yb) = (0.0, 0.0);
        let (mut lt, mut lb) = (0.0, 0.0);
        // `take`: a bare `zip` would consume one element of the longer chain and drop it.
        let common = top_f.len().min(bottom_f.len());
        let mut top = upper.iter_mut().zip(top_f);
        let mut bottom = lower.iter_mut().rev().zip(bottom_f);
        for ((bt, ft), (bb, fb)) in top.by_ref().take(common).zip(bottom.by_ref().take(common)) {
            yt = *bt - lt * yt;
            yb = *bb - lb * yb;
            *bt = yt * ft[1];
            *bb = yb * fb[1];
            (lt, lb) = (ft[0], fb[0]);
        }
        for (bt, ft) in top {
            yt = *bt - lt * yt;
            *bt = yt * ft[1];
            lt = ft[0];
        }
        for (bb, fb) in bottom {
            yb = *bb - lb * yb;
            *bb = yb * fb[1];
            lb = fb[0];
        }
        // Twist row: the products are 0 when a side is empty (l = 0, y = 0).
        let xm = (mid[0] - lt * yt - lb * yb) * self.inv_twist;
        mid[0] = xm;
        // Outward: x_i = y_i/d_i − l_i x_{i+1} (top), x_j = y_j/d_j − l_j x_{j−1} (bottom).
        let (mut xt, mut xb) = (xm, xm);
        let mut top = upper.iter_mut().rev().zip(top_f.iter().rev());
        let mut bottom = lower.iter_mut().zip(bottom_f.iter().rev());
        for ((bt, ft), (bb, fb)) in top.by_ref().take(common).zip(bottom.by_ref().take(common)) {
            xt = *bt - ft[0] * xt;
            xb = *bb - fb[0] * xb;
            *bt = xt;
            *bb = xb;
        }
        for (bt, ft) in top {
            xt = *bt - ft[0] * xt;
            *bt = xt;
        }
        for (bb, fb) in bottom {
            xb = *bb - fb[0] * xb;
            *bb = xb;
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
