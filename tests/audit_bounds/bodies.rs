//! The bodies of the audit's bound tests: each step matrix with its dense copies, the
//! constraints (and frictional nodes) of its answers and the vectors they are built from; the
//! bar (tridiagonal and sparse), the plane and the frictional plane.

use super::*;

/// A step matrix with its independent dense copies, the constraints (and frictional nodes) of
/// the answers, and the vectors the answers are built from.
pub(super) struct Body<S> {
    pub(super) name: &'static str,
    pub(super) c: DMatrix<f64>,
    pub(super) c_inv: DMatrix<f64>,
    /// `‖C‖∞` and `‖C⁻¹‖∞`, largest absolute row sums of the dense copies.
    pub(super) c_norm: f64,
    pub(super) inv_norm: f64,
    pub(super) ulps: f64,
    pub(super) constraints: Constraints,
    pub(super) friction: Option<Friction>,
    /// The numbers of normals and of frictional nodes, and the latter's `μ`.
    pub(super) m: usize,
    pub(super) p: usize,
    pub(super) mu: Vec<f64>,
    /// `(i, s)` of every row of `E`: the normals, then the tangents (`s = +1`).
    pub(super) rows: Vec<(usize, f64)>,
    /// `σ = max_k S_kk`, `S = E C⁻¹ Eᵀ`: the Tresca solver's scale.
    pub(super) sigma: f64,
    pub(super) z: Vec<f64>,
    /// `w` with `‖C w‖∞` small (a soft mode) and large (a stiff mode), `‖w‖∞ = 1`.
    pub(super) soft: Vec<f64>,
    pub(super) stiff: Vec<f64>,
    pub(super) system: fn(&DMatrix<f64>) -> S,
}

/// `C`, the round-off ulps of its system, and how the solvers hold it.
pub(super) type Matrix<S> = (DMatrix<f64>, f64, fn(&DMatrix<f64>) -> S);

impl<S: SpdSystem> Body<S> {
    pub(super) fn new(
        name: &'static str,
        (c, ulps, system): Matrix<S>,
        (constraints, friction): (Constraints, Option<Friction>),
        z: Vec<f64>,
    ) -> Self {
        assert_eq!(c, c.transpose(), "{name}: C is symmetric");
        let c_inv = c.clone().try_inverse().expect("C is invertible");
        let all = (friction.as_ref()).map_or(constraints.clone(), |f| f.rows(&constraints));
        let rows: Vec<(usize, f64)> = all.unknowns.into_iter().zip(all.directions).collect();
        let sigma = rows.iter().map(|&(i, _)| c_inv[(i, i)]).fold(0.0, f64::max);
        let eigen = c.clone().symmetric_eigen();
        let mode = |j: usize| {
            let w = eigen.eigenvectors.column(j);
            w.iter().map(|x| x / w.amax()).collect()
        };
        let mu = friction.as_ref().map_or(vec![], |f| f.coefficients.clone());
        Self {
            name,
            c_norm: inf_norm(&c),
            inv_norm: inf_norm(&c_inv),
            m: constraints.len(),
            p: mu.len(),
            soft: mode(eigen.eigenvalues.imin()),
            stiff: mode(eigen.eigenvalues.imax()),
            c,
            c_inv,
            ulps,
            constraints,
            friction,
            mu,
            rows,
            sigma,
            z,
            system,
        }
    }
}

/// `c` as the plane body's solvers hold theirs, a `SparseSystem` on the pattern of its nonzeros.
pub(super) fn sparse(c: &DMatrix<f64>) -> SparseSystem {
    let (mut row_ptr, mut cols, mut values) = (vec![0], vec![], vec![]);
    for i in 0..c.nrows() {
        for j in (0..c.ncols()).filter(|&j| c[(i, j)] != 0.0) {
            cols.push(j);
            values.push(c[(i, j)]);
        }
        row_ptr.push(cols.len());
    }
    let n = c.nrows();
    let pattern = Pattern { n, row_ptr, cols };
    SparseSystem::new(&pattern, &values, "C").expect("C is positive definite")
}

pub(super) fn constraints(unknowns: Vec<usize>, directions: Vec<f64>) -> Constraints {
    Constraints {
        unknowns,
        directions,
    }
}

