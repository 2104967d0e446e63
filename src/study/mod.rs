//! The studies a user runs on top of the core: errors against closed forms, refinement and
//! work-precision (`converge`), solvers side by side (`compare`), the mass variants, the
//! α → 0 sweep and the talk's figures. The certificate's studies (the generated tables of
//! VERIFICATION.md, the tolerance registry) are the workspace member `viscobar-certificate`.
//!
//! Top layer: may import every other layer; nothing imports it.

pub mod accuracy;
pub mod compare;
pub mod converge;
pub(crate) mod convergence_table;
pub(crate) mod figure_writer;
pub mod figures;
pub(crate) mod friction_figure;
pub mod mass_figure;
pub mod mass_variants;
pub(crate) mod plane_contact_figure;
pub mod plane_figure;
pub(crate) mod refine;
pub(crate) mod sampled_run;
pub(crate) mod temperature_figure;
pub mod viscosity_sweep;
pub mod work_precision;

pub use refine::StudyScene;
