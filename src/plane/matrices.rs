//! The consistent Q1 mass and stiffness matrices of plane strain,
//!
//! ```text
//!   vᵀ M u = ∫ ρ u·v,     vᵀ K u = ∫ λ div u div v + 2μ ε(u):ε(v),
//! ```
//!
//! assembled cell by cell with 2 × 2 Gauss points, exact for both on rectangles (the mass
//! integrand is bi-quadratic, the stiffness one at most bi-quadratic). With selective reduced
//! integration ([`Integration::Selective`]) the `λ` term is taken at the cell centre (one
//! point), the `2μ ε:ε` term still at 2 × 2: no volumetric locking as `λ/μ → ∞`. Both share
//! one symmetric CSR pattern (the 3 × 3 node stencil, two components per node); the clamped
//! degrees of freedom are then removed ([`Pattern::restrict`]).

use crate::linalg::sparse::Pattern;
use crate::plane::mesh::Grid;
pub use crate::scene::plane::Integration;

/// The material: Lamé coefficients and density.
#[derive(Clone, Copy, Debug)]
pub struct Material {
    pub lambda: f64,
    pub mu: f64,
    pub density: f64,
}

/// `M` and `K` on all `2 (nx + 1)(ny + 1)` degrees of freedom, on one pattern.
#[derive(Clone, Debug)]
pub struct Matrices {
    pub pattern: Pattern,
    pub mass: Vec<f64>,
    pub stiffness: Vec<f64>,
}

/// The 3 × 3 node stencil of every node, two components each: the pattern of M and K.
pub fn stencil(grid: &Grid) -> Pattern {
    let n = grid.dofs();
    let mut row_ptr = Vec::with_capacity(n + 1);
    let mut cols = Vec::with_capacity(18 * n);
    row_ptr.push(0);
    for node in 0..grid.nodes() {
        let (i, j) = grid.position(node);
        let mut neighbours = Vec::with_capacity(9);
        for jj in j.saturating_sub(1)..=(j + 1).min(grid.ny) {
            for ii in i.saturating_sub(1)..=(i + 1).min(grid.nx) {
                neighbours.push(grid.node(ii, jj));
            }
        }
        for _component in 0..2 {
            for &m in &neighbours {
                cols.push(2 * m);
                cols.push(2 * m + 1);
            }
            row_ptr.push(cols.len());
        }
    }
    Pattern { n, row_ptr, cols }
}

/// Gauss abscissae on `[0, 1]`, `(1 ∓ 1/√3)/2`, each of weight ½.
fn gauss() -> [f64; 2] {
    let d = 0.5 / 3f64.sqrt();
    [0.5 - d, 0.5 + d]
}

/// The 8 × 8 element mass and stiffness of a `hx × hy` cell, local nodes in the order of
/// [`Grid::cell_nodes`], local dofs `2a + c` (full integration).
pub fn element(hx: f64, hy: f64, m: Material) -> ([[f64; 8]; 8], [[f64; 8]; 8]) {
    element_with(hx, hy, m, Integration::Full)
}

