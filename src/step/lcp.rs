//! Exact solver of the dense linear complementarity problem `w = S r + q >= 0, r >= 0,
//! rᵀw = 0` with `S` symmetric positive definite (`m × m`; the condensed contact problem
//! `S = E C⁻¹ Eᵀ` of [`crate::step::condensed_lcp`]). An SPD matrix is a P-matrix, so the solution
//! exists and is unique for every `q` (Cottle, Pang & Stone, *The Linear Complementarity
//! Problem*, Thm 3.3.7).
//!
//! Method: block principal pivoting with Murty's least-index safeguard, the driver of
//! [`crate::step::pivoting`] (shared with the bar's [`crate::step::block_pivot`]). For an active
//! set `A`: `S_AA r_A = −q_A` by a dense Cholesky in a buffer kept for the run, `w = q + S r`;
//! an index is infeasible when `r_k S_kk` (active) or `w_k` (free) is below minus the round-off
//! threshold on `‖S‖∞ max|r| + max|q|`. The active set is kept for the next call (warm start).
//! [`DenseLcp::solve`] allocates nothing.

use crate::step::pivoting::{
    ActiveSetProblem, MurtyOrder, iteration_limit, pivot, round_off_threshold,
};

/// A dense LCP that could not be solved.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum LcpError {
    #[error("the contact matrix S is not positive definite (pivot {index})")]
    NotPositiveDefinite { index: usize },
    #[error("no complementary solution after {iterations} pivots")]
    IterationLimit { iterations: u32 },
    #[error("the contact reactions are not finite")]
    NonFinite,
}

/// The LCP `w = S r + q >= 0 ⊥ r >= 0` for one `S`, solved for many `q`.
#[derive(Clone, Debug)]
pub struct DenseLcp {
    m: usize,
    /// `S`, row-major.
    s: Vec<f64>,
    /// `max_k Σ_j |S_kj|`.
    s_norm: f64,
    active: Vec<bool>,
    /// The active indices of the current iterate.
    index: Vec<usize>,
    /// Cholesky factor of `S_AA`, row-major with stride `|A|`, and the set it was made for
    /// (a warm start that keeps the active set reuses it: no refactorisation).
    factor: Vec<f64>,
    factored: Vec<bool>,
    factor_valid: bool,
    infeasible: Vec<usize>,
    max_iterations: u32,
}

impl DenseLcp {
    /// Set-up for the symmetric `m × m` matrix `s` (row-major); refuses one whose Cholesky
    /// factorisation fails (not positive definite).
    pub fn new(s: Vec<f64>, m: usize) -> Result<Self, LcpError> {
        assert_eq!(s.len(), m * m, "S must be m x m");
        let s_norm = (0..m)
            .map(|k| s[k * m..(k + 1) * m].iter().map(|v| v.abs()).sum::<f64>())
            .fold(0.0, f64::max);
        let mut this = Self {
            m,
            s,
            s_norm,
            active: vec![true; m],
            index: Vec::with_capacity(m),
            factor: vec![0.0; m * m],
            factored: vec![false; m],
            factor_valid: false,
            infeasible: Vec::with_capacity(m),
            max_iterations: iteration_limit(m),
        };
        // The whole matrix must factorise: S positive definite.
        this.collect_active();
        this.factor_active()?;
        this.factor_valid = false;
        this.active.fill(false);
        Ok(this)
    }

    /// `m`.
    pub fn dim(&self) -> usize {
        self.m
    }

    /// `S_jk`.
    pub fn entry(&self, j: usize, k: usize) -> f64 {
        self.s[j * self.m + k]
    }

    /// `max_k Σ_j |S_kj|`.
    pub fn norm(&self) -> f64 {
        self.s_norm
    }

    /// The active set of the last answer (`r_k` may be positive only there).
    pub fn active(&self) -> &[bool] {
        &self.active
    }

    /// Forgets the warm start.
    pub fn reset(&mut self) {
        self.active.fill(false);
    }

    /// Test access: sets the warm-start active set.
    #[cfg(test)]
    fn set_active(&mut self, active: &[bool]) {
        self.active.copy_from_slice(active);
    }

