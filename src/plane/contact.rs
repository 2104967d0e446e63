//! Signorini contact on the plane body's edges, solved exactly by condensation.
//!
//! Each node of a Signorini edge that is not clamped carries one contact normal `k`: the
//! unknown `i_k` of the component normal to the edge and the sign `σ_k` of the outward normal
//! (`n = σ_k e_c`), so `u·n = σ_k u_{i_k}` and `E` (`m × n`, row `k` = `σ_k e_{i_k}ᵀ`) selects
//! components with sign. A corner shared by two Signorini edges has two normals, one per
//! component (each wall holds its own component; they never compete). A clamped node carries
//! none (`u = 0` there, admissible when `g >= 0`, checked at set-up).
//!
//! The step problem, in the increment `z = u^{n+1} − u^n`:
//!
//! ```text
//!   C z = b − Eᵀ r,   h − E z >= 0,   r >= 0,   rᵀ(h − E z) = 0,   h = g − E u^n.
//! ```
//!
//! With `z⁰ = C⁻¹ b`, `z = z⁰ − C⁻¹ Eᵀ r` and the gap `w = h − E z = S r + q`, `S = E C⁻¹ Eᵀ`
//! (SPD: `E` has full row rank), `q = h − E z⁰`: the LCP of [`crate::step::lcp`]. `S` is formed
//! once per run by solves with the factor of `C` on blocks of unit columns
//! ([`SparseCholesky::solve_columns_in_place`]). Each step: `z⁰` (one solve), the LCP, and,
//! when some `r_k > 0`, `z` again from `C z = b − Eᵀ r` (a second solve: backward stable,
//! where `z⁰ − C⁻¹Eᵀr` would cancel digits when contact stops a fast body).
//!
//! Energy: the scheme times `δ/2`, `δ = u^{n+1} − u^{n−1}`, gains the contact term
//! `−½ r·Eδ = −D`, and `D = ½ Σ_k r_k (g_k − σ_k u^{n−1}_{i_k}) >= 0` by complementarity and
//! the admissibility of `u^{n−1}`: contact only dissipates.

use crate::plane::error::PlaneError;
use crate::plane::factor::SparseCholesky;
use crate::plane::matrices::Pattern;
pub use crate::plane::normals::{Normal, normals};
use crate::plane::osqp::PlaneOsqp;
use crate::scene::schema::{SolverMethod, SolverSpec};
use crate::step::lcp::DenseLcp;
use crate::step::osqp::OsqpSettings;
use crate::step::report::AuditReport;

/// How the contact problem of a step is solved.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub enum ContactMethod {
    /// Condensation and the exact LCP solver (this module).
    #[default]
    Exact,
    /// Normal compliance `ε r_k = max(0, u·n − g)`: the LCP on `S + εI` (`w + ε r >= 0 ⊥
    /// r >= 0` is that law), solved exactly.
    Penalty { epsilon: f64 },
    /// OSQP on the full sparse QP, audited ([`crate::plane::osqp`]).
    Osqp(OsqpSettings),
}

impl ContactMethod {
    /// The method a scene's `[solver]` table names, with its settings (the bar's defaults for
    /// those not given; the table is validated with the scene).
    pub fn from_spec(spec: &SolverSpec) -> Self {
        match spec.method {
            SolverMethod::Exact => ContactMethod::Exact,
            SolverMethod::Osqp => ContactMethod::Osqp(spec.osqp_settings()),
            SolverMethod::Penalty => ContactMethod::Penalty {
                epsilon: spec.penalty_settings().epsilon,
            },
        }
    }

    /// `exact`, `penalty`, `osqp`.
    pub fn name(&self) -> &'static str {
        match self {
            ContactMethod::Exact => "exact",
            ContactMethod::Penalty { .. } => "penalty",
            ContactMethod::Osqp(_) => "osqp",
        }
    }
}

/// Largest block of unit columns solved at once when forming `S`, in doubles (`n · block`):
/// 32 MiB of right-hand sides, so that the set-up stays within the run's memory budget.
const S_BLOCK_DOUBLES: usize = 1 << 22;

