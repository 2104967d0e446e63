//! Symmetric block-tridiagonal matrices of 2 × 2 blocks and their block `LDLᵀ` without
//! pivoting, for quasi-definite matrices of two fields interleaved node by node (a positive
//! definite field first, a negative definite one second): every leading block of such a matrix
//! is quasi-definite, so each pivot block `D_i = [[p, q], [q, s]]` has `p > 0 > s` and
//! `det D_i = ps − q² < 0` sums two terms of one sign (no cancellation); `D_i⁻¹` is stored.
//! A solve is one forward and one backward sweep of 2 × 2 products. The same factorisation
//! row by row is the test-only `banded` module's (the tests compare them).

/// A 2 × 2 block, `b[r][c]`.
pub type Block = [[f64; 2]; 2];

/// A symmetric matrix of `n × n` blocks of order 2, zero off the block tridiagonal:
/// `diag[i] = A_ii` (symmetric) and `lower[i] = A_{i,i−1}` (`lower[0]` unused).
#[derive(Clone, Debug, PartialEq)]
pub struct BlockTridiag {
    pub diag: Vec<Block>,
    pub lower: Vec<Block>,
}

impl BlockTridiag {
    /// The zero matrix of `n` block rows.
    pub fn zeros(n: usize) -> Self {
        Self {
            diag: vec![[[0.0; 2]; 2]; n],
            lower: vec![[[0.0; 2]; 2]; n],
        }
    }

    /// The number of block rows.
    pub fn blocks(&self) -> usize {
        self.diag.len()
    }

    /// `y = A x`, both interleaved (entry `i` of block row `i`).
    pub fn mul_into(&self, x: &[[f64; 2]], y: &mut [[f64; 2]]) {
        let n = self.blocks();
        for i in 0..n {
            let mut s = mul(&self.diag[i], x[i]);
            if i > 0 {
                s = add(s, mul(&self.lower[i], x[i - 1]));
            }
            if i + 1 < n {
                s = add(s, mul_transposed(&self.lower[i + 1], x[i + 1]));
            }
            y[i] = s;
        }
    }
}

/// `B x`.
#[inline(always)]
pub(super) fn mul(b: &Block, x: [f64; 2]) -> [f64; 2] {
    [
        b[0][0] * x[0] + b[0][1] * x[1],
        b[1][0] * x[0] + b[1][1] * x[1],
    ]
}

/// `Bᵀ x`.
#[inline(always)]
pub(super) fn mul_transposed(b: &Block, x: [f64; 2]) -> [f64; 2] {
    [
        b[0][0] * x[0] + b[1][0] * x[1],
        b[0][1] * x[0] + b[1][1] * x[1],
    ]
}

/// `D⁻¹ y` from `[a, b, c]`.
#[inline(always)]
pub(super) fn d_inv_mul(&[a, b, c]: &[f64; 3], y: [f64; 2]) -> [f64; 2] {
    [a * y[0] + b * y[1], b * y[0] + c * y[1]]
}

#[inline(always)]
fn add(a: [f64; 2], b: [f64; 2]) -> [f64; 2] {
    [a[0] + b[0], a[1] + b[1]]
}

/// A singular or non-finite pivot block: the matrix is not quasi-definite (or not finite).
#[derive(Clone, Copy, Debug, PartialEq, thiserror::Error)]
#[error("pivot block {block} of the block LDLᵀ has determinant {determinant}")]
pub struct SingularBlock {
    pub block: usize,
    pub determinant: f64,
}

/// `A = L D Lᵀ` with `L` unit block lower bidiagonal and `D` block diagonal.
#[derive(Clone, Debug)]
pub struct BlockLdlt {
    /// `l[i] = L_{i,i−1}` (`l[0]` zero).
    l: Vec<Block>,
    /// `D_i⁻¹ = [[a, b], [b, c]]` as `[a, b, c]`.
    inv_d: Vec<[f64; 3]>,
    /// The positive eigenvalues of `D` (the rest are negative).
    positive: usize,
}

