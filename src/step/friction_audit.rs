//! The independent check of a frictional step answer `(z, r_N, r_T)`, recomputed with the
//! body's own `C` (never from a solver's residuals): the step equation
//! `C z = b + Σ_k r_N,k s_k e_{i_k} + Σ_j r_T,j e_{t_j}`, no penetration, `r_N >= 0`, normal
//! complementarity, the cone `|r_T,j| <= g_j` and the slip law `g_j |δ_j| + r_T,j δ_j = 0`
//! (`δ_j = (z + w)_{t_j}` the central slip; `g_j = μ_j r_N` for Coulomb, given for a Tresca
//! problem, 0 for the frictionless start-up), and the step equation's residual mapped to
//! displacement by one solve. Each check's tolerance is the answer's own
//! round-off floor plus the solver's stopping slack (0 for the exact solver);
//! `docs/friction.md#audit` derives the floors.

use crate::linalg::norms::max_abs;
use crate::linalg::system::{SpdSystem, inverse_norm_estimate};
use crate::step::audit::{first_failure, ratio};
use crate::step::report::{AuditReport, StepFailure, Worst};
use crate::step::solver::{Constraints, Friction};

/// The thresholds `g_j` of the tangential reactions.
#[derive(Clone, Copy, Debug)]
pub enum Thresholds<'a> {
    /// Coulomb: `g_j = μ_j r_N,k_j` of the answer itself.
    Coulomb,
    /// A Tresca problem's given thresholds.
    Given(&'a [f64]),
    /// No friction (the start-up step): `r_T = 0`.
    Zero,
}

/// The law an answer is held to.
#[derive(Clone, Copy, Debug)]
pub struct FrictionLaw<'a> {
    pub thresholds: Thresholds<'a>,
    /// The previous increment at the tangents (`None` at the start-up step: no slip law).
    pub previous: Option<&'a [f64]>,
    /// The solver's stopping slack in force (added to the force floors) and in displacement.
    pub slack_force: f64,
    pub slack_displacement: f64,
}

/// The audit of one run. [`FrictionAudit::check`] allocates nothing.
#[derive(Clone, Debug)]
pub struct FrictionAudit {
    /// The normals followed by the tangents.
    rows: Constraints,
    friction: Friction,
    m: usize,
    c_norm: f64,
    inv_norm: f64,
    residual: Vec<f64>,
    report: AuditReport,
}

impl FrictionAudit {
    /// Set-up for `C` (its norm and Hager's estimate of `‖C⁻¹‖∞`), the normal `constraints`
    /// and the `friction` rows.
    pub fn new(
        system: &mut impl SpdSystem,
        constraints: &Constraints,
        friction: &Friction,
    ) -> Self {
        let n = system.dim();
        Self {
            rows: friction.rows(constraints),
            friction: friction.clone(),
            m: constraints.len(),
            c_norm: system.inf_norm(),
            inv_norm: inverse_norm_estimate(system),
            residual: vec![0.0; n],
            report: AuditReport {
                primal_violation: Some(Worst::default()),
                complementarity: Some(Worst::default()),
                friction_cone: Some(Worst::default()),
                slip_law: Some(Worst::default()),
                ..Default::default()
            },
        }
    }

    /// The worst residuals so far.
    pub fn report(&self) -> &AuditReport {
        &self.report
    }