/// `S = E C⁻¹ Eᵀ` (row-major, symmetrised bitwise), from blocks of unit columns solved with
/// the factor of `C`.
pub fn condensed_matrix(normals: &[Normal], chol: &mut SparseCholesky) -> Vec<f64> {
    let (m, n) = (normals.len(), chol.dim());
    let mut s = vec![0.0; m * m];
    let block = (S_BLOCK_DOUBLES / n.max(1)).clamp(1, m.max(1));
    let mut x = vec![0.0; n * block];
    for start in (0..m).step_by(block) {
        let cols = block.min(m - start);
        let x = &mut x[..n * cols];
        x.fill(0.0);
        for c in 0..cols {
            let nk = &normals[start + c];
            x[c * n + nk.unknown] = nk.sign;
        }
        chol.solve_columns_in_place(x, cols);
        for c in 0..cols {
            for (j, nj) in normals.iter().enumerate() {
                s[j * m + start + c] = nj.sign * x[c * n + nj.unknown];
            }
        }
    }
    for j in 0..m {
        for k in 0..j {
            let v = 0.5 * (s[j * m + k] + s[k * m + j]);
            s[j * m + k] = v;
            s[k * m + j] = v;
        }
    }
    s
}

/// The contact state of one step.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct ContactStep {
    /// `D = ½ r·E(u^{n+1} − u^{n−1})`.
    pub dissipation: f64,
    /// Normals with `r_k > 0`.
    pub active: usize,
    /// `Σ_k r_k`.
    pub total_reaction: f64,
    /// `max_k max(0, −gap_k)`, `gap_k = g_k − σ_k u^{n+1}_{i_k}`.
    pub penetration: f64,
    /// `max_k |r_k gap_k|`.
    pub complementarity: f64,
    /// `max_k max(|g_k|, |u^{n+1}·n|)`: the scale of the gaps' round-off.
    pub gap_scale: f64,
    /// Active sets tried by the LCP solver.
    pub iterations: u32,
}

/// The contact solver of a run: the normals, `S` with its LCP solver (exact, penalty) or OSQP,
/// and work space.
pub struct Contact {
    pub normals: Vec<Normal>,
    method: ContactMethod,
    lcp: Option<DenseLcp>,
    osqp: Option<Box<PlaneOsqp>>,
    q: Vec<f64>,
    r: Vec<f64>,
    w: Vec<f64>,
}

impl Contact {
    /// Forms `S` and its LCP solver (exact, penalty: `S + εI`) or sets OSQP up (`c` the values
    /// of `C` on `pattern`, factorised in `chol`).
    pub fn new(
        normals: Vec<Normal>,
        chol: &mut SparseCholesky,
        method: ContactMethod,
        pattern: &Pattern,
        c: &[f64],
    ) -> Result<Self, PlaneError> {
        let m = normals.len();
        let setup = |reason: String| PlaneError::Contact { step: 0, reason };
        let (mut lcp, mut osqp) = (None, None);
        match method {
            ContactMethod::Exact | ContactMethod::Penalty { .. } => {
                let mut s = condensed_matrix(&normals, chol);
                if let ContactMethod::Penalty { epsilon } = method {
                    if !(epsilon.is_finite() && epsilon > 0.0) {
                        return Err(setup(format!("penalty epsilon {epsilon} must be > 0")));
                    }
                    for k in 0..m {
                        s[k * m + k] += epsilon;
                    }
                }
                lcp = Some(DenseLcp::new(s, m).map_err(|e| setup(e.to_string()))?);
            }
            ContactMethod::Osqp(settings) => {
                osqp = Some(Box::new(
                    PlaneOsqp::new(pattern, c, &normals, chol, settings).map_err(setup)?,
                ));
            }
        }
        Ok(Self {
            normals,
            method,
            lcp,
            osqp,
            q: vec![0.0; m],
            r: vec![0.0; m],
            w: vec![0.0; m],
        })
    }

    /// `m`.
    pub fn len(&self) -> usize {
        self.normals.len()
    }

    pub fn is_empty(&self) -> bool {
        self.normals.is_empty()
    }

    pub fn method(&self) -> ContactMethod {
        self.method
    }

