//! The audit's bounds, checked at their edges: for each check of `step::audit` under each law and
//! each way a solver calls it, an answer whose checked value is `(1 − DELTA)` times the check's
//! tolerance is accepted and one at `(1 + DELTA)` is refused by that check, so that a loosened or
//! mis-scaled bound fails. The cases: OSQP's Signorini answers (tolerances with `AUDIT_MARGIN`)
//! on the bar's tridiagonal `C` and the plane body's sparse `C`; the penalty law and Signorini at
//! the round-off floors on the bar's matrix (tridiagonal and sparse); on a frictional plane body
//! the exact solver's Coulomb and frictionless start-up answers (slack 0) and OSQP's Tresca
//! answers (its stopping slack, also inaccurate).
//!
//! Each expected tolerance is computed here from the documented formulas (docs/step-solvers.md,
//! "KKT audit"; docs/friction.md, "Audit"; the systems' `roundoff_ulps` as documented) on
//! independent dense copies of `C` and `C⁻¹` (nalgebra), never read back from the audit.
//! Stationarity holds by construction, `b = C z − Eᵀ r − extra` (`extra` the residual placed by
//! the stationarity tests), and every check but the one under test stays far inside its bound;
//! the bounds depend on the answer's norms, so each answer is placed by a fixed-point iteration
//! and its ratio re-measured before it is audited. Constraints push both ways, `s = ±1`.

mod common;

use common::{amax, inf_norm, ratio};
use nalgebra::{DMatrix, DVector};
use viscobar::linalg::SymTridiag;
use viscobar::linalg::sparse::Pattern;
use viscobar::linalg::system::{SparseSystem, SpdSystem, TridiagSystem, inverse_norm_estimate};
use viscobar::plane::matrices::{Material, assemble};
use viscobar::plane::mesh::Grid;
use viscobar::step::audit::{KktAudit, Slack};
use viscobar::step::law::{Law, LawFamily, Slip};
use viscobar::step::report::{AuditReport, StepFailure};
use viscobar::step::solver::{Constraints, Friction};

/// Answers sit at `(1 ∓ DELTA)` times a tolerance: far beyond the round-off of evaluating the
/// formula twice (about 1e-12 relative), close enough that any mis-scaling of a bound by more
/// than 0.1 % turns one of the two verdicts.
const DELTA: f64 = 1e-3;
/// An answer is placed at its intended ratio to within a tenth of `DELTA` (the fixed point
/// converges; the dyadic penalty answers round their bound `lo` by about 2e-6 of their value,
/// the frictional ones round to ulps of the thresholds and gaps they sit next to).
const PLACEMENT: f64 = 1e-4;
/// Rounds of the placement's fixed-point iteration: a bound moves with the placed quantity by at
/// most `10·EPS_REL` = 1e-5 times it (through the norms), so each round divides the error by 1e5.
const PLACEMENT_ROUNDS: usize = 4;
/// The audit's own ratios (its report and its error) agree with the independent ones to a tenth
/// of `DELTA`: the same formulas in f64 from the same data; the only other difference, Hager's
/// estimate of `‖C⁻¹‖∞` (a lower bound), is exact for the bar's M-matrix and on the frictional
/// body (to `HAGER_EXACT`), and weighs less than `HAGER_SHARE` of the displacement tolerance in
/// the plane's Signorini answers.
const AGREEMENT: f64 = 1e-4;
/// Bound on `‖C⁻¹‖∞ floor_f / tol_dz` in OSQP's Signorini answers (asserted), so that Hager's
/// estimate falling short of the true norm cannot move the displacement bound by `AGREEMENT`.
const HAGER_SHARE: f64 = 1e-5;
/// Hager's estimate against the dense `‖C⁻¹‖∞` on the frictional body, relative: a few hundred
/// ulps of round-off.
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
/// OSQP's tolerances for the Signorini answers: distinct, so that swapping or dropping either
/// term of a bound moves it by more than `DELTA`; large enough that the round-off floors stay
/// below `HAGER_SHARE` of each bound (the round-off-level answers test the force floors alone).
const EPS_ABS: f64 = 1e-7;
const EPS_REL: f64 = 1e-6;
/// OSQP's default `eps_abs` and `eps_rel` (`OSQP_DEFAULT_EPS`), which the Tresca solver runs with.
const OSQP_EPS: f64 = 1e-10;

/// The audit's checks, in its order.
#[derive(Clone, Copy, Debug, PartialEq)]
enum Check {
    Primal,
    Negative,
    Complementarity,
    PenaltyLaw,
    Cone,
    Slip,
    Stationarity,
    Displacement,
}

const CHECKS: [Check; 8] = [
    Check::Primal,
    Check::Negative,
    Check::Complementarity,
    Check::PenaltyLaw,
    Check::Cone,
    Check::Slip,
    Check::Stationarity,
    Check::Displacement,
];