/// [`element`] with the stiffness integrated by `rule`: `Full`, every term at 2 × 2 Gauss
/// points; `Selective`, the `λ div u div v` term at the centre (weight `hx hy`), the
/// `2μ ε(u):ε(v)` term at 2 × 2.
pub fn element_with(
    hx: f64,
    hy: f64,
    m: Material,
    rule: Integration,
) -> ([[f64; 8]; 8], [[f64; 8]; 8]) {
    // Local node a at (sx[a], sy[a]) of the unit square.
    let (sx, sy) = ([0.0, 1.0, 1.0, 0.0], [0.0, 0.0, 1.0, 1.0]);
    let hat = |s: f64, at: f64| if s == 0.0 { 1.0 - at } else { at };
    let slope = |s: f64| if s == 0.0 { -1.0 } else { 1.0 };
    let (mut me, mut ke) = ([[0.0; 8]; 8], [[0.0; 8]; 8]);
    let weight = 0.25 * hx * hy;
    // The λ taken at the Gauss points: all of it (full), none (selective: at the centre).
    let lambda = if rule == Integration::Full {
        m.lambda
    } else {
        0.0
    };
    let l2m = lambda + 2.0 * m.mu;
    for xi in gauss() {
        for eta in gauss() {
            let mut n = [0.0; 4];
            let (mut nx, mut ny) = ([0.0; 4], [0.0; 4]);
            for a in 0..4 {
                n[a] = hat(sx[a], xi) * hat(sy[a], eta);
                nx[a] = slope(sx[a]) / hx * hat(sy[a], eta);
                ny[a] = hat(sx[a], xi) * slope(sy[a]) / hy;
            }
            for a in 0..4 {
                for b in 0..4 {
                    // Products of shape functions first: (a, b) and (b, a) get the same bits.
                    let (nn, xx, yy) = (n[a] * n[b], nx[a] * nx[b], ny[a] * ny[b]);
                    let (xy, yx) = (nx[a] * ny[b], ny[a] * nx[b]);
                    let mass = weight * m.density * nn;
                    me[2 * a][2 * b] += mass;
                    me[2 * a + 1][2 * b + 1] += mass;
                    ke[2 * a][2 * b] += weight * (l2m * xx + m.mu * yy);
                    ke[2 * a + 1][2 * b + 1] += weight * (m.mu * xx + l2m * yy);
                    ke[2 * a][2 * b + 1] += weight * (lambda * xy + m.mu * yx);
                    ke[2 * a + 1][2 * b] += weight * (lambda * yx + m.mu * xy);
                }
            }
        }
    }
    if rule == Integration::Full {
        return (me, ke);
    }
    // λ div u div v at the centre, weight hx hy.
    let (mut cx, mut cy) = ([0.0; 4], [0.0; 4]);
    for a in 0..4 {
        cx[a] = slope(sx[a]) / hx * 0.5;
        cy[a] = 0.5 * slope(sy[a]) / hy;
    }
    let centre = hx * hy * m.lambda;
    for a in 0..4 {
        for b in 0..4 {
            let (xx, yy) = (cx[a] * cx[b], cy[a] * cy[b]);
            let (xy, yx) = (cx[a] * cy[b], cy[a] * cx[b]);
            ke[2 * a][2 * b] += centre * xx;
            ke[2 * a + 1][2 * b + 1] += centre * yy;
            ke[2 * a][2 * b + 1] += centre * xy;
            ke[2 * a + 1][2 * b] += centre * yx;
        }
    }
    (me, ke)
}

/// Assembles `M` and `K` on all degrees of freedom (full integration).
pub fn assemble(grid: &Grid, material: Material) -> Matrices {
    assemble_with(grid, material, Integration::Full)
}

