//! The plane body: a Kelvin–Voigt body in plane strain on `(0, W) × (0, H)`, Q1 elements on a
//! tensor grid graded in `y` (`mesh`), the consistent Q1 mass `M` and stiffness `K`
//! (`matrices`), stepped by the scheme ([`crate::scheme`]) through its kernels (`body`);
//! the step matrix is factorised once per run by a sparse Cholesky (faer, AMD). Edges may be
//! Signorini: each node of such an edge carries a contact normal (`normals`), with Coulomb
//! friction where the edge has a coefficient (`friction`). With `λ = 0`,
//! `μ = ½`, `ρ = 1` and data `(f(x), 0)` it reduces to the bar exactly (VERIFICATION.md,
//! "Plane body").
//!
//! Imports `crate::linalg`, [`crate::step`], [`crate::scene`] and [`crate::scheme`].
//!
//! A plane run is a [`PlaneSimulation`]; `examples/plane_tilted_drop_exact.rs` steps one.

pub(crate) mod body;
pub mod closed_form;
pub(crate) mod coupling;
pub(crate) mod energy;
pub(crate) mod friction;
pub(crate) mod heat;
pub(crate) mod matrices;
pub(crate) mod mesh;
pub(crate) mod normals;
pub(crate) mod stress;

pub use body::{PlaneBody, PlaneDiscretisation, PlaneSimulation};
pub use mesh::Grid;
