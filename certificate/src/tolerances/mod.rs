//! The tolerance registry (`verify --tolerances`): for the tolerances of `tests/` and
//! `certificate/src/bar/stiff.rs`, the measured worst value of what each guards and the ratio
//! worst / tolerance, so that a check that cannot fail shows (target: no ratio below
//! [`RATIO_FLOOR`] without a reason). The tolerances measured here live here, each in the
//! module of its subject beside its measurement (or in the study that measures them), and the
//! tests import them, so test and table share one constant and one measurement. The others are
//! found by scanning the sources (`scanner.rs`) and listed with the reason they are not measured.

mod friction;
mod matrices;
mod plane;
mod plane_heat;
mod random_problems;
mod scanner;
mod scenes;
mod solvers;
mod thermal;

pub use friction::*;
pub use matrices::*;
pub use plane::*;
pub use plane_heat::*;
pub use random_problems::*;
pub use scenes::*;
pub use solvers::*;
pub use thermal::*;

use crate::bar::stiff::{CaseResult, checks};
use crate::bar::viscous_contact;
use std::fmt::Write;
use viscobar::internals::linalg::spectrum::reference::STURM_ERROR_ULPS;
use viscobar::scene::{self, MassVariant};
use viscobar::scheme::RunError;

/// A tolerance more than this many times looser than its measured worst value needs a reason.
pub const RATIO_FLOOR: f64 = 1e-3;

/// One measured tolerance.
#[derive(Clone, Debug, PartialEq)]
pub struct Measured {
    /// The constant (or check) and where it is used.
    pub name: String,
    pub used_in: &'static str,
    pub tolerance: f64,
    pub worst: f64,
    /// Why a ratio below [`RATIO_FLOOR`] is right, or what was measured.
    pub note: &'static str,
}

impl Measured {
    pub fn ratio(&self) -> f64 {
        self.worst / self.tolerance
    }
}

/// A checked quantity of the stiff case matrix: its ratio value / tolerance over the completed
/// runs of one solver class.
#[derive(Clone, Debug, PartialEq)]
pub struct StiffCheck {
    pub check: &'static str,
    pub solver: &'static str,
    pub runs: usize,
    pub max_ratio: f64,
    pub min_ratio: f64,
    /// Runs whose ratio is below [`RATIO_FLOOR`] (an exact 0 counted apart).
    pub below_floor: usize,
    pub zero: usize,
}