impl Check {
    /// The name the audit gives the check in `StepFailure::AuditFailed`, under a normal or a
    /// frictional law.
    fn what(self, frictional: bool) -> &'static str {
        match (self, frictional) {
            (Check::Primal, _) => "primal violation (lo_k - s_k z_k)+",
            (Check::Negative, false) => "negative reaction (-r_k)+",
            (Check::Negative, true) => "negative reaction (-r_N)+",
            (Check::Complementarity, false) => "complementarity |r_k (s_k z_k - lo_k)|",
            (Check::Complementarity, true) => "complementarity |r_N (s_k z_k - lo_k)|",
            (Check::PenaltyLaw, _) => "penalty law |eps r_k - (lo_k - s_k z_k)+|",
            (Check::Cone, _) => "friction cone (|r_T| - mu r_N)+",
            (Check::Slip, _) => "slip law |mu r_N |delta| + r_T delta|",
            (Check::Stationarity, false) => "stationarity |Cz - b - r|",
            (Check::Stationarity, true) => "stationarity |Cz - b - E^T r|",
            (Check::Displacement, false) => "stationarity in displacement |C^-1 (Cz - b - r)|",
            (Check::Displacement, true) => "stationarity in displacement |C^-1 (Cz - b - E^T r)|",
        }
    }

    /// The worst ratio the audit's report holds for the check (`None` when the law omits it).
    fn reported(self, report: &AuditReport) -> Option<f64> {
        let worst = match self {
            Check::Primal => report.primal_violation,
            Check::Negative => Some(report.negative_reaction),
            Check::Complementarity => report.complementarity,
            Check::PenaltyLaw => report.penalty_law,
            Check::Cone => report.friction_cone,
            Check::Slip => report.slip_law,
            Check::Stationarity => Some(report.stationarity),
            Check::Displacement => Some(report.stationarity_displacement),
        };
        worst.map(|w| w.max_over_tolerance)
    }
}

/// The law of a case, as the test states it (the thresholds `g_j` of friction).
#[derive(Clone, Copy, Debug)]
enum Kind {
    Signorini,
    Penalty(f64),
    Frictionless,
    Coulomb,
    Tresca(&'static [f64; P]),
}

/// The solver's stopping slack: none (an exact solver), OSQP's `eps` on the Signorini problem,
/// or OSQP's on a Tresca problem with its factor (`AUDIT_MARGIN`, times `INACCURATE_FACTOR`).
#[derive(Clone, Copy, Debug)]
enum Stop {
    Exact,
    Osqp { eps_abs: f64, eps_rel: f64 },
    Tresca(f64),
}

/// One way a solver calls the audit.
#[derive(Clone, Copy, Debug)]
struct Case {
    name: &'static str,
    kind: Kind,
    /// Whether the previous increment is known (no slip law at the start-up step).
    previous: bool,
    stop: Stop,
}

impl Case {
    fn frictional(&self) -> bool {
        matches!(
            self.kind,
            Kind::Frictionless | Kind::Coulomb | Kind::Tresca(_)
        )
    }

    fn family<'a>(&self, friction: &'a Option<Friction>) -> LawFamily<'a> {
        match (self.kind, friction) {
            (Kind::Penalty(_), _) => LawFamily::Penalty,
            (Kind::Signorini, _) => LawFamily::Signorini,
            (_, Some(f)) => LawFamily::Frictional(f),
            (_, None) => panic!("{}: a frictional law on a body without friction", self.name),
        }
    }

    /// The law handed to the audit for answer `a`.
    fn law<'a>(&self, body_mu: &'a [f64], a: &'a Answer) -> Law<'a> {
        let slip = Slip { previous: &a.w };
        match self.kind {
            Kind::Signorini => Law::Signorini,
            Kind::Penalty(epsilon) => Law::Penalty { epsilon },
            Kind::Frictionless => Law::Frictionless,
            Kind::Coulomb => Law::Coulomb { mu: body_mu, slip },
            Kind::Tresca(g) => Law::Tresca {
                thresholds: g,
                slip: self.previous.then_some(slip),
            },
        }
    }

    /// Whether the bounds are round-off floors only.
    fn roundoff_level(&self) -> bool {
        matches!(self.stop, Stop::Exact)
    }
}

const SIGNORINI: Case = Case {
    name: "OSQP, Signorini",
    kind: Kind::Signorini,
    previous: false,
    stop: Stop::Osqp {
        eps_abs: EPS_ABS,
        eps_rel: EPS_REL,
    },
};
const SIGNORINI_EXACT: Case = Case {
    name: "Signorini at round-off",
    kind: Kind::Signorini,
    previous: false,
    stop: Stop::Exact,
};
fn penalty(epsilon: f64) -> Case {
    Case {
        name: "penalty",
        kind: Kind::Penalty(epsilon),
        previous: false,
        stop: Stop::Exact,
    }
}
const COULOMB: Case = Case {
    name: "exact solver, Coulomb",
    kind: Kind::Coulomb,
    previous: true,
    stop: Stop::Exact,
};
const START: Case = Case {
    name: "exact solver, start-up",
    kind: Kind::Frictionless,
    previous: false,
    stop: Stop::Exact,
};
const TRESCA: Case = Case {
    name: "OSQP, Tresca",
    kind: Kind::Tresca(&GIVEN),
    previous: true,
    stop: Stop::Tresca(MARGIN),
};
const TRESCA_START: Case = Case {
    name: "OSQP, start-up, inaccurate",
    kind: Kind::Tresca(&GIVEN_ZERO),
    previous: false,
    stop: Stop::Tresca(MARGIN * INACCURATE),
};
const FRICTION_CASES: [Case; 4] = [COULOMB, START, TRESCA, TRESCA_START];

