//! The frictional step by OSQP, for comparison with the exact solver: Coulomb's law as the
//! fixed point of Tresca problems. Given thresholds `g_j = μ_j r_N` of the previous iterate,
//! the Tresca step is the convex QP on the condensed reactions (box-constrained multipliers)
//!
//! ```text
//!   minimise ½ rᵀ S r + qᵀ r   subject to   r_N >= 0,   −g <= r_T <= g,
//! ```
//!
//! (`S`, `q` of [`crate::step::condensed_lemke`]; its KKT conditions are Signorini on the
//! normals and Tresca's law on the central slip, relative to a sliding obstacle), solved by
//! OSQP, set up once and warm-started; `z` then from `C z = b + Eᵀ r`, and each answer audited against the Tresca law it solved
//! ([`crate::step::audit`]). The iteration starts from the previous step's normal
//! reactions and stops when they change by at most [`FIXED_POINT_TOL`] (relative); beyond
//! [`FIXED_POINT_MAX_ITERATIONS`] it is an error. The start-up step is the same fixed point with
//! `w = 0` (the slip `u^1 − u^0`), from `g = 0`.

use crate::linalg::norms::max_abs;
use crate::linalg::system::{Csc, SpdSystem};
use crate::step::audit::{AUDIT_MARGIN, INACCURATE_FACTOR, KktAudit, Slack};
use crate::step::condensed_lcp::condensed_matrix;
use crate::step::law::{Law, LawFamily, Slip};
use crate::step::osqp::{OSQP_INFTY, OsqpSettings, accepted, identity_allowance, osqp_csc};
use crate::step::solver::{Constraints, Friction};
use crate::step::{SetupError, SolveInfo, SolverReport, StepFailure, StepSolver};
use osqp::Problem;

/// The fixed point stops when the normal reactions change by at most this, relative to their
/// largest: polished OSQP answers are exact to round-off, so the iteration can settle far below
/// OSQP's own `eps`, and this keeps its error well under the comparison's 1e-7.
pub const FIXED_POINT_TOL: f64 = 1e-12;
/// Tresca problems allowed per step: the iteration contracts at a rate of about `μ` times the
/// normal–tangential coupling of `S` (measured below 0.5 on the built-in scenes), so a few
/// dozen suffice; beyond this it is reported as not converging.
pub const FIXED_POINT_MAX_ITERATIONS: u32 = 200;

/// OSQP on the Tresca problems of the fixed point.
pub struct OsqpTresca<S: SpdSystem> {
    system: S,
    constraints: Constraints,
    friction: Friction,
    settings: OsqpSettings,
    problem: Problem,
    sigma: f64,
    /// The previous increment at the tangents (0 until given: the start-up step's law).
    previous: Vec<f64>,
    /// The obstacles' tangential displacements `v_j` (zeros unless an obstacle slides).
    obstacle: Vec<f64>,
    /// `q / σ`, the bounds, the thresholds, the iterate and the warm start.
    q: Vec<f64>,
    lower: Vec<f64>,
    upper: Vec<f64>,
    thresholds: Vec<f64>,
    r: Vec<f64>,
    /// The normal reactions before the current Tresca problem.
    r_before: Vec<f64>,
    y_prev: Vec<f64>,
    audit: KktAudit,
    inaccurate_steps: u64,
}

/// The upper triangle of the dense symmetric `k × k` matrix `s / sigma`, in CSC.
fn dense_upper(s: &[f64], k: usize, sigma: f64) -> Csc {
    let (mut indptr, mut indices, mut data) = (vec![0], Vec::new(), Vec::new());
    for j in 0..k {
        for i in 0..=j {
            indices.push(i);
            data.push(s[i * k + j] / sigma);
        }
        indptr.push(indices.len());
    }
    Csc {
        nrows: k,
        ncols: k,
        indptr,
        indices,
        data,
    }
}

impl<S: SpdSystem> OsqpTresca<S> {
    /// Forms `S` and sets OSQP up on it with `A = I`.
    pub fn new(
        mut system: S,
        constraints: Constraints,
        friction: Friction,
        settings: OsqpSettings,
    ) -> Result<Self, SetupError> {
        settings.validate()?;
        let (m, p) = (constraints.len(), friction.len());
        let k = m + p;
        let s = condensed_matrix(&friction.rows(&constraints), &mut system);
        let sigma = (0..k).map(|i| s[i * k + i]).fold(0.0, f64::max);
        if !(sigma > 0.0 && sigma.is_finite()) {
            return Err(SetupError::Contact(format!("S has diagonal scale {sigma}")));
        }
        let identity = Csc {
            nrows: k,
            ncols: k,
            indptr: (0..=k).collect(),
            indices: (0..k).collect(),
            data: vec![1.0; k],
        };
        let (q, lower, upper) = (vec![0.0; k], vec![-OSQP_INFTY; k], vec![OSQP_INFTY; k]);
        let problem = Problem::new(
            osqp_csc(dense_upper(&s, k, sigma)),
            &q,
            osqp_csc(identity),
            &lower,
            &upper,
            &settings.to_osqp(),
        )
        .map_err(|e| SetupError::Osqp(e.to_string()))?;
        let audit = KktAudit::new(&mut system, &constraints, LawFamily::Frictional(&friction));
        Ok(Self {
            system,
            constraints,
            settings,
            problem,
            sigma,
            previous: vec![0.0; p],
            obstacle: vec![0.0; p],
            q,
            lower,
            upper,
            thresholds: vec![0.0; p],
            r: vec![0.0; k],
            r_before: vec![0.0; m],
            y_prev: vec![0.0; k],
            audit,
            inaccurate_steps: 0,
            friction,
        })
    }