/// The bar: `n` nodes, `C = m I + k L` with `L` the free bar's difference matrix (rows `1, −1`
/// at the ends, `−1, 2, −1` inside). Dyadic entries, so that products with dyadic `z` are exact;
/// an M-matrix with `C 1 = m 1`, so `C⁻¹ >= 0` and `‖C⁻¹‖∞ = 1/m` (= 64: soft, so that the
/// displacement check can bind before the force check), and Hager's estimate is exact. A lower
/// bound at its left end (`s = +1`) and an upper one at its right end.
pub(super) const BAR_NODES: usize = 8;
pub(super) const BAR_MASS: f64 = 1.0 / 64.0;
pub(super) const BAR_STIFFNESS: f64 = 4.0;
pub(super) const BAR_Z: [f64; BAR_NODES] = [0.5, 0.625, 0.75, 0.8125, 0.75, 0.5, 0.125, -0.25];

pub(super) fn bar_matrix() -> SymTridiag {
    let n = BAR_NODES;
    let mut diag = vec![BAR_MASS + 2.0 * BAR_STIFFNESS; n];
    diag[0] = BAR_MASS + BAR_STIFFNESS;
    diag[n - 1] = BAR_MASS + BAR_STIFFNESS;
    SymTridiag::new(diag, vec![-BAR_STIFFNESS; n - 1])
}

pub(super) fn bar_dense() -> DMatrix<f64> {
    let c = bar_matrix();
    DMatrix::from_fn(BAR_NODES, BAR_NODES, |i, j| match i.abs_diff(j) {
        0 => c.diag[i],
        1 => c.off[i.min(j)],
        _ => 0.0,
    })
}

pub(super) fn bar_rows() -> (Constraints, Option<Friction>) {
    (constraints(vec![0, BAR_NODES - 1], vec![1.0, -1.0]), None)
}

/// The bar as the bar's solvers hold it (`TridiagSystem`), and as a `SparseSystem`: its dyadic
/// entries make the sparse floors testable.
pub(super) fn bar() -> Body<TridiagSystem> {
    let system = |_: &_| TridiagSystem::new(&bar_matrix()).expect("C is positive definite");
    Body::new(
        "bar",
        (bar_dense(), TRIDIAG_ULPS, system),
        bar_rows(),
        BAR_Z.to_vec(),
    )
}

pub(super) fn sparse_bar() -> Body<SparseSystem> {
    let c = (bar_dense(), SPARSE_ULPS, sparse as fn(&_) -> _);
    Body::new("bar on a pattern", c, bar_rows(), BAR_Z.to_vec())
}

/// The plane body: Q1 matrices on a grid of square cells (all degrees of freedom kept),
/// `C = M/Δt² + (½ + α/(2Δt)) K` as the plane's step matrix; a long step makes it soft along
/// the rigid translations, which `K` does not resist, and `‖C‖∞ ‖C⁻¹‖∞` large.
pub(super) const MATERIAL: Material = Material {
    lambda: 4.0,
    mu: 4.0,
    density: 1.0,
};
pub(super) const DT: f64 = 2.0;
pub(super) const VISCOSITY: f64 = 0.5;
/// A node's `u_x` and `u_y`.
pub(super) const X: usize = 0;
pub(super) const Y: usize = 1;

pub(super) fn plane_dense(grid: &Grid) -> DMatrix<f64> {
    let m = assemble(grid, MATERIAL);
    let (a, b) = (1.0 / (DT * DT), 0.5 + VISCOSITY / (2.0 * DT));
    let (n, pattern) = (m.pattern.n, &m.pattern);
    let mut c = DMatrix::zeros(n, n);
    for row in 0..n {
        for at in pattern.row_ptr[row]..pattern.row_ptr[row + 1] {
            c[(row, pattern.cols[at])] = a * m.mass[at] + b * m.stiffness[at];
        }
    }
    c
}

/// The plane body on 2 × 2 cells of the unit square, with the bottom edge's middle node pushed
/// up (`u_y`, `s = +1`) and the top edge's middle node pushed down (`s = −1`); `z` a rigid
/// motion and a little shear, so that `C z` stays small next to the reactions.
pub(super) fn plane_grid() -> Grid {
    Grid::new(1.0, 1.0, 2, 2, 1.0)
}

pub(super) fn plane() -> Body<SparseSystem> {
    let (grid, c) = (plane_grid(), plane_dense(&plane_grid()));
    let z = (0..c.nrows()).map(|d| {
        let (i, j) = grid.position(d / 2);
        let (x, y) = (grid.xs[i], grid.ys[j]);
        [0.2 - 0.3 * y + 0.05 * x * y, -0.1 + 0.3 * x][d % 2]
    });
    let (bottom, top) = (2 * grid.node(1, 0) + Y, 2 * grid.node(1, 2) + Y);
    let rows = constraints(vec![bottom, top], vec![1.0, -1.0]);
    let c = (c, SPARSE_ULPS, sparse as fn(&_) -> _);
    Body::new("plane", c, (rows, None), z.collect())
}