/// A step matrix with its independent dense copies, the constraints (and frictional nodes) of
/// the answers, and the vectors the answers are built from.
struct Body<S> {
    name: &'static str,
    c: DMatrix<f64>,
    c_inv: DMatrix<f64>,
    /// `‖C‖∞` and `‖C⁻¹‖∞`, largest absolute row sums of the dense copies.
    c_norm: f64,
    inv_norm: f64,
    ulps: f64,
    constraints: Constraints,
    friction: Option<Friction>,
    /// `(i, s)` of every row of `E`: the normals, then the tangents (`s = +1`).
    rows: Vec<(usize, f64)>,
    /// `σ = max_k S_kk`, `S = E C⁻¹ Eᵀ`: the Tresca solver's scale.
    sigma: f64,
    /// The displacement of the answers.
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
        (constraints, friction): (Constraints, Option<Friction>),
        z: Vec<f64>,
        system: fn() -> S,
    ) -> Self {
        assert_eq!(c, c.transpose(), "{name}: C is symmetric");
        let c_inv = c.clone().try_inverse().expect("C is invertible");
        let all = friction
            .as_ref()
            .map_or_else(|| constraints.clone(), |f| f.rows(&constraints));
        let rows: Vec<(usize, f64)> = all.unknowns.into_iter().zip(all.directions).collect();
        let sigma = rows.iter().map(|&(i, _)| c_inv[(i, i)]).fold(0.0, f64::max);
        let (soft, stiff) = extreme_modes(&c);
        Self {
            name,
            c_norm: inf_norm(&c),
            inv_norm: inf_norm(&c_inv),
            c,
            c_inv,
            ulps,
            constraints,
            friction,
            rows,
            sigma,
            z,
            soft,
            stiff,
            system,
        }
    }
}

impl<S> Body<S> {
    fn m(&self) -> usize {
        self.constraints.len()
    }

    fn p(&self) -> usize {
        self.friction.as_ref().map_or(0, Friction::len)
    }

