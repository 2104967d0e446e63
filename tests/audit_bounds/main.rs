//! The audit's bounds at their edges: for each check of `step::audit`, under each law and each
//! way a solver calls it, an answer at `(1 − DELTA)` times the check's tolerance is accepted and
//! one at `(1 + DELTA)` is refused by that check, so that a loosened or mis-scaled bound fails.
//! Cases: OSQP's Signorini answers on the bar's tridiagonal and the plane's sparse `C`; the
//! penalty law and Signorini at round-off on the bar's matrix (tridiagonal and sparse); on a
//! frictional plane, the exact solver's Coulomb answers (the start-up step's among them, `w = 0`)
//! and OSQP's Tresca answers, accurate and inaccurate.
//! Each tolerance is computed here from the documented formulas (docs/step-solvers.md, "KKT
//! audit"; docs/friction.md, "Audit") on dense copies of `C` and `C⁻¹` (nalgebra), never read
//! from the audit. `b = C z − Eᵀ r − extra` makes the residual `extra`; every other check stays
//! far inside; answers are placed by a fixed-point iteration (the bounds move with the norms).

mod bodies;
#[path = "../common/mod.rs"]
mod common;

use bodies::*;

use common::{amax, inf_norm, ratio};
use nalgebra::{DMatrix, DVector};
use viscobar::internals::linalg::SymTridiag;
use viscobar::internals::linalg::sparse::Pattern;
use viscobar::internals::linalg::system::{
    SparseSystem, SpdSystem, TridiagSystem, inverse_norm_estimate,
};
use viscobar::internals::plane::matrices::{Material, assemble};
use viscobar::internals::plane::mesh::Grid;
use viscobar::step::audit::{KktAudit, Slack};
use viscobar::step::law::{Law, LawFamily, Slip};
use viscobar::step::report::{AuditReport, StepFailure};
use viscobar::step::solver::{Constraints, Friction};

/// Answers sit at `(1 ∓ DELTA)` times a tolerance: far above round-off (1e-12), below any
/// mis-scaling worth catching (0.1 %).
const DELTA: f64 = 1e-3;
/// An answer is placed at its ratio to a tenth of `DELTA` (dyadic answers round by about 2e-6).
const PLACEMENT: f64 = 1e-4;
/// Rounds of the placement: a bound moves by at most 1e-5 times the placed quantity.
const PLACEMENT_ROUNDS: usize = 4;
/// The audit's ratios agree with these to a tenth of `DELTA`: the same formulas on the same data,
/// Hager's `‖C⁻¹‖∞` exact (bar, `HAGER_EXACT`) or below `HAGER_SHARE` of the bound (plane).
const AGREEMENT: f64 = 1e-4;
/// Bound on `‖C⁻¹‖∞ floor_f / tol_dz` in OSQP's Signorini answers, so Hager's may fall short.
const HAGER_SHARE: f64 = 1e-5;
/// Hager's estimate against the dense `‖C⁻¹‖∞` on the frictional body: round-off.
const HAGER_EXACT: f64 = 1e-12;
/// Every check but the one under test stays below half its tolerance: a verdict is that check's.
const FAR_INSIDE: f64 = 0.5;
/// `AUDIT_MARGIN` as documented: the audit applies OSQP's `eps` times ten.
const MARGIN: f64 = 10.0;
/// `INACCURATE_FACTOR` as documented: an answer accepted as inaccurate gets ten times more.
const INACCURATE: f64 = 10.0;
/// `TridiagSystem::roundoff_ulps` as documented (a row's rounding and the solve's, margin three).
const TRIDIAG_ULPS: f64 = 32.0;
/// `SparseSystem::roundoff_ulps` as documented (18-term rows and the sparse solve, margin two).
const SPARSE_ULPS: f64 = 64.0;
/// OSQP's tolerances: distinct (a swapped term moves a bound), above the floors' `HAGER_SHARE`.
const EPS_ABS: f64 = 1e-7;
const EPS_REL: f64 = 1e-6;
/// OSQP's default `eps_abs` and `eps_rel` (`OSQP_DEFAULT_EPS`), which the Tresca solver runs with.
const OSQP_EPS: f64 = 1e-10;

/// The audit's checks, in its order, by index: their names under a normal and a frictional law.
const PRIMAL: usize = 0;
const NEGATIVE: usize = 1;
const COMPLEMENTARITY: usize = 2;
const PENALTY_LAW: usize = 3;
const CONE: usize = 4;
const SLIP: usize = 5;
const STATIONARITY: usize = 6;
const DISPLACEMENT: usize = 7;
const NAMES: [[&str; 2]; 8] = [
    ["primal violation (lo_k - s_k z_k)+"; 2],
    ["negative reaction (-r_k)+", "negative reaction (-r_N)+"],
    [
        "complementarity |r_k (s_k z_k - lo_k)|",
        "complementarity |r_N (s_k z_k - lo_k)|",
    ],
    ["penalty law |eps r_k - (lo_k - s_k z_k)+|"; 2],
    ["friction cone (|r_T| - mu r_N)+"; 2],
    ["slip law |mu r_N |delta| + r_T delta|"; 2],
    ["stationarity |Cz - b - r|", "stationarity |Cz - b - E^T r|"],
    [
        "stationarity in displacement |C^-1 (Cz - b - r)|",
        "stationarity in displacement |C^-1 (Cz - b - E^T r)|",
    ],
];

