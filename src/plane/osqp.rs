//! OSQP on the plane body's full sparse step problem with Signorini edges, the bar's
//! [`crate::step::osqp`] on the plane:
//!
//! ```text
//!   minimise ½ zᵀ C z − bᵀ z   s.t.   E z <= h,   h = g − E u^n,
//! ```
//!
//! `P = C` (upper triangle in CSC, from the symmetric CSR pattern: column `j` of the upper
//! triangle is row `j`'s columns `<= j`), `q = −b`, `A = E` (one `±1` per row), `l = −∞`
//! ([`OSQP_INFTY`]), `u = h`. Set up once per run; each step updates `q` and `u` and
//! warm-starts from the previous answer. OSQP's dual `y` is `>= 0` at an active upper bound
//! and `C z − b + Eᵀ y = 0`, so the reaction is `r = y` (the exact solver's `C z = b − Eᵀ r`).
//!
//! Every answer is audited as the bar's ([`crate::step::audit`], OSQP's own criterion times
//! [`AUDIT_MARGIN`], plus round-off floors): primal `max (E z − h)⁺`, `max (−r)⁺`,
//! complementarity `|r_k (h − E z)_k| <= tol_z |r_k| + tol_f |(h − Ez)_k|`, stationarity
//! `‖C z − b + Eᵀ r‖∞` and the same mapped to displacement by a solve with the factor of `C`.
//! A status other than "solved" is an error, but "solved inaccurate" with `accept_inaccurate`
//! (audited at [`INACCURATE_FACTOR`] times the tolerances, counted). With no contact normal
//! `A` is `0 × n` and OSQP solves the unconstrained problem, as the bar's does.

use crate::plane::factor::SparseCholesky;
use crate::plane::matrices::Pattern;
use crate::plane::normals::Normal;
use crate::step::audit::{AUDIT_MARGIN, INACCURATE_FACTOR, dual_tolerance, record_and_check};
use crate::step::osqp::{OSQP_INFTY, OsqpSettings};
use crate::step::report::{AuditReport, StepFailure, Worst};
use osqp::{CscMatrix, Problem, Settings, Status};
use std::borrow::Cow;

/// Round-off floor of the plane audit, in units of `ε·(magnitude of the terms)`: a row of
/// `C z` sums 18 products (about 18 ulps of `|C||z|`), the sparse solve that produced `z` adds
/// its backward error (below 16 ulps, `factor.rs`), `− b + r` two more; 64 leaves a margin
/// of about two.
pub const PLANE_ROUNDOFF_ULPS: f64 = 64.0;
/// Safety factor on the estimate `‖C⁻¹ 1‖∞` of `‖C⁻¹‖∞` (exact for an M-matrix, a lower bound
/// otherwise): `C = M/Δt² + …` is dominated by the consistent mass, whose inverse has entries
/// of both signs but a row sum within a small factor of its norm.
pub const INVERSE_NORM_MARGIN: f64 = 4.0;

/// OSQP on the plane's step problem, set up once, audited every step.
pub struct PlaneOsqp {
    problem: Problem,
    settings: OsqpSettings,
    pattern: Pattern,
    c: Vec<f64>,
    /// `‖C‖∞` and the estimate of `‖C⁻¹‖∞`.
    c_norm: f64,
    inv_norm: f64,
    q: Vec<f64>,
    upper: Vec<f64>,
    x_prev: Vec<f64>,
    y_prev: Vec<f64>,
    residual: Vec<f64>,
    report: AuditReport,
    inaccurate_steps: u64,
}

