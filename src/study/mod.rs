//! The studies that verify the core: errors against closed forms, refinement and
//! work-precision, solver agreement, the stiff and extreme case matrix, the mass variants, the
//! talk's figures and the generated tables of VERIFICATION.md.
//!
//! Top layer: may import every other layer; nothing imports it.

pub mod accuracy;
// TEMP pub mod agreement;
pub mod compare;
pub mod converge;
pub mod convergence_table;
pub mod figure_writer;
pub mod figures;
pub mod mass_figure;
pub mod mass_variants;
// TEMP pub mod plane_checks;
// TEMP pub mod plane_contact;
pub mod plane_contact_figure;
pub mod plane_figure;
pub mod refine;
pub mod sampled_run;
// TEMP pub mod stiff;
// TEMP pub mod stiff_runs;
// TEMP pub mod timings;
// TEMP pub mod tolerances;
// TEMP pub mod verify;
pub mod viscosity_sweep;
// TEMP pub mod viscous_contact;
pub mod work_precision;
