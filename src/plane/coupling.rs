//! The thermoelastic coupling of the plane body (`γ > 0`): the matrix `G_{(i,c),J} = ∫ ψ_J ∂_c φ_i`
//! (displacement unknown `(i, c)`, temperature node `J`), and the step's displacement problem
//! with the temperature eliminated, `S = C + (γ² w/2) G_F B⁻¹ G_Fᵀ` (`B` the heat step's matrix
//! on the unknown temperatures `F`, `w` its weight), as an [`SpdSystem`] for the exact contact
//! solvers: `S x = y` by one `LDLᵀ` solve of the quasi-definite
//! `[[C, −γw G_F], [−γw G_Fᵀ, −2w B]]`. Each exchange state and heat step (Crank–Nicolson or
//! implicit Euler) has its own `S`; [`CoupledSolver`] builds the step solver of a state when the
//! run first meets it and keeps it. Derivation: docs/thermal.md, "The plane body".

use std::cell::RefCell;
use std::sync::atomic::Ordering;

use crate::linalg::cholesky::SparseCholesky;
use crate::linalg::sparse::Pattern;
use crate::linalg::system::{Csc, SpdSystem, hager_norm_estimate};
use crate::plane::mesh::Grid;
use crate::scheme::in_contact;
use crate::step::{
    CondensedLcp, CondensedLemke, Constraints, Friction, SetupError, SolveInfo, SolverReport,
    StepFailure, StepSolver,
};
use crate::thermal::solver::ImplicitFlag;

/// `G` on the rows of the displacement unknowns and the columns of the temperature nodes, in
/// compressed rows; cell by cell as tensor products (`∫ X_a' X_c = ±½` in the derivative's
/// direction, the P1 mass in the other).
#[derive(Clone, Debug)]
pub struct CouplingMatrix {
    row_ptr: Vec<usize>,
    cols: Vec<usize>,
    values: Vec<f64>,
}

impl CouplingMatrix {
    /// `G` of `grid` on the displacement unknowns `free` (degree of freedom `2 node + c` of
    /// each) and the nodes of `stencil` (the scalar Q1 pattern).
    pub fn new(grid: &Grid, stencil: &Pattern, free: &[usize]) -> Self {
        let mut per_component = [vec![0.0; stencil.nnz()], vec![0.0; stencil.nnz()]];
        let d1 = [[-0.5, -0.5], [0.5, 0.5]];
        let m1 = |h: f64| [[h / 3.0, h / 6.0], [h / 6.0, h / 3.0]];
        for j in 0..grid.ny {
            for i in 0..grid.nx {
                let (mx, my) = (
                    m1(grid.xs[i + 1] - grid.xs[i]),
                    m1(grid.ys[j + 1] - grid.ys[j]),
                );
                for (a, b) in [(0, 0), (1, 0), (0, 1), (1, 1)] {
                    let row = grid.node(i + a, j + b);
                    for (c, d) in [(0, 0), (1, 0), (0, 1), (1, 1)] {
                        let p = stencil.position(row, grid.node(i + c, j + d));
                        per_component[0][p] += d1[a][c] * my[b][d];
                        per_component[1][p] += mx[a][c] * d1[b][d];
                    }
                }
            }
        }
        let (mut row_ptr, mut cols, mut values) = (vec![0], Vec::new(), Vec::new());
        for &dof in free {
            let (node, c) = (dof / 2, dof % 2);
            let row = stencil.row_ptr[node]..stencil.row_ptr[node + 1];
            cols.extend_from_slice(&stencil.cols[row.clone()]);
            values.extend_from_slice(&per_component[c][row]);
            row_ptr.push(cols.len());
        }
        Self {
            row_ptr,
            cols,
            values,
        }
    }

    /// `G` restricted to the columns `keep` maps to `Some(new column)`.
    pub fn restrict_columns(&self, keep: &[Option<usize>]) -> Self {
        let (mut row_ptr, mut cols, mut values) = (vec![0], Vec::new(), Vec::new());
        for r in 0..self.rows() {
            for k in self.row_ptr[r]..self.row_ptr[r + 1] {
                if let Some(c) = keep[self.cols[k]] {
                    cols.push(c);
                    values.push(self.values[k]);
                }
            }
            row_ptr.push(cols.len());
        }
        Self {
            row_ptr,
            cols,
            values,
        }
    }

    pub fn rows(&self) -> usize {
        self.row_ptr.len() - 1
    }