/// The frictional plane body on 4 × 6 cells: the normal constraints `(i, j, s)` at `u_y` of node
/// `(i, j)`, three on the bottom edge pushed up, one on the top edge pushed down.
pub(super) const NX: usize = 4;
pub(super) const NY: usize = 6;
pub(super) const M: usize = 4;
pub(super) const NORMALS: [(usize, usize, f64); M] =
    [(0, 0, 1.0), (2, 0, 1.0), (4, 0, 1.0), (2, NY, -1.0)];
/// The frictional nodes: their normal constraint (the tangent is that node's `u_x`) and `μ`
/// (dyadic, so that `μ r_N` is exact; at most 3/8, so that a negative `r_N` leaves the cone and
/// the slip law of its node below `FAR_INSIDE`).
pub(super) const P: usize = 3;
pub(super) const FRICTIONAL: [usize; P] = [1, 2, 3];
pub(super) const MU: [f64; P] = [0.25, 0.375, 0.25];
/// The nonzero entries of `z`, at nodes pairwise three cells apart (no row of `C` meets two of
/// them, so `C z` is exact and the audit's residual has the bits recomputed here): a free
/// interior unknown (`‖C‖∞ ‖z‖∞` dominates `τ_f`), the top normal's unknown (`s z ≠ 0`) and the
/// second tangent's (`δ = z_t + w`).
pub(super) const Z_ENTRIES: [(usize, usize, usize, f64); 3] =
    [(2, 3, X, 0.5), (2, NY, Y, -0.0625), (4, 0, X, 0.03125)];
/// The base answer's normal reactions: the unit one sets `‖r‖∞`, the frictional ones are smaller
/// (their thresholds round finely against the tolerances), the top constraint is inactive.
pub(super) const REACTIONS: [f64; M] = [1.0, 0.25, 0.5, 0.0];
/// The base answer's gaps: the inactive top one makes `ε' max|lo_k|` a visible part of `τ_z`.
pub(super) const GAPS: [f64; M] = [0.0, 0.0, 0.0, 256.0];
/// The previous increment at the tangents: node 0 slides forward (`δ = 1/2`), node 1 sticks
/// (`δ = z_t + w = 0`), node 2 slides back.
pub(super) const PREVIOUS: [f64; P] = [0.5, -0.03125, -0.03125];
/// The central slips of the slip-law answers (powers of two: `g|δ|` and `r_T δ` are exact).
pub(super) const SLIPS: [f64; P] = [0.5, -0.25, 0.5];
/// A normal reaction for the answers that need the top constraint active and pressed.
pub(super) const PRESSED: f64 = 0.5;
/// The Tresca thresholds of the OSQP case: distinct from the answer's `μ r_N`, so that an audit
/// reading the wrong ones refuses the base answer.
pub(super) const GIVEN: [f64; P] = [0.125, 0.25, 0.0625];
/// A residual along the left edge's `u_x` with alternating signs (rows where `C z = 0`, so that
/// `b = −residual` is exact): a stiff load, whose displacement stays small.
pub(super) const STIFF_ROWS: [(usize, usize, f64); 3] = [(0, 2, 1.0), (0, 3, -1.0), (0, 4, 1.0)];

pub(super) fn friction_grid() -> Grid {
    Grid::new(NX as f64 * 0.5, NY as f64 * 0.5, NX, NY, 1.0)
}

pub(super) fn dof(i: usize, j: usize, axis: usize) -> usize {
    2 * friction_grid().node(i, j) + axis
}

pub(super) fn friction_plane() -> Body<SparseSystem> {
    let c = plane_dense(&friction_grid());
    let normals = constraints(
        NORMALS.iter().map(|&(i, j, _)| dof(i, j, Y)).collect(),
        NORMALS.iter().map(|&(.., s)| s).collect(),
    );
    let tangents = FRICTIONAL
        .iter()
        .map(|&k| dof(NORMALS[k].0, NORMALS[k].1, X));
    let friction = Friction {
        normals: FRICTIONAL.to_vec(),
        tangents: tangents.collect(),
        coefficients: MU.to_vec(),
    };
    let mut z = vec![0.0; c.nrows()];
    for (i, j, axis, v) in Z_ENTRIES {
        z[dof(i, j, axis)] = v;
    }
    for i in 0..c.nrows() {
        let terms = (0..c.nrows()).filter(|&l| c[(i, l)] != 0.0 && z[l] != 0.0);
        assert!(terms.count() <= 1, "row {i} of C meets two entries of z");
    }
    let c = (c, SPARSE_ULPS, sparse as fn(&_) -> _);
    Body::new("frictional plane", c, (normals, Some(friction)), z)
}
