//! Refinement study of the manufactured viscous-contact scene (`viscous-contact`,
//! [`ViscousContact`]): errors of the displacement, the reaction and the contact times against
//! the closed form, `dx` and `dt` halved together. Shared by `tests/closed_forms.rs` and the
//! generated table of VERIFICATION.md; derivation in
//! [docs/viscous-contact.md](../../docs/viscous-contact.md).

use crate::bar::closed_form::{self, ClosedForm};
use crate::scene::{self, Scene};
use crate::study::accuracy::{error_against, observed_order};
use crate::study::converge::contact_time_error;
use crate::time::RunError;
use crate::time::run::run_in_memory;
use std::fmt::Write;

/// The built-in scene's name.
pub const SCENE: &str = "viscous-contact";

/// Time kept off each end of the contact window for [`Row::reaction_interior`]: a tenth of
/// the window, longer than the discrete contact set's lag at the scene's own mesh (about 4
/// steps, 0.0625, in the table).
pub const INTERIOR_MARGIN: f64 = 0.1;

/// One level of the study.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Row {
    pub elements: u64,
    pub dt: f64,
    pub dx: f64,
    /// `max_n ‖u_h(t_n) − u(·, t_n)‖_{L2}` (trapezoidal rule on the nodes).
    pub l2: f64,
    /// `max_n |r^{n+1} − (−s(0, t_n))|`: the reaction of the step centred at `t_n` (the scheme's
    /// equation is centred there) against the closed form's.
    pub reaction: f64,
    /// The same on `[t1 + m, t2 − m]`, `m` = [`INTERIOR_MARGIN`]: away from the landing and the
    /// take-off, where the discrete contact set differs from the exact one for a few steps.
    pub reaction_interior: f64,
    /// [`contact_time_error`] of the left end's episodes against `[t1, t2]`.
    pub contact_times: f64,
}

/// The closed form of the scene (a built-in one always has it).
pub fn closed_form(scene: &Scene) -> closed_form::ViscousContact {
    let exact = closed_form::for_scene(SCENE, scene).expect("viscous-contact has its closed form");
    let [t1, t2] = closed_form::VISCOUS_CONTACT_WINDOW;
    closed_form::ViscousContact {
        length: scene.bar.length,
        alpha: scene.bar.viscosity,
        gap: scene.left.gap.expect("Signorini left end"),
        t1,
        t2,
        pulse: closed_form::VISCOUS_CONTACT_PULSE,
        initial_amplitude: closed_form::VISCOUS_CONTACT_INITIAL_AMPLITUDE,
    }
    .checked_against(exact.as_ref())
}

impl closed_form::ViscousContact {
    /// `self`, after checking it is the closed form `other` (same displacement at a few points).
    fn checked_against(self, other: &dyn ClosedForm) -> Self {
        for (x, t) in [(0.3, 0.2), (0.7, 1.1), (1.0, 2.0)] {
            assert_eq!(self.displacement(x, t), other.displacement(x, t));
        }
        self
    }
}

/// One level: the scene refined `level` times (dx and dt halved together).
pub fn row(base: &Scene, level: u32) -> Result<Row, RunError> {
    let exact = closed_form(base);
    let scene = base.refined(level);
    let l2 = error_against(&scene, &exact)?.l2;
    let (records, summary, _) = run_in_memory(SCENE, &scene)?;
    let dt = scene.time.step;
    let (mut reaction, mut reaction_interior) = (0.0f64, 0.0f64);
    for r in &records {
        let t_n = (r.step - 1) as f64 * dt;
        let e = (r.reaction[0] - exact.reaction(t_n)).abs();
        reaction = reaction.max(e);
        if t_n >= exact.t1 + INTERIOR_MARGIN && t_n <= exact.t2 - INTERIOR_MARGIN {
            reaction_interior = reaction_interior.max(e);
        }
    }
    let discrete = summary
        .contact_intervals
        .get("left")
        .cloned()
        .unwrap_or_default();
    let window = exact.contact_intervals(scene.time.end).expect("one window");
    Ok(Row {
        elements: scene.mesh.elements,
        dt,
        dx: scene.dx(),
        l2,
        reaction,
        reaction_interior,
        contact_times: contact_time_error(&window, &discrete).expect("one window"),
    })
}

/// Levels `0..levels` of the built-in scene.
pub fn study(levels: u32) -> Result<Vec<Row>, RunError> {
    let (_, base) = scene::load(SCENE, &[])?;
    (0..levels).map(|l| row(&base, l)).collect()
}

/// Observed orders (least squares over all rows) of the displacement, the reaction (all
/// steps, then the window's interior) and the contact times.
pub fn orders(rows: &[Row]) -> [f64; 4] {
    let h: Vec<f64> = rows.iter().map(|r| r.dx).collect();
    let of = |f: fn(&Row) -> f64| observed_order(&h, &rows.iter().map(f).collect::<Vec<_>>());
    [
        of(|r| r.l2),
        of(|r| r.reaction),
        of(|r| r.reaction_interior),
        of(|r| r.contact_times),
    ]
}

/// The table of VERIFICATION.md.
pub fn markdown(rows: &[Row]) -> String {
    let mut md = String::from(
        "| elements | dt | L2 error (max over t) | reaction error (all steps) | reaction error (window interior) | contact time error |\n|---|---|---|---|---|---|\n",
    );
    for r in rows {
        let _ = writeln!(
            md,
            "| {} | {} | {:.3e} | {:.3e} | {:.3e} | {:.3e} |",
            r.elements, r.dt, r.l2, r.reaction, r.reaction_interior, r.contact_times
        );
    }
    let [p, q, qi, c] = orders(rows);
    let _ = writeln!(
        md,
        "| observed order | | {p:.3} | {q:.3} | {qi:.3} | {c:.3} |"
    );
    md
}

/// The generated block `viscous-contact` of VERIFICATION.md: [`VERIFY_LEVELS`] levels.
pub fn section() -> Result<crate::study::verify::Section, RunError> {
    Ok(crate::study::verify::Section {
        id: "viscous-contact",
        markdown: markdown(&study(VERIFY_LEVELS)?),
    })
}

/// Levels of the VERIFICATION.md table (the same as the other convergence tables).
pub const VERIFY_LEVELS: u32 = crate::study::verify::CONVERGENCE_LEVELS;