impl PlaneOsqp {
    /// Set-up for `C` (values `c` on `pattern`) and the contact normals.
    pub fn new(
        pattern: &Pattern,
        c: &[f64],
        normals: &[Normal],
        chol: &mut SparseCholesky,
        settings: OsqpSettings,
    ) -> Result<Self, String> {
        settings.validate().map_err(|e| e.to_string())?;
        let n = pattern.n;
        let m = normals.len();
        // P: upper triangle in CSC.
        let (mut indptr, mut indices, mut data) = (vec![0], Vec::new(), Vec::new());
        for r in 0..n {
            let range = pattern.row_ptr[r]..pattern.row_ptr[r + 1];
            for (&col, &v) in pattern.cols[range.clone()].iter().zip(&c[range]) {
                if col <= r {
                    indices.push(col);
                    data.push(v);
                }
            }
            indptr.push(indices.len());
        }
        let p = CscMatrix {
            nrows: n,
            ncols: n,
            indptr: Cow::Owned(indptr),
            indices: Cow::Owned(indices),
            data: Cow::Owned(data),
        };
        // A = E: column i holds the row k with unknown_k = i (at most one).
        let mut row_of = vec![usize::MAX; n];
        for (k, nk) in normals.iter().enumerate() {
            row_of[nk.unknown] = k;
        }
        let (mut aptr, mut aind, mut adata) = (vec![0], Vec::new(), Vec::new());
        for &k in &row_of {
            if k != usize::MAX {
                aind.push(k);
                adata.push(normals[k].sign);
            }
            aptr.push(aind.len());
        }
        let a = CscMatrix {
            nrows: m,
            ncols: n,
            indptr: Cow::Owned(aptr),
            indices: Cow::Owned(aind),
            data: Cow::Owned(adata),
        };
        let osqp_settings: Settings = Settings::default()
            .verbose(false)
            .eps_abs(settings.eps_abs)
            .eps_rel(settings.eps_rel)
            .max_iter(settings.max_iter)
            .polish(settings.polish)
            .warm_start(true)
            .adaptive_rho_interval(Some(settings.adaptive_rho_interval));
        let q = vec![0.0; n];
        let lower = vec![-OSQP_INFTY; m];
        let upper = vec![OSQP_INFTY; m];
        let problem =
            Problem::new(p, &q, a, &lower, &upper, &osqp_settings).map_err(|e| e.to_string())?;
        let c_norm = (0..n)
            .map(|r| {
                (pattern.row_ptr[r]..pattern.row_ptr[r + 1])
                    .map(|k| c[k].abs())
                    .sum()
            })
            .fold(0.0f64, f64::max);
        let mut ones = vec![1.0; n];
        chol.solve_in_place(&mut ones);
        let inv_norm = INVERSE_NORM_MARGIN * ones.iter().fold(0.0f64, |a, v| a.max(v.abs()));
        Ok(Self {
            problem,
            settings,
            pattern: pattern.clone(),
            c: c.to_vec(),
            c_norm,
            inv_norm,
            q,
            upper,
            x_prev: vec![0.0; n],
            y_prev: vec![0.0; m],
            residual: vec![0.0; n],
            report: AuditReport {
                primal_violation: Some(Worst::default()),
                complementarity: Some(Worst::default()),
                ..Default::default()
            },
            inaccurate_steps: 0,
        })
    }

    /// The worst audit residuals so far.
    pub fn report(&self) -> &AuditReport {
        &self.report
    }

    /// Steps accepted as "solved inaccurate" (`solver.accept_inaccurate`).
    pub fn inaccurate_steps(&self) -> u64 {
        self.inaccurate_steps
    }

    /// Solves the step with right-hand side `b` at the state `u = u^n`: `z` and the reactions
    /// `r`, audited; returns OSQP's iterations. Allocates nothing but what OSQP's C code does
    /// not (it allocates nothing per solve).
    pub fn solve(
        &mut self,
        normals: &[Normal],
        b: &[f64],
        u: &[f64],
        chol: &mut SparseCholesky,
        z: &mut [f64],
        r: &mut [f64],
    ) -> Result<u32, StepFailure> {
        if !b.iter().all(|v| v.is_finite()) {
            return Err(StepFailure::NonFinite);
        }
        for (qi, bi) in self.q.iter_mut().zip(b) {
            *qi = -bi;
        }
        for (h, nk) in self.upper.iter_mut().zip(normals) {
            *h = nk.gap - nk.sign * u[nk.unknown];
        }
        self.problem.update_lin_cost(&self.q);
        if !normals.is_empty() {
            self.problem.update_upper_bound(&self.upper);
        }
        self.problem.warm_start(&self.x_prev, &self.y_prev);
        let status = self.problem.solve();
        let iterations = status.iter();
        let (solution, inaccurate) = match status {
            Status::Solved(s) => (s, false),
            Status::SolvedInaccurate(s) if self.settings.accept_inaccurate => (s, true),
            other => {
                return Err(StepFailure::Osqp {
                    status: crate::step::osqp::status_of(&other),
                    iterations,
                });
            }
        };
        z.copy_from_slice(solution.x());
        for (rk, y) in r.iter_mut().zip(solution.y()) {
            // 0.0 + y: no −0.0 reactions.
            *rk = 0.0 + y;
        }
        self.x_prev.copy_from_slice(z);
        self.y_prev.copy_from_slice(solution.y());
        // "Solved inaccurate" met OSQP's test at 10x the tolerances: audited at those.
        let factor = if inaccurate { INACCURATE_FACTOR } else { 1.0 };
        self.audit(normals, b, z, r, chol, factor)?;
        self.inaccurate_steps += u64::from(inaccurate);
        Ok(iterations)
    }

