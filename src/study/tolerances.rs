//! The tolerance registry (`viscobar verify --tolerances`, issue #22): for the tolerances of
//! `tests/` and `src/study/stiff.rs`, the measured worst value of what each guards and the
//! ratio worst / tolerance, so that a check that cannot fail shows (target: no ratio below
//! [`RATIO_FLOOR`] without a reason). The tolerances measured here live here (or in the study
//! that measures them) and the tests import them, so test and table share one constant and one
//! measurement. The others are found by scanning the sources and listed with the reason they
//! are not measured.

use crate::bar::closed_form::{ClosedForm, FallingBar};
use crate::linalg::spectrum::reference::STURM_ERROR_ULPS;
use crate::linalg::tridiag::SymTridiag;
use crate::scene::{self, builtin_names};
use crate::study::accuracy::error_against;
use crate::study::stiff::{CaseResult, checks};
use crate::study::viscous_contact;
use crate::time::RunError;
use crate::time::run::run_in_memory;
use std::fmt::Write;

/// A tolerance more than this many times looser than its measured worst value needs a reason.
pub const RATIO_FLOOR: f64 = 1e-3;

/// Relative residual of the energy identity for a solver exact to round-off (exact, penalty):
/// the identity is exact algebra given `C z = b + r`, so only round-off remains (measured below
/// 1e-14 on every built-in scene, VERIFICATION.md, sections "Scenes" and "Step solvers").
pub const IDENTITY_TOL: f64 = 1e-12;
/// An energy increase of an unforced run, relative to `E^{1/2}`, that round-off can make.
pub const ENERGY_RISE_TOL: f64 = 1e-13;
/// Gap negative by round-off only: the exact solver puts an active node on the obstacle up to
/// the rounding of `u^n + z` with |u| <= 1.
pub const GAP_TOL: f64 = 1e-14;
/// Reaction negative by round-off only (reactions of order 10).
pub const REACTION_TOL: f64 = 1e-12;
/// `|gap · reaction|`: round-off in the gap times a reaction of order 10.
pub const COMPLEMENTARITY_TOL: f64 = 1e-12;

/// L2 error bounds at the kinked scenes' own meshes (`tests/closed_forms.rs`): 1.25x the
/// measured L2 error (VERIFICATION.md's convergence table, first row of each scene), so that
/// round-off changes pass and a regression of the contact step (wrong reaction, wrong
/// start-up) fails.
pub const IMPACT_L2_BOUND: f64 = 1.25 * 2.10e-2;
pub const CLAMPED_IMPACT_L2_BOUND: f64 = 1.25 * 1.09e-2;
pub const FALLING_BAR_L2_BOUND: f64 = 1.25 * 2.987e-2;

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

/// Worst values over every built-in scene (its own solver) of what the scene-wide tolerances
/// of `tests/energy_and_contact.rs` guard: identity residual, energy rise (unforced scenes,
/// relative to `E^{1/2}`), negative gap, negative reaction, `|gap · reaction|`.
pub fn scene_worst() -> Result<[f64; 5], RunError> {
    let mut w = [0.0f64; 5];
    for name in builtin_names() {
        let (_, scene) = scene::load(name, &[])?;
        let (records, _, sim) = run_in_memory(name, &scene)?;
        let constrained = !sim.discretisation().constraints.is_empty();
        let e0 = records[0].energy;
        for (i, r) in records.iter().enumerate() {
            w[0] = w[0].max(r.identity_residual);
            if scene.load.density.is_none() && i > 0 {
                w[1] = w[1].max((r.energy - records[i - 1].energy) / e0);
            }
            if constrained {
                w[2] = w[2].max(-r.min_gap);
                w[3] = w[3].max(-r.min_reaction);
                w[4] = w[4].max(r.max_complementarity);
            }
        }
    }
    Ok(w)
}

