//! The frictional audit's bounds, checked at their edges: for each check of `step::friction_audit`
//! and each way the solvers call it (the exact solver: Coulomb, or zero thresholds at start-up,
//! slack 0; OSQP's Tresca problems: given thresholds, OSQP's stopping slack), an answer whose
//! checked value is `(1 − DELTA)` times the check's tolerance is accepted and one at `(1 + DELTA)`
//! is refused by that check, so that a loosened or mis-scaled bound fails.
//!
//! Each expected tolerance is computed here from the table of docs/friction.md ("Audit"), with
//! `SparseSystem::roundoff_ulps` as documented, on independent dense copies of `C` and `C⁻¹`
//! (nalgebra), never read back from the audit. The plane body's `z` has three nonzero entries
//! whose rows of `C` do not overlap, so that `C z` is exact and the audit's stationarity residual
//! has the bits recomputed here; every check but the one under test stays far inside its bound.
//! The bounds depend on the answer's norms, so each answer is placed by a fixed-point iteration
//! and its ratio re-measured before it is audited. Normals push both ways, `s = ±1`.

mod common;

use common::{amax, inf_norm, ratio};
use nalgebra::{DMatrix, DVector};
use viscobar::internals::linalg::sparse::Pattern;
use viscobar::internals::linalg::system::{SparseSystem, inverse_norm_estimate};
use viscobar::internals::plane::matrices::{Material, assemble};
use viscobar::internals::plane::mesh::Grid;
use viscobar::step::friction_audit::{FrictionAudit, FrictionLaw, Thresholds};
use viscobar::step::report::{AuditReport, StepFailure};
use viscobar::step::solver::{Constraints, Friction};

/// Answers sit at `(1 ∓ DELTA)` times a tolerance: far beyond the round-off of evaluating the
/// formula twice (about 1e-12 relative), close enough that any mis-scaling of a bound by more
/// than 0.1 % turns one of the two verdicts.
const DELTA: f64 = 1e-3;
/// An answer is placed at its intended ratio to within a tenth of `DELTA` (the placed values are
/// rounded to ulps of the thresholds and gaps they sit next to, below 1e-5 of the tolerances).
const PLACEMENT: f64 = 1e-4;
/// Rounds of the placement's fixed-point iteration: a bound moves with the placed quantity by at
/// most about 1e-6 times it (through the norms), so each round divides the error by 1e6.
const PLACEMENT_ROUNDS: usize = 4;
/// The audit's own ratios (its report and its error) agree with the independent ones to a tenth
/// of `DELTA`: the same formulas in f64 from the same data; Hager's estimate of `‖C⁻¹‖∞` is exact
/// to 1e-12 on this body (asserted) and the sparse solve agrees with `C⁻¹` to about 1e-14.
const AGREEMENT: f64 = 1e-4;
/// Hager's estimate against the dense `‖C⁻¹‖∞`, relative: a few hundred ulps of round-off.
const HAGER_EXACT: f64 = 1e-12;
/// Every check but the one under test stays below half its tolerance: a verdict is that check's.
const FAR_INSIDE: f64 = 0.5;
/// `SparseSystem::roundoff_ulps` as documented (18-term rows and the sparse solve, margin two).
const SPARSE_ULPS: f64 = 64.0;
/// `AUDIT_MARGIN` as documented: the Tresca solver's slack is OSQP's criterion times ten.
const MARGIN: f64 = 10.0;
/// `INACCURATE_FACTOR` as documented: an answer accepted as inaccurate gets ten times more.
const INACCURATE: f64 = 10.0;
/// OSQP's default `eps_abs` and `eps_rel` (`OSQP_DEFAULT_EPS`), which the Tresca solver runs with.
const OSQP_EPS: f64 = 1e-10;

/// The plane body: Q1 matrices on a 4 × 6 grid of square cells (all degrees of freedom kept),
/// `C = M/Δt² + (½ + α/(2Δt)) K` as the plane's step matrix (as in tests/audit_bounds.rs); the
/// long step makes `‖C‖∞ ‖C⁻¹‖∞` large, so that `ε'‖z‖∞` is below `DELTA` of `‖C⁻¹‖∞ τ_f`.
const NX: usize = 4;
const NY: usize = 6;
const MATERIAL: Material = Material {
    lambda: 4.0,
    mu: 4.0,
    density: 1.0,
};
const DT: f64 = 2.0;
const VISCOSITY: f64 = 0.5;
/// A node's `u_x` and `u_y`.
const X: usize = 0;
const Y: usize = 1;

