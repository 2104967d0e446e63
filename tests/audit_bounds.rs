//! The KKT audit's bounds, checked at their edges: for each check of each audited solver (OSQP
//! on the bar's tridiagonal `C` and on the plane body's sparse `C`; the bar's penalty solver),
//! an answer whose checked value is `(1 − DELTA)` times the check's tolerance is accepted and
//! one at `(1 + DELTA)` is refused by that check, so that a loosened or mis-scaled bound fails.
//!
//! Each expected tolerance is computed here from the formulas of `step::audit` (with
//! `AUDIT_MARGIN` and the systems' `roundoff_ulps` as documented) on independent dense copies of
//! `C` and `C⁻¹` (nalgebra), never read back from the audit. Stationarity holds by construction,
//! `b = C z − Σ r_k s_k e_{i_k}` (minus a chosen residual for its two checks), and every check
//! but the one under test stays far inside its bound; the bounds depend on the answer's norms,
//! so each answer is placed by a fixed-point iteration and its ratio re-measured before it is
//! audited. Constraints push in both directions, `s = +1` and `s = −1`.

mod common;

use common::{amax, inf_norm, ratio};
use nalgebra::{DMatrix, DVector};
use viscobar::internals::linalg::SymTridiag;
use viscobar::internals::linalg::sparse::Pattern;
use viscobar::internals::linalg::system::{SparseSystem, SpdSystem, TridiagSystem};
use viscobar::internals::plane::matrices::{Material, assemble};
use viscobar::internals::plane::mesh::Grid;
use viscobar::step::audit::{KktAudit, Law};
use viscobar::step::report::{AuditReport, StepFailure};
use viscobar::step::solver::Constraints;

/// Answers sit at `(1 ∓ DELTA)` times a tolerance: far beyond the round-off of evaluating the
/// formula twice (about 1e-12 relative), close enough that any mis-scaling of a bound by more
/// than 0.1 % turns one of the two verdicts.
const DELTA: f64 = 1e-3;
/// An answer is placed at its intended ratio to within a tenth of `DELTA` (the fixed point
/// converges; the dyadic penalty answers round their bound `lo` by about 2e-6 of their value).
const PLACEMENT: f64 = 1e-4;
/// Rounds of the placement's fixed-point iteration: a bound moves with the placed quantity by at
/// most `10·EPS_REL` = 1e-5 times it (through the norms), so each round divides the error by 1e5.
const PLACEMENT_ROUNDS: usize = 4;
/// The audit's own ratios (its report and its error) agree with the independent ones to a tenth
/// of `DELTA`: the same formula in f64 from the same data; the only other difference, Hager's
/// estimate of `‖C⁻¹‖∞` (a lower bound), is exact for the bar's M-matrix and weighs less than
/// `HAGER_SHARE` of the displacement tolerance in the plane's answers.
const AGREEMENT: f64 = 1e-4;
/// Bound on `‖C⁻¹‖∞ floor_f / tol_dz` in the Signorini answers (asserted), so that Hager's
/// estimate falling short of the true norm cannot move the displacement bound by `AGREEMENT`.
const HAGER_SHARE: f64 = 1e-5;
/// Every check but the one under test stays below half its tolerance: a verdict is that check's.
const FAR_INSIDE: f64 = 0.5;
/// `AUDIT_MARGIN` as documented: the audit applies OSQP's `eps` times ten.
const MARGIN: f64 = 10.0;
/// `TridiagSystem::roundoff_ulps` as documented (a row's rounding and the solve's, margin three).
const TRIDIAG_ULPS: f64 = 32.0;
/// `SparseSystem::roundoff_ulps` as documented (18-term rows and the sparse solve, margin two).
const SPARSE_ULPS: f64 = 64.0;
/// OSQP's tolerances for the Signorini answers: distinct, so that swapping or dropping either
/// term of a bound moves it by more than `DELTA`; large enough that the round-off floors stay
/// below `HAGER_SHARE` of each bound (the round-off-level answers test the force floors alone).
const EPS_ABS: f64 = 1e-7;
const EPS_REL: f64 = 1e-6;
const SIGNORINI: Law = Law::Signorini {
    eps_abs: EPS_ABS,
    eps_rel: EPS_REL,
};