/// The L2 error of a built-in scene at its own mesh against its closed form.
pub fn l2_at_scene_mesh(name: &str) -> Result<f64, RunError> {
    let (_, base) = scene::load(name, &[])?;
    let exact = crate::bar::closed_form::for_scene(name, &base).expect("built-in closed form");
    Ok(error_against(&base, exact.as_ref())?.l2)
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
    let (_, fb_scene) = scene::load("falling-bar", &[])?;
    let gravity = fb_scene
        .load
        .density
        .as_ref()
        .and_then(|d| d.trim().parse::<f64>().ok())
        .map(|l| -l)
        .expect("uniform gravity");
    let fb = FallingBar::new(
        fb_scene.bar.length,
        gravity,
        fb_scene.left.gap.expect("Signorini left end"),
    )
    .expect("the built-in falling bar");
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
        note: "κ up to 4e11; the former bound 64 ε κ was about 600 %",
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
                let ratio = value / tol;
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

/// Midpoints of the falling bar's energy quadrature ([`falling_bar_quadrature`]).
pub const FALLING_BAR_QUAD_POINTS: usize = 20_000;
/// Step of that quadrature's differences, capped at a quarter of the piece: the closed form is
/// quadratic on each piece, so any step is exact up to round-off `ε|u|/step`.
pub const QUAD_FD_STEP: f64 = 1e-3;

/// Where the falling bar's kink (the front of the impact's wave, speed 1) is at `t`, if on the
/// open bar: with the time folded into the first half period, at `x = τ` or `2L − τ` in
/// contact (`τ` since the impact), at the distance of `s` (since the release) to the nearest
/// multiple of `2L` in flight; none in the free fall.
pub fn falling_bar_kink(fb: &FallingBar, t: f64) -> Option<f64> {
    let (l, p) = (fb.length, fb.period());
    let r = t.rem_euclid(p);
    let tau = (if r > 0.5 * p { p - r } else { r }) - fb.fall_time();
    let x = if tau <= 0.0 {
        return None;
    } else if tau <= 2.0 * l {
        tau.min(2.0 * l - tau)
    } else {
        let s = tau - 2.0 * l;
        (s - 2.0 * l * (s / (2.0 * l)).round()).abs()
    };
    (x > 0.0 && x < l).then_some(x)
}

/// The falling bar's total energy `½∫u_t² + ½∫u_x² + g∫u` (zero) and `∫u` (against
/// [`FallingBar::integral`]) by a midpoint quadrature of differences of the displacement, each
/// cell cut at the kink, at 321 times over two periods: worst errors and their bounds.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct FallingBarQuadrature {
    pub energy_worst: f64,
    /// `g·dx²`: on each piece the integrand `f` is quadratic in `x` with
    /// `|f''| = |u_xt² + u_xx² + g u_xx| ≤ 10g²` (`|u_xx|, |u_xt| ≤ 2g`: two waves of curvature
    /// `g`), so the midpoint rule errs by at most `L dx²/24 · 10g² ≈ 0.4 g² dx² L`; differences
    /// of step `≥ dx/4` (exact on quadratics) add round-off `≈ 4 ε |u| / d · slope · L ≈ 9e-11`.
    /// (The former bound, a kink spoiling a midpoint, `2 slope² dx ≈ 1.6e-4`, was 1e5 times the
    /// measured error.)
    pub energy_tol: f64,
    pub mass_worst: f64,
    /// `dx² g L/12` (midpoint error with `u_xx = 2g`, reached in flight) plus the sum's
    /// round-off, `QUAD_POINTS · ε · L max|u|`, `max|u| ≤ 2a0 + gL²`.
    pub mass_tol: f64,
}

pub fn falling_bar_quadrature(fb: &FallingBar) -> FallingBarQuadrature {
    let (l, g) = (fb.length, fb.gravity);
    let u = |x: f64, t: f64| fb.displacement(x, t);
    let n = FALLING_BAR_QUAD_POINTS;
    let dx = l / n as f64;
    let mut out = FallingBarQuadrature {
        energy_worst: 0.0,
        energy_tol: g * dx * dx,
        mass_worst: 0.0,
        mass_tol: dx * dx * g * l / 12.0 + n as f64 * f64::EPSILON * l * (2.0 * fb.gap + g * l * l),
    };
    for i in 0..=320 {
        let t = 0.05 * i as f64 + 0.0123; // off the phase boundaries, two periods
        // Each cell is cut at the kink (at most one crosses the bar at a time, speed 1), so
        // that u is one quadratic in (x, t) on each piece and on every stencil; the stencils
        // stay inside their piece in x, and in t (the kink moves by the step).
        let kink = falling_bar_kink(fb, t);
        let (mut kinetic, mut elastic, mut mass) = (0.0, 0.0, 0.0);
        for j in 0..n {
            let (a, b) = (j as f64 * dx, (j + 1) as f64 * dx);
            let cuts = match kink {
                Some(k) if a < k && k < b => [[a, k], [k, b]],
                _ => [[a, b], [b, b]],
            };
            for [p, q] in cuts {
                let w = q - p;
                if w <= 0.0 {
                    continue;
                }
                let (x, d) = (0.5 * (p + q), (0.25 * w).min(QUAD_FD_STEP));
                let ut = (u(x, t + d) - u(x, t - d)) / (2.0 * d);
                let ux = (u(x + d, t) - u(x - d, t)) / (2.0 * d);
                kinetic += 0.5 * ut * ut * w;
                elastic += 0.5 * ux * ux * w;
                mass += u(x, t) * w;
            }
        }
        let total = kinetic + elastic + g * mass;
        out.energy_worst = out.energy_worst.max(total.abs());
        out.mass_worst = out.mass_worst.max((mass - fb.integral(t)).abs());
    }
    out
}

/// The step matrices of `linalg::spectrum`'s κ test, `(α, Δt/Δx)` on 21 nodes, κ from 4 to
/// 4e11.
pub const KAPPA_CASES: [(f64, f64); 4] = [(0.0, 1e-3), (0.0, 1.0), (1e3, 100.0), (1e6, 1e4)];

