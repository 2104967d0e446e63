//! The seam between the scheme and the per-step minimisation, for every body.
//!
//! Every step of the scheme (talk, "Numerical scheme": minimise J over K_h) is, in the increment
//! `z = u^{n+1} - u^n` that the scheme solves for, the quadratic programme
//!
//! ```text
//!   minimise ½ zᵀ C z − bᵀ z   subject to   s_k z_{i_k} >= lo_k  for each constraint k,
//! ```
//!
//! with `C` symmetric positive definite and constant in time, constraint `k` bounding unknown
//! `i_k` in the direction `s_k = ±1` ([`Constraints`]). Its KKT conditions, which every
//! implementation must meet, are `C z = b + Σ_k r_k s_k e_{i_k}`, `s_k z_{i_k} >= lo_k`,
//! `r_k >= 0`, `r_k (s_k z_{i_k} − lo_k) = 0`; the multipliers `r_k` are the contact reactions.

use crate::step::report::{SolveInfo, SolverReport, StepFailure};

/// The constrained unknowns of a step problem and the direction of each bound: constraint `k`
/// is `s_k z_{i_k} >= lo_k` with `i_k = unknowns[k]`, `s_k = directions[k]` (`±1`), and its
/// reaction `r_k >= 0` pushes along `s_k e_{i_k}`. The bar's bounds are lower bounds
/// (`s = +1`); an edge of the plane body pushes along its inward normal.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Constraints {
    pub unknowns: Vec<usize>,
    pub directions: Vec<f64>,
}

impl Constraints {
    /// Lower bounds `z_i >= lo` at each of `unknowns`.
    pub fn lower_bounds(unknowns: &[usize]) -> Self {
        Self {
            unknowns: unknowns.to_vec(),
            directions: vec![1.0; unknowns.len()],
        }
    }

    /// `m`, the number of constraints.
    pub fn len(&self) -> usize {
        self.unknowns.len()
    }

    pub fn is_empty(&self) -> bool {
        self.unknowns.is_empty()
    }
}

/// The frictional nodes of a step problem: node `j` adds the tangential reaction `r_T,j` along
/// `+e_{t_j}` to the normal constraint `normals[j]`, with coefficient `μ_j > 0`.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Friction {
    /// The normal constraint `k_j` of each frictional node.
    pub normals: Vec<usize>,
    /// The unknown `t_j` of its tangential component.
    pub tangents: Vec<usize>,
    /// `μ_j`.
    pub coefficients: Vec<f64>,
}

impl Friction {
    /// `w` at the tangential unknowns, into `out` (one per frictional node).
    pub fn tangential_into(&self, w: &[f64], out: &mut [f64]) {
        for (v, &t) in out.iter_mut().zip(&self.tangents) {
            *v = w[t];
        }
    }

    /// `p`, the frictional nodes.
    pub fn len(&self) -> usize {
        self.normals.len()
    }

    pub fn is_empty(&self) -> bool {
        self.normals.is_empty()
    }

    /// The normal constraints followed by the tangential rows (direction `+1`), as one set of
    /// rows `E` for the condensation.
    pub fn rows(&self, constraints: &Constraints) -> Constraints {
        let mut all = constraints.clone();
        all.unknowns.extend(&self.tangents);
        all.directions.extend(std::iter::repeat_n(1.0, self.len()));
        all
    }
}

/// A solver for the step problem. Built once per run for a fixed `C` and fixed
/// [`Constraints`]; `solve` is called every step and must not allocate.
pub trait StepSolver {
    /// Short name used in outputs (`exact`, ...).
    fn name(&self) -> &'static str;

    /// Given `rhs = b` and `lower = lo` (one entry per constraint, in the order given at
    /// construction), writes the minimiser into `z` and the multipliers into `reactions` (a
    /// frictional solver writes, after them, the tangential reaction of each frictional node,
    /// `crate::step::condensed_lemke`).
    fn solve(
        &mut self,
        rhs: &[f64],
        lower: &[f64],
        z: &mut [f64],
        reactions: &mut [f64],
    ) -> Result<SolveInfo, StepFailure>;

    /// [`StepSolver::solve`], then the scheme's update `u += z`. A solver may fuse the two into
    /// one pass over the unknowns; the bits are those of the solve followed by the addition.
    fn solve_and_advance(
        &mut self,
        rhs: &[f64],
        lower: &[f64],
        z: &mut [f64],
        reactions: &mut [f64],
        u: &mut [f64],
    ) -> Result<SolveInfo, StepFailure> {
        let info = self.solve(rhs, lower, z, reactions)?;
        add_in_place(u, z);
        Ok(info)
    }

    /// The previous increment `w = u^n − u^{n−1}`, given before each solve of a step after the
    /// start-up step: a frictional solver's central slip is `(z + w)` at its tangential
    /// unknowns. Default: ignored.
    fn set_previous_increment(&mut self, _w: &[f64]) {}

    /// `v_j`, the tangential displacement of each frictional node's obstacle over the slip's
    /// interval (one per frictional node), given before a solve when an obstacle slides along
    /// its edge: the slip becomes `(z + w)_{t_j} − v_j` ([`crate::step::law::Slip`]). Default:
    /// ignored (no friction law).
    fn set_obstacle_slide(&mut self, _v: &[f64]) {}

    /// Statistics over all solves so far; `None` for solvers that keep none.
    fn report(&self) -> Option<SolverReport> {
        None
    }

    /// The relative error of the energy identity that the solver's law lets its answers carry
    /// beyond round-off, from its audit so far: 0 for a solver exact to round-off (exact,
    /// penalty, Lemke); an iterative solver's stationarity residual `ρ` enters the identity as
    /// `½ ρ·δ` (the certificate's scaling, [`crate::scheme::certify`]).
    fn identity_allowance(&self) -> f64 {
        0.0
    }
}

/// `u += z`, the scheme's update.
pub(crate) fn add_in_place(u: &mut [f64], z: &[f64]) {
    for (ui, zi) in u.iter_mut().zip(z) {
        *ui += zi;
    }
}