    /// `y = scale · G x`.
    pub fn mul_into(&self, x: &[f64], scale: f64, y: &mut [f64]) {
        for (r, yr) in y.iter_mut().enumerate() {
            let mut s = 0.0;
            for k in self.row_ptr[r]..self.row_ptr[r + 1] {
                s += self.values[k] * x[self.cols[k]];
            }
            *yr = scale * s;
        }
    }

    /// `y = scale · Gᵀ x`.
    pub fn transpose_mul_into(&self, x: &[f64], scale: f64, y: &mut [f64]) {
        y.fill(0.0);
        for (r, xr) in x.iter().enumerate() {
            for k in self.row_ptr[r]..self.row_ptr[r + 1] {
                y[self.cols[k]] += self.values[k] * xr;
            }
        }
        for v in y.iter_mut() {
            *v *= scale;
        }
    }
}

/// The heat step's matrix `B = M + c (κ K + h X χ)` on the unknown temperatures, its
/// exchange entries kept apart so that each state's values are made without a new pattern.
#[derive(Clone, Debug)]
pub struct HeatStepMatrix {
    pub pattern: Pattern,
    pub mass: Vec<f64>,
    pub stiffness: Vec<f64>,
    pub kappa: f64,
    /// Per exchange node: its diagonal position in `pattern` (`None` when held) and `h X_j`'s
    /// factors `(h, X_j)`.
    pub exchange: Vec<(Option<usize>, f64, f64)>,
}

impl HeatStepMatrix {
    /// `B`'s values for the exchange state `chi` and `c`.
    pub fn values(&self, chi: &[bool], c: f64, out: &mut [f64]) {
        for ((v, m), k) in out.iter_mut().zip(&self.mass).zip(&self.stiffness) {
            *v = m + c * self.kappa * k;
        }
        for (&(position, h, weight), &chi) in self.exchange.iter().zip(chi) {
            if let (true, Some(p)) = (chi, position) {
                out[p] += c * h * weight;
            }
        }
    }
}

/// `S = C + (γ² w/2) G_F B⁻¹ G_Fᵀ` of one state (see the module doc). `mul_into` takes a
/// solve with `B`, whose factor and work space sit in a `RefCell` (the seam multiplies through
/// `&self`); nothing allocates after set-up.
pub struct CoupledSystem {
    c_pattern: Pattern,
    c: Vec<f64>,
    g: CouplingMatrix,
    /// `γ² w/2`.
    weight: f64,
    heat: RefCell<(SparseCholesky, Vec<f64>)>,
    augmented: SparseCholesky,
    work: Vec<f64>,
    norm: f64,
}

/// Where an entry of the quasi-definite matrix takes its value from: an entry of `C`, of `G`
/// (in either triangle) or of `B`.
enum Source {
    C(usize),
    G(usize),
    B(usize),
}

/// The symmetric pattern of `[[C, G], [Gᵀ, B]]` (`G` with `B`'s order of columns), each row's
/// columns ascending, and the source of each entry.
fn augmented_pattern(c: &Pattern, g: &CouplingMatrix, b: &Pattern) -> (Pattern, Vec<Source>) {
    let (n, m) = (c.n, b.n);
    let mut transpose: Vec<Vec<(usize, usize)>> = vec![Vec::new(); m];
    for r in 0..n {
        for k in g.row_ptr[r]..g.row_ptr[r + 1] {
            transpose[g.cols[k]].push((r, k));
        }
    }
    let (mut row_ptr, mut cols, mut from) = (vec![0], Vec::new(), Vec::new());
    for r in 0..n {
        for k in c.row_ptr[r]..c.row_ptr[r + 1] {
            cols.push(c.cols[k]);
            from.push(Source::C(k));
        }
        let mut coupling: Vec<(usize, usize)> = (g.row_ptr[r]..g.row_ptr[r + 1])
            .map(|k| (n + g.cols[k], k))
            .collect();
        coupling.sort_unstable();
        for (col, k) in coupling {
            cols.push(col);
            from.push(Source::G(k));
        }
        row_ptr.push(cols.len());
    }
    for (j, column) in transpose.iter().enumerate() {
        for &(r, k) in column {
            cols.push(r);
            from.push(Source::G(k));
        }
        for k in b.row_ptr[j]..b.row_ptr[j + 1] {
            cols.push(n + b.cols[k]);
            from.push(Source::B(k));
        }
        row_ptr.push(cols.len());
    }
    (
        Pattern {
            n: n + m,
            row_ptr,
            cols,
        },
        from,
    )
}

