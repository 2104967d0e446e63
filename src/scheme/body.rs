//! What a body supplies to the scheme: its matrices as kernels on the unknowns. The scheme
//! never sees a matrix; the bar implements [`Body`] with tridiagonal kernels
//! (`crate::bar::body`), the plane body with sparse ones (`crate::plane::body`).

use crate::scheme::error::RunError;

/// The sums of one step's energy identity, after `u += z` (`u = u^{n+1}`, `z = u^{n+1} − u^n`,
/// `w = u^n − u^{n−1}`).
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct EnergySums {
    /// `zᵀ M z`.
    pub kinetic: f64,
    /// `|u^{n+1}|²_K`.
    pub potential: f64,
    /// `|z + w|²_K = |u^{n+1} − u^{n−1}|²_K`.
    pub viscous: f64,
    /// `F^n·(z + w)`.
    pub work: f64,
}

/// The thermal terms of one step's energy identity, for a body with a temperature `θ` at the
/// half steps (`θ̄ = (θ^{n+1/2} + θ^{n−1/2})/2`; derivation in `docs/thermal.md`).
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct HeatTerms {
    /// `½ |θ^{n+1/2}|²_M`, part of `E^{n+1/2}`.
    pub energy: f64,
    /// `Δt κ |θ̄|²_K >= 0`.
    pub dissipation: f64,
    /// `Δt Σ_e h χ_e (θ̄_e − θ_obs) θ̄_e`: heat given to the obstacles (either sign).
    pub exchange: f64,
    /// `Δt Q·θ̄` and the heat let in at the fixed-temperature ends.
    pub supply: f64,
    /// `(w − ½)|θ^{n+1/2} − θ^{n−1/2}|²_M >= 0`: the numerical dissipation of an implicit
    /// Euler heat step (`w = 1`; 0 on a Crank–Nicolson step, `w = ½`).
    pub smoothing: f64,
    /// `Σ_j θ_w,j q_j`: the thermal energy the frictional heat `q` brings (plane body).
    pub frictional_supply: f64,
    /// `Σ_j q_j = Σ_j η_j d_j`: the heat friction puts into the body over the step (`d_j` a
    /// frictional node's share of `D_f`, `η_j` its edge's `frictional_heating`).
    pub frictional_heating: f64,
    /// `Σ_j (1 − η_j) d_j`: the rest of `D_f`, the heat that goes to the obstacles.
    pub obstacle_heating: f64,
    /// `1ᵀ M θ^{n+1/2}`: the body's heat content (plane body; 0 on the bar).
    pub heat_content: f64,
}

/// Which heat balance a body with a temperature reports beside the identity's thermal terms
/// (the plane body's: its heat content, and the heat friction puts into it and into the
/// obstacles).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct HeatOutputs {
    /// `1ᵀ M θ`.
    pub heat_content: bool,
    /// Frictional heating (`Σ θ_w q`, `Σ q`).
    pub frictional_heating: bool,
    /// Heat to the obstacles, where some `η < 1`.
    pub obstacle_heating: bool,
}

/// `x ↦ (M x)` restricted to the unknowns, for `x` given at every degree of freedom of the
/// mesh (clamped ones included): the load vector of a nodal interpolant. Kept by a load that
/// is evaluated every step; may use scratch space of its own.
pub type FullMassRows = Box<dyn FnMut(&[f64], &mut [f64]) + Send>;