/// A tolerance constant found in the sources and not measured here.
#[derive(Clone, Debug, PartialEq)]
pub struct Uncovered {
    pub name: String,
    pub file: String,
    pub reason: &'static str,
}
/// Every measured tolerance but the stiff matrix's.
pub fn measured() -> Result<Vec<Measured>, RunError> {
    let [identity, rise, gap, reaction, complementarity] = scene_worst()?;
    let common = "tests/common (energy_and_contact, solvers, …)";
    let mut v = vec![
        Measured {
            name: "IDENTITY_TOL".into(),
            used_in: common,
            tolerance: IDENTITY_TOL,
            worst: identity,
            note: "round-off of sums of n terms; n up to 2561 nodes",
        },
        Measured {
            name: "ENERGY_RISE_TOL".into(),
            used_in: common,
            tolerance: ENERGY_RISE_TOL,
            worst: rise,
            note: "a rise is round-off only; most steps lose energy (negative worst: never rises)",
        },
        Measured {
            name: "GAP_TOL".into(),
            used_in: common,
            tolerance: GAP_TOL,
            worst: gap,
            note: "round-off of `u + z` at an active node (distributed obstacle: many nodes)",
        },
        Measured {
            name: "REACTION_TOL".into(),
            used_in: common,
            tolerance: REACTION_TOL,
            worst: reaction,
            note: "0 by construction: a round-off negative reaction is clamped to 0",
        },
        Measured {
            name: "COMPLEMENTARITY_TOL".into(),
            used_in: common,
            tolerance: COMPLEMENTARITY_TOL,
            worst: complementarity,
            note: "0 by construction: active gaps are exactly 0, inactive reactions exactly 0",
        },
    ];
    for (name, bound, scene_name) in [
        ("IMPACT_L2_BOUND", IMPACT_L2_BOUND, "impact"),
        (
            "CLAMPED_IMPACT_L2_BOUND",
            CLAMPED_IMPACT_L2_BOUND,
            "clamped-impact",
        ),
        ("FALLING_BAR_L2_BOUND", FALLING_BAR_L2_BOUND, "falling-bar"),
    ] {
        v.push(Measured {
            name: name.into(),
            used_in: "tests/closed_forms.rs",
            tolerance: bound,
            worst: l2_at_scene_mesh(scene_name)?,
            note: "1.25x the measured error (a regression bound)",
        });
    }
    let (_, base) = scene::load(viscous_contact::SCENE, &[])?;
    let row = viscous_contact::row(&base, 0)?;
    v.push(Measured {
        name: "viscous_contact::L2_BOUND".into(),
        used_in: "tests/viscous_contact.rs",
        tolerance: viscous_contact::L2_BOUND,
        worst: row.l2,
        note: "1.25x the measured error (a regression bound)",
    });
    v.push(Measured {
        name: "viscous_contact::REACTION_INTERIOR_BOUND".into(),
        used_in: "tests/viscous_contact.rs",
        tolerance: viscous_contact::REACTION_INTERIOR_BOUND,
        worst: row.reaction_interior,
        note: "1.25x the measured error (a regression bound)",
    });
    let vc = viscous_contact::closed_form(&base);
    for (name, tolerance, worst, note) in [
        (
            "viscous_contact::PDE_FD_TOL",
            viscous_contact::PDE_FD_TOL,
            viscous_contact::pde_residual_worst(&vc),
            "the stencils' truncation bound",
        ),
        (
            "viscous_contact::JOIN_SLOPE_BOUND",
            viscous_contact::JOIN_SLOPE_BOUND,
            viscous_contact::join_slope_worst(&vc),
            "a bound on the next derivative",
        ),
        (
            "viscous_contact::ENERGY_QUAD_TOL",
            viscous_contact::ENERGY_QUAD_TOL,
            viscous_contact::energy_quadrature_worst(&vc),
            "midpoint rule and differences",
        ),
    ] {
        v.push(Measured {
            name: name.into(),
            used_in: "tests/viscous_contact.rs",
            tolerance,
            worst,
            note,
        });
    }
    let fb = builtin_falling_bar()?;
    let q = falling_bar_quadrature(&fb);
    v.push(Measured {
        name: "falling bar energy: g·dx²".into(),
        used_in: "tests/closed_forms.rs",
        tolerance: q.energy_tol,
        worst: q.energy_worst,
        note: "midpoint rule on quadratic pieces plus the differences' round-off",
    });
    v.push(Measured {
        name: "falling bar ∫u: dx² g L/12 + round-off".into(),
        used_in: "tests/closed_forms.rs",
        tolerance: q.mass_tol,
        worst: q.mass_worst,
        note: "the midpoint error is reached in flight",
    });
    v.push(Measured {
        name: "FALLING_BAR_ROUNDOFF".into(),
        used_in: "tests/closed_forms.rs",
        tolerance: FALLING_BAR_ROUNDOFF,
        // A failed phase check (an error) shows as an infinite worst value.
        worst: falling_bar_identities_worst(&fb).unwrap_or(f64::INFINITY),
        note: "diamond identities of polynomials of size ≤ 1 (4000 points, two periods)",
    });
    v.push(Measured {
        name: "falling bar reaction −u_x(0): g·FD_STEP + FD_ROUNDOFF".into(),
        used_in: "tests/closed_forms.rs",
        tolerance: 1.0,
        worst: falling_bar_reaction_fd_ratio(&fb),
        note: "ratio to the bound: one-sided difference of a quadratic, plus its round-off",
    });
    let (_, time_error, mean_error) = impact_contact_errors()?;
    v.push(Measured {
        name: "CONTACT_TIME_TOL".into(),
        used_in: "tests/closed_forms.rs",
        tolerance: CONTACT_TIME_TOL,
        worst: time_error,
        note: "impact at 400 elements: the kink smeared over a few cells",
    });
    v.push(Measured {
        name: "MEAN_REACTION_TOL".into(),
        used_in: "tests/closed_forms.rs",
        tolerance: MEAN_REACTION_TOL,
        worst: mean_error,
        note: "impact at 400 elements: mean reaction against v0",
    });
    let (small, _) = osqp_small_problems()?;
    v.push(Measured {
        name: "SMALL_TOL".into(),
        used_in: "tests/solvers.rs",
        tolerance: SMALL_TOL,
        worst: small,
        note: "OSQP, polished, on two hand-made problems with closed-form answers",
    });
    let osqp = solver_worst_all("osqp")?;
    let penalty = solver_worst_all("penalty")?;
    let polished = "polished OSQP returns the active set's exact solve (round-off only); the \
                    bound is what the audit accepts from an unpolished answer, which a run may \
                    return (polishing can fail), so no tighter constant is safe";
    for (name, tolerance, worst, note) in [
        (
            "OSQP identity / (IDENTITY_TOL + stationarity ratio · OSQP_IDENTITY_TOL)",
            1.0,
            osqp.identity_ratio,
            "a posteriori: the run's own audited stationarity scales the a-priori bound",
        ),
        ("OSQP_GAP_TOL", OSQP_GAP_TOL, osqp.negative_gap, polished),
        (
            "OSQP_REACTION_TOL",
            OSQP_REACTION_TOL,
            osqp.negative_reaction,
            polished,
        ),
        (
            "OSQP |gap·r| / (OSQP_GAP_TOL |r| + OSQP_REACTION_TOL |gap|)",
            1.0,
            osqp.complementarity_ratio,
            polished,
        ),
        (
            "OSQP_AGREEMENT_TOL",
            OSQP_AGREEMENT_TOL,
            osqp.agreement,
            "the issue's stated requirement (1e-7), kept as the outer contract; the check that \
             can fail is the per-run bound of the next row",
        ),
        (
            "OSQP |u − u_exact| / (steps · (AGREEMENT_ULPS_PER_STEP ε max|u| + audited ‖C⁻¹ρ‖∞))",
            1.0,
            osqp.agreement_ratio,
            "a posteriori: two backward-stable solves per step, plus OSQP's own residual, \
             accumulated linearly",
        ),
        (
            "PENALTY_LAW_TOL",
            PENALTY_LAW_TOL,
            penalty.law,
            "rounding of u + z + a in the recorded gap",
        ),
    ] {
        v.push(Measured {
            name: name.into(),
            used_in: "tests/solvers.rs (every built-in scene, mass variants)",
            tolerance,
            worst,
            note,
        });
    }
    let (mass_sum, _) = mass_sum_worst();
    let (solve, _) = ldlt_family_worst();
    let too_few = |e: viscobar::bar::matrices::TooFewElements| {
        invalid(
            "mesh.elements",
            e.to_string(),
            "enough for the mass variant",
        )
    };
    let variants = mass_variant_worst().map_err(too_few)?;
    let (entries, _) = documented_entries_worst().map_err(too_few)?;
    let (resting, _) = resting_bar_worst()?;
    let start = start_energy_errors()?
        .iter()
        .map(|&(e, dx, _)| e.abs() / dx)
        .fold(0.0, f64::max);
    for (name, used_in, tolerance, worst, note) in [
        (
            "MASS_SUM_TOL",
            "tests/matrices.rs",
            MASS_SUM_TOL,
            mass_sum,
            "sums of J + 2 rounded entries, J up to 1000",
        ),
        (
            "SOLVE_ULPS: |x̂ − x|∞ / (SOLVE_ULPS ε ‖A‖∞ ‖x‖₂ / λ_min)",
            "tests/matrices.rs",
            1.0,
            solve,
            "LDLᵀ on 78 SPD tridiagonal systems: Higham's backward error 4u|A| plus forming \
             b = Ax, times each system's own ‖A⁻¹‖₂",
        ),
        (
            "VARIANT_SUM_TOL",
            "tests/matrices.rs",
            VARIANT_SUM_TOL,
            variants.sum,
            "1ᵀM1 and xᵀM1 of every mass variant, J + 2 rounded entries, J up to 1000",
        ),
        (
            "EIGEN_TOL_ULPS (units of ε‖M‖∞)",
            "tests/matrices.rs",
            EIGEN_TOL_ULPS,
            variants.kernel_ulps,
            "exactly 0: the massless nodes' rows and columns are exactly 0 (asserted \
             bitwise), which the dense QR keeps apart; the bound is its backward error had they \
             not been (n ≤ 65)",
        ),
        (
            "ENTRY_TOL",
            "tests/matrices.rs",
            ENTRY_TOL,
            entries,
            "lumped and redistributed entries at Δx = 0.1 against the documented ones",
        ),
        (
            "RESTING_TOL",
            "tests/energy_and_contact.rs",
            RESTING_TOL,
            resting,
            "measured exactly 0: every node active puts u on the obstacle exactly, and the \
             reactions come out with the bits of M·1; the bound keeps round-off's room",
        ),
        (
            "START_ENERGY_ERROR_PER_DX",
            "tests/energy_and_contact.rs",
            START_ENERGY_ERROR_PER_DX,
            start,
            "first order in dx (the kink of u0): a regression bound",
        ),
    ] {
        v.push(Measured {
            name: name.into(),
            used_in,
            tolerance,
            worst,
            note,
        });
    }
    let start_worst = start_up_motion()?
        .iter()
        .filter(|(mass, _, _)| *mass == MassVariant::Redistributed)
        .map(|&(_, moved, scale)| moved / scale)
        .fold(0.0, f64::max);
    for (name, used_in, tolerance, worst, note) in [
        (
            "DROP_TOL",
            "tests/mass.rs",
            DROP_TOL,
            mass_study_drop_worst()?,
            "impact at α = 0, every mass variant and level: sums over a few hundred steps",
        ),
        (
            "START_TOL",
            "tests/mass.rs",
            START_TOL,
            start_worst,
            "measured exactly 0: the massless end's projected first step comes out with the \
             bits of w = 0 (not shown to be 0 by construction; the bound keeps the solve's \
             round-off room)",
        ),
        (
            "RELEASE_TOL",
            "tests/episodes.rs",
            RELEASE_TOL,
            release_errors()?.into_iter().fold(0.0, f64::max),
            "impact's release time at 100, 200, 400 elements; 0.02 at the coarsest",
        ),
        (
            "SEPARATION_TOL",
            "tests/loads.rs",
            SEPARATION_TOL,
            separation_worst()?,
            "six fixed separable loads at three steps (the test draws more at random): the \
             regrouped sum's roundings",
        ),
        (
            "ENERGY_ROUNDOFF_TOL",
            "tests/diagnostics.rs",
            ENERGY_ROUNDOFF_TOL,
            thinned_energy_worst()?,
            "every built-in scene, energies recomputed after thinned steps: round-off of E",
        ),
    ] {
        v.push(Measured {
            name: name.into(),
            used_in,
            tolerance,
            worst,
            note,
        });
    }
    let (tie, _, _) = exact_tie()?;
    v.push(Measured {
        name: "TIE_TOL".into(),
        used_in: "tests/exact_solver.rs",
        tolerance: TIE_TOL,
        worst: tie,
        note: "measured exactly 0 on this tie (not shown to be 0 by construction: other \
               candidates differ by round-off, which the bound allows)",
    });
    v.push(Measured {
        name: "EQUAL_ERROR_RTOL".into(),
        used_in: "tests/converge.rs",
        tolerance: EQUAL_ERROR_RTOL,
        worst: equal_error_excess(&equal_error_study()?),
        note: "one-end, 100 and 200 elements: l2_exact / l2_osqp − 1 (OSQP at eps 1e-10); the \
               two answers differ by OSQP's residual, so the errors by about 1e-9 relative",
    });
    v.push(Measured {
        name: "exact solver: max(kkt_ratio, distance to the dense oracle / a-posteriori bound)"
            .into(),
        used_in: "tests/exact_solver.rs (proptest; seeded sample), active_set.rs",
        tolerance: 1.0,
        worst: oracle_agreement_worst()?,
        note: "KKT residuals against their per-case round-off bound, and each answer's distance \
               to the minimiser bounded from its own residuals (oracle_distance_bound: \
               λ_min(C), feasibility and complementarity), which checks the oracle and the bound \
               rather than the solver",
    });
    let (kkt_worst_ratio, _) = random_kkt_worst()?;
    v.push(Measured {
        name: "exact many-bound solver: kkt / (KKT_ULPS ε (‖C‖∞‖z‖∞ + ‖b‖∞ + ‖r‖∞) / scale)".into(),
        used_in: "tests/active_set.rs, osqp_many_bounds.rs (proptests; seeded sample)",
        tolerance: 1.0,
        worst: kkt_worst_ratio,
        note: "per case: the solver's accepted tie slack plus a backward-stable LDLᵀ solve and \
               the residual's roundings",
    });
    let (eig, kappa) = kappa_reference_worst();
    v.push(Measured {
        name: "spectrum::reference::STURM_ERROR_ULPS (eigenvalues, units of ε‖C‖∞)".into(),
        used_in: "src/linalg/spectrum.rs (tests)",
        tolerance: STURM_ERROR_ULPS,
        worst: eig,
        note: "Kahan's backward error of the Sturm count plus Weyl; double-double reference",
    });
    v.push(Measured {
        name: "κ(C): relative error / STURM_ERROR_ULPS ε‖C‖ (1/λ_min + 1/λ_max)".into(),
        used_in: "src/linalg/spectrum.rs (tests)",
        tolerance: 1.0,
        worst: kappa,
        note: "κ up to 4e11; the eigenvalues' bound (Weyl) at both ends of the spectrum",
    });
    Ok(v)
}

