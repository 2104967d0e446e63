//! The studies that verify the core: errors against closed forms, refinement and
//! work-precision, solver agreement, the stiff and extreme case matrix, the mass variants, the
//! talk's figures and the generated tables of VERIFICATION.md.
//!
//! Top layer: may import every other layer; nothing imports it.

pub mod accuracy;
pub mod agreement;
pub mod compare;
pub mod converge;
pub mod figure_writer;
pub mod figures;
pub mod mass_figure;
pub mod mass_variants;
pub mod plane_checks;
pub mod plane_contact;
pub mod plane_contact_figure;
pub mod plane_figure;
pub mod sampled_run;
pub mod stiff;
pub mod stiff_runs;
pub mod timings;
pub mod tolerances;
pub mod verify;
pub mod viscosity_sweep;
pub mod viscous_contact;
pub mod work_precision;