    /// One Tresca problem with the current thresholds: OSQP's answer into `reactions`, `z`
    /// from the step equation, the audit; returns whether OSQP's answer was inaccurate.
    fn tresca(
        &mut self,
        rhs: &[f64],
        lower: &[f64],
        z: &mut [f64],
        reactions: &mut [f64],
    ) -> Result<bool, StepFailure> {
        let m = self.constraints.len();
        for (j, g) in self.thresholds.iter().enumerate() {
            self.lower[m + j] = -g;
            self.upper[m + j] = *g;
        }
        for k in 0..m {
            (self.lower[k], self.upper[k]) = (0.0, OSQP_INFTY);
        }
        self.problem.update_bounds(&self.lower, &self.upper);
        self.problem.warm_start(&self.r, &self.y_prev);
        let (solution, inaccurate) =
            accepted(self.problem.solve(), self.settings.accept_inaccurate)?;
        reactions.copy_from_slice(solution.x());
        self.y_prev.copy_from_slice(solution.y());
        self.r.copy_from_slice(reactions);
        z.copy_from_slice(rhs);
        let (unknowns, signs) = (&self.constraints.unknowns, &self.constraints.directions);
        for (k, r) in reactions[..m].iter().enumerate() {
            z[unknowns[k]] += signs[k] * r;
        }
        for (j, r) in reactions[m..].iter().enumerate() {
            z[self.friction.tangents[j]] += r;
        }
        self.system.solve_in_place(z);
        // OSQP's residuals, in the scaled QP, bound the reactions' error (force) and the gaps'
        // and slips' (σ times it): the audit allows its margin over them.
        let factor = AUDIT_MARGIN * if inaccurate { INACCURATE_FACTOR } else { 1.0 };
        let eps = self.settings.eps_abs + self.settings.eps_rel * max_abs(&reactions[..]);
        let eps_q = self.settings.eps_abs + self.settings.eps_rel * max_abs(&self.q);
        let law = Law::Tresca {
            thresholds: &self.thresholds,
            slip: Slip {
                previous: &self.previous,
                obstacle: &self.obstacle,
            },
        };
        let slack = Slack::Bounds {
            force: factor * eps,
            displacement: factor * self.sigma * eps_q.max(eps),
        };
        (self.audit).check(&mut self.system, law, slack, rhs, lower, z, reactions)?;
        Ok(inaccurate)
    }
}

impl<S: SpdSystem> StepSolver for OsqpTresca<S> {
    fn name(&self) -> &'static str {
        "osqp"
    }

    fn set_previous_increment(&mut self, w: &[f64]) {
        self.friction.tangential_into(w, &mut self.previous);
    }

    fn set_obstacle_slide(&mut self, v: &[f64]) {
        self.obstacle.copy_from_slice(v);
    }

    fn solve(
        &mut self,
        rhs: &[f64],
        lower: &[f64],
        z: &mut [f64],
        reactions: &mut [f64],
    ) -> Result<SolveInfo, StepFailure> {
        let (m, p) = (self.constraints.len(), self.friction.len());
        if !(rhs.iter().all(|v| v.is_finite()) && lower.iter().all(|v| v.is_finite())) {
            return Err(StepFailure::NonFinite);
        }
        z.copy_from_slice(rhs);
        self.system.solve_in_place(z);
        let inv = 1.0 / self.sigma;
        let (unknowns, signs) = (&self.constraints.unknowns, &self.constraints.directions);
        for k in 0..m {
            self.q[k] = (signs[k] * z[unknowns[k]] - lower[k]) * inv;
        }
        let slip = Slip {
            previous: &self.previous,
            obstacle: &self.obstacle,
        };
        for j in 0..p {
            self.q[m + j] = slip.at(j, z[self.friction.tangents[j]]) * inv;
        }
        self.problem.update_lin_cost(&self.q);
        let mut inaccurate = false;
        let mut iterations = 0;
        loop {
            // Thresholds from the current normal reactions (the previous step's at first).
            for (j, g) in self.thresholds.iter_mut().enumerate() {
                *g = self.friction.coefficients[j] * self.r[self.friction.normals[j]].max(0.0);
            }
            self.r_before.copy_from_slice(&self.r[..m]);
            iterations += 1;
            inaccurate |= self.tresca(rhs, lower, z, reactions)?;
            let change = (reactions[..m].iter().zip(&self.r_before))
                .fold(0.0f64, |a, (x, y)| a.max((x - y).abs()));
            let scale = max_abs(&reactions[..m]).max(f64::MIN_POSITIVE);
            if p == 0 || change <= FIXED_POINT_TOL * scale {
                break;
            }
            if iterations >= FIXED_POINT_MAX_ITERATIONS {
                return Err(StepFailure::FixedPoint {
                    iterations,
                    change: change / scale,
                });
            }
        }
        if inaccurate {
            self.inaccurate_steps += 1;
        }
        Ok(SolveInfo { iterations })
    }

    fn report(&self) -> Option<SolverReport> {
        Some(SolverReport {
            audit: self.audit.report().clone(),
            inaccurate_steps: Some(self.inaccurate_steps),
        })
    }

    fn identity_allowance(&self) -> f64 {
        let ratio = self.audit.report().stationarity.max_over_tolerance;
        identity_allowance(ratio, self.inaccurate_steps, self.settings.eps_rel)
    }
}