impl CoupledSystem {
    /// `S` of `C` (values `c` on `c_pattern`), `G_F`, `B` (values `b` on `b_pattern`), `γ` and
    /// `w`: factorises `B` and the quasi-definite matrix, and estimates `‖S‖∞`.
    pub fn new(
        (c_pattern, c): (&Pattern, &[f64]),
        g: CouplingMatrix,
        (b_pattern, b): (&Pattern, &[f64]),
        gamma: f64,
        w: f64,
    ) -> Result<Self, SetupError> {
        let contact = |e: crate::linalg::cholesky::FactorError| SetupError::Contact(e.to_string());
        let (pattern, from) = augmented_pattern(c_pattern, &g, b_pattern);
        let values: Vec<f64> = from
            .iter()
            .map(|s| match *s {
                Source::C(k) => c[k],
                Source::G(k) => -gamma * w * g.values[k],
                Source::B(k) => -2.0 * w * b[k],
            })
            .collect();
        let augmented = SparseCholesky::quasi_definite(&pattern, &values, "the coupled step")
            .map_err(contact)?;
        let heat = SparseCholesky::new(b_pattern, b, "the heat step").map_err(contact)?;
        let mut this = Self {
            c_pattern: c_pattern.clone(),
            c: c.to_vec(),
            weight: 0.5 * gamma * gamma * w,
            heat: RefCell::new((heat, vec![0.0; b_pattern.n])),
            work: vec![0.0; pattern.n],
            augmented,
            norm: 0.0,
            g,
        };
        let n = this.dim();
        let mut y = vec![0.0; n];
        this.norm = hager_norm_estimate(n, |x| {
            this.mul_into(x, &mut y);
            x.copy_from_slice(&y);
        });
        Ok(this)
    }
}

impl SpdSystem for CoupledSystem {
    fn dim(&self) -> usize {
        self.c_pattern.n
    }

    /// `C x + (γ² w/2) G_F B⁻¹ G_Fᵀ x`.
    fn mul_into(&self, x: &[f64], y: &mut [f64]) {
        let mut heat = self.heat.borrow_mut();
        let (factor, t) = &mut *heat;
        self.g.transpose_mul_into(x, 1.0, t);
        factor.solve_in_place(t);
        self.g.mul_into(t, self.weight, y);
        let p = &self.c_pattern;
        for (r, yr) in y.iter_mut().enumerate() {
            let mut s = 0.0;
            for k in p.row_ptr[r]..p.row_ptr[r + 1] {
                s += self.c[k] * x[p.cols[k]];
            }
            *yr += s;
        }
    }

    fn solve_in_place(&mut self, x: &mut [f64]) {
        let n = x.len();
        self.work[..n].copy_from_slice(x);
        self.work[n..].fill(0.0);
        self.augmented.solve_in_place(&mut self.work);
        x.copy_from_slice(&self.work[..n]);
    }

    /// Hager's estimate of `‖S‖₁ = ‖S‖∞` (`S` symmetric; its products only), made at set-up.
    fn inf_norm(&self) -> f64 {
        self.norm
    }

    // The penalty law's audit alone reads `S_ii` and `(|S||x|)_i` (`S − C` is dense); the
    // coupled plane admits the exact solver only (`solver.method`).
    fn diagonal(&self, _i: usize) -> f64 {
        unreachable!("the penalty method is refused on a plane body with a coupled temperature")
    }

    fn abs_row_product(&self, _i: usize, _x: &[f64]) -> f64 {
        unreachable!("the penalty method is refused on a plane body with a coupled temperature")
    }

    /// `C x`'s row (18 products) and `G_F B⁻¹ G_Fᵀ x` (two rows of 18 and 9 products and a
    /// sparse solve, each within `SparseSystem`'s 64 ulps of its magnitudes, which `‖S‖`
    /// bounds), and the quasi-definite solve's backward error (`LDLᵀ` without pivoting,
    /// stable for quasi-definite matrices whose blocks are well conditioned, Gill, Saunders
    /// & Shinnerl 1996): twice the sparse system's allowance.
    fn roundoff_ulps(&self) -> f64 {
        128.0
    }

    fn upper_triangle(&self) -> Csc {
        unreachable!("OSQP is refused on a plane body with a coupled temperature (solver.method)")
    }
}