/// The normal constraints `(i, j, s)` at `u_y` of node `(i, j)`: three on the bottom edge pushed
/// up, one on the top edge pushed down.
const M: usize = 4;
const NORMALS: [(usize, usize, f64); M] = [(0, 0, 1.0), (2, 0, 1.0), (4, 0, 1.0), (2, NY, -1.0)];
/// The frictional nodes: their normal constraint (the tangent is that node's `u_x`) and `μ`
/// (dyadic, so that `μ r_N` is exact; at most 3/8, so that a negative `r_N` leaves the cone and
/// the slip law of its node below `FAR_INSIDE`).
const P: usize = 3;
const FRICTIONAL: [usize; P] = [1, 2, 3];
const MU: [f64; P] = [0.25, 0.375, 0.25];

/// The nonzero entries of `z`, at nodes pairwise three cells apart (no row of `C` meets two of
/// them, so `C z` is exact): a free interior unknown (`‖C‖∞ ‖z‖∞` dominates `τ_f`), the top
/// normal's unknown (`s z ≠ 0`) and the second tangent's (`δ = z_t + w`).
const Z_ENTRIES: [(usize, usize, usize, f64); 3] =
    [(2, 3, X, 0.5), (2, NY, Y, -0.0625), (4, 0, X, 0.03125)];
/// The base answer's normal reactions: the unit one sets `‖r‖∞`, the frictional ones are smaller
/// (their thresholds round finely against the tolerances), the top constraint is inactive.
const REACTIONS: [f64; M] = [1.0, 0.25, 0.5, 0.0];
/// The base answer's gaps: the inactive top one makes `ε' max|lo_k|` a visible part of `τ_z`.
const GAPS: [f64; M] = [0.0, 0.0, 0.0, 256.0];
/// The previous increment at the tangents: node 0 slides forward (`δ = 1/2`), node 1 sticks
/// (`δ = z_t + w = 0`), node 2 slides back.
const PREVIOUS: [f64; P] = [0.5, -0.03125, -0.03125];
/// The central slips of the slip-law answers (powers of two: `g|δ|` and `r_T δ` are exact).
const SLIPS: [f64; P] = [0.5, -0.25, 0.5];
/// A normal reaction for the answers that need the top constraint active and pressed.
const PRESSED: f64 = 0.5;
/// The Tresca thresholds of the OSQP case: distinct from the answer's `μ r_N`, so that an audit
/// reading the wrong ones refuses the base answer.
const GIVEN: [f64; P] = [0.125, 0.25, 0.0625];
/// The start-up Tresca problem's thresholds (`g = 0`).
const GIVEN_ZERO: [f64; P] = [0.0; P];
/// A residual along the left edge's `u_x` with alternating signs (rows where `C z = 0`, so that
/// `b = −residual` is exact): a stiff load, whose displacement stays small.
const STIFF_ROWS: [(usize, usize, f64); 3] = [(0, 2, 1.0), (0, 3, -1.0), (0, 4, 1.0)];

/// The audit's checks, in its order.
#[derive(Clone, Copy, Debug, PartialEq)]
enum Check {
    Primal,
    Negative,
    Complementarity,
    Cone,
    Slip,
    Stationarity,
    Displacement,
}

const CHECKS: [Check; 7] = [
    Check::Primal,
    Check::Negative,
    Check::Complementarity,
    Check::Cone,
    Check::Slip,
    Check::Stationarity,
    Check::Displacement,
];