/// The audit's checks, in the order of its report.
#[derive(Clone, Copy, Debug, PartialEq)]
enum Check {
    Primal,
    Negative,
    Complementarity,
    PenaltyLaw,
    Stationarity,
    Displacement,
}

const CHECKS: [Check; 6] = [
    Check::Primal,
    Check::Negative,
    Check::Complementarity,
    Check::PenaltyLaw,
    Check::Stationarity,
    Check::Displacement,
];

impl Check {
    /// The name the audit gives the check in `StepFailure::AuditFailed`.
    fn what(self) -> &'static str {
        match self {
            Check::Primal => "primal violation (lo_k - s_k z_k)+",
            Check::Negative => "negative reaction (-r_k)+",
            Check::Complementarity => "complementarity |r_k (s_k z_k - lo_k)|",
            Check::PenaltyLaw => "penalty law |eps r_k - (lo_k - s_k z_k)+|",
            Check::Stationarity => "stationarity |Cz - b - r|",
            Check::Displacement => "stationarity in displacement |C^-1 (Cz - b - r)|",
        }
    }

    /// The worst ratio the audit's report holds for the check (`None` when the law omits it).
    fn reported(self, report: &AuditReport) -> Option<f64> {
        let worst = match self {
            Check::Primal => report.primal_violation,
            Check::Negative => Some(report.negative_reaction),
            Check::Complementarity => report.complementarity,
            Check::PenaltyLaw => report.penalty_law,
            Check::Stationarity => Some(report.stationarity),
            Check::Displacement => Some(report.stationarity_displacement),
        };
        worst.map(|w| w.max_over_tolerance)
    }
}

/// A step matrix with its independent dense copies, the constraints of the answers, and the
/// vectors the Signorini answers are built from.
struct Body<S> {
    name: &'static str,
    c: DMatrix<f64>,
    c_inv: DMatrix<f64>,
    /// `‖C‖∞` and `‖C⁻¹‖∞`, largest absolute row sums of the dense copies.
    c_norm: f64,
    inv_norm: f64,
    ulps: f64,
    constraints: Constraints,
    /// The displacement of the Signorini answers (both constraints active).
    z: Vec<f64>,
    /// `w` with `‖C w‖∞` small (a soft mode) and large (a stiff mode), `‖w‖∞ = 1`.
    soft: Vec<f64>,
    stiff: Vec<f64>,
    system: fn() -> S,
}

impl<S: SpdSystem> Body<S> {
    fn new(
        name: &'static str,
        c: DMatrix<f64>,
        ulps: f64,
        constraints: Constraints,
        z: Vec<f64>,
        system: fn() -> S,
    ) -> Self {
        let c_inv = c.clone().try_inverse().expect("C is invertible");
        let (soft, stiff) = extreme_modes(&c);
        Self {
            name,
            c_norm: inf_norm(&c),
            inv_norm: inf_norm(&c_inv),
            c,
            c_inv,
            ulps,
            constraints,
            z,
            soft,
            stiff,
            system,
        }
    }

    fn audit(&self, law: Law) -> KktAudit<S> {
        let penalty = matches!(law, Law::Penalty { .. });
        KktAudit::with_system((self.system)(), self.constraints.clone(), penalty)
    }

    /// `(i_k, s_k)`.
    fn constraint(&self, k: usize) -> (usize, f64) {
        (self.constraints.unknowns[k], self.constraints.directions[k])
    }
}

/// The eigenvectors of `C`'s smallest and largest eigenvalues, scaled to `‖w‖∞ = 1`.
fn extreme_modes(c: &DMatrix<f64>) -> (Vec<f64>, Vec<f64>) {
    let eigen = c.clone().symmetric_eigen();
    let mode = |j: usize| {
        let w = eigen.eigenvectors.column(j);
        w.iter().map(|x| x / w.amax()).collect()
    };
    (
        mode(eigen.eigenvalues.imin()),
        mode(eigen.eigenvalues.imax()),
    )
}