    fn collect_active(&mut self) {
        self.index.clear();
        for (k, &a) in self.active.iter().enumerate() {
            if a {
                self.index.push(k);
            }
        }
    }

    /// `S_AA = L Lᵀ` into `factor` (stride `|A|`).
    fn factor_active(&mut self) -> Result<(), LcpError> {
        let (a, m) = (self.index.len(), self.m);
        let l = &mut self.factor;
        for i in 0..a {
            for j in 0..=i {
                let mut v = self.s[self.index[i] * m + self.index[j]];
                for k in 0..j {
                    v -= l[i * a + k] * l[j * a + k];
                }
                if i == j {
                    if v.is_nan() || v <= 0.0 {
                        return Err(LcpError::NotPositiveDefinite {
                            index: self.index[i],
                        });
                    }
                    l[i * a + i] = v.sqrt();
                } else {
                    l[i * a + j] = v / l[j * a + j];
                }
            }
        }
        Ok(())
    }

    /// `r_A = −S_AA⁻¹ q_A`, `r_F = 0`, then `w = S r + q` (every row, so that `w_A` shows the
    /// round-off of the answer).
    fn solve_active(&mut self, q: &[f64], r: &mut [f64], w: &mut [f64]) -> Result<(), LcpError> {
        if !(self.factor_valid && self.factored == self.active) {
            self.factor_valid = false;
            self.factor_active()?;
            self.factored.copy_from_slice(&self.active);
            self.factor_valid = true;
        }
        let (a, m) = (self.index.len(), self.m);
        let l = &self.factor;
        r.fill(0.0);
        // Forward, then backward substitution, in the compact slots r[index[i]].
        for i in 0..a {
            let mut v = -q[self.index[i]];
            for k in 0..i {
                v -= l[i * a + k] * r[self.index[k]];
            }
            r[self.index[i]] = v / l[i * a + i];
        }
        for i in (0..a).rev() {
            let mut v = r[self.index[i]];
            for k in i + 1..a {
                v -= l[k * a + i] * r[self.index[k]];
            }
            r[self.index[i]] = v / l[i * a + i];
        }
        for k in 0..m {
            let row = &self.s[k * m..(k + 1) * m];
            let mut v = q[k];
            for &j in &self.index {
                v += row[j] * r[j];
            }
            w[k] = v;
        }
        Ok(())
    }

    /// Solves `w = S r + q >= 0 ⊥ r >= 0`, warm-started from the previous active set; returns
    /// the number of active sets tried. `r` is clamped to `>= 0` (it is negative only within
    /// round-off), `w` is `S r + q` as computed. Allocates nothing.
    pub fn solve(&mut self, q: &[f64], r: &mut [f64], w: &mut [f64]) -> Result<u32, LcpError> {
        let m = self.m;
        assert!(q.len() == m && r.len() == m && w.len() == m);
        if m == 0 {
            return Ok(1);
        }
        let q_max = q.iter().fold(0.0f64, |a, v| a.max(v.abs()));
        let max_iterations = self.max_iterations;
        let mut run = DenseIteration {
            lcp: self,
            q,
            r: &mut *r,
            w,
            q_max,
        };
        let iterations = pivot(&mut run, max_iterations)?;
        for v in r.iter_mut() {
            *v = v.max(0.0);
        }
        Ok(iterations)
    }
}

/// One call of [`DenseLcp::solve`]: the LCP, its `q` and the answer being built.
struct DenseIteration<'a> {
    lcp: &'a mut DenseLcp,
    q: &'a [f64],
    r: &'a mut [f64],
    w: &'a mut [f64],
    q_max: f64,
}