/// Assembles `M` and `K` on all degrees of freedom, `K` integrated by `rule`.
pub fn assemble_with(grid: &Grid, material: Material, rule: Integration) -> Matrices {
    let pattern = stencil(grid);
    let mut mass = vec![0.0; pattern.nnz()];
    let mut stiffness = vec![0.0; pattern.nnz()];
    for j in 0..grid.ny {
        let (me, ke) = element_with(grid.hx, grid.hy(j), material, rule);
        for i in 0..grid.nx {
            let nodes = grid.cell_nodes(i, j);
            for (a, &na) in nodes.iter().enumerate() {
                for c in 0..2 {
                    let row = 2 * na + c;
                    for (b, &nb) in nodes.iter().enumerate() {
                        for d in 0..2 {
                            let at = pattern.position(row, 2 * nb + d);
                            mass[at] += me[2 * a + c][2 * b + d];
                            stiffness[at] += ke[2 * a + c][2 * b + d];
                        }
                    }
                }
            }
        }
    }
    Matrices {
        pattern,
        mass,
        stiffness,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Relative round-off allowed in a row of `K r` for a rigid motion `r`: each entry is a
    /// sum of at most 4 cells × 4 Gauss points of rounded products, and a row adds 18 of
    /// them, so a few hundred ulps of `‖K‖∞ ‖r‖∞` at most.
    const KERNEL_TOL: f64 = 1e-13;
    /// `1ᵀ M_c 1` adds `(2 (nx + 1)(ny + 1))²`-ish rounded entries: relative round-off.
    const MASS_SUM_TOL: f64 = 1e-12;

    fn grid() -> Grid {
        Grid::new(2.0, 0.5, 7, 5, 4.0)
    }

    const MATERIAL: Material = Material {
        lambda: 1.7,
        mu: 0.6,
        density: 2.5,
    };

    fn dense(p: &Pattern, a: &[f64]) -> Vec<Vec<f64>> {
        let mut d = vec![vec![0.0; p.n]; p.n];
        for (r, row) in d.iter_mut().enumerate() {
            for k in p.row_ptr[r]..p.row_ptr[r + 1] {
                row[p.cols[k]] = a[k];
            }
        }
        d
    }

    #[test]
    fn mass_and_stiffness_are_symmetric_bitwise() {
        let m = assemble(&grid(), MATERIAL);
        for a in [&m.mass, &m.stiffness] {
            let d = dense(&m.pattern, a);
            for (r, row) in d.iter().enumerate() {
                for (c, v) in row.iter().enumerate() {
                    assert_eq!(v.to_bits(), d[c][r].to_bits(), "({r}, {c})");
                }
            }
        }
    }

    #[test]
    fn mass_is_positive_definite_with_total_mass_rho_w_h_per_component() {
        let g = grid();
        let m = assemble(&g, MATERIAL);
        let total = MATERIAL.density * g.width * g.height;
        for c in 0..2 {
            let e: Vec<f64> = (0..g.dofs()).map(|d| f64::from(d % 2 == c)).collect();
            let sum = m.pattern.quad(&m.mass, &e);
            assert!((sum - total).abs() <= MASS_SUM_TOL * total, "{c}: {sum}");
        }
        // Positive definite: a dense Cholesky succeeds (nalgebra).
        let d = dense(&m.pattern, &m.mass);
        let n = d.len();
        let dm = nalgebra::DMatrix::from_fn(n, n, |r, c| d[r][c]);
        assert!(nalgebra::Cholesky::new(dm).is_some());
    }

    #[test]
    fn rigid_motions_are_in_the_kernel_of_k_to_round_off() {
        let g = grid();
        let m = assemble(&g, MATERIAL);
        let norm = (0..g.dofs())
            .map(|r| {
                (m.pattern.row_ptr[r]..m.pattern.row_ptr[r + 1])
                    .map(|k| m.stiffness[k].abs())
                    .sum::<f64>()
            })
            .fold(0.0, f64::max);
        type Motion = fn(f64, f64) -> (f64, f64);
        let motions: [(&str, Motion); 3] = [
            ("x translation", |_, _| (1.0, 0.0)),
            ("y translation", |_, _| (0.0, 1.0)),
            ("rotation", |x, y| (-y, x)),
        ];
        for (name, f) in motions {
            let mut r = vec![0.0; g.dofs()];
            for node in 0..g.nodes() {
                let (x, y) = g.point(node);
                (r[2 * node], r[2 * node + 1]) = f(x, y);
            }
            let mut kr = vec![0.0; g.dofs()];
            m.pattern.mul_into(&m.stiffness, &r, &mut kr);
            let scale = norm * r.iter().fold(0.0f64, |a, v| a.max(v.abs()));
            let worst = kr.iter().fold(0.0f64, |a, v| a.max(v.abs()));
            assert!(
                worst <= KERNEL_TOL * scale,
                "{name}: {worst:e} vs {scale:e}"
            );
        }
        // And K is not zero on a stretch: the kernel test can fail.
        let mut s = vec![0.0; g.dofs()];
        for node in 0..g.nodes() {
            s[2 * node] = g.point(node).0;
        }
        assert!(m.pattern.quad(&m.stiffness, &s) > 1.0);
    }

    #[test]
    fn restriction_keeps_the_entries_of_the_kept_rows_and_columns() {
        let g = Grid::new(1.0, 1.0, 2, 2, 1.0);
        let m = assemble(&g, MATERIAL);
        let keep: Vec<Option<usize>> = (0..g.dofs())
            .scan(0, |next, d| {
                Some((d % 3 != 0).then(|| {
                    *next += 1;
                    *next - 1
                }))
            })
            .collect();
        let (p, from) = m.pattern.restrict(&keep);
        let full = dense(&m.pattern, &m.stiffness);
        let values: Vec<f64> = from.iter().map(|&k| m.stiffness[k]).collect();
        let small = dense(&p, &values);
        let kept: Vec<usize> = (0..g.dofs()).filter(|d| keep[*d].is_some()).collect();
        for (a, &ra) in kept.iter().enumerate() {
            for (b, &rb) in kept.iter().enumerate() {
                assert_eq!(small[a][b], full[ra][rb]);
            }
        }
    }
}