/// The bar: `n` nodes, `C = m I + k L` with `L` the free bar's difference matrix (rows `1, −1`
/// at the ends, `−1, 2, −1` inside). Dyadic entries, so that products with dyadic `z` are exact;
/// an M-matrix with `C 1 = m 1`, so `C⁻¹ >= 0` and `‖C⁻¹‖∞ = 1/m` (= 64: soft, so that the
/// displacement check can bind before the force check), and Hager's estimate is exact.
const BAR_NODES: usize = 8;
const BAR_MASS: f64 = 1.0 / 64.0;
const BAR_STIFFNESS: f64 = 4.0;

fn bar_matrix() -> SymTridiag {
    let n = BAR_NODES;
    let mut diag = vec![BAR_MASS + 2.0 * BAR_STIFFNESS; n];
    diag[0] = BAR_MASS + BAR_STIFFNESS;
    diag[n - 1] = BAR_MASS + BAR_STIFFNESS;
    SymTridiag::new(diag, vec![-BAR_STIFFNESS; n - 1])
}

fn bar_dense() -> DMatrix<f64> {
    let c = bar_matrix();
    DMatrix::from_fn(BAR_NODES, BAR_NODES, |i, j| match i.abs_diff(j) {
        0 => c.diag[i],
        1 => c.off[i.min(j)],
        _ => 0.0,
    })
}

/// A lower bound at the bar's left end (`s = +1`) and an upper one at its right end.
fn bar_constraints() -> Constraints {
    Constraints {
        unknowns: vec![0, BAR_NODES - 1],
        directions: vec![1.0, -1.0],
    }
}

/// The bar as the bar's solvers hold it, a `TridiagSystem`.
fn bar() -> Body<TridiagSystem> {
    Body::new(
        "bar",
        bar_dense(),
        TRIDIAG_ULPS,
        bar_constraints(),
        vec![0.5, 0.625, 0.75, 0.8125, 0.75, 0.5, 0.125, -0.25],
        || TridiagSystem::new(&bar_matrix()).expect("C is positive definite"),
    )
}

/// The bar's matrix held as the plane body's solvers hold theirs, a `SparseSystem` on a
/// `Pattern`: its dyadic entries make the sparse system's round-off floors testable.
fn sparse_bar() -> Body<SparseSystem> {
    let system = || {
        let dense = bar_dense();
        let (mut row_ptr, mut cols, mut values) = (vec![0], Vec::new(), Vec::new());
        for i in 0..BAR_NODES {
            for j in i.saturating_sub(1)..(i + 2).min(BAR_NODES) {
                cols.push(j);
                values.push(dense[(i, j)]);
            }
            row_ptr.push(cols.len());
        }
        let pattern = Pattern {
            n: BAR_NODES,
            row_ptr,
            cols,
        };
        SparseSystem::new(&pattern, &values, "C").expect("C is positive definite")
    };
    let bar = bar();
    Body::new(
        "bar on a pattern",
        bar.c,
        SPARSE_ULPS,
        bar.constraints,
        bar.z,
        system,
    )
}

/// The plane body: Q1 matrices on a 2 × 2 grid of the unit square (all degrees of freedom kept),
/// `C = M/Δt² + (½ + α/(2Δt)) K` as the plane's step matrix; a long step makes it soft along
/// the rigid translations, which `K` does not resist.
const PLANE_CELLS: usize = 2;
const PLANE_MATERIAL: Material = Material {
    lambda: 4.0,
    mu: 4.0,
    density: 1.0,
};
const PLANE_DT: f64 = 2.0;
const PLANE_VISCOSITY: f64 = 0.5;

fn plane_grid() -> Grid {
    Grid::new(1.0, 1.0, PLANE_CELLS, PLANE_CELLS, 1.0)
}