    fn mu(&self) -> &[f64] {
        self.friction.as_ref().map_or(&[], |f| &f.coefficients)
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

/// The dense copy of a matrix on a pattern.
fn dense(pattern: &Pattern, values: &[f64]) -> DMatrix<f64> {
    let mut c = DMatrix::zeros(pattern.n, pattern.n);
    for row in 0..pattern.n {
        for at in pattern.row_ptr[row]..pattern.row_ptr[row + 1] {
            c[(row, pattern.cols[at])] = values[at];
        }
    }
    c
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
fn bar_constraints() -> (Constraints, Option<Friction>) {
    let constraints = Constraints {
        unknowns: vec![0, BAR_NODES - 1],
        directions: vec![1.0, -1.0],
    };
    (constraints, None)
}

const BAR_Z: [f64; BAR_NODES] = [0.5, 0.625, 0.75, 0.8125, 0.75, 0.5, 0.125, -0.25];

/// The bar as the bar's solvers hold it, a `TridiagSystem`.
fn bar() -> Body<TridiagSystem> {
    let system = || TridiagSystem::new(&bar_matrix()).expect("C is positive definite");
    let (c, z) = (bar_dense(), BAR_Z.to_vec());
    Body::new("bar", c, TRIDIAG_ULPS, bar_constraints(), z, system)
}

/// The bar's matrix held as the plane body's solvers hold theirs, a `SparseSystem` on a
/// `Pattern`: its dyadic entries make the sparse system's round-off floors testable.
fn sparse_bar() -> Body<SparseSystem> {
    let system = || {
        let c = bar_dense();
        let (mut row_ptr, mut cols, mut values) = (vec![0], Vec::new(), Vec::new());
        for i in 0..BAR_NODES {
            for j in i.saturating_sub(1)..(i + 2).min(BAR_NODES) {
                cols.push(j);
                values.push(c[(i, j)]);
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
    let (c, z) = (bar_dense(), BAR_Z.to_vec());
    Body::new(
        "bar on a pattern",
        c,
        SPARSE_ULPS,
        bar_constraints(),
        z,
        system,
    )
}

/// The plane body: Q1 matrices on a grid of square cells (all degrees of freedom kept),
/// `C = M/Δt² + (½ + α/(2Δt)) K` as the plane's step matrix; a long step makes it soft along
/// the rigid translations, which `K` does not resist, and `‖C‖∞ ‖C⁻¹‖∞` large.
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

fn plane_matrix(grid: &Grid) -> (Pattern, Vec<f64>) {
    let m = assemble(grid, MATERIAL);
    let (a, b) = (1.0 / (DT * DT), 0.5 + VISCOSITY / (2.0 * DT));
    let values = (m.mass.iter().zip(&m.stiffness))
        .map(|(m, k)| a * m + b * k)
        .collect();
    (m.pattern, values)
}

/// The plane body on 2 × 2 cells of the unit square, with the bottom edge's middle node pushed
/// up (`u_y`, `s = +1`) and the top edge's middle node pushed down (`s = −1`).
fn plane_grid() -> Grid {
    Grid::new(1.0, 1.0, 2, 2, 1.0)
}

fn plane() -> Body<SparseSystem> {
    let grid = plane_grid();
    let (pattern, values) = plane_matrix(&grid);
    let z = (0..pattern.n)
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
    let constraints = Constraints {
        unknowns: vec![2 * grid.node(1, 0) + Y, 2 * grid.node(1, 2) + Y],
        directions: vec![1.0, -1.0],
    };
    let system = || {
        let (pattern, values) = plane_matrix(&plane_grid());
        SparseSystem::new(&pattern, &values, "C").expect("C is positive definite")
    };
    let c = dense(&pattern, &values);
    Body::new("plane", c, SPARSE_ULPS, (constraints, None), z, system)
}

/// The frictional plane body on 4 × 6 cells: the normal constraints `(i, j, s)` at `u_y` of node
/// `(i, j)`, three on the bottom edge pushed up, one on the top edge pushed down.
const NX: usize = 4;
const NY: usize = 6;
const M: usize = 4;
const NORMALS: [(usize, usize, f64); M] = [(0, 0, 1.0), (2, 0, 1.0), (4, 0, 1.0), (2, NY, -1.0)];
/// The frictional nodes: their normal constraint (the tangent is that node's `u_x`) and `μ`
/// (dyadic, so that `μ r_N` is exact; at most 3/8, so that a negative `r_N` leaves the cone and
/// the slip law of its node below `FAR_INSIDE`).
const P: usize = 3;
const FRICTIONAL: [usize; P] = [1, 2, 3];
const MU: [f64; P] = [0.25, 0.375, 0.25];
/// The nonzero entries of `z`, at nodes pairwise three cells apart (no row of `C` meets two of
/// them, so `C z` is exact and the audit's residual has the bits recomputed here): a free
/// interior unknown (`‖C‖∞ ‖z‖∞` dominates `τ_f`), the top normal's unknown (`s z ≠ 0`) and the
/// second tangent's (`δ = z_t + w`).
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

fn friction_grid() -> Grid {
    Grid::new(NX as f64 * 0.5, NY as f64 * 0.5, NX, NY, 1.0)
}

fn dof(i: usize, j: usize, axis: usize) -> usize {
    2 * friction_grid().node(i, j) + axis
}

fn friction_plane() -> Body<SparseSystem> {
    let (pattern, values) = plane_matrix(&friction_grid());
    let c = dense(&pattern, &values);
    let constraints = Constraints {
        unknowns: NORMALS.iter().map(|&(i, j, _)| dof(i, j, Y)).collect(),
        directions: NORMALS.iter().map(|&(.., s)| s).collect(),
    };
    let friction = Friction {
        normals: FRICTIONAL.to_vec(),
        tangents: (FRICTIONAL.iter())
            .map(|&k| dof(NORMALS[k].0, NORMALS[k].1, X))
            .collect(),
        coefficients: MU.to_vec(),
    };
    let mut z = vec![0.0; pattern.n];
    for (i, j, axis, v) in Z_ENTRIES {
        z[dof(i, j, axis)] = v;
    }
    for i in 0..pattern.n {
        let terms = (0..pattern.n).filter(|&l| c[(i, l)] != 0.0 && z[l] != 0.0);
        assert!(terms.count() <= 1, "row {i} of C meets two entries of z");
    }
    let system = || {
        let (pattern, values) = plane_matrix(&friction_grid());
        SparseSystem::new(&pattern, &values, "C").expect("C is positive definite")
    };
    let rows = (constraints, Some(friction));
    Body::new("frictional plane", c, SPARSE_ULPS, rows, z, system)
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
    fn slip<S>(&self, body: &Body<S>, j: usize) -> f64 {
        self.z[body.rows[body.m() + j].0] + self.w[j]
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
        let delta = if case.previous {
            self.slip(body, j)
        } else {
            0.0
        };
        self.r[body.m() + j] = if delta != 0.0 {
            -g * delta.signum()
        } else {
            g / 2.0
        };
    }

    /// The tangential reactions of the frictional nodes of normal `k` settled again.
    fn settle_normal<S>(&mut self, body: &Body<S>, case: &Case, k: usize) {
        for j in (0..body.p()).filter(|&j| FRICTIONAL[j] == k) {
            self.settle(body, case, j);
        }
    }
}

/// `g_j` of the answer under the case's law, as documented: `μ_j r_N,k_j`, given, or 0.
fn threshold<S>(body: &Body<S>, case: &Case, a: &Answer, j: usize) -> f64 {
    match case.kind {
        Kind::Coulomb => body.mu()[j] * a.r[FRICTIONAL[j]],
        Kind::Tresca(g) => g[j],
        _ => 0.0,
    }
}

/// The penalty answers are exact in f64 (every value dyadic with few bits, sums without
/// rounding): their bounds are round-off floors, tens of ulps, so an answer rounded on the way
/// would move by a few percent of its bound. This `z` makes `(C z)_i` exactly 0 at both ends and
/// at node 3 (`C_00 z_0 = 4 z_1`, `z_2 = −z_4`), where a tiny reaction or residual stays exact.
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
/// The node of the exact stationarity residual.
const FREE_NODE: usize = 3;

/// The base answer of a case. Normal laws: every constraint active (`lo_k = s_k z_{i_k}`) under
/// a unit reaction, at the round-off level on `EXACT_Z`, the penalty law's springs compressed by
/// exactly `ε` (the law holds without rounding). Friction: the normals as `REACTIONS` and `GAPS`,
/// the tangential reactions by the case's law, `w = PREVIOUS`.
fn base<S>(body: &Body<S>, case: &Case) -> Answer {
    let friction = body.friction.is_some();
    let z = match case.stop {
        Stop::Exact if !friction => EXACT_Z.to_vec(),
        _ => body.z.clone(),
    };
    let (mut r, gaps) = if friction {
        (REACTIONS.to_vec(), GAPS.to_vec())
    } else {
        (vec![1.0; body.m()], vec![0.0; body.m()])
    };
    r.resize(body.m() + body.p(), 0.0);
    let epsilon = if let Kind::Penalty(e) = case.kind {
        e
    } else {
        0.0
    };
    let mut a = Answer {
        lo: (body.rows[..body.m()].iter().zip(gaps))
            .map(|(&(i, s), gap)| s * z[i] - gap + epsilon)
            .collect(),
        extra: vec![0.0; z.len()],
        w: PREVIOUS[..body.p()].to_vec(),
        z,
        r,
    };
    for j in 0..body.p() {
        a.settle(body, case, j);
    }
    a
}

/// The audit's quantities for one answer, from the documented formulas.
struct Eval {
    b: Vec<f64>,
    /// The solver's slacks `(s_f, s_z)` as the Tresca solver passes them.
    slack: (f64, f64),
    tol_f: f64,
    tol_z: f64,
    tol_dz: f64,
    floor_f: f64,
    /// The penalty law's round-off bound of each constraint.
    law_tol: Vec<f64>,
    /// `(value, tolerance)` of each check, in the order of [`CHECKS`].
    checks: [(f64, f64); 8],
    /// Whether the recomputed stationarity residual is `extra`, bit for bit.
    exact: bool,
}

impl Eval {
    fn ratio(&self, check: Check) -> f64 {
        let (value, tolerance) = self.checks[check as usize];
        ratio(value, tolerance)
    }
}

/// OSQP's stopping slack as the Tresca solver passes it (docs/friction.md, "Audit"):
/// `s_f = A (eps_abs + eps_rel ‖r‖∞)`, `s_z = A σ (eps_abs + eps_rel max(‖r‖∞, ‖q/σ‖∞))` with
/// `q = (s_k z⁰_{i_k} − lo_k, z⁰_{t_j} + w_j)`, `z⁰ = C⁻¹ b`.
fn tresca_slack<S>(body: &Body<S>, case: &Case, factor: f64, a: &Answer, b: &[f64]) -> (f64, f64) {
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
fn evaluate<S>(body: &Body<S>, case: &Case, a: &Answer) -> Eval {
    let (n, m) = (a.z.len(), body.m());
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
    // The slack in force, displacement and gaps.
    let (s_f, s_dz, s_z, slack) = match case.stop {
        Stop::Exact => (0.0, 0.0, 0.0, (0.0, 0.0)),
        Stop::Osqp { eps_abs, eps_rel } => {
            let (e_a, e_r) = (MARGIN * eps_abs, MARGIN * eps_rel);
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
    // τ_dz and τ_z: with friction the rounding of the condensed problem's z (docs/friction.md).
    let (tol_dz, tol_z) = if case.frictional() {
        let r_sum: f64 = a.r.iter().map(|v| v.abs()).sum();
        let floor = body.inv_norm * (tol_f + ulp * r_sum) + ulp * z_norm;
        (floor + s_dz, floor + ulp * p_scale + s_z)
    } else {
        (s_dz + body.inv_norm * floor_f, s_z + ulp * p_scale)
    };
    let (mut primal, mut negative, mut comp, mut law) = (0.0f64, 0.0f64, (0.0, 0.0), (0.0, 0.0));
    let mut law_tol = vec![0.0; m];
    let keep = |worst: &mut (f64, f64), pair: (f64, f64)| {
        if ratio(pair.0, pair.1) >= ratio(worst.0, worst.1) {
            *worst = pair;
        }
    };
    for (k, &(i, s)) in body.rows[..m].iter().enumerate() {
        let gap = s * a.z[i] - a.lo[k];
        negative = negative.max(-a.r[k]);
        if let Kind::Penalty(epsilon) = case.kind {
            let value = (epsilon * a.r[k] - (-gap).max(0.0)).abs();
            let coupled: f64 = (body.rows[..m].iter().zip(&a.r))
                .map(|(&(l, _), r)| body.c_inv[(i, l)].abs() * r.abs())
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
            keep(&mut law, (value, law_tol[k]));
        } else {
            primal = primal.max(-gap);
            let t = tol_z * a.r[k].abs() + tol_f * gap.abs();
            keep(&mut comp, ((a.r[k] * gap).abs(), t));
        }
    }
    let (mut cone, mut slip) = ((0.0, 0.0), (0.0, 0.0));
    for j in 0..body.p() {
        let (g, rt) = (threshold(body, case, a, j), a.r[m + j]);
        keep(&mut cone, ((rt.abs() - g).max(0.0), tol_f + ulp * g.abs()));
        if case.previous {
            let delta = a.slip(body, j);
            let t = tol_f * delta.abs() + (tol_z + ulp * a.w[j].abs()) * (g.abs() + rt.abs());
            keep(&mut slip, ((g * delta.abs() + rt * delta).abs(), t));
        }
    }
    Eval {
        b,
        slack,
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
            law,
            cone,
            slip,
            (residual.amax(), tol_f),
            (dz.amax(), tol_dz),
        ],
    }
}

/// The audit's verdict on `a`, from a fresh audit as the solvers set it up.
fn audit<S: SpdSystem>(
    body: &Body<S>,
    case: &Case,
    a: &Answer,
    e: &Eval,
) -> (KktAudit, Result<(), StepFailure>) {
    let mut system = (body.system)();
    let mut audit = KktAudit::new(&mut system, &body.constraints, case.family(&body.friction));
    let slack = match case.stop {
        Stop::Exact => Slack::NONE,
        Stop::Osqp { eps_abs, eps_rel } => Slack::Osqp { eps_abs, eps_rel },
        Stop::Tresca(_) => Slack::Bounds {
            force: e.slack.0,
            displacement: e.slack.1,
        },
    };
    let law = case.law(body.mu(), a);
    let verdict = audit.check(&mut system, law, slack, &e.b, &a.lo, &a.z, &a.r);
    (audit, verdict)
}

/// Places `base` at `(1 − DELTA)` and at `(1 + DELTA)` times the tolerance of `placed` with
/// `place(answer, factor, evaluation)`, and requires the audit to accept the first and to refuse
/// the second by `refused` (`placed` but for the frictional displacement check); then that the
/// audit's ratios are the documented ones.
fn bracket<S: SpdSystem>(
    body: &Body<S>,
    case: &Case,
    (placed, refused): (Check, Check),
    label: &str,
    base: &Answer,
    place: impl Fn(&mut Answer, f64, &Eval),
) {
    let [inside, outside] = [1.0 - DELTA, 1.0 + DELTA].map(|f| {
        let at = format!(
            "{}, {} ({label}): {placed:?} at {f} × its tolerance",
            body.name, case.name
        );
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
        // The normal laws' answers: exact at round-off, Hager's share small otherwise.
        match (case.frictional(), case.roundoff_level()) {
            (true, _) => {}
            (false, true) => assert!(e.exact, "{at}: the round-off-level answer is not exact"),
            (false, false) => {
                let share = body.inv_norm * e.floor_f / e.tol_dz;
                assert!(share <= HAGER_SHARE, "{at}: floor share {share:e}");
            }
        }
        let (audit, verdict) = audit(body, case, &a, &e);
        (at, e, audit, verdict)
    });
    if let Err(err) = &inside.3 {
        panic!("{}: refused: {err}", inside.0);
    }
    let name = refused.what(case.frictional());
    let (what, value, tolerance) = match &outside.3 {
        Err(StepFailure::AuditFailed {
            what,
            value,
            tolerance,
        }) => (*what, *value, *tolerance),
        other => panic!("{}: not refused by `{name}`: {other:?}", outside.0),
    };
    assert_eq!(what, name, "{}: refused by another check", outside.0);
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
    let (v, t) = outside.1.checks[refused as usize];
    assert!(
        (tolerance / t - 1.0).abs() <= AGREEMENT && (value / v - 1.0).abs() <= AGREEMENT,
        "{}: the audit's {value:e} against {tolerance:e} is not the documented {v:e} against {t:e}",
        outside.0
    );
}

/// Constraint `k` and its direction, as a label.
fn label<S>(body: &Body<S>, k: usize) -> String {
    format!("constraint {k}, s = {}", body.rows[k].1)
}

/// Constraint `k` inactive (`r_k = 0`, its node's `r_T` by the law), its bound raised past
/// `s_k z_{i_k}` by the violation.
fn primal_violation_on<S: SpdSystem>(body: &Body<S>, cases: &[Case]) {
    for case in cases {
        for k in 0..body.m() {
            let (i, s) = body.rows[k];
            let mut a = base(body, case);
            a.r[k] = 0.0;
            a.settle_normal(body, case, k);
            let checks = (Check::Primal, Check::Primal);
            bracket(body, case, checks, &label(body, k), &a, |a, f, e| {
                a.lo[k] = s * a.z[i] + f * e.tol_z;
            });
        }
    }
}

#[test]
fn primal_violation() {
    primal_violation_on(&bar(), &[SIGNORINI]);
    primal_violation_on(&plane(), &[SIGNORINI]);
    primal_violation_on(&friction_plane(), &FRICTION_CASES);
}

/// Constraint `k` of `prepare`'s answer active with the reaction `−v`; under Coulomb its node's
/// `r_T = 0` (the threshold `μ r_N` is negative, and the cone and slip law stay at `μ` times the
/// ratio).
fn negative_reaction_on<S: SpdSystem>(
    body: &Body<S>,
    cases: &[Case],
    prepare: impl Fn(&mut Answer, &Case, usize),
) {
    for case in cases {
        for k in 0..body.m() {
            let mut a = base(body, case);
            prepare(&mut a, case, k);
            let checks = (Check::Negative, Check::Negative);
            bracket(body, case, checks, &label(body, k), &a, |a, f, e| {
                a.r[k] = -f * e.tol_f;
                a.settle_normal(body, case, k);
            });
        }
    }
}

/// The penalty and round-off cases bound a negative reaction by the force floor `floor_f` (64
/// ulps on the sparse system): a reaction `−v` at an end whose row of `C z` is exactly 0, for
/// the penalty law with the constraint inactive (gap ¼).
#[test]
fn negative_reaction() {
    let (bar, plane, friction) = (bar(), plane(), friction_plane());
    negative_reaction_on(&bar, &[SIGNORINI, SIGNORINI_EXACT], |_, _, _| {});
    negative_reaction_on(&sparse_bar(), &[SIGNORINI_EXACT], |_, _, _| {});
    negative_reaction_on(&bar, &[penalty(STIFF_SPRINGS)], |a, _, k| {
        a.lo[k] -= STIFF_SPRINGS + 0.25;
        a.r[k] = 0.0;
    });
    negative_reaction_on(&plane, &[SIGNORINI], |_, _, _| {});
    negative_reaction_on(&friction, &FRICTION_CASES, |a, _, k| {
        a.activate(&friction, k)
    });
}

/// Constraint `k` pressed (`r > 0`) at a gap `g`: `r g = f (τ_z r + τ_f g)`.
fn complementarity_on<S: SpdSystem>(body: &Body<S>, cases: &[Case]) {
    for case in cases {
        for k in 0..body.m() {
            let (i, s) = body.rows[k];
            let mut a = base(body, case);
            if a.r[k] == 0.0 {
                a.r[k] = PRESSED;
                a.settle_normal(body, case, k);
            }
            let checks = (Check::Complementarity, Check::Complementarity);
            bracket(body, case, checks, &label(body, k), &a, |a, f, e| {
                let r = a.r[k];
                let gap = f * e.tol_z * r / (r - f * e.tol_f);
                a.lo[k] = s * a.z[i] - gap;
            });
        }
    }
}

#[test]
fn complementarity() {
    complementarity_on(&bar(), &[SIGNORINI]);
    complementarity_on(&plane(), &[SIGNORINI]);
    complementarity_on(&friction_plane(), &FRICTION_CASES);
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
    for case in [penalty(SOFT_SPRINGS), penalty(STIFF_SPRINGS)] {
        let Kind::Penalty(epsilon) = case.kind else {
            unreachable!()
        };
        for k in 0..bar.m() {
            let (i, s) = bar.rows[k];
            let mut a = base(&bar, &case);
            a.z[i] = s / 1024.0;
            a.r[k] = 1.0 / 2048.0 / epsilon;
            a.lo[k] = s * a.z[i] + epsilon * a.r[k];
            let at = format!("epsilon = {epsilon}, {}", label(&bar, k));
            let checks = (Check::PenaltyLaw, Check::PenaltyLaw);
            bracket(&bar, &case, checks, &at, &a, |a, f, e| {
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
    let body = friction_plane();
    for case in FRICTION_CASES.iter().filter(|c| c.previous) {
        for j in 0..P {
            let k = FRICTIONAL[j];
            let mut a = base(&body, case);
            if a.r[k] == 0.0 {
                a.r[k] = PRESSED;
                a.activate(&body, k);
            }
            let delta = SLIPS[j];
            a.w[j] = delta - a.z[body.rows[M + j].0];
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

/// A residual `extra = v d` with `‖d‖∞ = 1`, placed at the force tolerance.
fn stationarity_on<S: SpdSystem>(body: &Body<S>, cases: &[Case], label: &str, d: &[f64]) {
    for case in cases {
        let a = base(body, case);
        let checks = (Check::Stationarity, Check::Stationarity);
        bracket(body, case, checks, label, &a, |a, f, e| {
            for (x, y) in a.extra.iter_mut().zip(d) {
                *x = f * e.tol_f * y;
            }
        });
    }
}

/// OSQP's answers: a residual along the stiff mode `w`, `C w / ‖C w‖∞`, whose displacement stays
/// small. At round-off (the penalty law, Signorini on the sparse system's 64 ulps) and with
/// friction: a residual at rows where `C z` is exactly 0, so that it is exact (the bar's node 3;
/// `±1` at `STIFF_ROWS`). The penalty answers' displacement check, `‖C⁻¹ ρ‖∞ <= ‖C⁻¹‖∞ floor_f`,
/// cannot fail while stationarity holds (Hager's estimate is exact for the bar's `C`).
/// `C w / ‖C w‖∞` along the stiff mode `w`.
fn stiff<S>(body: &Body<S>) -> Vec<f64> {
    let cw = &body.c * DVector::from_column_slice(&body.stiff);
    cw.iter().map(|y| y / cw.amax()).collect()
}

#[test]
fn stationarity() {
    let (bar, plane) = (bar(), plane());
    stationarity_on(&bar, &[SIGNORINI], "stiff residual", &stiff(&bar));
    let plane_d = stiff(&plane);
    stationarity_on(&plane, &[SIGNORINI], "stiff residual", &plane_d);
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
    let a = base(body, &SIGNORINI);
    let checks = (Check::Displacement, Check::Displacement);
    bracket(body, &SIGNORINI, checks, "soft residual", &a, |a, f, e| {
        for (x, y) in a.extra.iter_mut().zip(cw.iter()) {
            *x = f * e.tol_dz * y;
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
    assert!(
        (bar.inv_norm * BAR_MASS - 1.0).abs() <= 1e-12,
        "‖C⁻¹‖∞ = 1/m"
    );
    soft_residual(&bar);
    soft_residual(&plane());
    let body = friction_plane();
    let row_sum = |i: usize| body.c_inv.row(i).iter().map(|v| v.abs()).sum::<f64>();
    let top = (0..body.z.len())
        .max_by(|&p, &q| row_sum(p).total_cmp(&row_sum(q)))
        .expect("C has rows");
    let signs: Vec<f64> = body.c_inv.row(top).iter().map(|v| v.signum()).collect();
    for case in FRICTION_CASES.iter().filter(|c| c.roundoff_level()) {
        let mut a = base(&body, case);
        a.r.fill(0.0);
        for k in 0..M {
            a.activate(&body, k);
        }
        let checks = (Check::Displacement, Check::Stationarity);
        let label = "residual along C⁻¹'s largest row";
        bracket(&body, case, checks, label, &a, |a, f, e| {
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
        });
    }
}

#[test]
fn hager_estimate_is_exact_on_the_frictional_body() {
    let body = friction_plane();
    let estimate = inverse_norm_estimate(&mut (body.system)());
    assert!(
        (estimate / body.inv_norm - 1.0).abs() <= HAGER_EXACT,
        "Hager's {estimate} against ‖C⁻¹‖∞ = {}",
        body.inv_norm
    );
}

/// Every body with the cases it is audited under.
fn for_each_case(mut f: impl FnMut(&dyn Fn(&Case) -> Outcome, &Case)) {
    let (bar, sparse, plane, friction) = (bar(), sparse_bar(), plane(), friction_plane());
    let cases = [
        SIGNORINI,
        SIGNORINI_EXACT,
        penalty(SOFT_SPRINGS),
        penalty(STIFF_SPRINGS),
    ];
    for case in &cases {
        f(&|c| outcome(&bar, c), case);
    }
    f(&|c| outcome(&sparse, c), &SIGNORINI_EXACT);
    f(&|c| outcome(&plane, c), &SIGNORINI);
    for case in &FRICTION_CASES {
        f(&|c| outcome(&friction, c), case);
    }
}

/// A case's base answer: its evaluation, the audit's report and verdict, and the verdicts on
/// the answer with a NaN `z`, an infinite normal and a NaN last reaction.
struct Outcome {
    eval: Eval,
    report: AuditReport,
    verdict: Result<(), StepFailure>,
    non_finite: Vec<Result<(), StepFailure>>,
}

fn outcome<S: SpdSystem>(body: &Body<S>, case: &Case) -> Outcome {
    let a = base(body, case);
    let eval = evaluate(body, case, &a);
    let (checked, verdict) = audit(body, case, &a, &eval);
    let non_finite = [(0, f64::NAN), (1, f64::INFINITY), (2, f64::NAN)].map(|(what, value)| {
        let mut bad = a.clone();
        match what {
            0 => bad.z[0] = value,
            1 => bad.r[0] = value,
            _ => *bad.r.last_mut().expect("reactions") = value,
        }
        audit(body, case, &bad, &eval).1
    });
    Outcome {
        eval,
        report: checked.report().clone(),
        verdict,
        non_finite: non_finite.to_vec(),
    }
}

/// The base answers satisfy their laws: the audit accepts them with every ratio far inside,
/// and its report lists exactly the law's checks.
#[test]
fn base_answers_are_accepted_and_reported() {
    for_each_case(|run, case| {
        let o = run(case);
        for c in CHECKS {
            assert!(o.eval.ratio(c) <= FAR_INSIDE, "{}: {c:?}", case.name);
        }
        o.verdict
            .unwrap_or_else(|err| panic!("{}: {err}", case.name));
        let penalty = matches!(case.kind, Kind::Penalty(_));
        let listed = [
            (Check::Primal, !penalty),
            (Check::Complementarity, !penalty),
            (Check::PenaltyLaw, penalty),
            (Check::Cone, case.frictional()),
            (Check::Slip, case.frictional()),
            (Check::Negative, true),
        ];
        for (c, expected) in listed {
            let reported = c.reported(&o.report).is_some();
            assert_eq!(reported, expected, "{}: {c:?} listed", case.name);
        }
    });
}

/// A non-finite `z`, normal or last (with friction tangential) reaction is refused before any
/// check.
#[test]
fn non_finite_answers() {
    for_each_case(|run, case| {
        for verdict in run(case).non_finite {
            let refused = matches!(verdict, Err(StepFailure::NonFinite));
            assert!(refused, "{}: {verdict:?}", case.name);
        }
    });
}
