//! An independent check of every step answer `(z, r)` against the conditions of its contact
//! [`Law`], recomputed with the body's own `C` ([`SpdSystem`]) and this crate's kernels, never
//! from a solver's own residuals: the step equation
//! `C z = b + Σ_k r_k s_k e_{i_k} (+ Σ_j r_T,j e_{t_j})`, its residual mapped to displacement by
//! one solve, and the law's conditions (feasibility, sign and complementarity of the normals;
//! the penalty law; the friction cone and the slip law). A solver that reports success with an
//! answer failing the audit returns [`StepFailure::AuditFailed`] instead of a result.
//!
//! Each tolerance is a round-off floor of the answer plus the solver's stopping [`Slack`]: OSQP's
//! own termination test with a margin, or a solver's absolute bounds (0 for an exact solver).
//! `docs/step-solvers.md#kkt-audit` derives the normal laws' floors, `docs/friction.md#audit`
//! the frictional ones.

use crate::linalg::norms::max_abs;
use crate::linalg::system::{SpdSystem, inverse_norm_estimate};
use crate::step::law::{Law, LawFamily, reaction_from_gap};
use crate::step::report::{AuditReport, StepFailure, Worst};
use crate::step::solver::{Constraints, Friction};

/// Margin over OSQP's own stopping test: OSQP evaluates its residuals on its scaled copy of the
/// data and may accept a polished answer that trades a little of one residual for the other
/// (polish.c), so the same formula recomputed here can come out a few times larger; ten times
/// still refuses anything that misses OSQP's own criterion by more than a decade.
pub const AUDIT_MARGIN: f64 = 10.0;

/// OSQP's "solved inaccurate" means its criterion held with both `eps` multiplied by 10
/// (auxil.c, `check_termination(.., approximate)`); accepted steps are audited accordingly.
pub const INACCURATE_FACTOR: f64 = 10.0;

/// Round-off floor of the bar's audit, in units of `ε·(magnitude of the terms)`
/// ([`crate::linalg::system::TridiagSystem`]'s `roundoff_ulps`, where the reason is given).
pub const ROUNDOFF_ULPS: f64 = 32.0;

/// OSQP's dual-residual tolerance (auxil.c; the module doc): `eps_abs + eps_rel · max(‖Cz‖∞,
/// ‖b‖∞, ‖r‖∞)`, from the three norms; the audit applies it with its margin, the studies and
/// tests with OSQP's own `eps` to read OSQP's verdict.
pub fn dual_tolerance(eps_abs: f64, eps_rel: f64, cz_norm: f64, b_norm: f64, r_norm: f64) -> f64 {
    eps_abs + eps_rel * cz_norm.max(b_norm).max(r_norm)
}

/// The solver's stopping slack, added to the audit's round-off floors.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Slack {
    /// OSQP's termination test with `eps_abs`, `eps_rel` as given to the solver (the audit
    /// multiplies them by [`AUDIT_MARGIN`]): `eps_abs + eps_rel ·` the scale of each check.
    Osqp { eps_abs: f64, eps_rel: f64 },
    /// A solver's own bounds on its error in force and in displacement (margins included).
    Bounds { force: f64, displacement: f64 },
}

impl Slack {
    /// An exact solver's: round-off floors only.
    pub const NONE: Slack = Slack::Bounds {
        force: 0.0,
        displacement: 0.0,
    };
}

