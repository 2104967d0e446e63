//! The plane body's stress for output: the Kelvin–Voigt stress `σ = A ε(u) + α A ε(v)` of plane
//! strain at each cell centre (the centre gradients of the Q1 interpolant; the same value for
//! either integration rule), and at the nodes the area-weighted mean of the centre values of
//! the (one to four) cells that share the node; von Mises from the averaged components, with
//! `σ_zz = λ tr ε(u + α v)`.

use crate::plane::matrices::Material;
use crate::plane::mesh::Grid;

/// `[σ_xx, σ_yy, σ_xy, σ_zz]` at the centre of every cell (row by row) for `u` and `v` at
/// every degree of freedom (`2 node + c`).
pub fn cell_stress(
    grid: &Grid,
    material: Material,
    alpha: f64,
    u: &[f64],
    v: &[f64],
) -> Vec<[f64; 4]> {
    let (lam, mu) = (material.lambda, material.mu);
    let mut out = Vec::with_capacity(grid.cells());
    for j in 0..grid.ny {
        let (hx, hy) = (grid.hx, grid.hy(j));
        for i in 0..grid.nx {
            let [a, b, c, d] = grid.cell_nodes(i, j);
            let w = |n: usize, k: usize| u[2 * n + k] + alpha * v[2 * n + k];
            // At the centre: ∂x = (right − left)/hx averaged over the two rows, ∂y likewise.
            let grad = |k: usize| {
                (
                    0.5 * ((w(b, k) - w(a, k)) + (w(c, k) - w(d, k))) / hx,
                    0.5 * ((w(d, k) - w(a, k)) + (w(c, k) - w(b, k))) / hy,
                )
            };
            let ((xx, xy), (yx, yy)) = (grad(0), grad(1));
            let tr = xx + yy;
            out.push([
                lam * tr + 2.0 * mu * xx,
                lam * tr + 2.0 * mu * yy,
                mu * (xy + yx),
                lam * tr,
            ]);
        }
    }
    out
}

/// The von Mises stress of `[σ_xx, σ_yy, σ_xy, σ_zz]`.
pub fn von_mises([sxx, syy, sxy, szz]: [f64; 4]) -> f64 {
    (0.5 * ((sxx - syy).powi(2) + (syy - szz).powi(2) + (szz - sxx).powi(2)) + 3.0 * sxy * sxy)
        .sqrt()
}

/// `[σ_xx, σ_yy, σ_xy, σ_zz]` at every node: the area-weighted mean of [`cell_stress`] over the
/// cells sharing the node.
pub fn nodal_stress(grid: &Grid, cells: &[[f64; 4]]) -> Vec<[f64; 4]> {
    let mut sum = vec![[0.0; 4]; grid.nodes()];
    let mut area = vec![0.0; grid.nodes()];
    for j in 0..grid.ny {
        let a = grid.hx * grid.hy(j);
        for i in 0..grid.nx {
            let s = cells[j * grid.nx + i];
            for n in grid.cell_nodes(i, j) {
                for (t, v) in sum[n].iter_mut().zip(s) {
                    *t += a * v;
                }
                area[n] += a;
            }
        }
    }
    for (s, a) in sum.iter_mut().zip(&area) {
        for v in s.iter_mut() {
            *v /= a;
        }
    }
    sum
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Each value is a few roundings of quantities of size one.
    const STRESS_TOL: f64 = 1e-14;

    /// A uniform strain gives the same stress in every cell and at every node (nodal means of
    /// equal values), Hooke's law in plane strain, on a graded grid.
    #[test]
    fn a_uniform_strain_gives_hookes_stress_everywhere() {
        let grid = Grid::new(2.0, 1.0, 5, 3, 4.0);
        let m = Material {
            lambda: 1.5,
            mu: 0.75,
            density: 1.0,
        };
        let (mut u, mut v) = (vec![0.0; grid.dofs()], vec![0.0; grid.dofs()]);
        for node in 0..grid.nodes() {
            let (x, y) = grid.point(node);
            (u[2 * node], u[2 * node + 1]) = (0.2 * x + 0.1 * y, 0.3 * x - 0.4 * y);
            (v[2 * node], v[2 * node + 1]) = (x, 0.0);
        }
        let alpha = 0.5;
        // ε(u + α v): exx = 0.2 + 0.5, eyy = −0.4, 2 exy = 0.1 + 0.3.
        let (exx, eyy, gxy) = (0.7, -0.4, 0.4);
        let tr = exx + eyy;
        let want = [
            m.lambda * tr + 2.0 * m.mu * exx,
            m.lambda * tr + 2.0 * m.mu * eyy,
            m.mu * gxy,
            m.lambda * tr,
        ];
        let cells = cell_stress(&grid, m, alpha, &u, &v);
        for s in cells.iter().chain(&nodal_stress(&grid, &cells)) {
            for (a, b) in s.iter().zip(want) {
                assert!((a - b).abs() <= STRESS_TOL, "{s:?} {want:?}");
            }
        }
        // Pure shear: von Mises is √3 |σ_xy|.
        assert!((von_mises([0.0, 0.0, 2.0, 0.0]) - 2.0 * 3f64.sqrt()).abs() <= STRESS_TOL);
    }
}