/// What a coupled state's step solver is made of: `C`, `G_F`, `B`'s parts, `γ`, the contact
/// constraints and the frictional nodes.
pub struct CoupledParts {
    pub c_pattern: Pattern,
    pub c: Vec<f64>,
    pub g: CouplingMatrix,
    pub heat: HeatStepMatrix,
    pub gamma: f64,
    pub dt: f64,
    pub constraints: Constraints,
    pub friction: Friction,
}

impl CoupledParts {
    /// The exact step solver of exchange state `chi`, Crank–Nicolson (`w = ½`, `B = M + Δt/2 A`)
    /// or implicit Euler (`w = 1`, `B = M + Δt A`).
    fn build(&self, chi: &[bool], implicit: bool) -> Result<Box<dyn StepSolver>, SetupError> {
        let (w, c) = if implicit {
            (1.0, self.dt)
        } else {
            (0.5, 0.5 * self.dt)
        };
        let mut b = vec![0.0; self.heat.pattern.nnz()];
        self.heat.values(chi, c, &mut b);
        let system = CoupledSystem::new(
            (&self.c_pattern, &self.c),
            self.g.clone(),
            (&self.heat.pattern, &b),
            self.gamma,
            w,
        )?;
        let constraints = self.constraints.clone();
        Ok(if self.friction.is_empty() {
            Box::new(CondensedLcp::new(system, constraints, 0.0)?)
        } else {
            Box::new(CondensedLemke::new(
                system,
                constraints,
                self.friction.clone(),
            )?)
        })
    }
}

/// One exact step solver per exchange state and heat step met so far; the state of a step is
/// read off its bounds (as the body reads it), the heat step off the body's [`ImplicitFlag`].
pub struct CoupledSolver {
    parts: CoupledParts,
    /// The constraints of the exchange nodes, in the order of a state's entries.
    exchange: Vec<usize>,
    implicit: ImplicitFlag,
    variants: Vec<(Vec<bool>, bool, Box<dyn StepSolver>)>,
    state: Vec<bool>,
    previous: Vec<f64>,
    slide: Option<Vec<f64>>,
}

impl CoupledSolver {
    pub fn new(parts: CoupledParts, exchange: Vec<usize>, implicit: ImplicitFlag) -> Self {
        Self {
            state: vec![false; exchange.len()],
            previous: Vec::new(),
            slide: None,
            variants: Vec::new(),
            parts,
            exchange,
            implicit,
        }
    }

    /// The solver of the step whose bounds are `lower`, made when first met.
    fn variant(&mut self, lower: &[f64]) -> Result<&mut Box<dyn StepSolver>, StepFailure> {
        for (s, &k) in self.state.iter_mut().zip(&self.exchange) {
            *s = in_contact(-lower[k]);
        }
        let implicit = self.implicit.load(Ordering::Relaxed);
        let found = (self.variants.iter()).position(|v| v.1 == implicit && v.0 == self.state);
        let index = match found {
            Some(i) => i,
            None => {
                let solver = (self.parts)
                    .build(&self.state, implicit)
                    .map_err(|e| StepFailure::Setup(e.to_string()))?;
                self.variants.push((self.state.clone(), implicit, solver));
                self.variants.len() - 1
            }
        };
        let solver = &mut self.variants[index].2;
        if !self.previous.is_empty() {
            solver.set_previous_increment(&self.previous);
        }
        if let Some(v) = &self.slide {
            solver.set_obstacle_slide(v);
        }
        Ok(solver)
    }
}