/// The names of the checks, in the order they are tried: primal violation, negative reaction,
/// complementarity, penalty law, friction cone, slip law, stationarity, stationarity in
/// displacement.
type Names = [&'static str; 8];

const NORMAL_NAMES: Names = [
    "primal violation (lo_k - s_k z_k)+",
    "negative reaction (-r_k)+",
    "complementarity |r_k (s_k z_k - lo_k)|",
    "penalty law |eps r_k - (lo_k - s_k z_k)+|",
    "",
    "",
    "stationarity |Cz - b - r|",
    "stationarity in displacement |C^-1 (Cz - b - r)|",
];

const FRICTIONAL_NAMES: Names = [
    "primal violation (lo_k - s_k z_k)+",
    "negative reaction (-r_N)+",
    "complementarity |r_N (s_k z_k - lo_k)|",
    "",
    "friction cone (|r_T| - mu r_N)+",
    "slip law |mu r_N |delta| + r_T delta|",
    "stationarity |Cz - b - E^T r|",
    "stationarity in displacement |C^-1 (Cz - b - E^T r)|",
];

/// The audit of one run: the constraint rows, `C`'s norms, scratch space and the worst
/// residuals. [`KktAudit::check`] allocates nothing.
#[derive(Clone, Debug)]
pub struct KktAudit {
    /// The normal constraints, then (friction) the tangents with direction `+1`.
    rows: Constraints,
    /// The normal constraints' count `m`, and the frictional nodes.
    m: usize,
    friction: Option<Friction>,
    /// `‖C‖_∞` and an estimate of `‖C⁻¹‖_∞`, for the round-off floors.
    c_norm: f64,
    inv_norm: f64,
    /// Penalty law: `|(C⁻¹)_{jk}|` on the constrained unknowns, row-major: solvers that form
    /// `z_j = z⁰_j + Σ_k (C⁻¹)_{jk} r_k` round `z_j` to ulps of `|z⁰_j|`, which is at most
    /// `|z_j| + Σ_k |(C⁻¹)_{jk} r_k|`.
    schur_abs: Vec<f64>,
    residual: Vec<f64>,
    report: AuditReport,
}

impl KktAudit {
    /// Set-up for `system` (`C` with its factorisation: its norm and Hager's estimate of
    /// `‖C⁻¹‖∞`), the normal `constraints` and the `family` of laws the run is held to.
    pub fn new(
        system: &mut impl SpdSystem,
        constraints: &Constraints,
        family: LawFamily<'_>,
    ) -> Self {
        let n = system.dim();
        let c_norm = system.inf_norm();
        let inv_norm = inverse_norm_estimate(system);
        // Only the penalty law reads `schur_abs` (and the penalty solver has at most two
        // nodes): for an obstacle under every node it would be a dense k×k block, O(k n) work.
        let nodes = &constraints.unknowns;
        let k = if matches!(family, LawFamily::Penalty) {
            nodes.len()
        } else {
            0
        };
        let mut schur_abs = vec![0.0; k * k];
        for (a, &na) in nodes[..k].iter().enumerate() {
            let col = system.column_of_inverse(na);
            for (b, &nb) in nodes[..k].iter().enumerate() {
                schur_abs[b * k + a] = col[nb].abs();
            }
        }
        let (normal, penalty, friction) = match family {
            LawFamily::Signorini => (true, false, None),
            LawFamily::Penalty => (false, true, None),
            LawFamily::Frictional(f) => (true, false, Some(f.clone())),
        };
        let frictional = friction.is_some();
        let report = AuditReport {
            primal_violation: normal.then(Worst::default),
            complementarity: normal.then(Worst::default),
            penalty_law: penalty.then(Worst::default),
            friction_cone: frictional.then(Worst::default),
            slip_law: frictional.then(Worst::default),
            ..Default::default()
        };
        Self {
            rows: friction
                .as_ref()
                .map_or_else(|| constraints.clone(), |f| f.rows(constraints)),
            m: constraints.len(),
            friction,
            c_norm,
            inv_norm,
            schur_abs,
            residual: vec![0.0; n],
            report,
        }
    }

    /// The worst residuals so far.
    pub fn report(&self) -> &AuditReport {
        &self.report
    }

    /// The report back to `report`, taken before answers a solver replaced (only the answer it
    /// returns is the step's).
    pub fn restore(&mut self, report: AuditReport) {
        self.report = report;
    }

    /// Checks one answer `(z, r)` (`r`: the `m` normal reactions, then with friction the `p`
    /// tangential ones) of the step problem with data `(b, lo)` against `law` with the solver's
    /// `slack`, records its residuals, and returns the first failed check. `system` is the `C`
    /// the audit was set up with.
    #[allow(clippy::too_many_arguments)]
    pub fn check(
        &mut self,
        system: &mut impl SpdSystem,
        law: Law<'_>,
        slack: Slack,
        b: &[f64],
        lower: &[f64],
        z: &[f64],
        r: &[f64],
    ) -> Result<(), StepFailure> {
        let frictional = law.is_frictional();
        debug_assert_eq!(
            frictional,
            self.friction.is_some(),
            "the audit's law family"
        );
        let (m, rows) = (self.m, self.rows.len());
        if !(z.iter().all(|v| v.is_finite()) && r[..rows].iter().all(|v| v.is_finite())) {
            return Err(StepFailure::NonFinite);
        }
        let ulp = system.roundoff_ulps() * f64::EPSILON;
        // The step equation's residual, with the norms of its terms.
        system.mul_into(z, &mut self.residual);
        let (mut cz_norm, mut b_norm, mut z_norm) = (0.0f64, 0.0f64, 0.0f64);
        for i in 0..z.len() {
            cz_norm = cz_norm.max(self.residual[i].abs());
            b_norm = b_norm.max(b[i].abs());
            z_norm = z_norm.max(z[i].abs());
            self.residual[i] -= b[i];
        }
        for (j, (&node, &s)) in self
            .rows
            .unknowns
            .iter()
            .zip(&self.rows.directions)
            .enumerate()
        {
            self.residual[node] -= s * r[j];
        }
        let r_norm = max_abs(&r[..rows]);
        let stationarity = max_abs(&self.residual);
        let mut p_scale = 0.0f64;
        for (j, &node) in self.rows.unknowns[..m].iter().enumerate() {
            p_scale = p_scale.max(z[node].abs()).max(lower[j].abs());
        }
        // A sliding obstacle's displacements are data of the condensed problem (its slips), to
        // whose size the answer's gaps are rounded: they join the gaps' scale (0 when fixed).
        if let Some(slip) = law.slip() {
            p_scale = slip.obstacle.iter().fold(p_scale, |a, v| a.max(v.abs()));
        }
        // The slack in force, in displacement, and in the gaps.
        let (slack_f, slack_dz, slack_z) = match slack {
            Slack::Osqp { eps_abs, eps_rel } => {
                let (a, e) = (AUDIT_MARGIN * eps_abs, AUDIT_MARGIN * eps_rel);
                let force = dual_tolerance(a, e, cz_norm, b_norm, r_norm);
                (force, a + e * z_norm, a + e * p_scale)
            }
            Slack::Bounds {
                force,
                displacement,
            } => (force, displacement, displacement),
        };
        let floor_f = ulp * (self.c_norm * z_norm + b_norm + r_norm);
        let tol_f = slack_f + floor_f;
        // The displacement floor: a backward-stable solve's error; with friction also the
        // rounding of z itself, formed from the condensed problem, which sums every reaction's
        // effect on each gap and slip (ulps of `Σ_j |S_kj r_j| <= ‖C⁻¹‖∞ ‖r‖₁`).
        let (floor_dz, floor_z) = if frictional {
            let r_sum: f64 = r[..rows].iter().map(|v| v.abs()).sum();
            let floor = self.inv_norm * (tol_f + ulp * r_sum) + ulp * z_norm;
            (floor, floor + ulp * p_scale)
        } else {
            (self.inv_norm * floor_f, ulp * p_scale)
        };
        system.solve_in_place(&mut self.residual);
        let displacement = max_abs(&self.residual);
        let tol_dz = slack_dz + floor_dz;
        let tol_z = slack_z + floor_z;
        let normal = !matches!(law, Law::Penalty { .. });
        let (mut primal, mut negative, mut comp) = (0.0f64, 0.0f64, (0.0f64, 0.0f64));
        let mut penalty = (0.0f64, 0.0f64);
        for (j, (&node, &s)) in self.rows.unknowns[..m]
            .iter()
            .zip(&self.rows.directions)
            .enumerate()
        {
            let gap = s * z[node] - lower[j];
            negative = negative.max(-r[j]);
            if let Law::Penalty { epsilon } = law {
                let v = Law::penalty_residual(epsilon, r[j], gap);
                let t = ulp * self.penalty_scale(system, epsilon, j, b, lower, z, r);
                worst(&mut penalty, (v, t));
            } else {
                primal = primal.max(-gap);
                let t = tol_z * r[j].abs() + tol_f * gap.abs();
                worst(&mut comp, ((r[j] * gap).abs(), t));
            }
        }
        let (mut cone, mut slip) = ((0.0f64, 0.0f64), (0.0f64, 0.0f64));
        if let Some(friction) = &self.friction {
            for (j, &tangent) in friction.tangents.iter().enumerate() {
                let rt = r[m + j];
                let g = law.threshold(j, r[friction.normals[j]]);
                let t = tol_f + ulp * g.abs();
                worst(&mut cone, ((rt.abs() - g).max(0.0), t));
                if let Some(w) = law.slip() {
                    let delta = w.at(j, z[tangent]);
                    let value = (g * delta.abs() + rt * delta).abs();
                    let t = tol_f * delta.abs() + (tol_z + ulp * w.scale(j)) * (g.abs() + rt.abs());
                    worst(&mut slip, (value, t));
                }
            }
        }
        let rep = &mut self.report;
        rep.steps += 1;
        rep.stationarity.observe(stationarity, tol_f);
        rep.stationarity_displacement.observe(displacement, tol_dz);
        rep.negative_reaction.observe(negative, tol_f);
        let checks = [
            (primal, tol_z),
            (negative, tol_f),
            comp,
            penalty,
            cone,
            slip,
            (stationarity, tol_f),
            (displacement, tol_dz),
        ];
        let listed = [
            &mut rep.primal_violation,
            &mut rep.complementarity,
            &mut rep.penalty_law,
            &mut rep.friction_cone,
            &mut rep.slip_law,
        ];
        for (w, c) in listed.into_iter().zip([0, 2, 3, 4, 5]) {
            if let Some(w) = w.as_mut() {
                w.observe(checks[c].0, checks[c].1);
            }
        }
        let (names, applies) = if frictional {
            (
                &FRICTIONAL_NAMES,
                [true, true, true, false, true, true, true, true],
            )
        } else {
            (
                &NORMAL_NAMES,
                [normal, true, normal, !normal, false, false, true, true],
            )
        };
        first_failure(
            (names.iter().zip(checks).zip(applies))
                .filter(|(_, applies)| *applies)
                .map(|((&what, (value, tolerance)), _)| (what, value, tolerance)),
        )
    }

    /// The magnitude whose ulps bound the penalty law's residual at constraint `j`: the gap's
    /// `|z⁰_j| + |lo_j|` (`z⁰_j` through `schur_abs`), `|ε r_j|`, and for a reaction taken from
    /// stationarity, `(Cz − b)_j`, that row's `|C||z| + |b|` times ε ([`reaction_from_gap`]).
    #[allow(clippy::too_many_arguments)]
    fn penalty_scale(
        &self,
        system: &impl SpdSystem,
        epsilon: f64,
        j: usize,
        b: &[f64],
        lower: &[f64],
        z: &[f64],
        r: &[f64],
    ) -> f64 {
        let (k, node) = (self.m, self.rows.unknowns[j]);
        let coupled: f64 = (0..k).map(|i| self.schur_abs[j * k + i] * r[i].abs()).sum();
        let row = if reaction_from_gap(system.diagonal(node), 1.0 / epsilon) {
            0.0
        } else {
            epsilon * (system.abs_row_product(node, z) + b[node].abs())
        };
        z[node].abs() + coupled + lower[j].abs() + (epsilon * r[j]).abs() + row
    }
}

/// Keeps in `worst` the pair `(value, tolerance)` with the larger ratio, so that value and
/// tolerance match.
fn worst(worst: &mut (f64, f64), pair: (f64, f64)) {
    if ratio(pair.0, pair.1) >= ratio(worst.0, worst.1) {
        *worst = pair;
    }
}

/// The audit's verdict on its checks `(what, value, tolerance)` in order: the first whose
/// value exceeds its tolerance (or is NaN) fails the step.
fn first_failure(
    checks: impl IntoIterator<Item = (&'static str, f64, f64)>,
) -> Result<(), StepFailure> {
    for (what, value, tolerance) in checks {
        // Negated so that a NaN residual fails.
        #[allow(clippy::neg_cmp_op_on_partial_ord)]
        if !(value <= tolerance) {
            return Err(StepFailure::AuditFailed {
                what,
                value,
                tolerance,
            });
        }
    }
    Ok(())
}

/// `value / tolerance`, infinite for a positive value against a zero tolerance.
fn ratio(value: f64, tolerance: f64) -> f64 {
    if tolerance > 0.0 {
        value / tolerance
    } else if value > 0.0 {
        f64::INFINITY
    } else {
        0.0
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::linalg::system::TridiagSystem;
    use crate::linalg::tridiag::SymTridiag;

    /// Regression: the Signorini audit of an obstacle under every node used to build the dense
    /// `k×k` block of `C⁻¹` (8 TB at 1e6 nodes), aborting OSQP runs on large distributed
    /// scenes and the stiff matrix. Set-up is now O(n) in time and memory.
    #[test]
    fn signorini_audit_of_an_obstacle_under_every_node_sets_up_in_linear_memory() {
        let n = 200_000;
        let c = SymTridiag::new(vec![4.0; n], vec![-1.0; n - 1]);
        let nodes: Vec<usize> = (0..n).collect();
        let mut system = TridiagSystem::new(&c).unwrap();
        let constraints = Constraints::lower_bounds(&nodes);
        let mut audit = KktAudit::new(&mut system, &constraints, LawFamily::Signorini);
        assert!(audit.schur_abs.is_empty());
        // An exact answer (z = C⁻¹ b, every bound inactive) passes the round-off audit.
        let z = vec![1.0; n];
        let b = c.mul(&z);
        let lower = vec![0.0; n];
        let r = vec![0.0; n];
        (audit.check(&mut system, Law::Signorini, Slack::NONE, &b, &lower, &z, &r)).unwrap();
    }
}
