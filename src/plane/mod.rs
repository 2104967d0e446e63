//! The plane body: a Kelvin–Voigt body in plane strain on `(0, W) × (0, H)`, Q1 elements on a
//! tensor grid graded in `y` ([`mesh`]), the consistent Q1 mass `M` and stiffness `K`
//! ([`matrices`]), stepped by the scheme ([`crate::scheme`]) through its kernels ([`body`]);
//! the step matrix is factorised once per run by a sparse Cholesky (faer, AMD). Edges may be
//! Signorini: each node of such an edge carries a contact normal ([`normals`]), with Coulomb
//! friction where the edge has a coefficient ([`friction`]). With `λ = 0`,
//! `μ = ½`, `ρ = 1` and data `(f(x), 0)` it reduces to the bar exactly (VERIFICATION.md,
//! "Plane body").
//!
//! Imports [`crate::linalg`], [`crate::step`], [`crate::scene`] and [`crate::scheme`].
//!
//! A plane run is a [`PlaneSimulation`]; `examples/plane_tilted_drop_exact.rs` steps one.

pub mod body;
pub mod closed_form;
pub mod energy;
pub mod friction;
pub mod matrices;
pub mod mesh;
pub mod normals;
pub mod stress;

pub use body::{PlaneBody, PlaneDiscretisation, PlaneSimulation};