/// The stiff matrix's checks, per check and solver class, over the completed runs.
pub fn stiff_checks(results: &[CaseResult]) -> Vec<StiffCheck> {
    let mut out: Vec<StiffCheck> = Vec::new();
    for r in results {
        for run in r.runs.iter().filter(|run| run.error.is_none()) {
            let solver = match run.solver {
                "exact" => "exact",
                "osqp" => "osqp",
                _ => "penalty",
            };
            for (check, value, tol) in checks(r, run) {
                if !tol.is_finite() {
                    continue; // reported, not checked (pre-asymptotic penalty distances)
                }
                // A zero value is a zero ratio, whatever its tolerance (0/0 included), as in
                // `stiff::Worst::ratio`.
                let ratio = if value == 0.0 { 0.0 } else { value / tol };
                let i = match out
                    .iter()
                    .position(|c| c.check == check && c.solver == solver)
                {
                    Some(i) => i,
                    None => {
                        out.push(StiffCheck {
                            check,
                            solver,
                            runs: 0,
                            max_ratio: 0.0,
                            min_ratio: f64::INFINITY,
                            below_floor: 0,
                            zero: 0,
                        });
                        out.len() - 1
                    }
                };
                let c = &mut out[i];
                c.runs += 1;
                c.max_ratio = c.max_ratio.max(ratio);
                if ratio == 0.0 {
                    c.zero += 1;
                } else {
                    c.min_ratio = c.min_ratio.min(ratio);
                    if ratio < RATIO_FLOOR {
                        c.below_floor += 1;
                    }
                }
            }
        }
    }
    out
}