impl BlockLdlt {
    /// `D_0 = A_00`; `L_i = A_{i,i−1} D_{i−1}⁻¹`, `D_i = A_ii − L_i A_{i,i−1}ᵀ`.
    pub fn factor(a: &BlockTridiag) -> Result<Self, SingularBlock> {
        let n = a.blocks();
        let mut l = vec![[[0.0; 2]; 2]; n];
        let mut inv_d = vec![[0.0; 3]; n];
        let mut positive = 0;
        for i in 0..n {
            let [[mut p, mut q], [_, mut s]] = a.diag[i];
            if i > 0 {
                let [ia, ib, ic] = inv_d[i - 1];
                let e = &a.lower[i];
                let li = [
                    [e[0][0] * ia + e[0][1] * ib, e[0][0] * ib + e[0][1] * ic],
                    [e[1][0] * ia + e[1][1] * ib, e[1][0] * ib + e[1][1] * ic],
                ];
                p -= li[0][0] * e[0][0] + li[0][1] * e[0][1];
                q -= li[0][0] * e[1][0] + li[0][1] * e[1][1];
                s -= li[1][0] * e[1][0] + li[1][1] * e[1][1];
                l[i] = li;
            }
            let d = p * s - q * q;
            if !(d.is_finite() && d != 0.0) {
                return Err(SingularBlock {
                    block: i,
                    determinant: d,
                });
            }
            inv_d[i] = [s / d, -q / d, p / d];
            // det < 0: one eigenvalue of each sign; det > 0: both of the trace's sign.
            positive += match (d < 0.0, p + s > 0.0) {
                (true, _) => 1,
                (false, true) => 2,
                (false, false) => 0,
            };
        }
        Ok(Self { l, inv_d, positive })
    }

    /// The number of block rows.
    pub fn blocks(&self) -> usize {
        self.inv_d.len()
    }

    /// The rows `L_{i,i−1}` (`L_{0,−1}` zero).
    pub(super) fn l(&self) -> &[Block] {
        &self.l
    }

    /// The rows `D_i⁻¹` as `[a, b, c]`.
    pub(super) fn inv_d(&self) -> &[[f64; 3]] {
        &self.inv_d
    }

    /// The positive and the negative eigenvalues of `D`: the inertia of `A` (Sylvester).
    pub fn inertia(&self) -> (usize, usize) {
        (self.positive, 2 * self.blocks() - self.positive)
    }

    /// `x ← A⁻¹ x` (interleaved): `y_i = x_i − L_i y_{i−1}`, then
    /// `x_i = D_i⁻¹ y_i − L_{i+1}ᵀ x_{i+1}`. Allocates nothing.
    pub fn solve_in_place(&self, x: &mut [[f64; 2]]) {
        let n = self.blocks();
        let x = &mut x[..n];
        let mut y = [0.0; 2];
        for (xi, li) in x.iter_mut().zip(&self.l) {
            let m = mul(li, y);
            y = [xi[0] - m[0], xi[1] - m[1]];
            *xi = y;
        }
        let Some(last) = n.checked_sub(1) else {
            return;
        };
        let mut z = d_inv_mul(&self.inv_d[last], x[last]);
        x[last] = z;
        for i in (0..last).rev() {
            let v = d_inv_mul(&self.inv_d[i], x[i]);
            let m = mul_transposed(&self.l[i + 1], z);
            z = [v[0] - m[0], v[1] - m[1]];
            x[i] = z;
        }
    }
    /// [`BlockLdlt::solve_in_place`] on two fields given apart, with the same bits: field
    /// `f = (values, first)` has its entry of block `i` at `values[i − first]` where that
    /// exists (0 in the right-hand side and not written back elsewhere); `y` (one entry per
    /// block) carries the forward sweep. Allocates nothing.
    pub fn solve_fields(&self, fields: [(&mut [f64], usize); 2], y: &mut [[f64; 2]]) {
        let [(u, fu), (t, ft)] = fields;
        let n = self.blocks();
        let y = &mut y[..n];
        let mut prev = [0.0; 2];
        for (i, (yi, li)) in y.iter_mut().zip(&self.l).enumerate() {
            let b = [
                u.get(i.wrapping_sub(fu)).copied().unwrap_or(0.0),
                t.get(i.wrapping_sub(ft)).copied().unwrap_or(0.0),
            ];
            let m = mul(li, prev);
            prev = [b[0] - m[0], b[1] - m[1]];
            *yi = prev;
        }
        let mut z = [0.0; 2];
        for i in (0..n).rev() {
            let v = d_inv_mul(&self.inv_d[i], y[i]);
            z = if i + 1 < n {
                let m = mul_transposed(&self.l[i + 1], z);
                [v[0] - m[0], v[1] - m[1]]
            } else {
                v
            };
            if let Some(x) = u.get_mut(i.wrapping_sub(fu)) {
                *x = z[0];
            }
            if let Some(x) = t.get_mut(i.wrapping_sub(ft)) {
                *x = z[1];
            }
        }
    }
}