/// The worst ratio the audit's report holds for each check (`None` when the law omits it).
fn reported(r: &AuditReport) -> [Option<f64>; 8] {
    let (ng, st, dz) = (
        r.negative_reaction,
        r.stationarity,
        r.stationarity_displacement,
    );
    let (pr, co, pe) = (r.primal_violation, r.complementarity, r.penalty_law);
    let [ng, st, dz] = [ng, st, dz].map(Some);
    [pr, ng, co, pe, r.friction_cone, r.slip_law, st, dz].map(|w| w.map(|w| w.max_over_tolerance))
}

/// The law of a case, as the test states it (the thresholds `g_j` of friction).
#[derive(Clone, Copy, Debug)]
enum Kind {
    Signorini,
    Penalty(f64),
    Coulomb,
    Tresca(&'static [f64; P]),
}

/// The solver's stopping slack: none (an exact solver), OSQP's `eps` on the Signorini problem,
/// or OSQP's on a Tresca problem with its factor (`AUDIT_MARGIN`, times `INACCURATE_FACTOR`).
#[derive(Clone, Copy, Debug)]
enum Stop {
    Exact,
    Osqp,
    Tresca(f64),
}

/// One way a solver calls the audit (the exact or OSQP's, accurate or inaccurate); `previous`:
/// whether the law has a slip law (the frictional ones; the start-up step's is Coulomb's with
/// `w = 0`, a case of `COULOMB`'s).
#[derive(Clone, Copy, Debug)]
struct Case(&'static str, Kind, bool, Stop);

const SIGNORINI: Case = Case("OSQP", Kind::Signorini, false, Stop::Osqp);
const SIGNORINI_EXACT: Case = Case("round-off", Kind::Signorini, false, Stop::Exact);
const COULOMB: Case = Case("Coulomb", Kind::Coulomb, true, Stop::Exact);
const TRESCA: Case = Case("Tresca", Kind::Tresca(&GIVEN), true, Stop::Tresca(MARGIN));
const LATE: Stop = Stop::Tresca(MARGIN * INACCURATE);
const TRESCA_LATE: Case = Case("Tresca, inaccurate", Kind::Tresca(&GIVEN), true, LATE);
const FRICTION_CASES: [Case; 3] = [COULOMB, TRESCA, TRESCA_LATE];

fn penalty(epsilon: f64) -> Case {
    Case("penalty", Kind::Penalty(epsilon), false, Stop::Exact)
}

impl Case {
    fn frictional(&self) -> bool {
        matches!(self.1, Kind::Coulomb | Kind::Tresca(_))
    }

    fn previous(&self) -> bool {
        self.2
    }

    /// The law handed to the audit for answer `a`, and the family the audit is set up for.
    fn law<'a, S>(&self, body: &'a Body<S>, a: &'a Answer) -> (Law<'a>, LawFamily<'a>) {
        let slip = Slip {
            previous: &a.w,
            obstacle: &a.v,
        };
        let law = match self.1 {
            Kind::Signorini => Law::Signorini,
            Kind::Penalty(epsilon) => Law::Penalty { epsilon },
            Kind::Coulomb => Law::Coulomb { mu: &body.mu, slip },
            Kind::Tresca(g) => Law::Tresca {
                thresholds: g,
                slip,
            },
        };
        let family = match (self.1, &body.friction) {
            (Kind::Penalty(_), _) => LawFamily::Penalty,
            (Kind::Signorini, _) | (_, None) => LawFamily::Signorini,
            (_, Some(f)) => LawFamily::Frictional(f),
        };
        (law, family)
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
    /// The obstacle's tangential displacement `v_j` (a sliding obstacle's; zeros here).
    v: Vec<f64>,
    extra: Vec<f64>,
}

impl Answer {
    /// `δ_j = (z + w)_{t_j} − v_j`, as the audit rounds it.
    fn slip<S>(&self, body: &Body<S>, j: usize) -> f64 {
        self.z[body.rows[body.m + j].0] + self.w[j] - self.v[j]
    }

    /// Constraint `k` active (`lo_k = s_k z_{i_k}`).
    fn activate<S>(&mut self, body: &Body<S>, k: usize) {
        let (i, s) = body.rows[k];
        self.lo[k] = s * self.z[i];
    }

    /// The tangential reaction of node `j` that the case's law asks for (with the thresholds'
    /// positive part): `−g sign δ` where it slides, `g/2` where it sticks.
    fn settle<S>(&mut self, body: &Body<S>, case: &Case, j: usize) {
        let g = threshold(body, case, self, j).max(0.0);
        let delta = if case.previous() {
            self.slip(body, j)
        } else {
            0.0
        };
        self.r[body.m + j] = if delta == 0.0 {
            g / 2.0
        } else {
            -g * delta.signum()
        };
    }

    /// The tangential reactions of the frictional nodes of normal `k` settled again.
    fn settle_normal<S>(&mut self, body: &Body<S>, case: &Case, k: usize) {
        for j in (0..body.p).filter(|&j| FRICTIONAL[j] == k) {
            self.settle(body, case, j);
        }
    }
}

/// `g_j` of the answer under the case's law, as documented: `μ_j r_N,k_j`, given, or 0.
fn threshold<S>(body: &Body<S>, case: &Case, a: &Answer, j: usize) -> f64 {
    match case.1 {
        Kind::Coulomb => body.mu[j] * a.r[FRICTIONAL[j]],
        Kind::Tresca(g) => g[j],
        _ => 0.0,
    }
}

/// The round-off-level answers are exact in f64 (every value dyadic with few bits, sums without
/// rounding): their bounds are tens of ulps, so an answer rounded on the way would move by a few
/// percent of its bound. This `z` makes `(C z)_i` exactly 0 at both ends and at `FREE_NODE`
/// (`C_00 z_0 = 4 z_1`, `z_2 = −z_4`), where a tiny reaction or residual stays exact.
const EXACT_Z: [f64; BAR_NODES] = [
    0.5,
    0.5 + 1.0 / 512.0,
    0.375,
    0.0,
    -0.375,
    0.125,
    -0.5 - 1.0 / 512.0,
    -0.5,
];
const FREE_NODE: usize = 3;

/// The base answer of a case. Normal laws: every constraint active (`lo_k = s_k z_{i_k}`) under
/// a unit reaction, on `EXACT_Z` at the round-off level, the penalty law's springs compressed
/// by exactly `ε` (the law holds without rounding). Friction: the normals as `REACTIONS` and
/// `GAPS`, the tangential reactions by the case's law, `w = PREVIOUS`.
fn base<S>(body: &Body<S>, case: &Case) -> Answer {
    let friction = body.friction.is_some();
    let z = match case.3 {
        Stop::Exact if !friction => EXACT_Z.to_vec(),
        _ => body.z.clone(),
    };
    let (mut r, gaps) = match friction {
        true => (REACTIONS.to_vec(), GAPS.to_vec()),
        false => (vec![1.0; body.m], vec![0.0; body.m]),
    };
    r.resize(body.m + body.p, 0.0);
    let epsilon = if let Kind::Penalty(e) = case.1 {
        e
    } else {
        0.0
    };
    let lo = (body.rows[..body.m].iter().zip(gaps)).map(|(&(i, s), gap)| s * z[i] - gap + epsilon);
    let (lo, w, extra) = (
        lo.collect(),
        PREVIOUS[..body.p].to_vec(),
        vec![0.0; z.len()],
    );
    let v = vec![0.0; w.len()];
    let mut a = Answer {
        z,
        r,
        lo,
        w,
        v,
        extra,
    };
    for j in 0..body.p {
        a.settle(body, case, j);
    }
    a
}

/// The audit's quantities for one answer, from the documented formulas: `(value, tolerance)` of
/// each check, the right-hand side, the solver's slacks `(s_f, s_z)` as the Tresca solver passes
/// them, the force floor, the penalty law's bound of each constraint, and whether the recomputed
/// stationarity residual is `extra`, bit for bit.
struct Eval {
    checks: [(f64, f64); 8],
    tol: Tol,
    b: Vec<f64>,
    slack: (f64, f64),
    floor_f: f64,
    law_tol: Vec<f64>,
    exact: bool,
}

impl Eval {
    fn ratio(&self, check: usize) -> f64 {
        ratio(self.checks[check].0, self.checks[check].1)
    }
}

/// `τ_f`, `τ_z`, `τ_dz`.
struct Tol {
    f: f64,
    z: f64,
    dz: f64,
}

/// OSQP's stopping slack as the Tresca solver passes it (docs/friction.md, "Audit"):
/// `s_f = A (eps_abs + eps_rel ‖r‖∞)`, `s_z = A σ (eps_abs + eps_rel max(‖r‖∞, ‖q/σ‖∞))` with
/// `q = (s_k z⁰_{i_k} − lo_k, z⁰_{t_j} + w_j)`, `z⁰ = C⁻¹ b`.
fn tresca_slack<S>(body: &Body<S>, case: &Case, factor: f64, a: &Answer, b: &[f64]) -> (f64, f64) {
    let z0 = &body.c_inv * DVector::from_column_slice(b);
    let mut q = 0.0f64;
    for (k, &(i, s)) in body.rows.iter().enumerate() {
        let (lo, w) = match k.checked_sub(M) {
            None => (a.lo[k], 0.0),
            Some(j) => (0.0, if case.previous() { a.w[j] } else { 0.0 }),
        };
        q = q.max(((s * z0[i] + w - lo) / body.sigma).abs());
    }
    let r_norm = amax(&a.r);
    let eps = OSQP_EPS + OSQP_EPS * r_norm;
    let eps_q = OSQP_EPS + OSQP_EPS * r_norm.max(q);
    (factor * eps, factor * body.sigma * eps_q.max(eps))
}

/// Keeps in `worst` the pair `(value, tolerance)` with the larger ratio.
fn keep(worst: &mut (f64, f64), pair: (f64, f64)) {
    if ratio(pair.0, pair.1) >= ratio(worst.0, worst.1) {
        *worst = pair;
    }
}

/// The audit's checks of `a` under `case`, computed independently (see the module doc).
fn evaluate<S>(body: &Body<S>, case: &Case, a: &Answer) -> Eval {
    let (n, m) = (a.z.len(), body.m);
    let cz = &body.c * DVector::from_column_slice(&a.z);
    let mut b: Vec<f64> = (0..n).map(|i| cz[i] - a.extra[i]).collect();
    for (k, &(i, s)) in body.rows.iter().enumerate() {
        b[i] -= s * a.r[k];
    }
    // The residual as recomputed from b, and its image in displacement.
    let mut residual = DVector::from_fn(n, |i, _| cz[i] - b[i]);
    for (k, &(i, s)) in body.rows.iter().enumerate() {
        residual[i] -= s * a.r[k];
    }
    let dz = &body.c_inv * &residual;
    let (cz_norm, b_norm, z_norm, r_norm) = (cz.amax(), amax(&b), amax(&a.z), amax(&a.r));
    let p_scale = (body.rows[..m].iter().zip(&a.lo))
        .fold(0.0f64, |s, (&(i, _), lo)| s.max(a.z[i].abs()).max(lo.abs()));
    // A sliding obstacle's displacements join the gaps' scale where the law has a slip.
    let slip_law = case.frictional() && case.previous();
    let p_scale = if slip_law {
        a.v.iter().fold(p_scale, |s, v| s.max(v.abs()))
    } else {
        p_scale
    };
    // The slack in force, displacement and gaps.
    let (e_a, e_r) = (MARGIN * EPS_ABS, MARGIN * EPS_REL);
    let (s_f, s_dz, s_z, slack) = match case.3 {
        Stop::Exact => (0.0, 0.0, 0.0, (0.0, 0.0)),
        Stop::Osqp => {
            let force = e_a + e_r * cz_norm.max(b_norm).max(r_norm);
            (force, e_a + e_r * z_norm, e_a + e_r * p_scale, (0.0, 0.0))
        }
        Stop::Tresca(factor) => {
            let slack = tresca_slack(body, case, factor, a, &b);
            (slack.0, slack.1, slack.1, slack)
        }
    };
    let ulp = body.ulps * f64::EPSILON;
    let floor_f = ulp * (body.c_norm * z_norm + b_norm + r_norm);
    let tol_f = s_f + floor_f;
    // τ_dz and τ_z: with friction also the rounding of the condensed problem's z.
    let (tol_dz, tol_z) = if case.frictional() {
        let r_sum: f64 = a.r.iter().map(|v| v.abs()).sum();
        let floor = body.inv_norm * (tol_f + ulp * r_sum) + ulp * z_norm;
        (floor + s_dz, floor + ulp * p_scale + s_z)
    } else {
        (s_dz + body.inv_norm * floor_f, s_z + ulp * p_scale)
    };
    let (mut primal, mut negative, mut comp, mut law) = (0.0f64, 0.0f64, (0.0, 0.0), (0.0, 0.0));
    let mut law_tol = vec![0.0; m];
    for (k, &(i, s)) in body.rows[..m].iter().enumerate() {
        let gap = s * a.z[i] - a.lo[k];
        negative = negative.max(-a.r[k]);
        let Kind::Penalty(epsilon) = case.1 else {
            primal = primal.max(-gap);
            let t = tol_z * a.r[k].abs() + tol_f * gap.abs();
            keep(&mut comp, ((a.r[k] * gap).abs(), t));
            continue;
        };
        let value = (epsilon * a.r[k] - (-gap).max(0.0)).abs();
        let coupled: f64 = (body.rows[..m].iter().zip(&a.r))
            .map(|(&(l, _), r)| body.c_inv[(i, l)].abs() * r.abs())
            .sum();
        // The reaction taken from stationarity when the spring 1/ε is stiffer than C_ii.
        let abs_row: f64 = (0..n).map(|l| (body.c[(i, l)] * a.z[l]).abs()).sum();
        let from_gap = body.c[(i, i)] >= 1.0 / epsilon;
        let row = if from_gap { 0.0 } else { abs_row + b[i].abs() };
        law_tol[k] = ulp
            * (a.z[i].abs() + coupled + a.lo[k].abs() + (epsilon * a.r[k]).abs() + epsilon * row);
        keep(&mut law, (value, law_tol[k]));
    }
    let (mut cone, mut slip) = ((0.0, 0.0), (0.0, 0.0));
    for j in 0..body.p {
        let (g, rt) = (threshold(body, case, a, j), a.r[m + j]);
        keep(&mut cone, ((rt.abs() - g).max(0.0), tol_f + ulp * g.abs()));
        if case.previous() {
            let delta = a.slip(body, j);
            let t = tol_f * delta.abs()
                + (tol_z + ulp * (a.w[j].abs() + a.v[j].abs())) * (g.abs() + rt.abs());
            keep(&mut slip, ((g * delta.abs() + rt * delta).abs(), t));
        }
    }
    let (stationarity, displacement) = ((residual.amax(), tol_f), (dz.amax(), tol_dz));
    let exact = residual.iter().zip(&a.extra).all(|(x, y)| x == y);
    let (pr, ng) = ((primal, tol_z), (negative, tol_f));
    let checks = [pr, ng, comp, law, cone, slip, stationarity, displacement];
    let tol = Tol {
        f: tol_f,
        z: tol_z,
        dz: tol_dz,
    };
    Eval {
        checks,
        tol,
        b,
        slack,
        floor_f,
        law_tol,
        exact,
    }
}

/// The audit's verdict on `a`, from a fresh audit as the solvers set it up.
fn audit<S: SpdSystem>(
    body: &Body<S>,
    case: &Case,
    a: &Answer,
    e: &Eval,
) -> (KktAudit, Result<(), StepFailure>) {
    let mut system = (body.system)(&body.c);
    let (law, family) = case.law(body, a);
    let mut audit = KktAudit::new(&mut system, &body.constraints, family);
    let slack = match case.3 {
        Stop::Exact => Slack::NONE,
        Stop::Osqp => Slack::Osqp {
            eps_abs: EPS_ABS,
            eps_rel: EPS_REL,
        },
        Stop::Tresca(_) => Slack::Bounds {
            force: e.slack.0,
            displacement: e.slack.1,
        },
    };
    let verdict = audit.check(&mut system, law, slack, &e.b, &a.lo, &a.z, &a.r);
    (audit, verdict)
}

/// Places `base` at `(1 − DELTA)` and at `(1 + DELTA)` times the tolerance of `placed` with
/// `place(answer, factor, evaluation)`, and requires the audit to accept the first and to refuse
/// the second by `refused` (`placed` but for the frictional displacement check); then that the
/// audit's ratios are the documented ones.
fn bracket<S: SpdSystem>(
    (body, case, label): (&Body<S>, &Case, &str),
    (placed, refused): (usize, usize),
    base: &Answer,
    place: impl Fn(&mut Answer, f64, &Eval),
) {
    let frictional = case.frictional();
    let [placed_name, name] = [placed, refused].map(|c| NAMES[c][usize::from(frictional)]);
    let [inside, outside] = [1.0 - DELTA, 1.0 + DELTA].map(|f| {
        let at = format!("{}, {} ({label}): {placed_name} at {f}", body.name, case.0);
        let mut a = base.clone();
        for _ in 0..PLACEMENT_ROUNDS {
            let e = evaluate(body, case, &a);
            place(&mut a, f, &e);
        }
        let e = evaluate(body, case, &a);
        let off = (e.ratio(placed) - f).abs();
        assert!(off <= PLACEMENT, "{at}: placed off by {off}");
        for c in (0..8).filter(|&c| c != placed && c != refused) {
            let (r, what) = (e.ratio(c), NAMES[c][0]);
            assert!(r <= FAR_INSIDE, "{at}: {what} at {r}");
        }
        // The normal laws' answers: exact at round-off, Hager's share small otherwise.
        let share = body.inv_norm * e.floor_f / e.tol.dz;
        match (frictional, case.3) {
            (true, _) => {}
            (false, Stop::Exact) => assert!(e.exact, "{at}: the answer is not exact"),
            (false, _) => assert!(share <= HAGER_SHARE, "{at}: floor share {share:e}"),
        }
        let (audit, verdict) = audit(body, case, &a, &e);
        (at, e, audit, verdict)
    });
    if let Err(err) = &inside.3 {
        panic!("{}: refused: {err}", inside.0);
    }
    let Err(StepFailure::AuditFailed {
        what,
        value,
        tolerance,
    }) = outside.3
    else {
        panic!("{}: not refused by `{name}`: {:?}", outside.0, outside.3);
    };
    assert_eq!(what, name, "{}: refused by another check", outside.0);
    for (c, reported) in reported(inside.2.report()).into_iter().enumerate() {
        if let Some(reported) = reported {
            let (at, expected) = (&inside.0, inside.1.ratio(c));
            let off = (reported - expected).abs();
            assert!(
                off <= AGREEMENT,
                "{at}: {} ratio {reported}, not {expected}",
                NAMES[c][0]
            );
        }
    }
    let (v, t) = outside.1.checks[refused];
    let off = (tolerance / t - 1.0).abs().max((value / v - 1.0).abs());
    let at = &outside.0;
    assert!(
        off <= AGREEMENT,
        "{at}: {value:e} against {tolerance:e}, not {v:e} against {t:e}"
    );
}

/// For each constraint `k` of each case: primal violation (`k` inactive, `r_k = 0`, its node's
/// `r_T` by the law, its bound raised past `s_k z_{i_k}` by the violation); negative reaction
/// (`k` of `prepare`'s answer active with the reaction `−v`; under Coulomb its node's `r_T = 0`,
/// the threshold `μ r_N` being negative); complementarity (`k` pressed, `r > 0`, at a gap `g`:
/// `r g = f (τ_z r + τ_f g)`, both with `r` of order 1 and with `g` of order 1).
fn normal_checks<S: SpdSystem>(
    body: &Body<S>,
    cases: &[Case],
    checks: &[usize],
    prepare: impl Fn(&mut Answer, usize),
) {
    for case in cases {
        for k in 0..body.m {
            let (i, s) = body.rows[k];
            let label = format!("constraint {k}, s = {s}");
            let at = (body, case, label.as_str());
            let mut a = base(body, case);
            if checks.contains(&PRIMAL) {
                a.r[k] = 0.0;
                a.settle_normal(body, case, k);
                bracket(at, (PRIMAL, PRIMAL), &a, |a, f, e| {
                    a.lo[k] = s * a.z[i] + f * e.tol.z
                });
            }
            if checks.contains(&NEGATIVE) {
                let mut a = base(body, case);
                prepare(&mut a, k);
                bracket(at, (NEGATIVE, NEGATIVE), &a, |a, f, e| {
                    a.r[k] = -f * e.tol.f;
                    a.settle_normal(body, case, k);
                });
            }
            if checks.contains(&COMPLEMENTARITY) {
                let mut a = base(body, case);
                if a.r[k] == 0.0 {
                    a.r[k] = PRESSED;
                    a.settle_normal(body, case, k);
                }
                bracket(at, (COMPLEMENTARITY, COMPLEMENTARITY), &a, |a, f, e| {
                    let r = a.r[k];
                    a.lo[k] = s * a.z[i] - f * e.tol.z * r / (r - f * e.tol.f);
                });
                // Inactive at a gap `G` under a small reaction: `r G = f (τ_z r + τ_f G)`.
                let (mut a, gap) = (base(body, case), 0.25);
                a.lo[k] = s * a.z[i] - gap;
                bracket(at, (COMPLEMENTARITY, COMPLEMENTARITY), &a, |a, f, e| {
                    a.r[k] = f * e.tol.f * gap / (gap - f * e.tol.z);
                    a.settle_normal(body, case, k);
                });
            }
        }
    }
}

const ALL_NORMAL: [usize; 3] = [PRIMAL, NEGATIVE, COMPLEMENTARITY];

#[test]
fn primal_violation_negative_reaction_and_complementarity() {
    normal_checks(&bar(), &[SIGNORINI], &ALL_NORMAL, |_, _| {});
    normal_checks(&plane(), &[SIGNORINI], &ALL_NORMAL, |_, _| {});
    let friction = friction_plane();
    normal_checks(&friction, &FRICTION_CASES, &ALL_NORMAL, |a, k| {
        a.activate(&friction, k)
    });
}

/// At round-off a negative reaction is bounded by the force floor `floor_f` (64 ulps on the
/// sparse system): a reaction `−v` at an end whose row of `C z` is exactly 0; for the penalty law
/// with the constraint inactive (gap ¼).
#[test]
fn negative_reaction_at_round_off() {
    let bar = bar();
    normal_checks(&bar, &[SIGNORINI_EXACT], &[NEGATIVE], |_, _| {});
    normal_checks(&sparse_bar(), &[SIGNORINI_EXACT], &[NEGATIVE], |_, _| {});
    normal_checks(&bar, &[penalty(STIFF_SPRINGS)], &[NEGATIVE], |a, k| {
        a.lo[k] -= STIFF_SPRINGS + 0.25;
        a.r[k] = 0.0;
    });
}

/// Penalty parameters: `1/ε` softer than the bar's end entry `C_00 = 4 + 1/64` (reaction taken
/// from the gap) and stiffer (from stationarity, whose row adds to the law's bound). Powers of
/// two, so that `ε r` is exact.
const SOFT_SPRINGS: f64 = 0.5;
const STIFF_SPRINGS: f64 = 1.0 / 64.0;

/// The penalty law `|ε r_k − (lo_k − s_k z_{i_k})⁺|` at its bound: constraint `k` sits at
/// `s z = 2⁻¹⁰` with `ε r_k = 2⁻¹¹` and its bound raised to `s z + ε r_k − v`, so that the
/// gap, the compression and the law's value are exact differences of nearby dyadic numbers
/// (Sterbenz) and `v` is resolved to about 2e-6 of itself; the other constraint's unit
/// reaction, coupled through `C⁻¹`, sets most of the bound.
#[test]
fn penalty_law() {
    let bar = bar();
    for epsilon in [SOFT_SPRINGS, STIFF_SPRINGS] {
        for k in 0..bar.m {
            let (i, s) = bar.rows[k];
            let mut a = base(&bar, &penalty(epsilon));
            a.z[i] = s / 1024.0;
            a.r[k] = 1.0 / 2048.0 / epsilon;
            a.lo[k] = s * a.z[i] + epsilon * a.r[k];
            let label = format!("epsilon = {epsilon}, constraint {k}, s = {s}");
            let at = (&bar, &penalty(epsilon), label.as_str());
            bracket(at, (PENALTY_LAW, PENALTY_LAW), &a, |a, f, e| {
                a.lo[k] = (s * a.z[i] + epsilon * a.r[k]) - f * e.law_tol[k];
            });
        }
    }
}

/// Node `j` sticking (`δ = 0`, so the slip law holds exactly) with `|r_T| = g + v` (signs
/// alternating over the nodes): `v = f (τ_f + ε'|g|)`. Under Coulomb node 2's normal is inactive
/// (`g = 0`); the others press.
#[test]
fn friction_cone() {
    let body = friction_plane();
    for case in &FRICTION_CASES {
        for j in 0..P {
            let mut a = base(&body, case);
            a.w[j] = -a.z[body.rows[M + j].0];
            let sign = if j % 2 == 0 { 1.0 } else { -1.0 };
            let label = format!("node {j}, sign {sign}");
            let at = (&body, case, label.as_str());
            bracket(at, (CONE, CONE), &a, |a, f, e| {
                let g = threshold(&body, case, a, j);
                let ulp = SPARSE_ULPS * f64::EPSILON;
                a.r[M + j] = sign * (g + f * (e.tol.f + ulp * g.abs()));
            });
        }
    }
}

/// Node `j` sliding (`δ = SLIPS[j]`, its normal pressed) with `r_T` short of the cone by `y`,
/// `r_T = −sign δ (g − y)`: the slip law's value is `y |δ|`, placed at `f` times
/// `τ_f |δ| + (τ_z + ε'(|w| + |v|))(|g| + |r_T|)`, on a fixed obstacle (`v = 0`) and on one
/// sliding by `v = 1/4` over the step.
#[test]
fn slip_law() {
    let body = friction_plane();
    for case in FRICTION_CASES.iter().filter(|c| c.previous()) {
        for (j, obstacle) in (0..P).flat_map(|j| [(j, 0.0), (j, 0.25)]) {
            let k = FRICTIONAL[j];
            let mut a = base(&body, case);
            if a.r[k] == 0.0 {
                a.r[k] = PRESSED;
                a.activate(&body, k);
            }
            let delta = SLIPS[j];
            a.v[j] = obstacle;
            a.w[j] = delta + obstacle - a.z[body.rows[M + j].0];
            assert_eq!(a.slip(&body, j), delta, "the slip is exact");
            a.settle(&body, case, j);
            let label = format!("node {j}, delta = {delta}, v = {obstacle}");
            let at = (&body, case, label.as_str());
            bracket(at, (SLIP, SLIP), &a, |a, f, e| {
                let g = threshold(&body, case, a, j);
                let ulp = SPARSE_ULPS * f64::EPSILON;
                let t = e.tol.f * delta.abs()
                    + (e.tol.z + ulp * (a.w[j].abs() + a.v[j].abs()))
                        * (g.abs() + a.r[M + j].abs());
                a.r[M + j] = -delta.signum() * (g - f * t / delta.abs());
            });
        }
    }
}

/// A residual `extra = v d` with `‖d‖∞ = 1`, placed at the force tolerance.
fn stationarity_on<S: SpdSystem>(body: &Body<S>, cases: &[Case], label: &str, d: &[f64]) {
    for case in cases {
        let (a, at) = (base(body, case), (body, case, label));
        bracket(at, (STATIONARITY, STATIONARITY), &a, |a, f, e| {
            for (x, y) in a.extra.iter_mut().zip(d) {
                *x = f * e.tol.f * y;
            }
        });
    }
}

/// `C w / ‖C w‖∞` along the stiff mode `w`.
fn stiff<S>(body: &Body<S>) -> Vec<f64> {
    let cw = &body.c * DVector::from_column_slice(&body.stiff);
    cw.iter().map(|y| y / cw.amax()).collect()
}

/// OSQP's answers: a residual along the stiff mode, whose displacement stays small. At round-off
/// (the penalty law, Signorini on the sparse system's 64 ulps) and with friction: a residual at
/// rows where `C z` is exactly 0, so that it is exact (the bar's `FREE_NODE`; `±1` at
/// `STIFF_ROWS`). The penalty answers' displacement check, `‖C⁻¹ ρ‖∞ <= ‖C⁻¹‖∞ floor_f`, cannot
/// fail while stationarity holds (Hager's estimate is exact for the bar's `C`).
#[test]
fn stationarity() {
    let (bar, plane) = (bar(), plane());
    stationarity_on(&bar, &[SIGNORINI], "stiff residual", &stiff(&bar));
    stationarity_on(&plane, &[SIGNORINI], "stiff residual", &stiff(&plane));
    let mut free = vec![0.0; BAR_NODES];
    free[FREE_NODE] = 1.0;
    stationarity_on(&bar, &[penalty(STIFF_SPRINGS)], "exact residual", &free);
    stationarity_on(&sparse_bar(), &[SIGNORINI_EXACT], "exact residual", &free);
    let body = friction_plane();
    let cz = &body.c * DVector::from_column_slice(&body.z);
    let mut d = vec![0.0; body.z.len()];
    for (i, j, sign) in STIFF_ROWS {
        assert_eq!(cz[dof(i, j, X)], 0.0, "C z = 0 at the residual's rows");
        d[dof(i, j, X)] = sign;
    }
    stationarity_on(&body, &FRICTION_CASES, "exact residual", &d);
}

/// OSQP's Signorini answers: a residual `extra = C d` with `d = v w` along the soft mode `w`: its
/// displacement is `d`, `‖d‖∞ = v`, while `‖C d‖∞ = v ‖C w‖∞` stays far below the force bound.
fn soft_residual<S: SpdSystem>(body: &Body<S>) {
    let cw = &body.c * DVector::from_column_slice(&body.soft);
    let (a, at) = (base(body, &SIGNORINI), (body, &SIGNORINI, "soft residual"));
    bracket(at, (DISPLACEMENT, DISPLACEMENT), &a, |a, f, e| {
        for (x, y) in a.extra.iter_mut().zip(cw.iter()) {
            *x = f * e.tol.dz * y;
        }
    });
}

/// With friction the displacement check cannot refuse an answer by itself: `τ_dz >= ‖C⁻¹‖∞ τ_f`,
/// and `‖C⁻¹ρ‖∞ <= ‖C⁻¹‖∞ ‖ρ‖∞`, so past its bound stationarity, checked first, has already
/// failed. With slack 0, `r = 0` and `‖C‖∞‖C⁻¹‖∞` large, `τ_dz` is `‖C⁻¹‖∞ τ_f` to below `DELTA`:
/// a residual along the signs of `C⁻¹`'s largest row brings the displacement to its bound with
/// stationarity inside, so the audit's displacement ratio is held to the documented one at the
/// edge (within `AGREEMENT`), and just past it the answer is refused (by stationarity).
#[test]
fn stationarity_in_displacement() {
    let bar = bar();
    let off = (bar.inv_norm * BAR_MASS - 1.0).abs();
    assert!(off <= 1e-12, "‖C⁻¹‖∞ = 1/m");
    soft_residual(&bar);
    soft_residual(&plane());
    let body = friction_plane();
    let row_sum = |i: usize| body.c_inv.row(i).iter().map(|v| v.abs()).sum::<f64>();
    let top = (0..body.z.len()).max_by(|&p, &q| row_sum(p).total_cmp(&row_sum(q)));
    let row = body.c_inv.row(top.expect("C has rows"));
    let signs: Vec<f64> = row.iter().map(|v| v.signum()).collect();
    for case in FRICTION_CASES.iter().filter(|c| matches!(c.3, Stop::Exact)) {
        let mut a = base(&body, case);
        a.r.fill(0.0);
        for k in 0..M {
            a.activate(&body, k);
        }
        let at = (&body, case, "residual along C⁻¹'s largest row");
        bracket(at, (DISPLACEMENT, STATIONARITY), &a, |a, f, e| {
            // The residual is `extra` up to the rounding of `b` where `C z ≠ 0`: rescale by the
            // measured ratio.
            let (v, (value, tol)) = (amax(&a.extra), e.checks[DISPLACEMENT]);
            let v = if v == 0.0 {
                f * tol / body.inv_norm
            } else {
                v * f * tol / value
            };
            for (x, s) in a.extra.iter_mut().zip(&signs) {
                *x = s * v;
            }
        });
    }
}

#[test]
fn hager_estimate_is_exact_on_the_frictional_body() {
    let body = friction_plane();
    let estimate = inverse_norm_estimate(&mut (body.system)(&body.c));
    let (error, norm) = ((estimate / body.inv_norm - 1.0).abs(), body.inv_norm);
    assert!(
        error <= HAGER_EXACT,
        "Hager's {estimate} against ‖C⁻¹‖∞ = {norm}"
    );
}

/// Each case's base answer satisfies its law: the audit accepts it with every ratio far inside,
/// and its report lists exactly the law's checks. A non-finite `z`, normal or last (with friction
/// tangential) reaction is refused before any check.
fn base_answers<S: SpdSystem>(body: &Body<S>, cases: &[Case]) {
    for case in cases {
        let a = base(body, case);
        let e = evaluate(body, case, &a);
        let at = format!("{}, {}", body.name, case.0);
        for (c, [what, _]) in NAMES.iter().enumerate() {
            assert!(e.ratio(c) <= FAR_INSIDE, "{at}: {what}");
        }
        let (checked, verdict) = audit(body, case, &a, &e);
        verdict.unwrap_or_else(|err| panic!("{at}: {err}"));
        let (penalty, friction) = (matches!(case.1, Kind::Penalty(_)), case.frictional());
        let (normal, all) = (!penalty, true);
        let listed = [normal, all, normal, penalty, friction, friction, all, all];
        let reported = reported(checked.report()).map(|r| r.is_some());
        assert_eq!(reported, listed, "{at}: the checks the report lists");
        for what in 0..3 {
            let mut bad = a.clone();
            match what {
                0 => bad.z[0] = f64::NAN,
                1 => bad.r[0] = f64::INFINITY,
                _ => *bad.r.last_mut().expect("reactions") = f64::NAN,
            }
            let verdict = audit(body, case, &bad, &e).1;
            let refused = matches!(verdict, Err(StepFailure::NonFinite));
            assert!(refused, "{at}: {verdict:?}");
        }
    }
}

#[test]
fn base_answers_are_accepted_and_non_finite_ones_refused() {
    let penalties = [penalty(SOFT_SPRINGS), penalty(STIFF_SPRINGS)];
    base_answers(&bar(), &[SIGNORINI, SIGNORINI_EXACT]);
    base_answers(&bar(), &penalties);
    base_answers(&sparse_bar(), &[SIGNORINI_EXACT]);
    base_answers(&plane(), &[SIGNORINI]);
    base_answers(&friction_plane(), &FRICTION_CASES);
}
