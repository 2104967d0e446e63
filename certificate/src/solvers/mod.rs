//! The step solvers against each other (VERIFICATION.md, "Step solvers"):
//!
//! - [`agreement`]: OSQP and the penalty law against the exact solver on every built-in scene,
//!   the penalty's order in ε, OSQP's failures on stiff steps, random step problems
//!   (`solver-agreement`);
//! - [`general_twins`]: the bar's specialised exact solvers against the general one;
//! - [`oracle`]: the dense brute-force reference of the step problem;
//! - [`scale`]: contact at scale, the sparse penalty solver against the condensed one.
//!
//! Every solver at the bar's extremes is the stiff case matrix ([`crate::bar::stiff`]); the
//! plane's and friction's solvers are compared in [`crate::plane::contact`] and
//! [`crate::friction`].

pub mod agreement;
pub mod general_twins;
pub mod oracle;
pub mod scale;