fn plane_matrix() -> (Pattern, Vec<f64>) {
    let m = assemble(&plane_grid(), PLANE_MATERIAL);
    let (dt, alpha) = (PLANE_DT, PLANE_VISCOSITY);
    let (a, b) = (1.0 / (dt * dt), 0.5 + alpha / (2.0 * dt));
    let values = (m.mass.iter().zip(&m.stiffness))
        .map(|(m, k)| a * m + b * k)
        .collect();
    (m.pattern, values)
}

/// The plane body with the bottom edge's middle node pushed up (`u_y`, `s = +1`) and the top
/// edge's middle node pushed down (`s = −1`).
fn plane() -> Body<SparseSystem> {
    let grid = plane_grid();
    let (pattern, values) = plane_matrix();
    let n = pattern.n;
    let mut dense = DMatrix::zeros(n, n);
    for row in 0..n {
        for at in pattern.row_ptr[row]..pattern.row_ptr[row + 1] {
            dense[(row, pattern.cols[at])] = values[at];
        }
    }
    assert_eq!(dense, dense.transpose(), "the plane's C is symmetric");
    let (bottom, top) = (grid.node(1, 0), grid.node(1, PLANE_CELLS));
    let z = (0..n)
        .map(|d| {
            // A rigid motion and a little shear: C z stays small next to the reactions.
            let (i, j) = grid.position(d / 2);
            let (x, y) = (grid.xs[i], grid.ys[j]);
            if d % 2 == 0 {
                0.2 - 0.3 * y + 0.05 * x * y
            } else {
                -0.1 + 0.3 * x
            }
        })
        .collect();
    Body::new(
        "plane",
        dense,
        SPARSE_ULPS,
        Constraints {
            unknowns: vec![2 * bottom + 1, 2 * top + 1],
            directions: vec![1.0, -1.0],
        },
        z,
        || {
            let (pattern, values) = plane_matrix();
            SparseSystem::new(&pattern, &values, "C").expect("C is positive definite")
        },
    )
}

/// An answer `(z, r)` with its bounds `lo`; the right-hand side is
/// `b = C z − Σ_k r_k s_k e_{i_k} − extra`, so that the stationarity residual is `extra`.
#[derive(Clone, Debug)]
struct Answer {
    z: Vec<f64>,
    r: Vec<f64>,
    lo: Vec<f64>,
    extra: Vec<f64>,
}

impl Answer {
    /// Every constraint active (`lo_k = s_k z_{i_k}`) with a unit reaction.
    fn active<S>(body: &Body<S>, z: Vec<f64>) -> Self {
        let cs = &body.constraints;
        let lo = (cs.unknowns.iter().zip(&cs.directions))
            .map(|(&i, &s)| s * z[i])
            .collect();
        Self {
            r: vec![1.0; cs.len()],
            extra: vec![0.0; z.len()],
            lo,
            z,
        }
    }
}

/// The audit's quantities for one answer, from the documented formulas.
struct Eval {
    b: Vec<f64>,
    tol_f: f64,
    tol_z: f64,
    tol_dz: f64,
    floor_f: f64,
    /// The penalty law's round-off bound of each constraint.
    law_tol: Vec<f64>,
    /// `(value, tolerance)` of each check, in the order of [`CHECKS`].
    checks: [(f64, f64); 6],
    /// Whether the recomputed stationarity residual is `extra`, bit for bit.
    exact: bool,
}

impl Eval {
    fn ratio(&self, check: Check) -> f64 {
        let (value, tolerance) = self.checks[check as usize];
        ratio(value, tolerance)
    }
}

