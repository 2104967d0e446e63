//! The exact frictional step: Coulomb friction at the frictional nodes, with the central slip
//! `δ_j = (z + w)_{t_j} − v_j` (`w` the previous increment, `v_j` a sliding obstacle's) and the
//! law `|r_T| <= μ r_N`, `r_T = −μ r_N sign δ` where `δ ≠ 0`. Condensed onto the normals and the tangents,
//! `S = E C⁻¹ Eᵀ` (`E` the normal rows `s_k e_{i_k}ᵀ` and the tangential rows `e_{t_j}ᵀ`), the
//! step is the Stewart–Trinkle LCP in `(r_N, β⁺, β⁻, λ)` (`r_T = β⁺ − β⁻`, `λ` the slip
//! multiplier; size `m + 3p`), solved by [`Lemke`]; a step whose free motion is admissible is
//! `r = 0` without it. The start-up step is the same law with `w = 0` (the slip `u^1 − u^0`,
//! until [`StepSolver::set_previous_increment`] is first called). On the cone's boundary `r_T`
//! is set to `∓μ r_N` exactly; `z` then comes from `C z = b + Eᵀ r` by a second solve. Every
//! answer is audited ([`crate::step::audit`]); a warm-started answer the audit refuses is
//! replaced by a cold run's. Derivation, termination, audit: `docs/friction.md`.

use crate::linalg::system::SpdSystem;
use crate::step::audit::{KktAudit, Slack};
use crate::step::condensed_lcp::condensed_matrix;
use crate::step::law::{Law, LawFamily, Slip};
use crate::step::lcp::{DenseLcp, LcpError};
use crate::step::lemke::Lemke;
use crate::step::solver::{Constraints, Friction};
use crate::step::{SetupError, SolveInfo, SolverReport, StepFailure, StepSolver};

/// The Stewart–Trinkle LCP matrix of the condensed `S` (`(m + p)²`, row-major, normals then
/// tangents), scaled by `1/σ`: rows and columns `r_N` (`m`), `β⁺`, `β⁻`, `λ/σ` (`p` each),
///
/// ```text
///   [ S_NN   S_NT  −S_NT  0 ]
///   [ S_TN   S_TT  −S_TT  σI ]  / σ,   q = (E_N z⁰ − lo, δ⁰, −δ⁰, 0) / σ.
///   [−S_TN  −S_TT   S_TT  σI ]
///   [ σμP   −σI   −σI    0 ]
/// ```
pub fn stewart_trinkle_matrix(s: &[f64], m: usize, friction: &Friction, sigma: f64) -> Vec<f64> {
    let p = friction.len();
    let (k, n) = (m + p, m + 3 * p);
    let mut a = vec![0.0; n * n];
    // Row (or column) i of S appears as N (`i < m`), or as β⁺ (+1) and β⁻ (−1).
    let copies = |i: usize| -> [(usize, f64); 2] {
        if i < m {
            [(i, 1.0), (usize::MAX, 0.0)]
        } else {
            [(i, 1.0), (i + p, -1.0)]
        }
    };
    for i in 0..k {
        for j in 0..k {
            let v = s[i * k + j] / sigma;
            for (row, si) in copies(i).into_iter().filter(|c| c.0 != usize::MAX) {
                for (col, sj) in copies(j).into_iter().filter(|c| c.0 != usize::MAX) {
                    a[row * n + col] = si * sj * v;
                }
            }
        }
    }
    for l in 0..p {
        let (plus, minus, lambda) = (m + l, m + p + l, m + 2 * p + l);
        a[plus * n + lambda] = 1.0;
        a[minus * n + lambda] = 1.0;
        a[lambda * n + friction.normals[l]] = friction.coefficients[l];
        a[lambda * n + plus] = -1.0;
        a[lambda * n + minus] = -1.0;
    }
    a
}

/// The exact frictional solver (see the module doc).
pub struct CondensedLemke<S: SpdSystem> {
    system: S,
    constraints: Constraints,
    friction: Friction,
    lemke: Lemke,
    /// `σ = max_k S_kk`, the scale of the LCP.
    sigma: f64,
    /// The previous increment at the tangents (0 until given: the start-up step's law).
    previous: Vec<f64>,
    /// The obstacles' tangential displacements `v_j` (zeros unless an obstacle slides).
    obstacle: Vec<f64>,
    q: Vec<f64>,
    x: Vec<f64>,
    q_normal: Vec<f64>,
    audit: KktAudit,
}