impl ActiveSetProblem for DenseIteration<'_> {
    type Error = LcpError;
    const MURTY_ORDER: MurtyOrder = MurtyOrder::LeastIndex;

    fn solve_active_set(&mut self) -> Result<(), LcpError> {
        let lcp = &mut *self.lcp;
        let m = lcp.m;
        lcp.collect_active();
        lcp.solve_active(self.q, self.r, self.w)?;
        let r_max = self.r.iter().fold(0.0f64, |a, v| a.max(v.abs()));
        if !r_max.is_finite() {
            return Err(LcpError::NonFinite);
        }
        // Round-off of a row of S r + q (in units of w); r_k is weighed by S_kk.
        let tol = round_off_threshold(lcp.s_norm * r_max + self.q_max);
        lcp.infeasible.clear();
        for k in 0..m {
            let bad = if lcp.active[k] {
                self.r[k] * lcp.s[k * m + k] < -tol
            } else {
                self.w[k] < -tol
            };
            if bad {
                lcp.infeasible.push(k);
            }
        }
        Ok(())
    }

    fn infeasible(&self) -> &[usize] {
        &self.lcp.infeasible
    }

    fn flip_all_infeasible(&mut self) {
        let lcp = &mut *self.lcp;
        for &k in &lcp.infeasible {
            lcp.active[k] = !lcp.active[k];
        }
    }

    fn flip_one(&mut self, index: usize) {
        self.lcp.active[index] = !self.lcp.active[index];
    }

    fn iteration_limit_error(iterations: u32) -> LcpError {
        LcpError::IterationLimit { iterations }
    }
}

/// The LCP by enumeration of all `2^m` active sets (tests and small `m` only): the set whose
/// answer violates the conditions least (`max(−r_A, −w_F)`), solved by nalgebra's LU. Returns
/// `(r, w)`.
pub fn brute_force(s: &[f64], q: &[f64]) -> (Vec<f64>, Vec<f64>) {
    let m = q.len();
    assert!(m <= 20, "enumeration of 2^m sets");
    let mut best = (f64::INFINITY, vec![0.0; m], vec![0.0; m]);
    for mask in 0u32..(1 << m) {
        let idx: Vec<usize> = (0..m).filter(|k| mask >> k & 1 == 1).collect();
        let a = idx.len();
        let saa = nalgebra::DMatrix::from_fn(a, a, |i, j| s[idx[i] * m + idx[j]]);
        let qa = nalgebra::DVector::from_fn(a, |i, _| -q[idx[i]]);
        let ra = if a == 0 {
            qa
        } else {
            let Some(ra) = saa.lu().solve(&qa) else {
                continue;
            };
            ra
        };
        let mut r = vec![0.0; m];
        for (i, &k) in idx.iter().enumerate() {
            r[k] = ra[i];
        }
        let w: Vec<f64> = (0..m)
            .map(|k| q[k] + (0..m).map(|j| s[k * m + j] * r[j]).sum::<f64>())
            .collect();
        let violation = (0..m)
            .map(|k| if mask >> k & 1 == 1 { -r[k] } else { -w[k] })
            .fold(f64::NEG_INFINITY, f64::max);
        if violation < best.0 {
            best = (violation, r, w);
        }
    }
    (best.1, best.2)
}

#[cfg(test)]
mod tests {
    use super::*;
    use proptest::prelude::*;

    /// Agreement with enumeration: both solve the same `|A| × |A|` system (Cholesky against
    /// LU), so the answers differ by round-off times the condition of `S_AA`, below about 400
    /// for the matrices below (`BᵀB + 0.1 I`, `|B_ij| <= 1`, m <= 6): 1e-9 is 1e4 times that.
    const AGREEMENT_TOL: f64 = 1e-9;
    /// Complementarity and signs of an answer, relative to `‖S‖ ‖r‖ + ‖q‖`: a row of `S r + q`
    /// rounds to a few ulps of that scale times the condition of `S_AA` (≤ 1e4 here).
    const KKT_TOL: f64 = 1e-10;

    fn spd(m: usize, seed: &[f64]) -> Vec<f64> {
        // S = BᵀB + 0.1 I, B from the seed entries.
        let b = |i: usize, j: usize| seed[(i * m + j) % seed.len()];
        let mut s = vec![0.0; m * m];
        for i in 0..m {
            for j in 0..m {
                s[i * m + j] = (0..m).map(|k| b(k, i) * b(k, j)).sum::<f64>();
            }
            s[i * m + i] += 0.1;
        }
        s
    }