    fn audit(
        &mut self,
        normals: &[Normal],
        b: &[f64],
        z: &[f64],
        r: &[f64],
        chol: &mut SparseCholesky,
        factor: f64,
    ) -> Result<(), StepFailure> {
        if !(z.iter().all(|v| v.is_finite()) && r.iter().all(|v| v.is_finite())) {
            return Err(StepFailure::NonFinite);
        }
        let (eps_abs, eps_rel) = (
            AUDIT_MARGIN * factor * self.settings.eps_abs,
            AUDIT_MARGIN * factor * self.settings.eps_rel,
        );
        let ulp = PLANE_ROUNDOFF_ULPS * f64::EPSILON;
        self.pattern.mul_into(&self.c, z, &mut self.residual);
        let (mut cz_norm, mut b_norm, mut z_norm) = (0.0f64, 0.0f64, 0.0f64);
        for i in 0..z.len() {
            cz_norm = cz_norm.max(self.residual[i].abs());
            b_norm = b_norm.max(b[i].abs());
            z_norm = z_norm.max(z[i].abs());
            self.residual[i] -= b[i];
        }
        let mut r_norm = 0.0f64;
        for (nk, rk) in normals.iter().zip(r) {
            self.residual[nk.unknown] += nk.sign * rk;
            r_norm = r_norm.max(rk.abs());
        }
        let res_norm = self.residual.iter().fold(0.0f64, |a, v| a.max(v.abs()));
        let floor_f = ulp * (self.c_norm * z_norm + b_norm + r_norm);
        let tol_f = dual_tolerance(eps_abs, eps_rel, cz_norm, b_norm, r_norm) + floor_f;
        chol.solve_in_place(&mut self.residual);
        let dz_norm = self.residual.iter().fold(0.0f64, |a, v| a.max(v.abs()));
        let tol_dz = eps_abs + eps_rel * z_norm + self.inv_norm * floor_f;
        let mut p_scale = 0.0f64;
        for (nk, h) in normals.iter().zip(&self.upper) {
            p_scale = p_scale.max(z[nk.unknown].abs()).max(h.abs());
        }
        let tol_z = eps_abs + eps_rel * p_scale + ulp * p_scale;
        let (mut primal, mut negative, mut comp, mut comp_tol) = (0.0f64, 0.0f64, 0.0f64, 0.0);
        for ((nk, h), rk) in normals.iter().zip(&self.upper).zip(r) {
            let gap = h - nk.sign * z[nk.unknown];
            primal = primal.max(-gap);
            negative = negative.max(-rk);
            let c = (rk * gap).abs();
            let t = tol_z * rk.abs() + tol_f * gap.abs();
            if c * comp_tol >= comp * t {
                (comp, comp_tol) = (c, t);
            }
        }
        record_and_check(
            &mut self.report,
            [
                ("primal violation (Ez - h)+", primal, tol_z),
                ("negative reaction (-r_k)+", negative, tol_f),
                ("complementarity |r_k (h - Ez)_k|", comp, comp_tol),
                ("stationarity |Cz - b + E^T r|", res_norm, tol_f),
                (
                    "stationarity in displacement |C^-1 (Cz - b + E^T r)|",
                    dz_norm,
                    tol_dz,
                ),
            ],
            None,
        )
    }
}