impl<S: SpdSystem> CondensedLemke<S> {
    /// Forms `S` on the normals and tangents (one block solve per column), checks it positive
    /// definite (the unknowns of `E` distinct) and sets up both LCPs.
    pub fn new(
        mut system: S,
        constraints: Constraints,
        friction: Friction,
    ) -> Result<Self, SetupError> {
        let (m, p) = (constraints.len(), friction.len());
        let rows = friction.rows(&constraints);
        let s = condensed_matrix(&rows, &mut system);
        let k = m + p;
        let contact = |e: LcpError| SetupError::Contact(e.to_string());
        // S on normals and tangents must be positive definite (Lemke's termination needs it).
        DenseLcp::new(s.clone(), k).map_err(contact)?;
        let sigma = (0..k).map(|i| s[i * k + i]).fold(0.0, f64::max);
        let matrix = stewart_trinkle_matrix(&s, m, &friction, sigma);
        let n = m + 3 * p;
        let audit = KktAudit::new(&mut system, &constraints, LawFamily::Frictional(&friction));
        Ok(Self {
            system,
            constraints,
            lemke: Lemke::new(&matrix, n),
            sigma,
            previous: vec![0.0; p],
            obstacle: vec![0.0; p],
            q: vec![0.0; n],
            x: vec![0.0; n],
            q_normal: vec![0.0; m],
            audit,
            friction,
        })
    }

    /// `σ`, the scale of the LCP (`max_k S_kk`).
    pub fn scale(&self) -> f64 {
        self.sigma
    }

    /// The Stewart–Trinkle LCP by Lemke's method; the reactions, the tangential ones on the
    /// cone's boundary set to `∓μ r_N` exactly.
    fn frictional(&mut self, z: &[f64], reactions: &mut [f64]) -> Result<u32, StepFailure> {
        let (m, p) = (self.constraints.len(), self.friction.len());
        let inv = 1.0 / self.sigma;
        for k in 0..m {
            self.q[k] = self.q_normal[k] * inv;
        }
        let slip = Slip {
            previous: &self.previous,
            obstacle: &self.obstacle,
        };
        for j in 0..p {
            let delta = slip.at(j, z[self.friction.tangents[j]]);
            self.q[m + j] = delta * inv;
            self.q[m + p + j] = -delta * inv;
            self.q[m + 2 * p + j] = 0.0;
        }
        let outcome = self.lemke.solve(&self.q, &mut self.x)?;
        reactions[..m].copy_from_slice(&self.x[..m]);
        for j in 0..p {
            let (plus, minus) = (self.x[m + j], self.x[m + p + j]);
            let limit = self.friction.coefficients[j] * reactions[self.friction.normals[j]];
            let on_cone = self.lemke.x_basic(m + 2 * p + j) && (plus == 0.0 || minus == 0.0);
            reactions[m + j] = if on_cone {
                // w_λ = 0 (λ basic), so β⁺ + β⁻ = μ r_N, and one of them is 0.
                if plus >= minus { limit } else { -limit }
            } else {
                plus - minus
            };
        }
        Ok(outcome.pivots + 1)
    }
}

impl<S: SpdSystem> CondensedLemke<S> {
    /// One answer: the free step, or Lemke's; `z` from the step equation; the audit. Returns
    /// the audit's verdict, the bases tried and whether Lemke's method ran.
    fn attempt(
        &mut self,
        rhs: &[f64],
        lower: &[f64],
        z: &mut [f64],
        reactions: &mut [f64],
    ) -> (Result<(), StepFailure>, u32, bool) {
        let m = self.constraints.len();
        z.copy_from_slice(rhs);
        self.system.solve_in_place(z);
        let c = &self.constraints;
        for (k, q) in self.q_normal.iter_mut().enumerate() {
            *q = c.directions[k] * z[c.unknowns[k]] - lower[k];
        }
        let lemke = !self.q_normal.iter().all(|&q| q >= 0.0);
        let iterations = if lemke {
            match self.frictional(z, reactions) {
                Ok(iterations) => iterations,
                Err(failure) => return (Err(failure), 0, lemke),
            }
        } else {
            // The free step is admissible: r = 0 (no normal force, so no friction).
            reactions.fill(0.0);
            1
        };
        if reactions.iter().any(|&r| r != 0.0) {
            let (unknowns, signs) = (&self.constraints.unknowns, &self.constraints.directions);
            z.copy_from_slice(rhs);
            for (k, r) in reactions[..m].iter().enumerate() {
                z[unknowns[k]] += signs[k] * r;
            }
            for (j, r) in reactions[m..].iter().enumerate() {
                z[self.friction.tangents[j]] += r;
            }
            self.system.solve_in_place(z);
        }
        let law = Law::Coulomb {
            mu: &self.friction.coefficients,
            slip: Slip {
                previous: &self.previous,
                obstacle: &self.obstacle,
            },
        };
        let slack = Slack::NONE;
        let verdict = (self.audit).check(&mut self.system, law, slack, rhs, lower, z, reactions);
        (verdict, iterations, lemke)
    }
}

