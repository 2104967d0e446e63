//! The registry's source scanner: the `f64` constants of the workspace's `tests/` and of the
//! stiff matrix (`certificate/src/bar/stiff.rs`) that the registry does not measure, each with the
//! reason it is not measured.

use super::Uncovered;
use crate::workspace_root;

/// Files scanned for tolerance constants: every test file (in `tests/` and its folders: a test
/// split into modules, the shared helpers of `tests/common`) and the stiff matrix.
fn scanned_files() -> Vec<std::path::PathBuf> {
    let root = workspace_root();
    let mut files = Vec::new();
    let mut folders = vec![root.join("tests")];
    while let Some(folder) = folders.pop() {
        for entry in std::fs::read_dir(&folder).into_iter().flatten().flatten() {
            let path = entry.path();
            if path.is_dir() {
                folders.push(path);
            } else if path.extension().is_some_and(|x| x == "rs") {
                files.push(path);
            }
        }
    }
    files.push(root.join("certificate/src/bar/stiff.rs"));
    files.sort();
    files
}

/// Why a constant found in the sources is not measured here, from its name and file.
fn reason(name: &str, file: &str) -> &'static str {
    match (name, file) {
        ("LENGTH", _) => "a bar length (test data), not a tolerance",
        ("MODAL_ORDER", _) => "the order a band is centred on, not a tolerance",
        ("EXACT", _) => {
            "a zero tolerance: exact equality is asserted, so no ratio (every value exact, \
             `tests/expressions.rs`)"
        }
        ("BAR_CASE_MIN_MOTION", _) => {
            "a lower bound on the motion compared (the check must compare motion, not rest)"
        }
        ("NOTE_RATIO_FLOOR", _) => {
            "a reporting threshold (which ratios of the stiff matrix get a generated reason), \
             not a tolerance"
        }
        ("PHASE_SUM_TOL", _) => {
            "the rounding of three quotients of one total and of their sum (timing shares in \
             summary.json), not a tolerance of the numerics"
        }
        ("TWIN_TOL" | "FRICTIONLESS_TOL" | "CLOSED_BODY_HEAT_TOL" | "PLANE_GALILEAN_TOL", _) => {
            "a metamorphic relation over random draws (`tests/scene_property.rs`): the worst is \
             that of the seed's draws, printed by the soak, not of a fixed scene set"
        }
        ("PLANE_ACTIVE_GAP_TOL", _) => {
            "the plane's condensed exact solver leaves an active node at its second solve's \
             forward error from its bound (measured up to 3e-12 over the soak's draws); a \
             consistency check of the contact fields, not a round-off bound of the numerics"
        }
        ("CONE_ROUNDING" | "COULOMB_ROUNDING", _) => {
            "a rounding allowance on Coulomb's law node by node on the exact frictional step, \
             which sets a slipping node's r_T to ±μ r_N exactly and audits the sticking ones: \
             measured 0 on the runs checked (the tests print it)"
        }
        ("UNIT_ROUNDOFF", _) => "the unit round-off ε/2, a constant of the a-posteriori bounds",
        (
            "RESIDUAL_ROUNDINGS" | "SUM_TERM_ROUNDINGS" | "COMBINATION_ROUNDINGS" | "GAP_ROUNDINGS",
            _,
        ) => {
            "a count of roundings in the stiff matrix's a-posteriori bounds, not a tolerance \
             compared with a measured value (the bounds it enters are measured by the checks above)"
        }
        ("X_ROUNDING_TOL", _) => {
            "exactly 0 by construction where it is checked: the written x is rounded to 12 \
             significant digits and the bar's length L = 1 has fewer, so the last node's J·Δx \
             (within an ulp of 1) is written as 1 exactly (measured 0)"
        }
        ("DENSE_INVERSE_TOL", _) => {
            "no ratio: it is the slack of a proven inequality, ‖(I − D + DC)⁻¹‖∞ ≤ κ_H (Chen–Xiang), \
             checked densely; what it guards, the computed ‖(I − D + DC)⁻¹‖∞ / κ_H − 1, measured \
             at most −0.09 over the proptest's 200 cases (κ∞ ≤ 15): the inequality is never \
             within its slack of tight, so the slack (over the dense LU's n ε κ∞ ≤ 1e-13) is \
             never used; a wrong κ_H that undercuts the norm by more than round-off fails"
        }
        ("MARGIN" | "TRIDIAG_ULPS" | "SPARSE_ULPS" | "INACCURATE", f)
            if f.contains("audit_bounds") =>
        {
            "the audit's documented constant restated independently: the test's answers sit at \
             the bound it implies, so a change in the audit's fails the test"
        }
        (
            "EPS_ABS" | "EPS_REL" | "BAR_MASS" | "BAR_STIFFNESS" | "SOFT_SPRINGS" | "STIFF_SPRINGS"
            | "OSQP_EPS" | "DT" | "VISCOSITY" | "PRESSED",
            f,
        ) if f.contains("audit_bounds") => "test data (a matrix or a setting), not a tolerance",
        ("PLACEMENT" | "AGREEMENT" | "FAR_INSIDE", f) if f.contains("audit_bounds") => {
            "a requirement on the test's own construction (how close an answer sits to its \
             target bound, how far the other checks stay inside theirs), asserted before the \
             audit runs; not a tolerance of the numerics"
        }
        _ if name.contains("BAND") || name.contains("ORDER") => {
            "a two-sided band around a measured order (VERIFICATION.md gives the measured order)"
        }
        _ if name.contains("FD_STEP")
            || name.contains("DELTA")
            || name == "PENALTY_SMALL_EPSILON" =>
        {
            "a step or a parameter, not a tolerance"
        }
        _ if name.contains("FACTOR")
            || name.contains("GAIN")
            || name.contains("SLOWDOWN")
            || name.contains("SHARE")
            || name.ends_with("_MIN")
            || name.contains("MIN_RATIO")
            || name == "PENALTY_ASYMPTOTIC" =>
        {
            "a required factor or share (a lower bound on a measured ratio), not an upper tolerance"
        }
        _ => "not measured by the registry yet",
    }
}

/// The `f64` constants of the scanned files but those in `covered` (name, file): a constant
/// measured here is defined here and imported by the tests, so any definition left in a
/// scanned file is not measured, even if it shares a measured constant's name.
pub fn uncovered(covered: &[(&str, &str)]) -> Vec<Uncovered> {
    let mut out = Vec::new();
    for path in scanned_files() {
        let Ok(text) = std::fs::read_to_string(&path) else {
            continue;
        };
        let file = path
            .strip_prefix(workspace_root())
            .map_or(path.display().to_string(), |p| {
                p.display().to_string().trim_start_matches('/').to_string()
            });
        for line in text.lines() {
            // A constant at any visibility (`pub(super)` in a test split into modules).
            let l = line.trim_start();
            let l = ["pub(super) ", "pub(crate) ", "pub "]
                .iter()
                .find_map(|v| l.strip_prefix(v))
                .unwrap_or(l);
            let Some(rest) = l.strip_prefix("const ") else {
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
            if covered.iter().any(|&(c, f)| c == short && f == file) {
                continue;
            }
            out.push(Uncovered {
                name: short.to_string(),
                file: file.clone(),
                reason: reason(short, &file),
            });
        }
    }
    out
}