/// The audit's checks of `a` under `law`, computed independently (see the module doc).
fn evaluate<S>(body: &Body<S>, law: Law, a: &Answer) -> Eval {
    let n = a.z.len();
    let cs = &body.constraints;
    let cz = &body.c * DVector::from_column_slice(&a.z);
    let mut b: Vec<f64> = (0..n).map(|i| cz[i] - a.extra[i]).collect();
    for (k, (&i, &s)) in cs.unknowns.iter().zip(&cs.directions).enumerate() {
        b[i] -= s * a.r[k];
    }
    // The stationarity residual, recomputed from b, and its image in displacement.
    let mut residual = DVector::from_fn(n, |i, _| cz[i] - b[i]);
    for (k, (&i, &s)) in cs.unknowns.iter().zip(&cs.directions).enumerate() {
        residual[i] -= s * a.r[k];
    }
    let dz = &body.c_inv * &residual;
    let (cz_norm, b_norm, z_norm, r_norm) = (cz.amax(), amax(&b), amax(&a.z), amax(&a.r));
    let (eps_abs, eps_rel) = match law {
        Law::Signorini { eps_abs, eps_rel } => (MARGIN * eps_abs, MARGIN * eps_rel),
        Law::Penalty { .. } => (0.0, 0.0),
    };
    let ulp = body.ulps * f64::EPSILON;
    let floor_f = ulp * (body.c_norm * z_norm + b_norm + r_norm);
    let tol_f = eps_abs + eps_rel * cz_norm.max(b_norm).max(r_norm) + floor_f;
    let tol_dz = eps_abs + eps_rel * z_norm + body.inv_norm * floor_f;
    let p_scale = (cs.unknowns.iter().zip(&a.lo))
        .fold(0.0f64, |m, (&i, lo)| m.max(a.z[i].abs()).max(lo.abs()));
    let tol_z = eps_abs + eps_rel * p_scale + ulp * p_scale;
    let (mut primal, mut negative, mut comp, mut law_res) =
        (0.0f64, 0.0f64, (0.0, 0.0), (0.0, 0.0));
    let mut law_tol = vec![0.0; cs.len()];
    for (k, (&i, &s)) in cs.unknowns.iter().zip(&cs.directions).enumerate() {
        let gap = s * a.z[i] - a.lo[k];
        negative = negative.max(-a.r[k]);
        let pair = match law {
            Law::Signorini { .. } => {
                primal = primal.max(-gap);
                let pair = (
                    (a.r[k] * gap).abs(),
                    tol_z * a.r[k].abs() + tol_f * gap.abs(),
                );
                if ratio(pair.0, pair.1) >= ratio(comp.0, comp.1) {
                    comp = pair;
                }
                continue;
            }
            Law::Penalty { epsilon } => {
                let value = (epsilon * a.r[k] - (-gap).max(0.0)).abs();
                let coupled: f64 = (cs.unknowns.iter().zip(&a.r))
                    .map(|(&l, r)| body.c_inv[(i, l)].abs() * r.abs())
                    .sum();
                // The reaction taken from stationarity when the spring 1/ε is stiffer than C_ii.
                let row = if body.c[(i, i)] >= 1.0 / epsilon {
                    0.0
                } else {
                    let abs_row: f64 = (0..n).map(|l| (body.c[(i, l)] * a.z[l]).abs()).sum();
                    epsilon * (abs_row + b[i].abs())
                };
                law_tol[k] =
                    ulp * (a.z[i].abs() + coupled + a.lo[k].abs() + (epsilon * a.r[k]).abs() + row);
                (value, law_tol[k])
            }
        };
        if ratio(pair.0, pair.1) >= ratio(law_res.0, law_res.1) {
            law_res = pair;
        }
    }
    Eval {
        b,
        tol_f,
        tol_z,
        tol_dz,
        floor_f,
        law_tol,
        exact: residual.iter().zip(&a.extra).all(|(x, y)| x == y),
        checks: [
            (primal, tol_z),
            (negative, tol_f),
            comp,
            law_res,
            (residual.amax(), tol_f),
            (dz.amax(), tol_dz),
        ],
    }
}

/// Whether the law's bounds are round-off floors only.
fn roundoff_level(law: Law) -> bool {
    match law {
        Law::Signorini { eps_abs, eps_rel } => eps_abs == 0.0 && eps_rel == 0.0,
        Law::Penalty { .. } => true,
    }
}