impl<S: SpdSystem> StepSolver for CondensedLemke<S> {
    fn name(&self) -> &'static str {
        "exact"
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
        let before = self.audit.report().clone();
        let (result, iterations, lemke) = self.attempt(rhs, lower, z, reactions);
        match result {
            // A warm basis a round-off away from a stick/slip switch can leave a slip of the
            // wrong sign beyond the audit's floors: its answer is replaced by the cold run's
            // (the one the termination claim covers), and only that answer is audited.
            Err(StepFailure::AuditFailed { .. }) if lemke => {
                self.audit.restore(before);
                self.lemke.reset();
                let (result, more, _) = self.attempt(rhs, lower, z, reactions);
                result.map(|()| SolveInfo {
                    iterations: iterations + more,
                })
            }
            result => result.map(|()| SolveInfo { iterations }),
        }
    }

    fn report(&self) -> Option<SolverReport> {
        Some(SolverReport {
            audit: self.audit.report().clone(),
            inaccurate_steps: None,
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::linalg::system::TridiagSystem;
    use crate::linalg::tridiag::SymTridiag;
    use crate::step::CondensedLcp;
    use proptest::prelude::*;

    /// Frictional and frictionless answers of well-conditioned 12-unknown problems (κ(C) below
    /// 10): two exact methods, round-off apart.
    const AGREEMENT_TOL: f64 = 1e-12;

    /// Normals at unknowns 0, 4, 9 (directions +, −, +), frictional nodes with tangents 1, 5, 8.
    fn problem(mu: f64) -> (TridiagSystem, Constraints, Friction) {
        let n = 12;
        let c = SymTridiag::new(
            (0..n).map(|i| 4.0 + 0.1 * i as f64).collect(),
            vec![-1.0; n - 1],
        );
        let constraints = Constraints {
            unknowns: vec![0, 4, 9],
            directions: vec![1.0, -1.0, 1.0],
        };
        let friction = Friction {
            normals: vec![0, 1, 2],
            tangents: vec![1, 5, 8],
            coefficients: vec![mu; 3],
        };
        (TridiagSystem::new(&c).unwrap(), constraints, friction)
    }

    proptest! {
        #![proptest_config(ProptestConfig::with_cases(100))]
        #[test]
        fn zero_friction_is_the_frictionless_lcp_and_friction_meets_coulombs_law(
            b in prop::collection::vec(-1.0f64..1.0, 12),
            lo in prop::collection::vec(-0.3f64..0.3, 3),
            w in prop::collection::vec(-0.2f64..0.2, 12),
            mu in 0.05f64..1.5,
        ) {
            let (system, constraints, friction) = problem(0.0);
            let mut plain = CondensedLcp::new(system.clone(), constraints.clone(), 0.0).unwrap();
            let mut zero = CondensedLemke::new(system, constraints.clone(), friction).unwrap();
            zero.set_previous_increment(&w);
            let (mut z0, mut r0) = (vec![0.0; 12], vec![0.0; 3]);
            let (mut z1, mut r1) = (vec![0.0; 12], vec![0.0; 6]);
            plain.solve(&b, &lo, &mut z0, &mut r0).unwrap();
            zero.solve(&b, &lo, &mut z1, &mut r1).unwrap();
            for i in 0..12 {
                prop_assert!((z0[i] - z1[i]).abs() <= AGREEMENT_TOL, "z {i}");
            }
            for k in 0..3 {
                prop_assert!((r0[k] - r1[k]).abs() <= AGREEMENT_TOL, "r {k}");
                prop_assert_eq!(r1[3 + k], 0.0);
            }
            // With friction: the law, recomputed here from (z, r) (the solver's audit passed).
            let (system, constraints, friction) = problem(mu);
            let mut f = CondensedLemke::new(system, constraints.clone(), friction.clone()).unwrap();
            f.set_previous_increment(&w);
            f.solve(&b, &lo, &mut z1, &mut r1).unwrap();
            for k in 0..3 {
                let gap = constraints.directions[k] * z1[constraints.unknowns[k]] - lo[k];
                let (rn, rt) = (r1[k], r1[3 + k]);
                let delta = z1[friction.tangents[k]] + w[friction.tangents[k]];
                prop_assert!(gap >= -AGREEMENT_TOL && rn >= 0.0 && (gap * rn).abs() <= AGREEMENT_TOL);
                prop_assert!(rt.abs() <= mu * rn * (1.0 + 1e-15), "cone {k}: {rt} {rn}");
                if delta.abs() > AGREEMENT_TOL {
                    prop_assert!((rt + mu * rn * delta.signum()).abs() <= AGREEMENT_TOL, "slip {k}");
                }
            }
        }
    }
}
