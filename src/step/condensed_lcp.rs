//! The exact step solver by condensation onto the constraints, for any body whose `C` is
//! factorised ([`SpdSystem`]); with a compliance `ε > 0`, the penalty law on the same LCP.
//!
//! With `z⁰ = C⁻¹ b`, `z = z⁰ + C⁻¹ Eᵀ r` (`E` the `m × n` rows `s_k e_{i_k}ᵀ`) and the gap
//! `w = E z − lo = S r + q`, `S = E C⁻¹ Eᵀ` (SPD: `E` has full row rank), `q = E z⁰ − lo`: the
//! LCP `w >= 0 ⊥ r >= 0` of [`crate::step::lcp`], exact. Normal compliance `ε r = (lo − Ez)⁺`
//! is the LCP on `S + εI`. `S` is formed once per run by solves on blocks of unit columns.
//! Each step: `z⁰` (one solve), the LCP, and, when some `r_k > 0`, `z` again from
//! `C z = b + Eᵀ r` (a second solve: backward stable, where `z⁰ + C⁻¹Eᵀr` would cancel digits
//! when contact stops a fast body). Memory: `2m²` doubles besides the factor.

use crate::linalg::system::SpdSystem;
use crate::step::lcp::{DenseLcp, LcpError};
use crate::step::solver::Constraints;
use crate::step::{SetupError, SolveInfo, StepFailure, StepSolver};

/// Largest block of unit columns solved at once when forming `S`, in doubles (`n · block`):
/// 32 MiB of right-hand sides, so that the set-up stays within the run's memory budget.
const S_BLOCK_DOUBLES: usize = 1 << 22;

