//! Exact solver for the step QP with a bound at many nodes (distributed Signorini: an obstacle
//! under every node):
//!
//! ```text
//!   minimise ½ zᵀ C z − bᵀ z   subject to   z_i >= lo_i  for i in B,
//! ```
//!
//! `C` symmetric positive definite tridiagonal. With `y = z − lo` this is the linear
//! complementarity problem `λ = C y − (b − C lo)`, `y ≥ 0`, `λ ≥ 0`, `yᵀλ = 0` restricted to `B`;
//! `C` is a P-matrix, so the solution is unique.
//!
//! Method: block principal pivoting (Júdice & Pires, Comput. Oper. Res. 21, 1994) safeguarded
//! by Murty's single pivoting rule, finite on every P-matrix LCP
//! ([docs/step-solvers.md](../docs/step-solvers.md#block-principal-pivoting)).
//!
//! Each iteration solves `C_FF z_F = b_F − C_FA lo_A` on the free set `F` with `z_A = lo_A`: one
//! tridiagonal factorisation and solve of size `n` (active rows replaced by identity rows), O(n).
//! The active set is warm-started from the previous step; when it is empty, the factorisation
//! of `C` computed once per run is used.

use crate::linalg::ldlt::{Ldlt, NotPositiveDefinite};
use crate::linalg::norms::max_abs;
use crate::linalg::tridiag::SymTridiag;
use crate::step::{SolveInfo, StepFailure, StepSolver};

/// Block iterations allowed without a decrease of the number of infeasible indices before the
/// single-pivot safeguard takes over (Júdice & Pires use a small constant; 10 keeps the fast
/// block steps through transient increases).
pub const BLOCK_PATIENCE: u32 = 10;
/// An index counts as infeasible only beyond this many ulps of the quantities compared: below
/// it, the sign of `z_i − lo_i` or `λ_i` is round-off and either choice satisfies KKT.
pub const TIE_ULPS: f64 = 64.0;

/// Exact solver for bounds at many nodes.
#[derive(Clone, Debug)]
pub struct BlockPivotSolver {
    c: SymTridiag,
    /// `max_i Σ_j |C_ij|`, for the round-off threshold of the multipliers.
    c_norm: f64,
    factor: Ldlt,
    /// Constrained nodes (strictly increasing) and, per node, its constraint index or `NONE`.
    nodes: Vec<usize>,
    slot: Vec<usize>,
    /// Active flags per constraint, kept from the previous step (warm start).
    active: Vec<bool>,
    diag: Vec<f64>,
    off: Vec<f64>,
    l: Vec<f64>,
    inv_d: Vec<f64>,
    cz: Vec<f64>,
    infeasible: Vec<usize>,
    max_iterations: u32,
}

const NONE: usize = usize::MAX;

impl BlockPivotSolver {
    /// `nodes` must be strictly increasing indices into `0..C.dim()`.
    pub fn new(c: &SymTridiag, nodes: &[usize]) -> Result<Self, NotPositiveDefinite> {
        let n = c.dim();
        assert!(nodes.windows(2).all(|w| w[0] < w[1]) && nodes.iter().all(|&i| i < n));
        let factor = Ldlt::factor(c)?;
        let mut slot = vec![NONE; n];
        for (k, &i) in nodes.iter().enumerate() {
            slot[i] = k;
        }
        let c_norm = c.inf_norm();
        Ok(Self {
            c: c.clone(),
            c_norm,
            factor,
            nodes: nodes.to_vec(),
            slot,
            active: vec![false; nodes.len()],
            diag: vec![0.0; n],
            off: vec![0.0; n.saturating_sub(1)],
            l: vec![0.0; n.saturating_sub(1)],
            inv_d: vec![0.0; n],
            cz: vec![0.0; n],
            infeasible: Vec::with_capacity(nodes.len()),
            // Murty's rule is finite but may in theory need many pivots; beyond this the step
            // fails with an error instead of returning an unverified point.
            max_iterations: 50 * (nodes.len() as u32).max(1) + 100,
        })
    }

    fn is_active(&self, i: usize) -> bool {
        let k = self.slot[i];
        k != NONE && self.active[k]
    }