    /// `S_jk` (`S + εI` for the penalty; `None` with OSQP, which does not form it).
    pub fn s(&self, j: usize, k: usize) -> Option<f64> {
        self.lcp.as_ref().map(|l| l.entry(j, k))
    }

    /// OSQP's audit so far (OSQP only).
    pub fn audit(&self) -> Option<&AuditReport> {
        self.osqp.as_ref().map(|o| o.report())
    }

    /// Steps where OSQP's "solved inaccurate" was accepted (OSQP only).
    pub fn inaccurate_steps(&self) -> Option<u64> {
        self.osqp.as_ref().map(|o| o.inaccurate_steps())
    }

    /// The increment `z` of a step with right-hand side `b` at the state `u = u^n`, the
    /// reactions kept: exact and penalty by the unconstrained solve, the LCP and, when some
    /// `r_k > 0`, the solve of `C z = b − Eᵀ r`; OSQP by its own iteration, audited. Returns
    /// the iterations. Allocates nothing.
    pub fn step(
        &mut self,
        chol: &mut SparseCholesky,
        b: &[f64],
        u: &[f64],
        z: &mut [f64],
        step: usize,
    ) -> Result<u32, PlaneError> {
        if let Some(osqp) = &mut self.osqp {
            return osqp
                .solve(&self.normals, b, u, chol, z, &mut self.r)
                .map_err(|e| PlaneError::Contact {
                    step,
                    reason: format!("osqp: {e}"),
                });
        }
        z.copy_from_slice(b);
        chol.solve_in_place(z);
        let (iterations, touching) = self.solve(u, z, step)?;
        if touching {
            // z from C z = b − Eᵀ r directly (backward stable).
            z.copy_from_slice(b);
            self.subtract_reactions(z);
            chol.solve_in_place(z);
        }
        Ok(iterations)
    }

    /// The reactions `r_k` of the last step.
    pub fn reactions(&self) -> &[f64] {
        &self.r
    }

    /// Solves the step's LCP for the unconstrained increment `z0` at the state `u = u^n`;
    /// writes the reactions and, when any is positive, returns true (then `C z = b − Eᵀ r`,
    /// see [`Contact::subtract_reactions`]). Allocates nothing.
    fn solve(&mut self, u: &[f64], z0: &[f64], step: usize) -> Result<(u32, bool), PlaneError> {
        for (q, nk) in self.q.iter_mut().zip(&self.normals) {
            *q = nk.gap - nk.sign * (u[nk.unknown] + z0[nk.unknown]);
        }
        let iterations = self
            .lcp
            .as_mut()
            .expect("exact and penalty methods form S")
            .solve(&self.q, &mut self.r, &mut self.w)
            .map_err(|e| PlaneError::Contact {
                step,
                reason: e.to_string(),
            })?;
        Ok((iterations, self.r.iter().any(|&r| r > 0.0)))
    }

    /// `b ← b − Eᵀ r`.
    pub fn subtract_reactions(&self, b: &mut [f64]) {
        for (nk, r) in self.normals.iter().zip(&self.r) {
            b[nk.unknown] -= nk.sign * r;
        }
    }

    /// The step's contact figures, after `u = u^{n+1}`, with `delta = u^{n+1} − u^{n−1}`
    /// given as `z + w` (the two increments).
    pub fn measure(&self, u: &[f64], z: &[f64], w: &[f64], iterations: u32) -> ContactStep {
        let mut out = ContactStep {
            iterations,
            ..Default::default()
        };
        let mut dissipation = 0.0;
        for (nk, &r) in self.normals.iter().zip(&self.r) {
            let i = nk.unknown;
            let un = nk.sign * u[i];
            let gap = nk.gap - un;
            dissipation += r * nk.sign * (z[i] + w[i]);
            out.penetration = out.penetration.max(-gap);
            out.complementarity = out.complementarity.max((r * gap).abs());
            out.gap_scale = out.gap_scale.max(nk.gap.abs()).max(un.abs());
            out.total_reaction += r;
            out.active += usize::from(r > 0.0);
        }
        out.dissipation = 0.5 * dissipation;
        out
    }
}