fn sci(v: f64) -> String {
    format!("{v:.1e}")
}

/// The generated table of VERIFICATION.md (and the output of `verify --tolerances`).
pub fn markdown(measured: &[Measured], stiff: &[StiffCheck], uncovered: &[Uncovered]) -> String {
    let mut md = String::from(
        "| tolerance | used in | tolerance | measured worst | ratio | note |\n|---|---|---|---|---|---|\n",
    );
    for m in measured {
        let flag = if m.ratio() < RATIO_FLOOR {
            " (below 1e-3)"
        } else {
            ""
        };
        let _ = writeln!(
            md,
            "| `{}` | {} | {} | {} | {}{flag} | {} |",
            m.name.replace('|', "\\|"),
            m.used_in,
            sci(m.tolerance),
            sci(m.worst),
            sci(m.ratio()),
            m.note.replace('|', "\\|")
        );
    }
    md.push_str(
        "\nStiff case matrix (`certificate/src/bar/stiff.rs`, tolerances per case; ratio value / tolerance over the completed runs):\n\n\
         | check | solver | runs | max ratio | min nonzero ratio | runs below 1e-3 | runs at exactly 0 |\n|---|---|---|---|---|---|---|\n",
    );
    for c in stiff {
        let _ = writeln!(
            md,
            "| {} | {} | {} | {} | {} | {} | {} |",
            c.check.replace('|', "\\|"),
            c.solver,
            c.runs,
            sci(c.max_ratio),
            if c.min_ratio.is_finite() {
                sci(c.min_ratio)
            } else {
                "–".into()
            },
            c.below_floor,
            c.zero
        );
    }
    md.push_str("\nNot measured here (constants of type `f64` in the scanned files):\n\n| constant | file | reason |\n|---|---|---|\n");
    for u in uncovered {
        let _ = writeln!(md, "| `{}` | {} | {} |", u.name, u.file, u.reason);
    }
    md
}