/// Places `base` at `(1 − DELTA)` and at `(1 + DELTA)` times the tolerance of `check` with
/// `place(answer, factor, evaluation)`, and requires the audit to accept the first and to refuse
/// the second by `check`; then that the audit's ratios are the documented ones.
fn bracket<S: SpdSystem>(
    body: &Body<S>,
    law: Law,
    check: Check,
    case: &str,
    base: &Answer,
    place: impl Fn(&mut Answer, f64, &Eval),
) {
    let [inside, outside] = [1.0 - DELTA, 1.0 + DELTA].map(|f| {
        let at = format!("{} ({case}): {check:?} at {f} × its tolerance", body.name);
        let mut a = base.clone();
        for _ in 0..PLACEMENT_ROUNDS {
            let e = evaluate(body, law, &a);
            place(&mut a, f, &e);
        }
        let e = evaluate(body, law, &a);
        let placed = e.ratio(check);
        assert!((placed - f).abs() <= PLACEMENT, "{at}: placed at {placed}");
        for other in CHECKS.into_iter().filter(|&c| c != check) {
            let r = e.ratio(other);
            assert!(r <= FAR_INSIDE, "{at}: {other:?} not far inside ({r})");
        }
        if roundoff_level(law) {
            assert!(e.exact, "{at}: the round-off-level answer is not exact");
        } else {
            let share = body.inv_norm * e.floor_f / e.tol_dz;
            assert!(share <= HAGER_SHARE, "{at}: floor share {share:e}");
        }
        let mut audit = body.audit(law);
        let verdict = audit.check(law, &e.b, &a.lo, &a.z, &a.r);
        (at, e, audit, verdict)
    });
    if let Err(err) = &inside.3 {
        panic!("{}: refused: {err}", inside.0);
    }
    let (what, value, tolerance) = match &outside.3 {
        Err(StepFailure::AuditFailed {
            what,
            value,
            tolerance,
        }) => (*what, *value, *tolerance),
        other => panic!(
            "{}: not refused by `{}`: {other:?}",
            outside.0,
            check.what()
        ),
    };
    assert_eq!(
        what,
        check.what(),
        "{}: refused by another check",
        outside.0
    );
    for c in CHECKS {
        if let Some(reported) = c.reported(inside.2.report()) {
            let expected = inside.1.ratio(c);
            assert!(
                (reported - expected).abs() <= AGREEMENT,
                "{}: the audit's {c:?} ratio {reported} is not the documented {expected}",
                inside.0
            );
        }
    }
    let (v, t) = outside.1.checks[check as usize];
    assert!(
        (tolerance / t - 1.0).abs() <= AGREEMENT && (value / v - 1.0).abs() <= AGREEMENT,
        "{}: the audit's {value:e} against {tolerance:e} is not the documented {v:e} against {t:e}",
        outside.0
    );
}

fn primal_violation<S: SpdSystem>(body: &Body<S>) {
    for k in 0..body.constraints.len() {
        let (i, s) = body.constraint(k);
        // Inactive (r_k = 0), the bound raised past s_k z_{i_k} by the violation.
        let mut base = Answer::active(body, body.z.clone());
        base.r[k] = 0.0;
        let case = format!("constraint {k}, s = {s}");
        bracket(body, SIGNORINI, Check::Primal, &case, &base, |a, f, e| {
            a.lo[k] = s * a.z[i] + f * e.tol_z;
        });
    }
}

/// A reaction `−v` at constraint `k` of `base(k)`.
fn negative_reaction<S: SpdSystem>(body: &Body<S>, law: Law, base: impl Fn(usize) -> Answer) {
    for k in 0..body.constraints.len() {
        let case = format!("constraint {k}, s = {}", body.constraints.directions[k]);
        bracket(body, law, Check::Negative, &case, &base(k), |a, f, e| {
            a.r[k] = -f * e.tol_f;
        });
    }
}

fn complementarity<S: SpdSystem>(body: &Body<S>) {
    for k in 0..body.constraints.len() {
        let (i, s) = body.constraint(k);
        // A gap g under a unit reaction: r g = f (tol_z r + tol_f g).
        let base = Answer::active(body, body.z.clone());
        let case = format!("constraint {k}, s = {s}");
        bracket(
            body,
            SIGNORINI,
            Check::Complementarity,
            &case,
            &base,
            |a, f, e| {
                let r = a.r[k];
                let g = f * e.tol_z * r / (r - f * e.tol_f);
                a.lo[k] = s * a.z[i] - g;
            },
        );
    }
}

