//! Symmetric tridiagonal matrices and their LDLᵀ factorisation.
//!
//! nalgebra has no banded solver, so the O(n) kernels the time stepper needs live here: a
//! matrix-vector product, quadratic forms and a factorisation computed once per run and reused
//! for every step.

use crate::linalg::dispatch;
use std::cell::Cell;
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
        for (s, xi) in self.row_sums.iter().zip(&x[..n]) {
            q += s * xi * xi;
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
/// coefficient vectors. The right-hand side gets the same bits either way; the energy sums
/// do not (the uniform kernel sums in four lanes and scales once), and agree to round-off
/// (`simulation::tests::uniform_and_row_energy_sums_agree`).
///
/// Quadratic forms over the interior are accumulated as `Σ ws_i x_i²` and `Σ we_i (Δx_i)²` and
/// scaled at the end: per row (`ws = s`, `we = e`, scales 1) or, on a uniform mesh, as plain
/// sums scaled once by `s` and `e` (half the multiplications).
pub trait Interior: Copy {
    /// Whether every row has the same coefficients (the kernels may then factor them out).
    const UNIFORM: bool;
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
    const UNIFORM: bool = false;
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
    const UNIFORM: bool = true;
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

/// `u += z`, returning the new `max_i |u_i|`: `add_columns_in_place` with no column.
pub fn add_in_place(u: &mut [f64], z: &[f64]) -> f64 {
    #[cfg(target_arch = "x86_64")]
    if dispatch::has_avx() {
        // SAFETY: the CPU supports AVX.
        return unsafe { update_avx::<0, false>(u, z.as_ptr().cast_mut(), z.len(), []) };
    }
    update::<0, false>(u, z.as_ptr().cast_mut(), z.len(), [])
}

/// `z = (z + r₁ a₁) + r₂ a₂` (the `K` terms given, each `a` as long as `z`), then `u += z`;
/// returns the new `max_i |u_i|` (four running maxima: the maximum is exact, so the order
/// does not change the bits). On a CPU with AVX it runs as AVX instructions ([`dispatch`]):
/// the same operations on each entry, so the same bits.
pub(crate) fn add_columns_in_place<const K: usize>(
    u: &mut [f64],
    z: &mut [f64],
    terms: [(f64, &[f64]); K],
) -> f64 {
    assert!(
        terms.iter().all(|(_, a)| a.len() == z.len()),
        "column length"
    );
    #[cfg(target_arch = "x86_64")]
    if dispatch::has_avx() {
        // SAFETY: the CPU supports AVX; `z` is exclusively borrowed for the call.
        return unsafe { update_avx::<K, true>(u, z.as_mut_ptr(), z.len(), terms) };
    }
    update::<K, true>(u, z.as_mut_ptr(), z.len(), terms)
}

/// The portable update (see [`add_columns_in_place`]). `z` is `len` doubles at `z_ptr`,
/// written only when `WRITE_Z` (so that [`add_in_place`] can pass a shared slice).
fn update<const K: usize, const WRITE_Z: bool>(
    u: &mut [f64],
    z_ptr: *mut f64,
    len: usize,
    terms: [(f64, &[f64]); K],
) -> f64 {
    max4(update_from::<K, WRITE_Z>(
        u, z_ptr, len, &terms, 0, [0.0; 4],
    ))
}

/// Entries `from..len` of [`update`], entry `i` into running maximum `i mod 4` of `m`.
#[inline(always)]
fn update_from<const K: usize, const WRITE_Z: bool>(
    u: &mut [f64],
    z_ptr: *mut f64,
    len: usize,
    terms: &[(f64, &[f64]); K],
    from: usize,
    mut m: [f64; 4],
) -> [f64; 4] {
    assert_eq!(u.len(), len, "state length");
    for i in from..len {
        // SAFETY: `i < len`, and the callers' `z` is `len` doubles, writable when `WRITE_Z`.
        let mut zi = unsafe { *z_ptr.add(i) };
        for (r, a) in terms {
            zi += r * a[i];
        }
        if WRITE_Z && K > 0 {
            // SAFETY: as above.
            unsafe { *z_ptr.add(i) = zi };
        }
        u[i] += zi;
        m[i % 4] = m[i % 4].max(u[i].abs());
    }
    m
}

/// [`update`] in AVX instructions: blocks of four entries, then the rest one by one.
#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx")]
fn update_avx<const K: usize, const WRITE_Z: bool>(
    u: &mut [f64],
    z_ptr: *mut f64,
    len: usize,
    terms: [(f64, &[f64]); K],
) -> f64 {
    use std::arch::x86_64::{
        _mm256_add_pd, _mm256_andnot_pd, _mm256_loadu_pd, _mm256_max_pd, _mm256_mul_pd,
        _mm256_set1_pd, _mm256_setzero_pd, _mm256_storeu_pd,
    };
    assert_eq!(u.len(), len, "state length");
    let blocks = len / 4;
    let sign = _mm256_set1_pd(-0.0);
    let mut m = _mm256_setzero_pd();
    for b in 0..blocks {
        let i = 4 * b;
        // SAFETY: entries `i..i + 4` are inside `u`, `z` (`len` doubles) and every column.
        unsafe {
            let mut zi = _mm256_loadu_pd(z_ptr.add(i));
            for (r, a) in &terms {
                let ai = _mm256_loadu_pd(a[i..i + 4].as_ptr());
                zi = _mm256_add_pd(zi, _mm256_mul_pd(_mm256_set1_pd(*r), ai));
            }
            if WRITE_Z && K > 0 {
                _mm256_storeu_pd(z_ptr.add(i), zi);
            }
            let ui = _mm256_add_pd(_mm256_loadu_pd(u[i..i + 4].as_ptr()), zi);
            _mm256_storeu_pd(u[i..i + 4].as_mut_ptr(), ui);
            // max(|u|, m): `m` when |u| is NaN, as f64::max(m, |u|).
            m = _mm256_max_pd(_mm256_andnot_pd(sign, ui), m);
        }
    }
    let mut lanes = [0.0f64; 4];
    // SAFETY: `lanes` has room for four doubles.
    unsafe { _mm256_storeu_pd(lanes.as_mut_ptr(), m) };
    // The rest one by one.
    max4(update_from::<K, WRITE_Z>(
        u,
        z_ptr,
        len,
        &terms,
        4 * blocks,
        lanes,
    ))
}

/// The largest of four running maxima.
pub(crate) fn max4(m: [f64; 4]) -> f64 {
    m[0].max(m[1]).max(m[2].max(m[3]))
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

/// A factorisation of a symmetric positive definite tridiagonal matrix `A` built for a short
/// critical path: one step of odd–even reduction, then a twisted factorisation of the reduced
/// system. Computed once per run.
///
/// *Reduction.* The odd nodes are not neighbours of each other, so eliminating them first
/// (pivots `d_o`) leaves a tridiagonal Schur complement `A'` on the even nodes (`ν = ⌈n/2⌉`
/// rows): `D'_r = d_2r − e_2r−1²/d_2r−1 − e_2r²/d_2r+1`, `E'_r = −e_2r e_2r+1/d_2r+1`, right-hand
/// side `b'_r = b_2r − f2_2r−1 b_2r−1 − f1_2r+1 b_2r+1` with `f1_o = e_o−1/d_o`, `f2_o = e_o/d_o`.
/// Once the even unknowns are known, `x_o = b_o/d_o − f1_o x_o−1 − f2_o x_o+1`.
///
/// *Twisted factorisation of `A'`* ("burn at both ends"): `L D Lᵀ` from the top for reduced
/// rows `0..μ`, `U D Uᵀ` from the bottom for rows `μ+1..ν`, joined at the twist row `μ = ν/2`.
/// A solve runs the top and bottom chains interleaved in one loop (two dependent chains
/// overlap instead of one waiting on itself), and each link covers two nodes of the bar: a
/// quarter of the plain sweep's latency. The reduction's and the odd nodes' arithmetic is off
/// the chains, in the slots the chains leave free.
///
/// Both parts are Gaussian elimination without pivoting on the symmetrically permuted matrix
/// `P A Pᵀ`, which is positive definite, so the solve is backward stable like the plain `L D
/// Lᵀ` sweep (Higham, *Accuracy and Stability of Numerical Algorithms*, 2nd ed., Thm 10.5 and
/// §9.5); `tests/matrices.rs` measures its backward error. No fused multiply-add: results do
/// not depend on target-cpu flags.
#[derive(Clone, Debug)]
pub struct Ldlt {
    /// One entry per reduced row in the order the inward sweep visits it, with the odd node on
    /// its inner side (towards the twist): `top[r] = [l_r, 1/D_r, f1_o, f2_o, 1/d_o]` with
    /// `o = 2r + 1` for rows `r = 0..μ` (`l_r = E'_r/D_r`); `bottom[k]` the same for row
    /// `r = ν−1−k > μ` with `o = 2r − 1` and `l_r = E'_r−1/D_r`. A half that several
    /// factorisations have is stored once ([`Ldlt::factor_with_rows_changed`]).
    top: Arc<Vec<[f64; 5]>>,
    bottom: Arc<Vec<[f64; 5]>>,
    /// `[f1, 1/d]` of the last node when it is odd (`n` even): it is on no reduced row's inner
    /// side.
    outer: Option<[f64; 2]>,
    /// `1/D_μ`, the twist pivot.
    inv_twist: f64,
    n: usize,
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
    /// The node whose pivot failed (an odd node's `d_o`, or an even node's reduced pivot).
    pub index: usize,
    pub pivot: f64,
}

/// A value the solve reads from its right-hand side: `f64` for a separate one, `Cell<f64>`
/// when it is the solution vector itself (in place).
trait Value {
    fn value(&self) -> f64;
}

impl Value for f64 {
    #[inline(always)]
    fn value(&self) -> f64 {
        *self
    }
}

impl Value for Cell<f64> {
    #[inline(always)]
    fn value(&self) -> f64 {
        self.get()
    }
}

impl Ldlt {
    pub fn factor(a: &SymTridiag) -> Result<Self, NotPositiveDefinite> {
        Self::factor_by(a.dim(), |i| a.diag[i], |i| a.off[i], [None, None])
    }

    /// The factorisation of `a` with the rows and columns of `nodes` replaced by identity ones
    /// (the same entries the factorisation of that modified matrix reads, without copying it).
    pub fn factor_with_identity_rows(
        a: &SymTridiag,
        nodes: &[usize],
    ) -> Result<Self, NotPositiveDefinite> {
        Self::factor_with_rows_changed(a, nodes, RowChange::Identity, &[])
    }

    /// The factorisation of `a` with the rows of `nodes` changed by `change`, read from `a`
    /// without copying it. Each half is taken from a factorisation in `known` (made by this
    /// function from the same `a` with the same `change`, or the plain one with no nodes,
    /// given with its own nodes) whose changed rows among the nodes that half reads are the
    /// same: that half is then neither computed nor stored again. The top half reads nodes
    /// `0..=2μ`, the bottom half `2μ..n` (`2μ`, the twist node, both), so changed rows at one
    /// end leave the other end's half as it was.
    pub fn factor_with_rows_changed(
        a: &SymTridiag,
        nodes: &[usize],
        change: RowChange,
        known: &[(&[usize], &Ldlt)],
    ) -> Result<Self, NotPositiveDefinite> {
        let n = a.dim();
        let twist_node = 2 * (n.div_ceil(2) / 2);
        // The changed rows a half reads, as a sorted list.
        let seen = |nodes: &[usize], top: bool| {
            let mut v: Vec<usize> = (nodes.iter().copied())
                .filter(|&i| {
                    if top {
                        i <= twist_node
                    } else {
                        i >= twist_node
                    }
                })
                .collect();
            v.sort_unstable();
            v.dedup();
            v
        };
        let reuse = |top: bool| {
            let mine = seen(nodes, top);
            known.iter().find_map(|(their_nodes, f)| {
                (f.n == n && seen(their_nodes, top) == mine)
                    .then(|| Arc::clone(if top { &f.top } else { &f.bottom }))
            })
        };
        let changed = |i: usize| nodes.contains(&i);
        let halves = [reuse(true), reuse(false)];
        match change {
            RowChange::Identity => Self::factor_by(
                n,
                |i| if changed(i) { 1.0 } else { a.diag[i] },
                |i| {
                    if changed(i) || changed(i + 1) {
                        0.0
                    } else {
                        a.off[i]
                    }
                },
                halves,
            ),
            RowChange::AddToDiagonal(s) => Self::factor_by(
                n,
                |i| if changed(i) { a.diag[i] + s } else { a.diag[i] },
                |i| a.off[i],
                halves,
            ),
        }
    }

    /// The factorisation of the matrix with diagonal `d(i)` and off-diagonal `e(i) = A_i,i+1`;
    /// a half given in `reuse` (`[top, bottom]`, computed from the same entries) is taken as is.
    fn factor_by(
        n: usize,
        d: impl Fn(usize) -> f64,
        e: impl Fn(usize) -> f64,
        reuse: [Option<Arc<Vec<[f64; 5]>>>; 2],
    ) -> Result<Self, NotPositiveDefinite> {
        let [reuse_top, reuse_bottom] = reuse;
        let check = |index: usize, pivot: f64| {
            if pivot > 0.0 && pivot.is_finite() {
                Ok(pivot)
            } else {
                Err(NotPositiveDefinite { index, pivot })
            }
        };
        // Odd node `2k + 1`: [f1, f2, 1/d] (f2 = 0 for the last node); recomputed where
        // needed rather than stored, so the set-up holds nothing beyond the factorisation.
        for o in (1..n).step_by(2) {
            check(o, d(o))?;
        }
        let odd = |k: usize| {
            let o = 2 * k + 1;
            let f2 = if o + 1 < n { e(o) / d(o) } else { 0.0 };
            [e(o - 1) / d(o), f2, 1.0 / d(o)]
        };
        let nu = n.div_ceil(2);
        // The reduced matrix A' on the even nodes.
        let reduced_diag = |r: usize| {
            let i = 2 * r;
            let mut p = d(i);
            if r > 0 {
                p -= e(i - 1) * odd(r - 1)[1];
            }
            if i + 1 < n {
                p -= e(i) * odd(r)[0];
            }
            p
        };
        let reduced_off = |r: usize| -(e(2 * r) * odd(r)[1]);
        let twist = nu / 2;
        // The last multiplier of each half enters the twist pivot.
        let last_l = |half: &[[f64; 5]]| half.last().map_or(0.0, |row| row[0]);
        let top = match reuse_top {
            Some(top) => top,
            None => {
                let mut top = Vec::with_capacity(twist);
                let mut l_prev = 0.0;
                for r in 0..twist {
                    let p = if r == 0 {
                        reduced_diag(0)
                    } else {
                        reduced_diag(r) - reduced_off(r - 1) * l_prev
                    };
                    let p = check(2 * r, p)?;
                    l_prev = reduced_off(r) / p;
                    let [f1, f2, inv_d] = odd(r);
                    top.push([l_prev, 1.0 / p, f1, f2, inv_d]);
                }
                Arc::new(top)
            }
        };
        let bottom = match reuse_bottom {
            Some(bottom) => bottom,
            None => {
                let mut bottom = Vec::with_capacity(nu.saturating_sub(twist + 1));
                let mut l_next = 0.0;
                for r in (twist + 1..nu).rev() {
                    let p = if r == nu - 1 {
                        reduced_diag(r)
                    } else {
                        reduced_diag(r) - reduced_off(r) * l_next
                    };
                    let p = check(2 * r, p)?;
                    l_next = reduced_off(r - 1) / p;
                    let [f1, f2, inv_d] = odd(r - 1);
                    bottom.push([l_next, 1.0 / p, f1, f2, inv_d]);
                }
                Arc::new(bottom)
            }
        };
        let (l_prev, l_next) = (last_l(&top), last_l(&bottom));
        let mut inv_twist = 0.0;
        if n > 0 {
            let mut g = reduced_diag(twist);
            if twist > 0 {
                g -= reduced_off(twist - 1) * l_prev;
            }
            if twist + 1 < nu {
                g -= reduced_off(twist) * l_next;
            }
            inv_twist = 1.0 / check(2 * twist, g)?;
        }
        let outer = (n.is_multiple_of(2) && n > 0).then(|| {
            let [f1, _, inv_d] = odd(n / 2 - 1);
            [f1, inv_d]
        });
        Ok(Self {
            top,
            bottom,
            outer,
            inv_twist,
            n,
        })
    }

    pub fn dim(&self) -> usize {
        self.n
    }

    /// Overwrites `b` with `A⁻¹ b`.
    pub fn solve_in_place(&self, b: &mut [f64]) {
        assert_eq!(b.len(), self.n, "right-hand side length");
        let x = Cell::from_mut(b).as_slice_of_cells();
        self.solve_from::<_, false>(x, x, x);
    }

    /// `x = A⁻¹ b` (the same bits as copying `b` into `x` and solving in place).
    pub fn solve_into(&self, b: &[f64], x: &mut [f64]) {
        assert_eq!(b.len(), self.n, "right-hand side length");
        assert_eq!(x.len(), self.n, "solution length");
        let x = Cell::from_mut(x).as_slice_of_cells();
        self.solve_from::<_, false>(b, x, x);
    }

    /// `x = A⁻¹ b`, then `u += x`: the bits of [`Ldlt::solve_into`] followed by the addition,
    /// made as each `x_i` is found (the time step's update without a second pass over the
    /// bar). Unlike [`add_in_place`] it does not track `max |u_i|`: that running maximum, a
    /// chain of its own, made the fused sweep slower than the two passes.
    pub fn solve_into_and_add(&self, b: &[f64], x: &mut [f64], u: &mut [f64]) {
        assert_eq!(b.len(), self.n, "right-hand side length");
        assert_eq!(x.len(), self.n, "solution length");
        assert_eq!(u.len(), self.n, "state length");
        let x = Cell::from_mut(x).as_slice_of_cells();
        self.solve_from::<_, true>(b, x, Cell::from_mut(u).as_slice_of_cells());
    }

    /// The solve, reading the right-hand side from `b` (which may be `x` itself: every entry
    /// of `b` is read before `x` overwrites it). Inward, the two chains eliminate towards the
    /// twist row, folding in the odd nodes; outward, they substitute back, and each reduced
    /// row fills in its inner odd node. With `ADD`, each `x_i` is also added to `u_i`
    /// (otherwise `u` is not touched and may be `x`).
    fn solve_from<V: Value, const ADD: bool>(&self, b: &[V], x: &[Cell<f64>], u: &[Cell<f64>]) {
        let n = self.n;
        if n == 0 {
            return;
        }
        let (top_f, bottom_f) = (&self.top[..], &self.bottom[..]);
        let m = top_f.len();
        // Top rows r < μ own nodes (2r, 2r+1); the twist is node 2μ; bottom rows own
        // (2r−1, 2r); then the outer odd node when n is even.
        let bottom_nodes = 2 * bottom_f.len();
        let (b_top, b_rest) = b.split_at(2 * m);
        let (b_mid, b_rest) = b_rest.split_at(1);
        let (b_bottom, b_outer) = b_rest.split_at(bottom_nodes);
        let (x_top, x_rest) = x.split_at(2 * m);
        let (x_mid, x_rest) = x_rest.split_at(1);
        let (x_bottom, x_outer) = x_rest.split_at(bottom_nodes);
        let (u_top, u_rest) = u.split_at(2 * m);
        let (u_mid, u_rest) = u_rest.split_at(1);
        let (u_bottom, u_outer) = u_rest.split_at(bottom_nodes);
        let common = m.min(bottom_f.len());

        // Inward. Per chain: y (the elimination value), l (the multiplier of the row before)
        // and c, the term of the shared odd node (`f b_o`) the next row subtracts.
        let (mut yt, mut lt, mut ct) = (0.0, 0.0, 0.0);
        let (mut yb, mut lb) = (0.0, 0.0);
        let mut cb = match (self.outer, b_outer.first()) {
            (Some([f1, _]), Some(bo)) => f1 * bo.value(),
            _ => 0.0,
        };
        let inward_top =
            |b: &[V], x: &[Cell<f64>], f: &[f64; 5], y: &mut f64, l: &mut f64, c: &mut f64| {
                let (be, bo) = (b[0].value(), b[1].value());
                *y = ((be - *c) - f[2] * bo) - *l * *y;
                x[0].set(*y * f[1]);
                (*l, *c) = (f[0], f[3] * bo);
            };
        let inward_bottom =
            |b: &[V], x: &[Cell<f64>], f: &[f64; 5], y: &mut f64, l: &mut f64, c: &mut f64| {
                let (bo, be) = (b[0].value(), b[1].value());
                *y = ((be - f[3] * bo) - *c) - *l * *y;
                x[1].set(*y * f[1]);
                (*l, *c) = (f[0], f[2] * bo);
            };
        let mut top = b_top.chunks_exact(2).zip(x_top.chunks_exact(2)).zip(top_f);
        let mut bottom = (b_bottom.rchunks_exact(2).zip(x_bottom.rchunks_exact(2))).zip(bottom_f);
        for (((bt, xt), ft), ((bb, xb), fb)) in
            top.by_ref().take(common).zip(bottom.by_ref().take(common))
        {
            inward_top(bt, xt, ft, &mut yt, &mut lt, &mut ct);
            inward_bottom(bb, xb, fb, &mut yb, &mut lb, &mut cb);
        }
        for ((bt, xt), ft) in top {
            inward_top(bt, xt, ft, &mut yt, &mut lt, &mut ct);
        }
        for ((bb, xb), fb) in bottom {
            inward_bottom(bb, xb, fb, &mut yb, &mut lb, &mut cb);
        }
        // Twist row: the terms are 0 when a side is empty (l = 0, y = 0, c = 0).
        let xm = (((b_mid[0].value() - ct) - cb) - lt * yt - lb * yb) * self.inv_twist;
        x_mid[0].set(xm);

        let add = |u: &Cell<f64>, xi: f64| {
            if ADD {
                u.set(u.get() + xi);
            }
        };
        add(&u_mid[0], xm);

        // Outward: x_2r = y_r/D_r − l_r x_(next even), then the inner odd node from its two
        // even neighbours (left one first).
        let (mut xt_, mut xb_) = (xm, xm);
        let outward_top =
            |b: &[V], x: &[Cell<f64>], u: &[Cell<f64>], f: &[f64; 5], xn: &mut f64| {
                let xe = x[0].get() - f[0] * *xn;
                let xo = b[1].value() * f[4] - f[2] * xe - f[3] * *xn;
                x[1].set(xo);
                x[0].set(xe);
                add(&u[0], xe);
                add(&u[1], xo);
                *xn = xe;
            };
        let outward_bottom =
            |b: &[V], x: &[Cell<f64>], u: &[Cell<f64>], f: &[f64; 5], xn: &mut f64| {
                let xe = x[1].get() - f[0] * *xn;
                let xo = b[0].value() * f[4] - f[2] * *xn - f[3] * xe;
                x[0].set(xo);
                x[1].set(xe);
                add(&u[0], xo);
                add(&u[1], xe);
                *xn = xe;
            };
        let mut top = (b_top.chunks_exact(2).zip(x_top.chunks_exact(2)))
            .zip(u_top.chunks_exact(2).zip(top_f))
            .rev();
        let mut bottom = (b_bottom.rchunks_exact(2).zip(x_bottom.rchunks_exact(2)))
            .zip(u_bottom.rchunks_exact(2).zip(bottom_f))
            .rev();
        for ((bt, xt), (ut, ft)) in top.by_ref().take(m - common) {
            outward_top(bt, xt, ut, ft, &mut xt_);
        }
        for ((bb, xb), (ub, fb)) in bottom.by_ref().take(bottom_f.len() - common) {
            outward_bottom(bb, xb, ub, fb, &mut xb_);
        }
        for (((bt, xt), (ut, ft)), ((bb, xb), (ub, fb))) in top.zip(bottom) {
            outward_top(bt, xt, ut, ft, &mut xt_);
            outward_bottom(bb, xb, ub, fb, &mut xb_);
        }
        if let (Some([f1, inv_d]), Some(bo), Some(xo), Some(uo)) = (
            self.outer,
            b_outer.first(),
            x_outer.first(),
            u_outer.first(),
        ) {
            let v = bo.value() * inv_d - f1 * xb_;
            xo.set(v);
            add(uo, v);
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

#[cfg(test)]
mod tests {
    use super::*;

    /// Each factorisation made with halves taken from earlier ones (as the exact and penalty
    /// solvers make theirs) equals the one computed from scratch bit for bit, for identity rows
    /// and for a diagonal shift, at the ends, next to them, at the twist node and inside, at
    /// every size from 2 to 13 and at 101 and 1000; with both ends of a bar of 5 nodes or
    /// more, the plain factorisation and the three changed ones hold four distinct halves.
    #[test]
    fn shared_halves_equal_the_halves_computed_from_scratch() {
        let bits = |f: &Ldlt| {
            let half = |h: &[[f64; 5]]| h.iter().flatten().map(|x| x.to_bits()).collect::<Vec<_>>();
            (
                half(&f.top),
                half(&f.bottom),
                f.outer.map(|o| o.map(f64::to_bits)),
                f.inv_twist.to_bits(),
            )
        };
        for n in (2usize..=13).chain([101, 1000]) {
            let a = SymTridiag::new(
                (0..n).map(|i| 3.0 + (i as f64 * 0.7).sin()).collect(),
                (0..n - 1).map(|i| (i as f64 * 1.3).cos()).collect(),
            );
            let twist_node = 2 * (n.div_ceil(2) / 2);
            let plain = Ldlt::factor(&a).unwrap();
            let changes = [RowChange::Identity, RowChange::AddToDiagonal(7.5)];
            for (change, pair) in changes.into_iter().flat_map(|change| {
                [
                    [0, n - 1],
                    [1, n - 2],
                    [0, twist_node],
                    [twist_node, n - 1],
                    [n / 3, n - 1],
                ]
                .map(|pair| (change, pair))
            }) {
                let sets: [&[usize]; 3] = [&pair[..1], &pair[1..], &pair[..]];
                let mut made: Vec<Ldlt> = Vec::new();
                for set in sets {
                    let known: Vec<(&[usize], &Ldlt)> = std::iter::once((&[][..], &plain))
                        .chain(sets.iter().copied().zip(&made))
                        .collect();
                    let shared = Ldlt::factor_with_rows_changed(&a, set, change, &known).unwrap();
                    let fresh = Ldlt::factor_with_rows_changed(&a, set, change, &[]).unwrap();
                    assert_eq!(bits(&shared), bits(&fresh), "n {n}, {change:?} at {set:?}");
                    made.push(shared);
                }
                if pair == [0, n - 1] && n >= 5 {
                    let mut halves: Vec<&Arc<Vec<[f64; 5]>>> = Vec::new();
                    for f in std::iter::once(&plain).chain(&made) {
                        for h in [&f.top, &f.bottom] {
                            if !halves.iter().any(|k| Arc::ptr_eq(k, h)) {
                                halves.push(h);
                            }
                        }
                    }
                    assert_eq!(halves.len(), 4, "n {n}");
                }
            }
        }
    }

    /// The AVX and the portable updates give the same bits (`u`, `z` and the maximum), for
    /// zero, one and two columns and every tail length of the four-entry blocks; a NaN in `u`
    /// is skipped by the maximum on both paths, as `f64::max` does (mutation-checked: the
    /// AVX maximum with its operands swapped fails).
    #[cfg(target_arch = "x86_64")]
    #[test]
    fn updates_give_the_same_bits_with_and_without_avx() {
        if !dispatch::has_avx() {
            eprintln!("this CPU has no AVX: only the portable update runs, nothing to compare");
            return;
        }
        let bits = |x: &[f64]| x.iter().map(|v| v.to_bits()).collect::<Vec<_>>();
        for n in [0usize, 1, 2, 3, 4, 5, 6, 7, 8, 9, 101] {
            let v = |a: f64, offset: f64| {
                (0..n)
                    .map(|i| offset + (a * i as f64 + 0.3).sin())
                    .collect::<Vec<_>>()
            };
            let (mut u0, z0, a, b) = (v(0.7, 1e3), v(1.3, 0.0), v(2.1, 0.0), v(0.4, -1.0));
            // The largest entry, then a NaN in the same lane of the next block: a maximum that
            // took the NaN would lose the largest entry.
            if n > 6 {
                (u0[2], u0[6]) = (1e6, f64::NAN);
            }
            macro_rules! compare {
                ($k:literal, $write:literal, $terms:expr) => {{
                    let (mut u1, mut z1, mut u2, mut z2) =
                        (u0.clone(), z0.clone(), u0.clone(), z0.clone());
                    let m1 = update::<$k, $write>(&mut u1, z1.as_mut_ptr(), n, $terms);
                    // SAFETY: the CPU has AVX (checked above).
                    let m2 =
                        unsafe { update_avx::<$k, $write>(&mut u2, z2.as_mut_ptr(), n, $terms) };
                    assert_eq!(bits(&u1), bits(&u2), "u, n = {n}, {} columns", $k);
                    assert_eq!(bits(&z1), bits(&z2), "z, n = {n}, {} columns", $k);
                    assert_eq!(m1.to_bits(), m2.to_bits(), "max, n = {n}, {} columns", $k);
                    assert!(!m1.is_nan());
                }};
            }
            compare!(0, false, []);
            compare!(1, true, [(0.3, &a[..])]);
            compare!(2, true, [(0.3, &a[..]), (-7.0, &b[..])]);
        }
    }
}