#[cfg(test)]
impl BlockTridiag {
    /// The interleaved scalar matrix: block row `i` is rows `2i, 2i + 1` (the tests' reference,
    /// a banded `LDLᵀ` of the same matrix).
    pub(crate) fn to_banded(&self) -> crate::linalg::kernels::banded::SymBanded<3> {
        let mut s = crate::linalg::kernels::banded::SymBanded::<3>::zeros(2 * self.blocks());
        for i in 0..self.blocks() {
            for r in 0..2 {
                for c in 0..=r {
                    s.add(2 * i + r, 2 * i + c, self.diag[i][r][c]);
                }
                if i > 0 {
                    for c in 0..2 {
                        s.add(2 * i + r, 2 * (i - 1) + c, self.lower[i][r][c]);
                    }
                }
            }
        }
        s
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::linalg::kernels::banded::BandedLdlt;

    /// A quasi-definite block-tridiagonal matrix (an SPD field, a negative definite one, full
    /// couplings): the block factor's inertia and solve agree with the banded `LDLᵀ` of the
    /// same matrix row by row, both reproducing a chosen solution to round-off.
    #[test]
    fn the_block_factor_solves_as_the_banded_one() {
        for n in [1usize, 2, 3, 7, 40] {
            let mut a = BlockTridiag::zeros(n);
            for i in 0..n {
                let t = i as f64;
                a.diag[i] = [[4.0 + t.sin(), 0.7], [0.7, -(3.0 + t.cos())]];
                if i > 0 {
                    a.lower[i] = [[-1.0, -0.5], [0.4, 0.9]];
                }
            }
            let block = BlockLdlt::factor(&a).unwrap();
            let scalar = BandedLdlt::factor(&a.to_banded()).unwrap();
            assert_eq!(block.inertia(), (n, n));
            assert_eq!(scalar.inertia(), (n, n));
            let x: Vec<[f64; 2]> = (0..n)
                .map(|i| [(0.6 * i as f64).cos(), (0.6 * i as f64 + 0.3).cos()])
                .collect();
            let mut b = vec![[0.0; 2]; n];
            a.mul_into(&x, &mut b);
            let mut flat: Vec<f64> = b.iter().flatten().copied().collect();
            // The two fields apart, the first missing in block 0 and the second in the last
            // block (zero right-hand sides there): the bits of the interleaved solve.
            let (mut u, mut t): (Vec<f64>, Vec<f64>) = b.iter().map(|v| (v[0], v[1])).unzip();
            if n > 1 {
                (b[0][0], b[n - 1][1]) = (0.0, 0.0);
            }
            let (u, t) = if n > 1 {
                (&mut u[1..], &mut t[..n - 1])
            } else {
                (&mut u[..], &mut t[..])
            };
            let first = usize::from(n > 1);
            let mut interleaved = b.clone();
            block.solve_in_place(&mut interleaved);
            block.solve_fields([(u, first), (t, 0)], &mut vec![[0.0; 2]; n]);
            for (i, v) in interleaved.iter().enumerate() {
                if i >= first {
                    assert_eq!(u[i - first].to_bits(), v[0].to_bits());
                }
                if i < t.len() {
                    assert_eq!(t[i].to_bits(), v[1].to_bits());
                }
            }
            a.mul_into(&x, &mut b);
            block.solve_in_place(&mut b);
            scalar.solve_in_place(&mut flat);
            // Round-off: these blocks are well conditioned (κ below 100), so a backward-stable
            // solve leaves at most about 100 n ε.
            let tol = 100.0 * (2 * n) as f64 * f64::EPSILON;
            for i in 0..n {
                for r in 0..2 {
                    let (p, q, s) = (x[i][r], b[i][r], flat[2 * i + r]);
                    assert!(
                        (p - q).abs() <= tol && (p - s).abs() <= tol,
                        "n {n}: {p} {q} {s}"
                    );
                }
            }
        }
    }

    #[test]
    fn a_singular_block_is_refused() {
        let a = BlockTridiag::zeros(3);
        assert_eq!(BlockLdlt::factor(&a).unwrap_err().block, 0);
    }
}