impl Check {
    /// The name the audit gives the check in `StepFailure::AuditFailed`.
    fn what(self) -> &'static str {
        match self {
            Check::Primal => "primal violation (lo_k - s_k z_k)+",
            Check::Negative => "negative reaction (-r_N)+",
            Check::Complementarity => "complementarity |r_N (s_k z_k - lo_k)|",
            Check::Cone => "friction cone (|r_T| - mu r_N)+",
            Check::Slip => "slip law |mu r_N |delta| + r_T delta|",
            Check::Stationarity => "stationarity |Cz - b - E^T r|",
            Check::Displacement => "stationarity in displacement |C^-1 (Cz - b - E^T r)|",
        }
    }

    /// The worst ratio the audit's report holds for the check (the friction audit lists all).
    fn reported(self, report: &AuditReport) -> f64 {
        let worst = match self {
            Check::Primal => report.primal_violation,
            Check::Negative => Some(report.negative_reaction),
            Check::Complementarity => report.complementarity,
            Check::Cone => report.friction_cone,
            Check::Slip => report.slip_law,
            Check::Stationarity => Some(report.stationarity),
            Check::Displacement => Some(report.stationarity_displacement),
        };
        worst
            .expect("the friction audit reports every check")
            .max_over_tolerance
    }
}

/// The thresholds `g_j` an answer is held to.
#[derive(Clone, Copy, Debug)]
enum Kind {
    Coulomb,
    Given(&'static [f64; P]),
    Zero,
}

/// One way a solver calls the audit (src/step/condensed_lemke.rs, src/step/osqp_tresca.rs).
#[derive(Clone, Copy, Debug)]
struct Case {
    name: &'static str,
    kind: Kind,
    /// Whether the previous increment is known (no slip law at the start-up step).
    previous: bool,
    /// OSQP's slack factor (`AUDIT_MARGIN`, times `INACCURATE_FACTOR` if inaccurate); `None`
    /// for the exact solver (slack 0).
    osqp: Option<f64>,
}

const EXACT: Case = Case {
    name: "exact solver, Coulomb",
    kind: Kind::Coulomb,
    previous: true,
    osqp: None,
};
const EXACT_START: Case = Case {
    name: "exact solver, start-up",
    kind: Kind::Zero,
    previous: false,
    osqp: None,
};
const TRESCA: Case = Case {
    name: "OSQP, Tresca",
    kind: Kind::Given(&GIVEN),
    previous: true,
    osqp: Some(MARGIN),
};
const TRESCA_START: Case = Case {
    name: "OSQP, start-up, inaccurate",
    kind: Kind::Given(&GIVEN_ZERO),
    previous: false,
    osqp: Some(MARGIN * INACCURATE),
};
const CASES: [Case; 4] = [EXACT, EXACT_START, TRESCA, TRESCA_START];

fn grid() -> Grid {
    Grid::new(NX as f64 * 0.5, NY as f64 * 0.5, NX, NY, 1.0)
}

fn dof(i: usize, j: usize, axis: usize) -> usize {
    2 * grid().node(i, j) + axis
}

fn matrix() -> (Pattern, Vec<f64>) {
    let m = assemble(&grid(), MATERIAL);
    let (a, b) = (1.0 / (DT * DT), 0.5 + VISCOSITY / (2.0 * DT));
    let values = (m.mass.iter().zip(&m.stiffness))
        .map(|(m, k)| a * m + b * k)
        .collect();
    (m.pattern, values)
}

fn system() -> SparseSystem {
    let (pattern, values) = matrix();
    SparseSystem::new(&pattern, &values, "C").expect("C is positive definite")
}

/// The step matrix with its independent dense copies, the rows `E` and the base `z`.
struct Body {
    c: DMatrix<f64>,
    c_inv: DMatrix<f64>,
    /// `‖C‖∞` and `‖C⁻¹‖∞`, largest absolute row sums of the dense copies.
    c_norm: f64,
    inv_norm: f64,
    /// `σ = max_k S_kk`, `S = E C⁻¹ Eᵀ`: the Tresca solver's scale.
    sigma: f64,
    constraints: Constraints,
    friction: Friction,
    /// `(i, s)` of every row of `E`: the normals, then the tangents (`s = +1`).
    rows: Vec<(usize, f64)>,
    z: Vec<f64>,
}

fn body() -> Body {
    let (pattern, values) = matrix();
    let n = pattern.n;
    let mut c = DMatrix::zeros(n, n);
    for row in 0..n {
        for at in pattern.row_ptr[row]..pattern.row_ptr[row + 1] {
            c[(row, pattern.cols[at])] = values[at];
        }
    }
    assert_eq!(c, c.transpose(), "the plane's C is symmetric");
    let c_inv = c.clone().try_inverse().expect("C is invertible");
    let constraints = Constraints {
        unknowns: NORMALS.iter().map(|&(i, j, _)| dof(i, j, Y)).collect(),
        directions: NORMALS.iter().map(|&(.., s)| s).collect(),
    };
    let friction = Friction {
        normals: FRICTIONAL.to_vec(),
        tangents: FRICTIONAL
            .iter()
            .map(|&k| dof(NORMALS[k].0, NORMALS[k].1, X))
            .collect(),
        coefficients: MU.to_vec(),
    };
    let all = friction.rows(&constraints);
    let rows: Vec<(usize, f64)> = all.unknowns.into_iter().zip(all.directions).collect();
    let mut z = vec![0.0; n];
    for (i, j, axis, v) in Z_ENTRIES {
        z[dof(i, j, axis)] = v;
    }
    for i in 0..n {
        let terms = (0..n).filter(|&l| c[(i, l)] != 0.0 && z[l] != 0.0).count();
        assert!(
            terms <= 1,
            "row {i} of C meets {terms} entries of z: C z is not exact"
        );
    }
    let sigma = rows.iter().map(|&(i, _)| c_inv[(i, i)]).fold(0.0, f64::max);
    Body {
        c_norm: inf_norm(&c),
        inv_norm: inf_norm(&c_inv),
        c,
        c_inv,
        sigma,
        constraints,
        friction,
        rows,
        z,
    }
}

/// An answer: `z`, the reactions `r` (normals, then tangents), the bounds `lo`, the previous
/// increment `w` at the tangents; `b = C z − Eᵀ r − extra`, so that the residual is `extra`.
#[derive(Clone, Debug)]
struct Answer {
    z: Vec<f64>,
    r: Vec<f64>,
    lo: Vec<f64>,
    w: Vec<f64>,
    extra: Vec<f64>,
}

impl Answer {
    /// `δ_j = (z + w)_{t_j}`, as the audit rounds it.
    fn slip(&self, body: &Body, j: usize) -> f64 {
        self.z[body.friction.tangents[j]] + self.w[j]
    }

