//! The seam between the time stepper and the per-step minimisation.
//!
//! Every step of the scheme (talk, "Numerical scheme": minimise J over K_h) is, in the increment
//! `z = u^{n+1} - u^n` that the stepper solves for, the bound-constrained quadratic programme
//!
//! ```text
//!   minimise ½ zᵀ C z − bᵀ z   subject to   z_j >= lo_j  for each constrained node j,
//! ```
//!
//! with `C` symmetric positive definite tridiagonal and constant in time. Its KKT conditions,
//! which every implementation must meet, are `C z = b + Σ_j r_j e_j`, `z_j >= lo_j`, `r_j >= 0`,
//! `r_j (z_j − lo_j) = 0`; the multipliers `r_j` are the contact reactions.

use crate::step::report::{SolveInfo, SolverReport, StepFailure};

/// A solver for the step problem. Built once per run for a fixed `C` and a fixed list of
/// constrained nodes; `solve` is called every step and must not allocate.
pub trait StepSolver {
    /// Short name used in outputs (`exact`, ...).
    fn name(&self) -> &'static str;

    /// Given `rhs = b` and `lower = lo` (one entry per constrained node, in the order given at
    /// construction), writes the minimiser into `z` and the multipliers into `reactions`.
    fn solve(
        &mut self,
        rhs: &[f64],
        lower: &[f64],
        z: &mut [f64],
        reactions: &mut [f64],
    ) -> Result<SolveInfo, StepFailure>;

    /// `max_i |u^n_i|`, the state the next answer `z` is added to, given before each solve
    /// (the exact end solver weighs its cancellation error against it). Default: ignored.
    fn set_state_scale(&mut self, _max_abs_u: f64) {}

    /// [`StepSolver::solve`], then `u += z`; returns `max_i |u_i|` afterwards, the next
    /// step's state scale, or 0 from a solver that never reads it. The default makes the two
    /// passes; the exact solver merges its superposition `z⁰ + Σ r_j c_j` with the addition
    /// when it may, and without constrained nodes adds inside the solve (and returns 0).
    fn solve_and_advance(
        &mut self,
        rhs: &[f64],
        lower: &[f64],
        u: &mut [f64],
        z: &mut [f64],
        reactions: &mut [f64],
    ) -> Result<(SolveInfo, f64), StepFailure> {
        let info = self.solve(rhs, lower, z, reactions)?;
        Ok((info, crate::linalg::update::add_in_place(u, z)))
    }

    /// Statistics over all solves so far; `None` for solvers that keep none.
    fn report(&self) -> Option<SolverReport> {
        None
    }
}