/// The whole registry as Markdown: measured tolerances, the stiff matrix's checks from
/// `results`, and the rest (the generated block `tolerances` of VERIFICATION.md).
/// `increment_drift` and `backward_ulps` are measured by [`crate::verify`] (the rigid-mode run
/// of its round-off table; its solve study on `tests/matrices.rs`'s node counts).
pub fn registry_markdown(
    results: &[CaseResult],
    increment_drift: f64,
    backward_ulps: f64,
) -> Result<String, RunError> {
    let mut measured = measured()?;
    measured.extend(plane_measured()?);
    measured.extend(friction_measured()?);
    measured.extend(thermal_measured()?);
    measured.extend(plane_heat_measured()?);
    Ok(registry_markdown_of(
        measured,
        results,
        increment_drift,
        backward_ulps,
    ))
}

/// [`registry_markdown`] from the measurements `measured` (those of [`measured`],
/// [`plane_measured`], [`friction_measured`], [`thermal_measured`] and
/// [`plane_heat_measured`], in that order) taken apart.
pub fn registry_markdown_of(
    mut measured: Vec<Measured>,
    results: &[CaseResult],
    increment_drift: f64,
    backward_ulps: f64,
) -> String {
    measured.push(Measured {
        name: "BACKWARD_ULPS (units of ε)".into(),
        used_in: "tests/matrices.rs",
        tolerance: BACKWARD_ULPS,
        worst: backward_ulps,
        note: "Higham's γ₃ plus the residual's roundings, step matrices to 1e5 nodes",
    });
    measured.push(Measured {
        name: "INCREMENT_DRIFT_TOL".into(),
        used_in: "tests/roundoff.rs",
        tolerance: INCREMENT_DRIFT_TOL,
        worst: increment_drift,
        note: "rigid mode, 26 000 steps at J = 8192 (the run of the round-off table)",
    });
    // The stiff matrix's constants enter its per-case tolerances, measured by the checks above.
    let covered = [
        ("OSQP_AGREEMENT_REL", "certificate/src/bar/stiff.rs"),
        ("OSQP_STEP_ABS", "certificate/src/bar/stiff.rs"),
    ];
    markdown(
        &measured,
        &stiff_checks(results),
        &scanner::uncovered(&covered),
    )
}

/// The error of a built-in scene whose data the registry cannot use (not a panic).
fn invalid(field: &str, value: String, allowed: &str) -> RunError {
    RunError::Scene(viscobar::scene::SceneError::Invalid {
        field: field.into(),
        value,
        allowed: allowed.into(),
    })
}

/// The error of the exact solver failing on case (or call) `case` of a registry sample.
fn exact_sample_error(case: usize) -> impl FnOnce(viscobar::step::StepFailure) -> RunError {
    move |failure| RunError::Step {
        step: case,
        time: 0.0,
        solver: "exact".into(),
        failure,
    }
}