    /// Constraint `k` active (`lo_k = s_k z_{i_k}`).
    fn activate(&mut self, body: &Body, k: usize) {
        let (i, s) = body.rows[k];
        self.lo[k] = s * self.z[i];
    }

    /// The tangential reaction of node `j` that the case's law asks for (with the thresholds'
    /// positive part): `−g sign δ` where it slides, `g/2` where it sticks.
    fn settle(&mut self, body: &Body, case: &Case, j: usize) {
        let g = threshold(body, case, self, j).max(0.0);
        let delta = if case.previous {
            self.slip(body, j)
        } else {
            0.0
        };
        self.r[M + j] = if delta != 0.0 {
            -g * delta.signum()
        } else {
            g / 2.0
        };
    }

    /// The tangential reactions of the frictional nodes of normal `k` settled again.
    fn settle_normal(&mut self, body: &Body, case: &Case, k: usize) {
        for j in (0..P).filter(|&j| FRICTIONAL[j] == k) {
            self.settle(body, case, j);
        }
    }
}

/// `g_j` of the answer under the case's law, as documented: `μ_j r_N,k_j`, given, or 0.
fn threshold(body: &Body, case: &Case, a: &Answer, j: usize) -> f64 {
    match case.kind {
        Kind::Coulomb => body.friction.coefficients[j] * a.r[FRICTIONAL[j]],
        Kind::Given(g) => g[j],
        Kind::Zero => 0.0,
    }
}

/// The base answer of a case: every normal as `REACTIONS` and `GAPS`, the tangential reactions
/// by the case's law, `w = PREVIOUS`.
fn base(body: &Body, case: &Case) -> Answer {
    let mut r = REACTIONS.to_vec();
    r.extend([0.0; P]);
    let mut a = Answer {
        z: body.z.clone(),
        r,
        lo: body.rows[..M]
            .iter()
            .zip(GAPS)
            .map(|(&(i, s), gap)| s * body.z[i] - gap)
            .collect(),
        w: PREVIOUS.to_vec(),
        extra: vec![0.0; body.z.len()],
    };
    for j in 0..P {
        a.settle(body, case, j);
    }
    a
}

/// The audit's quantities for one answer, from the documented formulas.
struct Eval {
    b: Vec<f64>,
    /// The solver's slacks `(s_f, s_z)`.
    slack: (f64, f64),
    tol_f: f64,
    tol_z: f64,
    tol_dz: f64,
    /// `(value, tolerance)` of each check, in the order of [`CHECKS`].
    checks: [(f64, f64); 7],
}

impl Eval {
    fn ratio(&self, check: Check) -> f64 {
        let (value, tolerance) = self.checks[check as usize];
        ratio(value, tolerance)
    }
}

/// OSQP's stopping slack as the Tresca solver passes it (docs/friction.md, "Audit"):
/// `s_f = A (eps_abs + eps_rel ‖r‖∞)`, `s_z = A σ (eps_abs + eps_rel max(‖r‖∞, ‖q/σ‖∞))` with
/// `q = (s_k z⁰_{i_k} − lo_k, z⁰_{t_j} + w_j)`, `z⁰ = C⁻¹ b`; 0 for the exact solver.
fn slack(body: &Body, case: &Case, a: &Answer, b: &[f64]) -> (f64, f64) {
    let Some(factor) = case.osqp else {
        return (0.0, 0.0);
    };
    let z0 = &body.c_inv * DVector::from_column_slice(b);
    let mut q = 0.0f64;
    for (k, &(i, s)) in body.rows.iter().enumerate() {
        let w = if k < M || !case.previous {
            0.0
        } else {
            a.w[k - M]
        };
        let lo = if k < M { a.lo[k] } else { 0.0 };
        q = q.max(((s * z0[i] + w - lo) / body.sigma).abs());
    }
    let r_norm = amax(&a.r);
    let eps = OSQP_EPS + OSQP_EPS * r_norm;
    let eps_q = OSQP_EPS + OSQP_EPS * r_norm.max(q);
    (factor * eps, factor * body.sigma * eps_q.max(eps))
}

/// The audit's checks of `a` under `case`, computed independently (see the module doc).
fn evaluate(body: &Body, case: &Case, a: &Answer) -> Eval {
    let n = a.z.len();
    let cz = &body.c * DVector::from_column_slice(&a.z);
    let mut b: Vec<f64> = (0..n).map(|i| cz[i] - a.extra[i]).collect();
    for (k, &(i, s)) in body.rows.iter().enumerate() {
        b[i] -= s * a.r[k];
    }
    // The residual as recomputed from b (`C z` is exact: the audit's bits), and its image.
    let mut residual = DVector::from_fn(n, |i, _| cz[i] - b[i]);
    for (k, &(i, s)) in body.rows.iter().enumerate() {
        residual[i] -= s * a.r[k];
    }
    let dz = &body.c_inv * &residual;
    let slack = slack(body, case, a, &b);
    let ulp = SPARSE_ULPS * f64::EPSILON;
    let (z_norm, b_norm, r_norm) = (amax(&a.z), amax(&b), amax(&a.r));
    let r_sum: f64 = a.r.iter().map(|v| v.abs()).sum();
    // τ_f, τ_dz and τ_z of the table.
    let tol_f = ulp * (body.c_norm * z_norm + b_norm + r_norm) + slack.0;
    let tol_dz = body.inv_norm * (tol_f + ulp * r_sum) + ulp * z_norm + slack.1;
    let scale_z = (body.rows[..M].iter().zip(&a.lo))
        .fold(0.0f64, |m, (&(i, _), lo)| m.max(a.z[i].abs()).max(lo.abs()));
    let tol_z = tol_dz + ulp * scale_z;
    let (mut primal, mut negative, mut comp) = (0.0f64, 0.0f64, (0.0, 0.0));
    for (k, &(i, s)) in body.rows[..M].iter().enumerate() {
        let gap = s * a.z[i] - a.lo[k];
        primal = primal.max(-gap);
        negative = negative.max(-a.r[k]);
        let pair = (
            (a.r[k] * gap).abs(),
            tol_z * a.r[k].abs() + tol_f * gap.abs(),
        );
        if ratio(pair.0, pair.1) >= ratio(comp.0, comp.1) {
            comp = pair;
        }
    }
    let (mut cone, mut slip) = ((0.0, 0.0), (0.0, 0.0));
    for j in 0..P {
        let (g, rt) = (threshold(body, case, a, j), a.r[M + j]);
        let pair = ((rt.abs() - g).max(0.0), tol_f + ulp * g.abs());
        if ratio(pair.0, pair.1) >= ratio(cone.0, cone.1) {
            cone = pair;
        }
        if case.previous {
            let delta = a.slip(body, j);
            let pair = (
                (g * delta.abs() + rt * delta).abs(),
                tol_f * delta.abs() + (tol_z + ulp * a.w[j].abs()) * (g.abs() + rt.abs()),
            );
            if ratio(pair.0, pair.1) >= ratio(slip.0, slip.1) {
                slip = pair;
            }
        }
    }
    Eval {
        b,
        slack,
        tol_f,
        tol_z,
        tol_dz,
        checks: [
            (primal, tol_z),
            (negative, tol_f),
            comp,
            cone,
            slip,
            (residual.amax(), tol_f),
            (dz.amax(), tol_dz),
        ],
    }
}

/// The audit's verdict on `a`, from a fresh audit as the solvers set it up.
fn audit(
    body: &Body,
    case: &Case,
    a: &Answer,
    e: &Eval,
) -> (FrictionAudit, Result<(), StepFailure>) {
    let mut system = system();
    let mut audit = FrictionAudit::new(&mut system, &body.constraints, &body.friction);
    let law = FrictionLaw {
        thresholds: match case.kind {
            Kind::Coulomb => Thresholds::Coulomb,
            Kind::Given(g) => Thresholds::Given(g),
            Kind::Zero => Thresholds::Zero,
        },
        previous: case.previous.then_some(&a.w[..]),
        slack_force: e.slack.0,
        slack_displacement: e.slack.1,
    };
    let verdict = audit.check(&mut system, law, &e.b, &a.lo, &a.z, &a.r);
    (audit, verdict)
}

/// Places `base` at `(1 − DELTA)` and at `(1 + DELTA)` times the tolerance of `placed` with
/// `place(answer, factor, evaluation)`, and requires the audit to accept the first and to refuse
/// the second by `refused` (`placed` but for the displacement check); then that the audit's
/// ratios are the documented ones.
fn bracket(
    body: &Body,
    case: &Case,
    (placed, refused): (Check, Check),
    label: &str,
    base: &Answer,
    place: impl Fn(&mut Answer, f64, &Eval),
) {
    let [inside, outside] = [1.0 - DELTA, 1.0 + DELTA].map(|f| {
        let at = format!("{} ({label}): {placed:?} at {f} × its tolerance", case.name);
        let mut a = base.clone();
        for _ in 0..PLACEMENT_ROUNDS {
            let e = evaluate(body, case, &a);
            place(&mut a, f, &e);
        }
        let e = evaluate(body, case, &a);
        let at_ratio = e.ratio(placed);
        assert!(
            (at_ratio - f).abs() <= PLACEMENT,
            "{at}: placed at {at_ratio}"
        );
        for other in CHECKS.into_iter().filter(|&c| c != placed && c != refused) {
            let r = e.ratio(other);
            assert!(r <= FAR_INSIDE, "{at}: {other:?} not far inside ({r})");
        }
        let (audit, verdict) = audit(body, case, &a, &e);
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
            refused.what()
        ),
    };
    assert_eq!(
        what,
        refused.what(),
        "{}: refused by another check",
        outside.0
    );
    for c in CHECKS {
        let (reported, expected) = (c.reported(inside.2.report()), inside.1.ratio(c));
        assert!(
            (reported - expected).abs() <= AGREEMENT,
            "{}: the audit's {c:?} ratio {reported} is not the documented {expected}",
            inside.0
        );
    }
    let (v, t) = outside.1.checks[refused as usize];
    assert!(
        (tolerance / t - 1.0).abs() <= AGREEMENT && (value / v - 1.0).abs() <= AGREEMENT,
        "{}: the audit's {value:e} against {tolerance:e} is not the documented {v:e} against {t:e}",
        outside.0
    );
}

/// Normal `k` and its direction, as a label.
fn normal_label(k: usize) -> String {
    format!("normal {k}, s = {}", NORMALS[k].2)
}

#[test]
fn hager_estimate_is_exact_on_this_body() {
    let body = body();
    let estimate = inverse_norm_estimate(&mut system());
    assert!(
        (estimate / body.inv_norm - 1.0).abs() <= HAGER_EXACT,
        "Hager's {estimate} against ‖C⁻¹‖∞ = {}",
        body.inv_norm
    );
}

/// The base answers satisfy their laws: the audit accepts them with every ratio far inside.
#[test]
fn base_answers_are_accepted() {
    let body = body();
    for case in &CASES {
        let a = base(&body, case);
        let e = evaluate(&body, case, &a);
        for c in CHECKS {
            assert!(e.ratio(c) <= FAR_INSIDE, "{}: {c:?}", case.name);
        }
        let (_, verdict) = audit(&body, case, &a, &e);
        verdict.unwrap_or_else(|err| panic!("{}: {err}", case.name));
    }
}

/// Normal `k` inactive (`r_N = 0`, its node's `r_T` by the law), its bound raised past
/// `s_k z_{i_k}` by the violation.
#[test]
fn primal_violation() {
    let body = body();
    for case in &CASES {
        for k in 0..M {
            let (i, s) = body.rows[k];
            let mut a = base(&body, case);
            a.r[k] = 0.0;
            a.settle_normal(&body, case, k);
            let checks = (Check::Primal, Check::Primal);
            bracket(&body, case, checks, &normal_label(k), &a, |a, f, e| {
                a.lo[k] = s * a.z[i] + f * e.tol_z;
            });
        }
    }
}

/// Normal `k` active with the reaction `−v`; under Coulomb its node's `r_T = 0` (the threshold
/// `μ r_N` is negative, and the cone and slip law stay at `μ` times the ratio).
#[test]
fn negative_reaction() {
    let body = body();
    for case in &CASES {
        for k in 0..M {
            let mut a = base(&body, case);
            a.activate(&body, k);
            let checks = (Check::Negative, Check::Negative);
            bracket(&body, case, checks, &normal_label(k), &a, |a, f, e| {
                a.r[k] = -f * e.tol_f;
                a.settle_normal(&body, case, k);
            });
        }
    }
}

/// Normal `k` pressed (`r_N > 0`) at a gap `g`: `r g = f (τ_z r + τ_f g)`.
#[test]
fn complementarity() {
    let body = body();
    for case in &CASES {
        for k in 0..M {
            let (i, s) = body.rows[k];
            let mut a = base(&body, case);
            if a.r[k] == 0.0 {
                a.r[k] = PRESSED;
                a.settle_normal(&body, case, k);
            }
            let checks = (Check::Complementarity, Check::Complementarity);
            bracket(&body, case, checks, &normal_label(k), &a, |a, f, e| {
                let r = a.r[k];
                let gap = f * e.tol_z * r / (r - f * e.tol_f);
                a.lo[k] = s * a.z[i] - gap;
            });
        }
    }
}

/// Node `j` sticking (`δ = 0`, so the slip law holds exactly) with `|r_T| = g + v` (signs
/// alternating over the nodes): `v = f (τ_f + ε'|g|)`. Under Coulomb node 2's normal is inactive
/// (`g = 0`); the others press.
#[test]
fn friction_cone() {
    let body = body();
    for case in &CASES {
        for j in 0..P {
            let mut a = base(&body, case);
            a.w[j] = -a.z[body.friction.tangents[j]];
            let sign = if j % 2 == 0 { 1.0 } else { -1.0 };
            let label = format!("node {j}, sign {sign}");
            let checks = (Check::Cone, Check::Cone);
            bracket(&body, case, checks, &label, &a, |a, f, e| {
                let g = threshold(&body, case, a, j);
                let ulp = SPARSE_ULPS * f64::EPSILON;
                a.r[M + j] = sign * (g + f * (e.tol_f + ulp * g.abs()));
            });
        }
    }
}

/// Node `j` sliding (`δ = SLIPS[j]`, its normal pressed) with `r_T` short of the cone by `y`,
/// `r_T = −sign δ (g − y)`: the slip law's value is `y |δ|`, placed at `f` times
/// `τ_f |δ| + (τ_z + ε'|w|)(|g| + |r_T|)`. The start-up steps have no slip law.
#[test]
fn slip_law() {
    let body = body();
    for case in CASES.iter().filter(|c| c.previous) {
        for j in 0..P {
            let k = FRICTIONAL[j];
            let mut a = base(&body, case);
            if a.r[k] == 0.0 {
                a.r[k] = PRESSED;
                a.activate(&body, k);
            }
            let delta = SLIPS[j];
            a.w[j] = delta - a.z[body.friction.tangents[j]];
            assert_eq!(a.slip(&body, j), delta, "the slip is exact");
            a.settle(&body, case, j);
            let label = format!("node {j}, delta = {delta}");
            let checks = (Check::Slip, Check::Slip);
            bracket(&body, case, checks, &label, &a, |a, f, e| {
                let g = threshold(&body, case, a, j);
                let ulp = SPARSE_ULPS * f64::EPSILON;
                let t = e.tol_f * delta.abs()
                    + (e.tol_z + ulp * a.w[j].abs()) * (g.abs() + a.r[M + j].abs());
                a.r[M + j] = -delta.signum() * (g - f * t / delta.abs());
            });
        }
    }
}

/// A residual `±v` at `STIFF_ROWS`, exact (`C z = 0` there): `‖Cz − b − Eᵀr‖∞ = v`.
#[test]
fn stationarity() {
    let body = body();
    for case in &CASES {
        let a = base(&body, case);
        let cz = &body.c * DVector::from_column_slice(&a.z);
        let checks = (Check::Stationarity, Check::Stationarity);
        bracket(&body, case, checks, "stiff residual", &a, |a, f, e| {
            for (i, j, sign) in STIFF_ROWS {
                let row = dof(i, j, X);
                assert_eq!(cz[row], 0.0, "C z = 0 at the residual's rows");
                a.extra[row] = sign * f * e.tol_f;
            }
        });
    }
}

/// The displacement check cannot refuse an answer by itself: `τ_dz >= ‖C⁻¹‖∞ τ_f`, and
/// `‖C⁻¹ρ‖∞ <= ‖C⁻¹‖∞ ‖ρ‖∞`, so past its bound stationarity, checked first, has already failed.
/// With slack 0, `r = 0` and `‖C‖∞‖C⁻¹‖∞` large, `τ_dz` is `‖C⁻¹‖∞ τ_f` to below `DELTA`: a
/// residual along the signs of `C⁻¹`'s largest row brings the displacement to its bound with
/// stationarity inside, so the audit's displacement ratio is held to the documented one at the
/// edge (within `AGREEMENT`), and just past it the answer is refused (by stationarity).
#[test]
fn stationarity_in_displacement() {
    let body = body();
    let n = body.z.len();
    let top = (0..n)
        .max_by(|&p, &q| {
            let sum = |i: usize| body.c_inv.row(i).iter().map(|v| v.abs()).sum::<f64>();
            sum(p).total_cmp(&sum(q))
        })
        .expect("C has rows");
    let signs: Vec<f64> = body.c_inv.row(top).iter().map(|v| v.signum()).collect();
    for case in CASES.iter().filter(|c| c.osqp.is_none()) {
        let mut a = base(&body, case);
        a.r.fill(0.0);
        for k in 0..M {
            a.activate(&body, k);
        }
        let checks = (Check::Displacement, Check::Stationarity);
        bracket(
            &body,
            case,
            checks,
            "residual along C⁻¹'s largest row",
            &a,
            |a, f, e| {
                // The residual is `extra` up to the rounding of `b` where `C z ≠ 0`: rescale by the
                // measured ratio.
                let (v, ratio) = (amax(&a.extra), e.checks[Check::Displacement as usize]);
                let v = if v == 0.0 {
                    f * e.tol_dz / body.inv_norm
                } else {
                    v * f * ratio.1 / ratio.0
                };
                for (x, s) in a.extra.iter_mut().zip(&signs) {
                    *x = s * v;
                }
            },
        );
    }
}

/// A non-finite `z`, normal or tangential reaction is refused before any check.
#[test]
fn non_finite_answers() {
    let body = body();
    for case in &CASES {
        let a = base(&body, case);
        let e = evaluate(&body, case, &a);
        for (what, value) in [("z", f64::NAN), ("r_N", f64::INFINITY), ("r_T", f64::NAN)] {
            let mut bad = a.clone();
            match what {
                "z" => bad.z[0] = value,
                "r_N" => bad.r[0] = value,
                _ => bad.r[M + P - 1] = value,
            }
            let (_, verdict) = audit(&body, case, &bad, &e);
            assert!(
                matches!(verdict, Err(StepFailure::NonFinite)),
                "{}: {what} = {value}: {verdict:?}",
                case.name
            );
        }
    }
}
