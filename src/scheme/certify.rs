//! A run certifies itself: every measured step's energy-identity residual against its bound,
//! the bound the certificate's tests use (VERIFICATION.md, "Tolerances"), beside the step
//! solver's own audit, which rejects a step's answer where it is computed. The bound is the
//! body's round-off tolerance ([`crate::scheme::Body::identity_tolerance`]) plus what the step
//! solver's law lets its answers carry ([`crate::step::StepSolver::identity_allowance`]).
//! [`Certificate`] accumulates the verdict of a run; [`CertificateFailure`] names the first
//! step that breaks it.

use serde::Serialize;

/// Relative residual of the energy identity for a solver exact to round-off (exact, penalty,
/// Lemke): the identity is exact algebra given `C z = b + r`, so only round-off remains
/// (measured below 1e-14 on every built-in scene, VERIFICATION.md, "Scenes", "Step solvers").
pub const IDENTITY_TOL: f64 = 1e-12;
/// The plane's energy identity (with the contact term): exact algebra, round-off only,
/// relative to the largest of its terms (rows of 18 entries; the `K`-forms from strains).
pub const PLANE_IDENTITY_TOL: f64 = 1e-12;
/// The thermal bar's total-energy identity: exact algebra given the coupled solve, so round-off
/// only (sums of a few hundred terms; measured about 1e-14, VERIFICATION.md, "Thermal bar").
pub const THERMAL_IDENTITY_TOL: f64 = 1e-12;
/// The energy identity's round-off grows with `λ/μ` (either rule): the solve's backward error
/// `ε ‖C‖ |z|` lies partly along the stiff volumetric directions, which the energy weighs by
/// `λ`; measured 15–35 `ε λ/μ` on the cantilever up to `λ/μ = 5000`. The plane's bound is
/// `PLANE_IDENTITY_TOL + LAMBDA_IDENTITY_ULPS ε λ/μ`.
pub const LAMBDA_IDENTITY_ULPS: f64 = 64.0;

/// The identity's round-off follows the conditioning of the step's matrices: the solve's
/// backward error `ε ‖C‖ |z|` enters the energy as `ε κ |terms|`. Measured on the stiff case
/// matrix up to `κ(C) = 4e11` (VERIFICATION.md, "Stiff and extreme cases") at most 0.23 ε κ(C),
/// and on the thermal bar up to `κΔt/Δx² = 5e13` at most 0.07 ε κΔt/Δx²; four ulps per unit of
/// conditioning covers both with a margin of 17.
pub const CONDITION_IDENTITY_ULPS: f64 = 4.0;
/// A run whose bound would exceed this is refused at set-up, naming the key that makes it
/// stiff: an identity held only to two digits certifies nothing. (The stiff studies reach
/// `1.2e-3`: `impact` at `α = 1e6`, `Δt = 1e4 Δx` on 64 elements, `κ(C) = 1.3e12`.)
pub const MAX_IDENTITY_BOUND: f64 = 1e-2;

/// `tol + ε (n + CONDITION_IDENTITY_ULPS · condition)`: a body's identity bound with `n`
/// unknowns (the energy sums' worst-case rounding `γ_n`) and its step's `condition` number.
pub fn conditioned_bound(tol: f64, unknowns: usize, condition: f64) -> f64 {
    tol + f64::EPSILON * (unknowns as f64 + CONDITION_IDENTITY_ULPS * condition)
}

/// The check a step failed.
pub const IDENTITY_CHECK: &str = "energy identity residual";

/// The first step of a run that breaks its certificate.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct CertificateFailure {
    /// `n + 1`.
    pub step: usize,
    /// `t_{n+1}`.
    pub time: f64,
    /// What failed ([`IDENTITY_CHECK`]).
    pub check: &'static str,
    pub value: f64,
    pub bound: f64,
}

impl std::fmt::Display for CertificateFailure {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(
            f,
            "step {} (t = {}): {} {:.3e} exceeds its bound {:.3e}",
            self.step, self.time, self.check, self.value, self.bound
        )
    }
}

/// The verdict of a run so far: the measured steps and the first failure, if any.
#[derive(Clone, Debug, Default, PartialEq, Serialize)]
pub struct Certificate {
    /// Every measured step met its bound.
    pub certified: bool,
    /// Steps whose identity was measured (`[output] diagnostics_every`), the start-up's
    /// included.
    pub measured_steps: usize,
    /// The first step that broke its bound.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub first_failure: Option<CertificateFailure>,
}

impl Certificate {
    /// A run that has measured nothing yet.
    pub fn new() -> Self {
        Self {
            certified: true,
            ..Default::default()
        }
    }

    /// Takes a step's residual and its bound; returns the failure when this step is the first
    /// to break it (a NaN residual breaks it).
    pub fn observe(
        &mut self,
        step: usize,
        time: f64,
        residual: f64,
        bound: f64,
    ) -> Option<&CertificateFailure> {
        self.measured_steps += 1;
        if residual <= bound || self.first_failure.is_some() {
            return None;
        }
        self.certified = false;
        self.first_failure = Some(CertificateFailure {
            step,
            time,
            check: IDENTITY_CHECK,
            value: residual,
            bound,
        });
        self.first_failure.as_ref()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A residual at its bound passes, one ulp above fails, a NaN fails, and only the first
    /// failure is kept.
    #[test]
    fn the_first_step_over_its_bound_is_kept() {
        let mut c = Certificate::new();
        assert!(c.observe(1, 0.1, 1e-12, 1e-12).is_none());
        assert!(c.certified);
        let above = f64::from_bits(1e-12f64.to_bits() + 1);
        assert_eq!(c.observe(2, 0.2, above, 1e-12).map(|f| f.step), Some(2));
        assert!(c.observe(3, 0.3, f64::NAN, 1e-12).is_none());
        assert!(!c.certified);
        assert_eq!(c.measured_steps, 3);
        assert_eq!(c.first_failure.as_ref().map(|f| f.value), Some(above));
        let mut nan = Certificate::new();
        assert!(nan.observe(1, 0.1, f64::NAN, 1.0).is_some());
    }
}