/// A residual `extra = v C w / ‖C w‖∞` along the stiff mode `w`: `‖extra‖∞ = v`, while its
/// displacement `v w / ‖C w‖∞` stays small.
fn stationarity<S: SpdSystem>(body: &Body<S>) {
    let cw = &body.c * DVector::from_column_slice(&body.stiff);
    let base = Answer::active(body, body.z.clone());
    bracket(
        body,
        SIGNORINI,
        Check::Stationarity,
        "stiff residual",
        &base,
        |a, f, e| {
            for (x, y) in a.extra.iter_mut().zip(cw.iter()) {
                *x = f * e.tol_f * y / cw.amax();
            }
        },
    );
}

/// A residual `extra = C d` with `d = v w` along the soft mode `w`: its displacement is `d`,
/// `‖d‖∞ = v`, while `‖C d‖∞ = v ‖C w‖∞` stays far below the force tolerance.
fn stationarity_in_displacement<S: SpdSystem>(body: &Body<S>) {
    let cw = &body.c * DVector::from_column_slice(&body.soft);
    let base = Answer::active(body, body.z.clone());
    bracket(
        body,
        SIGNORINI,
        Check::Displacement,
        "soft residual",
        &base,
        |a, f, e| {
            for (x, y) in a.extra.iter_mut().zip(cw.iter()) {
                *x = f * e.tol_dz * y;
            }
        },
    );
}

#[test]
fn bar_primal_violation() {
    primal_violation(&bar());
}

#[test]
fn plane_primal_violation() {
    primal_violation(&plane());
}

#[test]
fn bar_negative_reaction() {
    let bar = bar();
    negative_reaction(&bar, SIGNORINI, |_| Answer::active(&bar, bar.z.clone()));
}

#[test]
fn plane_negative_reaction() {
    let plane = plane();
    negative_reaction(&plane, SIGNORINI, |_| {
        Answer::active(&plane, plane.z.clone())
    });
}

#[test]
fn bar_complementarity() {
    complementarity(&bar());
}

#[test]
fn plane_complementarity() {
    complementarity(&plane());
}

#[test]
fn bar_stationarity() {
    stationarity(&bar());
}

#[test]
fn plane_stationarity() {
    stationarity(&plane());
}

#[test]
fn bar_stationarity_in_displacement() {
    let bar = bar();
    assert!(
        (bar.inv_norm * BAR_MASS - 1.0).abs() <= 1e-12,
        "‖C⁻¹‖∞ = 1/m"
    );
    stationarity_in_displacement(&bar);
}

#[test]
fn plane_stationarity_in_displacement() {
    stationarity_in_displacement(&plane());
}

/// Penalty parameters: `1/ε` softer than the bar's end entry `C_00 = 4 + 1/64` (reaction taken
/// from the gap) and stiffer (from stationarity, whose row adds to the law's bound). Powers of
/// two, so that `ε r` is exact.
const SOFT_SPRINGS: f64 = 0.5;
const STIFF_SPRINGS: f64 = 1.0 / 64.0;

/// The penalty answers are exact in f64 (every value dyadic with few bits, sums without
/// rounding): their bounds are round-off floors, tens of ulps, so an answer rounded on the way
/// would move by a few percent of its bound. This `z` makes `(C z)_i` exactly 0 at both ends and
/// at node 3 (`C_00 z_0 = 4 z_1`, `z_2 = −z_4`), where a tiny reaction or residual stays exact.
const PENALTY_Z: [f64; BAR_NODES] = [
    0.5,
    0.5 + 1.0 / 512.0,
    0.375,
    0.0,
    -0.375,
    0.125,
    -0.5 - 1.0 / 512.0,
    -0.5,
];
/// The node of the exact stationarity residual.
const PENALTY_FREE_NODE: usize = 3;