/// A discretised body: mass `M`, stiffness `K` (the talk's `R`) and the step matrix
/// `C = M/Δt² + (½ + α/(2Δt)) K` on its unknowns, as kernels. None allocates but the set-up
/// ones ([`Body::solve_mass`], [`Body::full_mass_rows`]).
pub trait Body {
    /// `bar` or `plane`, as outputs name the body.
    const NAME: &'static str;
    /// The number of unknowns `n` (degrees of freedom not clamped).
    fn unknowns(&self) -> usize;
    /// `Δt`.
    fn dt(&self) -> f64;
    /// The viscosity `α`.
    fn viscosity(&self) -> f64;
    /// `b = F + M w/Δt² + K((½ − α/(2Δt)) w − u)`: the scheme's right-hand side `F̃^n − C u^n`
    /// in increment form (`force = None` without a load).
    fn rhs_into(&self, u: &[f64], w: &[f64], force: Option<&[f64]>, b: &mut [f64]);
    /// The sums of the energy identity of the step just taken.
    fn energy_sums(&self, u: &[f64], z: &[f64], w: &[f64], force: Option<&[f64]>) -> EnergySums;
    /// `|x|²_K`, in a form exact for rigid motions.
    fn stiffness_form(&self, x: &[f64]) -> f64;
    /// `|u − w|²_K` (the potential of `u^{n−1} = u^n − w`).
    fn stiffness_form_of_difference(&self, u: &[f64], w: &[f64]) -> f64;
    /// `|x|²_M`, in a form exact for rigid motions.
    fn mass_form(&self, x: &[f64]) -> f64;
    /// `y = M x`.
    fn mass_mul(&self, x: &[f64], y: &mut [f64]);
    /// `y = K x`.
    fn stiffness_mul(&self, x: &[f64], y: &mut [f64]);
    /// `y = C x`: the norm the start-up's Taylor step is projected in (a body whose step
    /// matrix depends on the step's state, the coupled plane, takes the start-up's).
    fn step_matrix_mul(&mut self, x: &[f64], y: &mut [f64]) -> Result<(), RunError>;
    /// `a ← M⁻¹ a` on the unknowns that carry mass, `0` on the others (start-up only).
    fn solve_mass(&self, a: &mut [f64]) -> Result<(), RunError>;
    /// The rows of the full-mesh mass matrix at the unknowns (`FullMassRows`).
    fn full_mass_rows(&self) -> FullMassRows;
    /// The mesh nodes (clamped ones included).
    fn nodes(&self) -> usize;
    /// The elements (cells).
    fn elements(&self) -> usize;
    /// The nodes along `x` and along `y` (the bar's `[J + 2, 1]`): node `i + j · lattice[0]`.
    fn lattice(&self) -> [usize; 2];
    /// Degrees of freedom per node: degree of freedom `components · node + c`.
    fn components(&self) -> usize;
    /// `(x, y)` of a node; `y = None` on the bar's line.
    fn point(&self, node: usize) -> (f64, Option<f64>);
    /// The unknown of a degree of freedom (`None` when clamped).
    fn unknown_of(&self, dof: usize) -> Option<usize>;
    /// `[σ_xx, σ_yy, σ_xy, σ_zz]` at every node of the displacement `u` and the velocity `v`
    /// on the unknowns, for output (may allocate); `None` for a body whose outputs show no
    /// stress tensor (the bar).
    fn nodal_stress(&self, _u: &[f64], _v: &[f64]) -> Option<Vec<[f64; 4]>> {
        None
    }
    /// The relative round-off bound of a step's energy identity for a solver exact to
    /// round-off ([`crate::scheme::certify`]).
    fn identity_tolerance(&self) -> f64 {
        crate::scheme::certify::IDENTITY_TOL
    }

    // A body with a temperature (the thermal bar) supplies the hooks below; the defaults are
    // those of a body without one, and leave its steps as they are.

    /// Whether the body has a temperature (its outputs gain the thermal columns).
    fn has_temperature(&self) -> bool {
        false
    }
    /// Brings the body's data to the step from `t_n` (boundary temperatures at `t_{n+1/2}`,
    /// which ends exchange heat), before the step's right-hand side; `n = 0` before the
    /// start-up step. `lower` are the step's bounds `lo_k = −g_k − s_k u^n_{i_k}`, the
    /// obstacles already moved to `t_{n+1}` ([`crate::scheme::ContactSet::lower_bounds_into`]):
    /// a body reads contact off them, never off gaps of its own. `w_old = u^n − u^{n−1}` (0
    /// before the start-up). Allocates nothing.
    fn prepare_step(&mut self, _n: usize, _lower: &[f64], _w_old: &[f64]) -> Result<(), RunError> {
        Ok(())
    }
    /// Completes the start-up increment `u^1 − u^0` that the scheme has put in `increment`
    /// (the displacement's Taylor step from `u^0 = u0`, `u_1 = v0`).
    fn complete_start_up(
        &self,
        _u0: &[f64],
        _v0: &[f64],
        _increment: &mut [f64],
    ) -> Result<(), RunError> {
        Ok(())
    }
    /// The heat balance the body reports ([`HeatOutputs`]; none by default).
    fn heat_outputs(&self) -> HeatOutputs {
        HeatOutputs::default()
    }
    /// The heat step of a body whose temperature follows its mechanics (the plane body's),
    /// after the solve of the step from `t_n`: `θ^{n−1/2} → θ^{n+1/2}` (`n = 0`: the
    /// start-up's half step `θ^0 → θ^{1/2}`), with the step's increments `(z, w_old)`
    /// (`w_old = None` at the start-up) and `friction_work[j]` frictional node `j`'s share of
    /// the step's `D_f` (empty without friction). Allocates nothing once each contact state's
    /// matrix is factorised.
    fn heat_step(
        &mut self,
        _n: usize,
        _increments: (&[f64], Option<&[f64]>),
        _friction_work: &[f64],
    ) -> Result<(), RunError> {
        Ok(())
    }
    /// The thermal terms of the start-up's record: `E^{1/2}`'s thermal part and, for a body
    /// whose heat step follows its mechanics, the start-up's heat inputs (`None` without a
    /// temperature).
    fn start_up_heat(&self, u: &[f64]) -> Option<HeatTerms> {
        self.heat_energy(u).map(|energy| HeatTerms {
            energy,
            ..Default::default()
        })
    }
    /// `½ |θ|²_M` of the state `u` (`None` without a temperature).
    fn heat_energy(&self, _u: &[f64]) -> Option<f64> {
        None
    }
    /// The thermal terms of the step just taken, after `u += z` (`None` without a temperature).
    fn heat_terms(&self, _u: &[f64], _z: &[f64], _w: &[f64]) -> Option<HeatTerms> {
        None
    }
    /// `θ` at a mesh node in the state `u` (`None` without a temperature).
    fn temperature(&self, _u: &[f64], _node: usize) -> Option<f64> {
        None
    }
}