    fn check_kkt(s: &[f64], q: &[f64], r: &[f64], w: &[f64]) {
        let m = q.len();
        let scale = s.iter().fold(0.0f64, |a, v| a.max(v.abs()))
            * m as f64
            * r.iter().fold(0.0f64, |a, v| a.max(v.abs()))
            + q.iter().fold(0.0f64, |a, v| a.max(v.abs()));
        let tol = KKT_TOL * scale.max(f64::MIN_POSITIVE);
        for k in 0..m {
            let wk = q[k] + (0..m).map(|j| s[k * m + j] * r[j]).sum::<f64>();
            assert!((wk - w[k]).abs() <= tol, "w[{k}]");
            assert!(r[k] >= 0.0 && wk >= -tol, "signs at {k}: r {} w {wk}", r[k]);
            assert!((r[k] * wk).abs() <= tol * r[k].max(1.0), "r w at {k}");
        }
    }

    proptest! {
        #![proptest_config(ProptestConfig::with_cases(200))]
        #[test]
        fn pivoting_matches_enumeration_on_random_spd_matrices(
            m in 1usize..7,
            seed in prop::collection::vec(-1.0f64..1.0, 1..49),
            q in prop::collection::vec(-2.0f64..2.0, 6),
            warm in prop::collection::vec(any::<bool>(), 6),
        ) {
            let s = spd(m, &seed);
            let q = &q[..m];
            let mut lcp = DenseLcp::new(s.clone(), m).unwrap();
            // A random warm start must not change the answer (uniqueness).
            lcp.set_active(&warm[..m]);
            let (mut r, mut w) = (vec![0.0; m], vec![0.0; m]);
            lcp.solve(q, &mut r, &mut w).unwrap();
            check_kkt(&s, q, &r, &w);
            let (rb, _) = brute_force(&s, q);
            let scale = rb.iter().fold(1.0f64, |a, v| a.max(v.abs()));
            for k in 0..m {
                prop_assert!((r[k] - rb[k]).abs() <= AGREEMENT_TOL * scale, "{k}: {} {}", r[k], rb[k]);
            }
        }
    }

    #[test]
    fn degenerate_cases() {
        // m = 0.
        let mut e = DenseLcp::new(vec![], 0).unwrap();
        assert_eq!(e.solve(&[], &mut [], &mut []), Ok(1));
        // q = 0: r = 0 (every set with r_A = 0 is a tie; none is infeasible).
        let s = spd(3, &[0.3, -0.7, 0.2, 0.9, 0.1]);
        let mut lcp = DenseLcp::new(s.clone(), 3).unwrap();
        let (mut r, mut w) = ([1.0; 3], [1.0; 3]);
        lcp.solve(&[0.0; 3], &mut r, &mut w).unwrap();
        assert_eq!(r, [0.0; 3]);
        // q >= 0: nothing active, on the first try.
        assert_eq!(lcp.solve(&[1.0, 0.0, 2.0], &mut r, &mut w), Ok(1));
        assert_eq!(r, [0.0; 3]);
        // All active: r = −S⁻¹q, w = 0 to round-off.
        let q = [-1.0, -2.0, -1.5];
        let (rb, _) = brute_force(&s, &q);
        lcp.solve(&q, &mut r, &mut w).unwrap();
        check_kkt(&s, &q, &r, &w);
        for k in 0..3 {
            assert!((r[k] - rb[k]).abs() <= AGREEMENT_TOL * rb[k].abs().max(1.0));
        }
        // The warm start: the same q again is solved on the first try.
        assert_eq!(lcp.solve(&q, &mut r, &mut w), Ok(1));
        // A nearly singular S (two almost equal normals, as on a very fine edge): still exact.
        let near = vec![1.0, 1.0 - 1e-8, 1.0 - 1e-8, 1.0];
        let mut lcp = DenseLcp::new(near.clone(), 2).unwrap();
        let q = [-1.0, -1.0];
        let (mut r, mut w) = ([0.0; 2], [0.0; 2]);
        lcp.solve(&q, &mut r, &mut w).unwrap();
        assert!(r.iter().all(|v| *v >= 0.0) && w.iter().all(|v| v.abs() <= 1e-7));
        // Not positive definite: refused.
        assert!(matches!(
            DenseLcp::new(vec![1.0, 2.0, 2.0, 1.0], 2),
            Err(LcpError::NotPositiveDefinite { .. })
        ));
    }
}