/// Both springs compressed by exactly `ε` under unit reactions: the law holds without rounding.
fn penalty_answer(bar: &Body<TridiagSystem>, epsilon: f64) -> Answer {
    let mut a = Answer::active(bar, PENALTY_Z.to_vec());
    for lo in &mut a.lo {
        *lo += epsilon;
    }
    a
}

/// The penalty law `|ε r_k − (lo_k − s_k z_{i_k})⁺|` at its bound: constraint `k` sits at
/// `s z = 2⁻¹⁰` with `ε r_k = 2⁻¹¹` and its bound raised to `s z + ε r_k − v`, so that the
/// gap, the compression and the law's value are exact differences of nearby dyadic numbers
/// (Sterbenz) and `v` is resolved to about 2e-6 of itself; the other constraint's unit
/// reaction, coupled through `C⁻¹`, sets most of the bound.
#[test]
fn bar_penalty_law() {
    let bar = bar();
    for epsilon in [SOFT_SPRINGS, STIFF_SPRINGS] {
        let law = Law::Penalty { epsilon };
        for k in 0..bar.constraints.len() {
            let (i, s) = bar.constraint(k);
            let mut base = penalty_answer(&bar, epsilon);
            base.z[i] = s / 1024.0;
            base.r[k] = 1.0 / 2048.0 / epsilon;
            base.lo[k] = s * base.z[i] + epsilon * base.r[k];
            let case = format!("epsilon = {epsilon}, constraint {k}, s = {s}");
            bracket(&bar, law, Check::PenaltyLaw, &case, &base, |a, f, e| {
                a.lo[k] = (s * a.z[i] + epsilon * a.r[k]) - f * e.law_tol[k];
            });
        }
    }
}

/// The penalty solver's negative-reaction bound, its round-off floor `floor_f`: a reaction
/// `−v` at an end whose row of `C z` is exactly 0, the constraint inactive (gap ¼).
#[test]
fn bar_penalty_negative_reaction() {
    let bar = bar();
    let epsilon = STIFF_SPRINGS;
    negative_reaction(&bar, Law::Penalty { epsilon }, |k| {
        let mut base = penalty_answer(&bar, epsilon);
        base.lo[k] -= epsilon + 0.25;
        base.r[k] = 0.0;
        base
    });
}

/// The penalty solver's stationarity bound, its round-off floor `floor_f`: a residual `v` at a
/// node whose row of `C z` is exactly 0 (`b_3 = −v`, exact). Its displacement check,
/// `‖C⁻¹ ρ‖∞ <= ‖C⁻¹‖∞ floor_f`, cannot fail while stationarity, `‖ρ‖∞ <= floor_f`, holds
/// (Hager's estimate is exact for this `C`): it is bracketed under the Signorini law only.
#[test]
fn bar_penalty_stationarity() {
    let bar = bar();
    let epsilon = STIFF_SPRINGS;
    let base = penalty_answer(&bar, epsilon);
    let law = Law::Penalty { epsilon };
    bracket(
        &bar,
        law,
        Check::Stationarity,
        "exact residual",
        &base,
        |a, f, e| {
            a.extra[PENALTY_FREE_NODE] = f * e.tol_f;
        },
    );
}

/// The sparse system's round-off floors (64 ulps), which the plane's Signorini answers above
/// leave below `HAGER_SHARE` of their bounds: the exact answers of the penalty tests on the bar's
/// matrix held as a `SparseSystem`, under the Signorini law with `eps = 0`, the reactions at
/// active bounds (gap 0), so that complementarity stays 0.
#[test]
fn sparse_roundoff_floors() {
    let bar = sparse_bar();
    let law = Law::Signorini {
        eps_abs: 0.0,
        eps_rel: 0.0,
    };
    let base = Answer::active(&bar, PENALTY_Z.to_vec());
    negative_reaction(&bar, law, |_| base.clone());
    bracket(
        &bar,
        law,
        Check::Stationarity,
        "exact residual",
        &base,
        |a, f, e| {
            a.extra[PENALTY_FREE_NODE] = f * e.tol_f;
        },
    );
}