impl StepSolver for CoupledSolver {
    fn name(&self) -> &'static str {
        "exact"
    }

    fn solve(
        &mut self,
        rhs: &[f64],
        lower: &[f64],
        z: &mut [f64],
        reactions: &mut [f64],
    ) -> Result<SolveInfo, StepFailure> {
        self.variant(lower)?.solve(rhs, lower, z, reactions)
    }

    fn set_previous_increment(&mut self, w: &[f64]) {
        self.previous.resize(w.len(), 0.0);
        self.previous.copy_from_slice(w);
    }

    fn set_obstacle_slide(&mut self, v: &[f64]) {
        let slide = self.slide.get_or_insert_with(|| vec![0.0; v.len()]);
        slide.copy_from_slice(v);
    }

    /// The report of the variant that solved the most steps.
    fn report(&self) -> Option<SolverReport> {
        (self.variants.iter())
            .filter_map(|v| v.2.report())
            .max_by_key(|r| r.audit.steps)
    }

    fn identity_allowance(&self) -> f64 {
        (self.variants.iter())
            .map(|v| v.2.identity_allowance())
            .fold(0.0, f64::max)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// `Σ_J (Gᵀ u)_J` sums a few hundred products of size at most 1: a few ulps of 2.
    const DIVERGENCE_TOL: f64 = 1e-14;

    /// `Gᵀ u` summed over the nodes is `∫ div u` (the `ψ_J` sum to 1). For `u = (x, 0)` on
    /// `[0, 2] × [0, 1]` (every node free), `Σ_J (Gᵀ u)_J = ∫ 1 = 2`; for `u = (0, y)`, 2 too.
    #[test]
    fn the_coupling_integrates_the_divergence() {
        let grid = Grid::new(2.0, 1.0, 5, 3, 2.0);
        let pattern = crate::plane::heat::node_stencil(&grid);
        let free: Vec<usize> = (0..grid.dofs()).collect();
        let g = CouplingMatrix::new(&grid, &pattern, &free);
        for c in 0..2 {
            let u: Vec<f64> = (0..grid.dofs())
                .map(|d| {
                    let (x, y) = grid.point(d / 2);
                    if d % 2 == c {
                        if c == 0 { x } else { y }
                    } else {
                        0.0
                    }
                })
                .collect();
            let mut t = vec![0.0; grid.nodes()];
            g.transpose_mul_into(&u, 1.0, &mut t);
            let total: f64 = t.iter().sum();
            assert!((total - 2.0).abs() <= DIVERGENCE_TOL, "{total}");
        }
    }

    /// `S x` of `x = S⁻¹ b` (the quasi-definite `LDLᵀ` solve against the product through `B`'s
    /// Cholesky factor) gives back `b`, backward stably.
    #[test]
    fn the_schur_solve_inverts_the_schur_product() {
        let grid = Grid::new(2.0, 1.0, 6, 4, 1.5);
        let m = crate::plane::matrices::assemble(
            &grid,
            crate::plane::matrices::Material {
                lambda: 1.0,
                mu: 0.5,
                density: 1.0,
            },
        );
        let (dt, alpha, gamma, kappa) = (0.05, 0.02, 0.7, 0.3);
        let c: Vec<f64> = (m.mass.iter().zip(&m.stiffness))
            .map(|(mm, k)| mm / (dt * dt) + (0.5 + alpha / (2.0 * dt)) * k)
            .collect();
        let stencil = crate::plane::heat::node_stencil(&grid);
        let (mass, stiffness) = crate::plane::heat::assemble(&grid, &stencil);
        let heat = HeatStepMatrix {
            pattern: stencil.clone(),
            mass,
            stiffness,
            kappa,
            exchange: Vec::new(),
        };
        let mut b_values = vec![0.0; stencil.nnz()];
        heat.values(&[], 0.5 * dt, &mut b_values);
        let free: Vec<usize> = (0..grid.dofs()).collect();
        let g = CouplingMatrix::new(&grid, &stencil, &free);
        let mut s =
            CoupledSystem::new((&m.pattern, &c), g, (&stencil, &b_values), gamma, 0.5).unwrap();
        let b: Vec<f64> = (0..grid.dofs())
            .map(|i| ((i * 7919) % 13) as f64 - 6.0)
            .collect();
        let mut x = b.clone();
        s.solve_in_place(&mut x);
        let mut sx = vec![0.0; x.len()];
        s.mul_into(&x, &mut sx);
        let max = |v: &[f64]| v.iter().fold(0.0f64, |a, b| a.max(b.abs()));
        let residual = sx
            .iter()
            .zip(&b)
            .map(|(p, q)| (p - q).abs())
            .fold(0.0, f64::max);
        let scale = s.inf_norm() * max(&x) + max(&b);
        assert!(
            residual <= s.roundoff_ulps() * f64::EPSILON * scale,
            "{residual:e} of {scale:e}"
        );
        // The coupling acts: `S x` differs from `C x` by more than round-off.
        let mut cx = vec![0.0; x.len()];
        m.pattern.mul_into(&c, &x, &mut cx);
        let coupling = cx
            .iter()
            .zip(&sx)
            .map(|(p, q)| (p - q).abs())
            .fold(0.0, f64::max);
        assert!(coupling > 1e6 * residual, "{coupling:e}");
    }
}