    /// Checks `(z, r)` (`r`: the `m` normal reactions, then the `p` tangential ones) of the
    /// step with data `(b, lo)` against `law`, records the residuals and returns the first
    /// failed check.
    pub fn check(
        &mut self,
        system: &mut impl SpdSystem,
        law: FrictionLaw<'_>,
        b: &[f64],
        lower: &[f64],
        z: &[f64],
        r: &[f64],
    ) -> Result<(), StepFailure> {
        let (m, p) = (self.m, self.friction.len());
        if !(z.iter().all(|v| v.is_finite()) && r[..m + p].iter().all(|v| v.is_finite())) {
            return Err(StepFailure::NonFinite);
        }
        let ulp = system.roundoff_ulps() * f64::EPSILON;
        // The step equation's residual, with the norms of its terms.
        system.mul_into(z, &mut self.residual);
        let (b_norm, z_norm) = (max_abs(b), max_abs(z));
        for (res, bi) in self.residual.iter_mut().zip(b) {
            *res -= bi;
        }
        for (k, (&i, &s)) in self
            .rows
            .unknowns
            .iter()
            .zip(&self.rows.directions)
            .enumerate()
        {
            self.residual[i] -= s * r[k];
        }
        let r_norm = max_abs(&r[..m + p]);
        let stationarity = max_abs(&self.residual);
        let tol_f = ulp * (self.c_norm * z_norm + b_norm + r_norm) + law.slack_force;
        // A backward-stable solve's displacement error and the rounding of z itself; the
        // condensed problem sums every reaction's effect on each gap and slip, so they round to
        // ulps of `Σ_j |S_kj r_j| <= ‖C⁻¹‖∞ ‖r‖₁`.
        let r_sum: f64 = r[..m + p].iter().map(|v| v.abs()).sum();
        let floor_z = self.inv_norm * (tol_f + ulp * r_sum) + ulp * z_norm;
        system.solve_in_place(&mut self.residual);
        let displacement = max_abs(&self.residual);
        let tol_dz = floor_z + law.slack_displacement;
        let mut scale_z = 0.0f64;
        for (k, &i) in self.rows.unknowns[..m].iter().enumerate() {
            scale_z = scale_z.max(z[i].abs()).max(lower[k].abs());
        }
        let tol_z = floor_z + ulp * scale_z + law.slack_displacement;
        let (mut primal, mut negative) = (0.0f64, 0.0f64);
        let mut comp = (0.0f64, 0.0f64);
        for k in 0..m {
            let (i, s) = (self.rows.unknowns[k], self.rows.directions[k]);
            let gap = s * z[i] - lower[k];
            primal = primal.max(-gap);
            negative = negative.max(-r[k]);
            let c = (r[k] * gap).abs();
            let t = tol_z * r[k].abs() + tol_f * gap.abs();
            if ratio(c, t) >= ratio(comp.0, comp.1) {
                comp = (c, t);
            }
        }
        let (mut cone, mut cone_tol) = (0.0f64, 0.0f64);
        let mut slip = (0.0f64, 0.0f64);
        for j in 0..p {
            let rt = r[m + j];
            let g = match law.thresholds {
                Thresholds::Coulomb => self.friction.coefficients[j] * r[self.friction.normals[j]],
                Thresholds::Given(g) => g[j],
                Thresholds::Zero => 0.0,
            };
            let excess = rt.abs() - g;
            let t = tol_f + ulp * g.abs();
            if ratio(excess.max(0.0), t) >= ratio(cone, cone_tol) {
                (cone, cone_tol) = (excess.max(0.0), t);
            }
            if let Some(w) = law.previous {
                let delta = z[self.friction.tangents[j]] + w[j];
                let value = (g * delta.abs() + rt * delta).abs();
                let t = tol_f * delta.abs() + (tol_z + ulp * w[j].abs()) * (g.abs() + rt.abs());
                if ratio(value, t) >= ratio(slip.0, slip.1) {
                    slip = (value, t);
                }
            }
        }
        let rep = &mut self.report;
        rep.steps += 1;
        rep.stationarity.observe(stationarity, tol_f);
        rep.stationarity_displacement.observe(displacement, tol_dz);
        rep.negative_reaction.observe(negative, tol_f);
        let observe = |w: &mut Option<Worst>, (v, t): (f64, f64)| {
            if let Some(w) = w.as_mut() {
                w.observe(v, t);
            }
        };
        observe(&mut rep.primal_violation, (primal, tol_z));
        observe(&mut rep.complementarity, comp);
        observe(&mut rep.friction_cone, (cone, cone_tol));
        observe(&mut rep.slip_law, slip);
        first_failure([
            ("primal violation (lo_k - s_k z_k)+", primal, tol_z),
            ("negative reaction (-r_N)+", negative, tol_f),
            ("complementarity |r_N (s_k z_k - lo_k)|", comp.0, comp.1),
            ("friction cone (|r_T| - mu r_N)+", cone, cone_tol),
            ("slip law |mu r_N |delta| + r_T delta|", slip.0, slip.1),
            ("stationarity |Cz - b - E^T r|", stationarity, tol_f),
            (
                "stationarity in displacement |C^-1 (Cz - b - E^T r)|",
                displacement,
                tol_dz,
            ),
        ])
    }
}