/// `S = E C⁻¹ Eᵀ` (row-major, symmetrised bitwise), from blocks of unit columns solved with
/// the factor of `C`.
pub fn condensed_matrix(constraints: &Constraints, system: &mut impl SpdSystem) -> Vec<f64> {
    let (m, n) = (constraints.len(), system.dim());
    let (unknowns, signs) = (&constraints.unknowns, &constraints.directions);
    let mut s = vec![0.0; m * m];
    let block = (S_BLOCK_DOUBLES / n.max(1)).clamp(1, m.max(1));
    let mut x = vec![0.0; n * block];
    for start in (0..m).step_by(block) {
        let cols = block.min(m - start);
        let x = &mut x[..n * cols];
        x.fill(0.0);
        for c in 0..cols {
            x[c * n + unknowns[start + c]] = signs[start + c];
        }
        system.solve_columns_in_place(x, cols);
        for c in 0..cols {
            for j in 0..m {
                s[j * m + start + c] = signs[j] * x[c * n + unknowns[j]];
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

/// Condensation and the exact LCP solver (or the penalty law with `ε > 0`).
pub struct CondensedLcp<S: SpdSystem> {
    system: S,
    constraints: Constraints,
    /// `None` without constraints: then a step is one solve.
    lcp: Option<DenseLcp>,
    /// `ε` of the penalty law, 0 for Signorini.
    epsilon: f64,
    q: Vec<f64>,
    w: Vec<f64>,
}

impl<S: SpdSystem> CondensedLcp<S> {
    /// Forms `S` (plus `εI` for the penalty law, `epsilon > 0`) and its LCP solver.
    pub fn new(mut system: S, constraints: Constraints, epsilon: f64) -> Result<Self, SetupError> {
        if !(epsilon.is_finite() && epsilon >= 0.0) {
            return Err(crate::step::SettingsError::new(
                "epsilon",
                epsilon,
                "must be a finite number > 0",
            )
            .into());
        }
        let m = constraints.len();
        let lcp = if m == 0 {
            None
        } else {
            let mut s = condensed_matrix(&constraints, &mut system);
            for k in 0..m {
                s[k * m + k] += epsilon;
            }
            Some(DenseLcp::new(s, m).map_err(|e| SetupError::Contact(e.to_string()))?)
        };
        Ok(Self {
            system,
            constraints,
            lcp,
            epsilon,
            q: vec![0.0; m],
            w: vec![0.0; m],
        })
    }

    /// `S_jk` (`S + εI` for the penalty law; `None` without constraints).
    pub fn s(&self, j: usize, k: usize) -> Option<f64> {
        self.lcp.as_ref().map(|l| l.entry(j, k))
    }

    /// Stored values of the factor of `C`, and the matrix with its factorisation.
    pub fn system(&self) -> &S {
        &self.system
    }
}

impl<S: SpdSystem> StepSolver for CondensedLcp<S> {
    fn name(&self) -> &'static str {
        if self.epsilon > 0.0 {
            "penalty"
        } else {
            "exact"
        }
    }

    /// `z⁰ = C⁻¹ b`, the LCP for the reactions, and, when one is positive, `z` from
    /// `C z = b + Eᵀ r`. Allocates nothing.
    fn solve(
        &mut self,
        rhs: &[f64],
        lower: &[f64],
        z: &mut [f64],
        reactions: &mut [f64],
    ) -> Result<SolveInfo, StepFailure> {
        z.copy_from_slice(rhs);
        self.system.solve_in_place(z);
        let Some(lcp) = &mut self.lcp else {
            return Ok(SolveInfo { iterations: 1 });
        };
        let (unknowns, signs) = (&self.constraints.unknowns, &self.constraints.directions);
        for (k, q) in self.q.iter_mut().enumerate() {
            *q = signs[k] * z[unknowns[k]] - lower[k];
        }
        let iterations = lcp
            .solve(&self.q, reactions, &mut self.w)
            .map_err(|e| match e {
                LcpError::IterationLimit { iterations } => {
                    StepFailure::IterationLimit { iterations }
                }
                LcpError::NonFinite | LcpError::NotPositiveDefinite { .. } => {
                    StepFailure::NonFinite
                }
            })?;
        if reactions.iter().any(|&r| r > 0.0) {
            // z from C z = b + Eᵀ r directly (backward stable).
            z.copy_from_slice(rhs);
            for (k, r) in reactions.iter().enumerate() {
                z[unknowns[k]] += signs[k] * r;
            }
            self.system.solve_in_place(z);
        }
        Ok(SolveInfo { iterations })
    }
}

/// The bar's specialised solvers against this general one on the bar's tridiagonal system:
/// each is its twin ([`crate::step::algorithm`] names which serves a scene).
#[cfg(test)]
mod twins {
    use super::*;
    use crate::linalg::system::TridiagSystem;
    use crate::linalg::tridiag::SymTridiag;
    use crate::step::{BlockPivoting, EndEnumeration, EndPenalty, PenaltySettings};

    /// Units of `ε max|z|` (`ε max r`) the twins' answers may differ by: both are backward
    /// stable on a matrix with `κ(C) <= 3` (diagonal 4, off-diagonals `−1`), and the condensed
    /// route's second solve and LCP add a few roundings of each quantity to the twin's.
    const TWIN_AGREEMENT_ULPS: f64 = 64.0;

    /// A deterministic pseudo-random number in `[−1, 1)` from `seed` and `i`.
    fn draw(seed: u64, i: usize) -> f64 {
        let x = (seed.wrapping_mul(0x9E37_79B9_7F4A_7C15)
            ^ (i as u64).wrapping_mul(0xBF58_476D_1CE4_E5B9))
        .wrapping_mul(0x94D0_49BB_1331_11EB);
        (x >> 11) as f64 / (1u64 << 52) as f64 - 1.0
    }

    fn bar_matrix(n: usize) -> SymTridiag {
        SymTridiag::new(vec![4.0; n], vec![-1.0; n - 1])
    }

    /// The largest of `|a − b|` over `max |a|` (0 when `a` vanishes), in units of ε.
    fn ulps_apart(a: &[f64], b: &[f64]) -> f64 {
        let scale = a.iter().fold(0.0f64, |m, v| m.max(v.abs()));
        if scale == 0.0 {
            return 0.0;
        }
        let worst = a
            .iter()
            .zip(b)
            .fold(0.0f64, |m, (x, y)| m.max((x - y).abs()));
        worst / (scale * f64::EPSILON)
    }

    /// Solves a run of problems with both solvers, warm starts included, and compares them;
    /// returns how many problems had a positive reaction (so that contact was exercised).
    fn compare(
        twin: &mut dyn StepSolver,
        general: &mut dyn StepSolver,
        n: usize,
        bounds: usize,
        seed: u64,
    ) -> usize {
        let mut contacts = 0;
        for problem in 0..40 {
            let s = seed * 1000 + problem;
            let rhs: Vec<f64> = (0..n).map(|i| draw(s, i)).collect();
            let lower: Vec<f64> = (0..bounds).map(|k| 0.2 * draw(s + 500, k) - 0.1).collect();
            let (mut za, mut zb) = (vec![0.0; n], vec![0.0; n]);
            let (mut ra, mut rb) = (vec![0.0; bounds], vec![0.0; bounds]);
            twin.solve(&rhs, &lower, &mut za, &mut ra).unwrap();
            general.solve(&rhs, &lower, &mut zb, &mut rb).unwrap();
            let (dz, dr) = (ulps_apart(&za, &zb), ulps_apart(&ra, &rb));
            assert!(
                dz <= TWIN_AGREEMENT_ULPS,
                "{}: z {dz} ulps apart",
                twin.name()
            );
            assert!(
                dr <= TWIN_AGREEMENT_ULPS,
                "{}: r {dr} ulps apart",
                twin.name()
            );
            contacts += usize::from(ra.iter().any(|&r| r > 0.0));
        }
        contacts
    }

    fn general(c: &SymTridiag, nodes: &[usize], epsilon: f64) -> CondensedLcp<TridiagSystem> {
        let system = TridiagSystem::new(c).unwrap();
        CondensedLcp::new(system, Constraints::lower_bounds(nodes), epsilon).unwrap()
    }

    #[test]
    fn end_enumeration_is_the_condensed_lcp_on_the_bar_ends() {
        for (n, ends) in [
            (2, vec![0, 1]),
            (9, vec![0]),
            (9, vec![8]),
            (30, vec![0, 29]),
        ] {
            let c = bar_matrix(n);
            let mut twin = EndEnumeration::new(&c, &ends).unwrap();
            let contacts = compare(&mut twin, &mut general(&c, &ends, 0.0), n, ends.len(), 1);
            assert!(contacts > 0, "n = {n}: no contact drawn");
        }
    }

    #[test]
    fn end_penalty_is_the_condensed_lcp_with_compliance_on_the_bar_ends() {
        for epsilon in [1e-1, 1e-4] {
            for (n, ends) in [(9, vec![0]), (30, vec![0, 29])] {
                let c = bar_matrix(n);
                let mut twin = EndPenalty::new(&c, &ends, PenaltySettings { epsilon }).unwrap();
                let mut general = general(&c, &ends, epsilon);
                let contacts = compare(&mut twin, &mut general, n, ends.len(), 2);
                assert!(contacts > 0, "n = {n}, ε = {epsilon}: no contact drawn");
            }
        }
    }

    #[test]
    fn block_pivoting_is_the_condensed_lcp_under_an_obstacle() {
        for n in [5, 40] {
            let c = bar_matrix(n);
            let nodes: Vec<usize> = (0..n).collect();
            let mut twin = BlockPivoting::new(&c, &nodes).unwrap();
            let contacts = compare(&mut twin, &mut general(&c, &nodes, 0.0), n, n, 3);
            assert!(contacts > 0, "n = {n}: no contact drawn");
        }
    }
}