    /// Solves with the current active set: `z_A = lo_A`, `C_FF z_F = b_F − C_FA lo_A`.
    fn solve_reduced(&mut self, rhs: &[f64], lower: &[f64], z: &mut [f64]) {
        let n = z.len();
        if !self.active.iter().any(|&a| a) {
            self.factor.solve_into(rhs, z);
            return;
        }
        for i in 0..n {
            if self.is_active(i) {
                self.diag[i] = 1.0;
                z[i] = lower[self.slot[i]];
            } else {
                self.diag[i] = self.c.diag[i];
                let mut r = rhs[i];
                if i > 0 && self.is_active(i - 1) {
                    r -= self.c.off[i - 1] * lower[self.slot[i - 1]];
                }
                if i + 1 < n && self.is_active(i + 1) {
                    r -= self.c.off[i] * lower[self.slot[i + 1]];
                }
                z[i] = r;
            }
            if i + 1 < n {
                let coupled = !self.is_active(i) && !self.is_active(i + 1);
                self.off[i] = if coupled { self.c.off[i] } else { 0.0 };
            }
        }
        // LDLᵀ of the reduced matrix (a principal submatrix of C with identity rows: SPD).
        let mut d_prev = self.diag[0];
        self.inv_d[0] = 1.0 / d_prev;
        for i in 1..n {
            let li = self.off[i - 1] / d_prev;
            self.l[i - 1] = li;
            d_prev = self.diag[i] - li * self.off[i - 1];
            self.inv_d[i] = 1.0 / d_prev;
        }
        let mut t = z[0];
        z[0] = t * self.inv_d[0];
        for ((zi, li), inv_d) in z[1..n].iter_mut().zip(&self.l).zip(&self.inv_d[1..]) {
            t = *zi - li * t;
            *zi = t * inv_d;
        }
        let mut next = z[n - 1];
        for i in (0..n - 1).rev() {
            next = z[i] - self.l[i] * next;
            z[i] = next;
        }
    }
}

impl StepSolver for BlockPivotSolver {
    fn name(&self) -> &'static str {
        "exact"
    }

    fn solve(
        &mut self,
        rhs: &[f64],
        lower: &[f64],
        z: &mut [f64],
        reactions: &mut [f64],
    ) -> Result<SolveInfo, StepFailure> {
        let eps = f64::EPSILON;
        let b_max = max_abs(rhs);
        let lo_max = max_abs(lower);
        let mut best_count = usize::MAX;
        let mut patience = BLOCK_PATIENCE;
        for iteration in 1..=self.max_iterations {
            self.solve_reduced(rhs, lower, z);
            self.c.mul_into(z, &mut self.cz);
            let z_max = max_abs(z.iter());
            if !z_max.is_finite() {
                return Err(StepFailure::NonFinite);
            }
            let tol_z = TIE_ULPS * eps * (z_max + lo_max);
            let tol_l = TIE_ULPS * eps * (self.c_norm * z_max + b_max);
            self.infeasible.clear();
            for (k, &i) in self.nodes.iter().enumerate() {
                let bad = if self.active[k] {
                    self.cz[i] - rhs[i] < -tol_l
                } else {
                    z[i] < lower[k] - tol_z
                };
                if bad {
                    self.infeasible.push(k);
                }
            }
            if self.infeasible.is_empty() {
                for (k, &i) in self.nodes.iter().enumerate() {
                    reactions[k] = if self.active[k] {
                        (self.cz[i] - rhs[i]).max(0.0)
                    } else {
                        0.0
                    };
                }
                return Ok(SolveInfo {
                    iterations: iteration,
                });
            }
            let count = self.infeasible.len();
            if count < best_count {
                best_count = count;
                patience = BLOCK_PATIENCE;
            } else {
                patience = patience.saturating_sub(1);
            }
            if patience > 0 || count < best_count {
                for &k in &self.infeasible {
                    self.active[k] = !self.active[k];
                }
            } else {
                let k = *self.infeasible.last().expect("non-empty");
                self.active[k] = !self.active[k];
            }
        }
        Err(StepFailure::IterationLimit {
            iterations: self.max_iterations,
        })
    }
}
