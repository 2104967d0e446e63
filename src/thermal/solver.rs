//! The thermal bar's step solvers behind the one seam ([`StepSolver`]), on the block layout
//! `[u | θ]`. An exchange end changes the temperature's step matrix while it is in contact, so
//! each exchange state has its own matrix, factorised once at set-up; the state of a step is
//! read off its bounds (`lo_k = −gap_k(u^n)`, [`exchange_state`]), exactly as the body reads
//! it for its right-hand side. Without coupling (`γ = 0`) the displacement is the bar's own
//! step, by the bar's own solver ([`DecoupledSolver`]: the bar's bits), and the temperature a
//! tridiagonal solve; with coupling, the exact end solver per exchange state on the coupled
//! matrix ([`CoupledSolver`], [`crate::thermal::system::CoupledEnds`]). Each has the matrices
//! of the implicit Euler steps beside the Crank–Nicolson ones, taken as the body's
//! [`ImplicitFlag`] says.

use std::sync::Arc;
use std::sync::atomic::{AtomicBool, Ordering};

use crate::linalg::kernels::ldlt::Ldlt;
use crate::scheme::in_contact;
use crate::step::{SolveInfo, SolverReport, StepFailure, StepSolver};

/// The exchange state of a step: bit `e` set when the `e`-th constraint of `exchange` is in
/// contact with `u^n`, its gap `−lower[k]` at most [`crate::scheme::CONTACT_GAP_TOL`]. The one
/// reading of the state: the solver's matrix and the body's right-hand side and heat terms
/// both take it from the step's bounds, where a moving obstacle has been put.
#[inline]
pub fn exchange_state(lower: &[f64], exchange: impl IntoIterator<Item = usize>) -> usize {
    exchange
        .into_iter()
        .enumerate()
        .filter(|&(_, k)| in_contact(-lower[k]))
        .fold(0, |mask, (e, _)| mask | (1 << e))
}

/// Whether the step being taken is an implicit Euler step of the heat: set by the body's
/// `prepare_step`, read by the step solver, which takes that step's matrix.
pub type ImplicitFlag = Arc<AtomicBool>;

/// The index of a step's matrix among `masks` exchange states: `mask`, after the
/// Crank–Nicolson ones for an implicit step.
#[inline]
fn variant(flag: &AtomicBool, mask: usize, masks: usize) -> usize {
    mask + usize::from(flag.load(Ordering::Relaxed)) * masks
}

/// `γ = 0`: the bar's step by the bar's solver on the displacement block, then
/// `θ`'s increment from `−H_χ z_θ = b_θ`.
pub struct DecoupledSolver {
    mechanical: Box<dyn StepSolver>,
    /// The step's heat block factorised, per exchange state: Crank–Nicolson's, then the
    /// implicit Euler step's ([`crate::thermal::matrices::ThermalMatrices::step_heat_matrix`]).
    heat: Vec<Ldlt>,
    n_u: usize,
    exchange: Vec<usize>,
    implicit: ImplicitFlag,
}

impl DecoupledSolver {
    pub fn new(
        mechanical: Box<dyn StepSolver>,
        heat: Vec<Ldlt>,
        n_u: usize,
        (exchange, implicit): (Vec<usize>, ImplicitFlag),
    ) -> Self {
        assert_eq!(heat.len(), 2 << exchange.len());
        Self {
            mechanical,
            heat,
            n_u,
            exchange,
            implicit,
        }
    }

    fn solve_heat(&self, rhs: &[f64], lower: &[f64], z: &mut [f64]) {
        let n_u = self.n_u;
        let zt = &mut z[n_u..];
        for (zi, b) in zt.iter_mut().zip(&rhs[n_u..]) {
            *zi = -b;
        }
        let mask = exchange_state(lower, self.exchange.iter().copied());
        let masks = 1 << self.exchange.len();
        self.heat[variant(&self.implicit, mask, masks)].solve_in_place(zt);
    }
}

impl StepSolver for DecoupledSolver {
    fn name(&self) -> &'static str {
        self.mechanical.name()
    }

    fn solve(
        &mut self,
        rhs: &[f64],
        lower: &[f64],
        z: &mut [f64],
        reactions: &mut [f64],
    ) -> Result<SolveInfo, StepFailure> {
        let n_u = self.n_u;
        let info = (self.mechanical).solve(&rhs[..n_u], lower, &mut z[..n_u], reactions)?;
        self.solve_heat(rhs, lower, z);
        Ok(info)
    }

    fn report(&self) -> Option<SolverReport> {
        self.mechanical.report()
    }

    fn identity_allowance(&self) -> f64 {
        self.mechanical.identity_allowance()
    }
}

/// `γ > 0`: one solver per exchange state and heat step (Crank–Nicolson or implicit Euler)
/// on the coupled matrix.
pub struct CoupledSolver {
    variants: Vec<Box<dyn StepSolver>>,
    exchange: Vec<usize>,
    implicit: ImplicitFlag,
}

impl CoupledSolver {
    /// `variants[mask]` solves the Crank–Nicolson steps of exchange state `mask`,
    /// `variants[mask + 2^e]` (`e` exchange ends) its implicit Euler steps.
    pub fn new(
        variants: Vec<Box<dyn StepSolver>>,
        (exchange, implicit): (Vec<usize>, ImplicitFlag),
    ) -> Self {
        assert_eq!(variants.len(), 2 << exchange.len());
        Self {
            variants,
            exchange,
            implicit,
        }
    }
}

impl StepSolver for CoupledSolver {
    fn name(&self) -> &'static str {
        self.variants[0].name()
    }

    fn solve(
        &mut self,
        rhs: &[f64],
        lower: &[f64],
        z: &mut [f64],
        reactions: &mut [f64],
    ) -> Result<SolveInfo, StepFailure> {
        let mask = exchange_state(lower, self.exchange.iter().copied());
        let masks = 1 << self.exchange.len();
        self.variants[variant(&self.implicit, mask, masks)].solve(rhs, lower, z, reactions)
    }

    /// The report of the variant that solved the most steps.
    fn report(&self) -> Option<SolverReport> {
        (self.variants.iter())
            .filter_map(|v| v.report())
            .max_by_key(|r| r.audit.steps)
    }

    fn identity_allowance(&self) -> f64 {
        (self.variants.iter())
            .map(|v| v.identity_allowance())
            .fold(0.0, f64::max)
    }
}
