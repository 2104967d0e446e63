//! The talk's scheme (VI)_h, once, for every body: the state `(u^{n−1}, u^n)`, the start-up
//! step, the step (right-hand side, constrained minimisation, advance), the energy identity,
//! the load and the step record. [`Scheme::step`](stepper::Scheme::step) is the talk's step
//! line by line. The scheme does not know which body it steps: a body supplies its matrices as
//! kernels through [`Body`] — the bar's in `crate::bar::body` (tridiagonal), the plane body's
//! in `crate::plane::body` (sparse) — and its constraints as a [`ContactSet`].
//!
//! Imports `crate::linalg`, [`crate::step`] and [`crate::scene`].

pub(crate) mod body;
pub mod certify;
pub(crate) mod clock;
pub(crate) mod contact;
pub(crate) mod error;
pub(crate) mod friction;
pub(crate) mod load;
pub(crate) mod slide;
pub(crate) mod stepper;

pub use body::{Body, EnergySums, HeatOutputs, HeatTerms};
pub use certify::{Certificate, CertificateFailure};
pub use contact::{CONTACT_GAP_TOL, ContactSet, ContactState, GroupState, in_contact};
pub use error::RunError;
pub use friction::{FrictionState, NodeState, SLIP_TOL, is_slipping};
pub use load::Load;
pub use slide::Slide;
pub use stepper::{Scheme, Setup, State, StepRecord, Unstarted};