/// Against the double-double reference on [`KAPPA_CASES`]: the worst eigenvalue error of the
/// f64 bisection in units of `ε‖C‖∞`, and the worst κ error relative to its bound
/// `STURM_ERROR_ULPS ε ‖C‖∞ (1/λ_min + 1/λ_max)`.
pub fn kappa_reference_worst() -> (f64, f64) {
    use crate::bar::matrices::{MatrixVariant, mass, stiffness};
    use crate::linalg::spectrum::{
        condition_number, extreme_eigenvalues, reference::eigenvalue_dd, smallest_eigenvalue_spd,
    };
    let nodes = 21;
    let dx = 1.0 / 20.0;
    let m = mass(MatrixVariant::Consistent, nodes, dx);
    let r = stiffness(MatrixVariant::Consistent, nodes, dx);
    let (mut eig, mut kappa) = (0.0f64, 0.0f64);
    for (alpha, ratio) in KAPPA_CASES {
        let dt = ratio * dx;
        let c = SymTridiag::combine(1.0 / (dt * dt), &m, 0.5 + alpha / (2.0 * dt), &r);
        let (lo, hi) = (eigenvalue_dd(&c, 0), eigenvalue_dd(&c, nodes - 1));
        let unit = f64::EPSILON * c.inf_norm();
        let (l, h) = extreme_eigenvalues(&c);
        for (got, reference) in [(l, lo), (smallest_eigenvalue_spd(&c), lo), (h, hi)] {
            eig = eig.max((got - reference.hi).abs() / unit);
        }
        let kappa_ref = hi.over(lo).hi;
        let rtol = STURM_ERROR_ULPS * unit * (1.0 / lo.hi + 1.0 / hi.hi);
        let got = condition_number(&c).unwrap_or(f64::NAN);
        kappa = kappa.max((got - kappa_ref).abs() / (rtol * kappa_ref));
    }
    (eig, kappa)
}

/// Files scanned for tolerance constants: every test file and the stiff matrix.
fn scanned_files() -> Vec<std::path::PathBuf> {
    let root = std::path::Path::new(env!("CARGO_MANIFEST_DIR"));
    let mut files: Vec<_> = std::fs::read_dir(root.join("tests"))
        .into_iter()
        .flatten()
        .flatten()
        .map(|e| e.path())
        .filter(|p| p.extension().is_some_and(|x| x == "rs"))
        .collect();
    files.push(root.join("tests/common/mod.rs"));
    files.push(root.join("src/study/stiff.rs"));
    files.sort();
    files
}

/// Why a constant found in the sources is not measured here, from its name.
fn reason(name: &str) -> &'static str {
    if name.contains("BAND") || name.contains("ORDER") {
        "a two-sided band around a measured order (VERIFICATION.md gives the measured order)"
    } else if name.contains("FD_STEP") || name.contains("DELTA") || name == "PENALTY_SMALL_EPSILON"
    {
        "a step or a parameter, not a tolerance"
    } else if name.contains("FACTOR")
        || name.contains("GAIN")
        || name.contains("SLOWDOWN")
        || name.contains("SHARE")
        || name == "PENALTY_ASYMPTOTIC"
    {
        "a required factor or share (a lower bound on a measured ratio), not an upper tolerance"
    } else {
        "not measured by the registry yet"
    }
}

/// The `f64` constants of the scanned files whose names are not in `covered`.
pub fn uncovered(covered: &[String]) -> Vec<Uncovered> {
    let mut out = Vec::new();
    for path in scanned_files() {
        let Ok(text) = std::fs::read_to_string(&path) else {
            continue;
        };
        let file = path
            .strip_prefix(env!("CARGO_MANIFEST_DIR"))
            .map_or(path.display().to_string(), |p| {
                p.display().to_string().trim_start_matches('/').to_string()
            });
        for line in text.lines() {
            let l = line.trim_start();
            let Some(rest) = l.strip_prefix("pub const ").or(l.strip_prefix("const ")) else {
                continue;
            };
            let Some((name, ty)) = rest.split_once(':') else {
                continue;
            };
            let ty = ty.split('=').next().unwrap_or("").trim();
            if !matches!(ty, "f64" | "(f64, f64)") {
                continue;
            }
            let short = name.trim();
            if covered
                .iter()
                .any(|c| c == short || c.ends_with(&format!("::{short}")))
            {
                continue;
            }
            out.push(Uncovered {
                name: short.to_string(),
                file: file.clone(),
                reason: reason(short),
            });
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
            m.name,
            m.used_in,
            sci(m.tolerance),
            sci(m.worst),
            sci(m.ratio()),
            m.note
        );
    }
    md.push_str(
        "\nStiff case matrix (`src/study/stiff.rs`, tolerances per case; ratio value / tolerance over the completed runs):\n\n\
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
pub fn registry_markdown(results: &[CaseResult]) -> Result<String, RunError> {
    let measured = measured()?;
    let mut covered: Vec<String> = measured.iter().map(|m| m.name.clone()).collect();
    // The stiff matrix's constants enter its per-case tolerances, measured by the checks above.
    covered.extend(["OSQP_AGREEMENT_REL", "OSQP_STEP_ABS"].map(String::from));
    Ok(markdown(
        &measured,
        &stiff_checks(results),
        &uncovered(&covered),
    ))
}
