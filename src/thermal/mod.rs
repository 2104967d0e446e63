//! The thermo-viscoelastic bar: the bar's displacement coupled to a temperature deviation `θ`
//! (P1 on the bar's mesh, at the half steps), `θ_t − κ θ_xx + γ u_xt = q`, stress
//! `u_x + α u_xt − γ θ`. The body (`body`) plugs into the one scheme; its matrices
//! (`matrices`), the coupled step matrix with its block `LDLᵀ` (`system`) and the step
//! solvers (`solver`; the contact on the ends stays exact, by the bar's end enumeration) are
//! set up once per run (`setup`); the heat steps are implicit Euler where the data are not
//! smooth (`smoothing`). Derivation and energy identity: `docs/thermal.md`.
//!
//! Imports `crate::linalg`, [`crate::step`], [`crate::scene`], [`crate::scheme`] and
//! [`crate::bar`].

pub(crate) mod body;
mod heat_rows;
pub(crate) mod matrices;
pub(crate) mod setup;
pub(crate) mod smoothing;
pub(crate) mod solver;
pub(crate) mod system;

pub use body::ThermalBody;
pub use setup::ThermalSimulation;
