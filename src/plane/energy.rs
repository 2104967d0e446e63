//! The sums of the plane body's energy identity (the scheme's, [`crate::scheme::Scheme::step`]).
//! The `K`-forms are evaluated cell by cell from the strains at the Gauss points, with nodal
//! differences ([`StrainForms`]): the same sums as `uᵀKu` in exact arithmetic, but a rigid
//! motion (a bending beam is locally one) adds no round-off, where `u·(Ku)` loses digits in
//! proportion to `‖K‖|u|²/uᵀKu`. They follow `K`'s integration rule: with selective reduced
//! integration the `λ (tr ε)²` term is taken at the cell centre, as in `K`.

use crate::linalg::sparse::Pattern;
use crate::plane::matrices::{Integration, Material};
use crate::plane::mesh::Grid;
use crate::scheme::body::EnergySums;

/// `∂N_a/∂x[g][a]`, `∂N_a/∂y[g][a]` at the Gauss points `g` of a cell row, and the weight.
type RowGradients = ([[f64; 4]; 4], [[f64; 4]; 4], f64);

/// `|u|²_K` cell by cell: `Σ_cells Σ_g w_g (λ (tr ε)² + 2μ ε:ε)` at the 2 × 2 Gauss points
/// that built `K` (selective: `Σ_g w_g 2μ ε:ε + hx hy λ (tr ε_centre)²`), the strains from
/// differences to the cell's first node.
pub struct StrainForms {
    nx: usize,
    ny: usize,
    material: Material,
    rule: Integration,
    /// Per cell row: `∂N_a/∂x`, `∂N_a/∂y` at each Gauss point, and the weight.
    rows: Vec<RowGradients>,
    /// Per cell row: `∂N_a/∂x`, `∂N_a/∂y` at the centre (selective integration's `λ` term).
    centres: Vec<([f64; 4], [f64; 4])>,
    /// Per cell (row by row), the unknown of each local degree of freedom `2a + c`
    /// ([`CLAMPED`] when clamped).
    cells: Vec<[u32; 8]>,
}

/// The unknown of a clamped degree of freedom in [`StrainForms`] (value 0).
const CLAMPED: u32 = u32::MAX;

impl StrainForms {
    /// The forms of full integration.
    pub fn new(grid: &Grid, material: Material, index: &[Option<usize>]) -> Self {
        Self::with_rule(grid, material, index, Integration::Full)
    }

    /// The forms of `K` integrated by `rule` ([`crate::plane::matrices::assemble_with`]).
    pub fn with_rule(
        grid: &Grid,
        material: Material,
        index: &[Option<usize>],
        rule: Integration,
    ) -> Self {
        let (sx, sy) = ([0.0, 1.0, 1.0, 0.0], [0.0, 0.0, 1.0, 1.0]);
        let d = 0.5 / 3f64.sqrt();
        let gauss = [0.5 - d, 0.5 + d];
        let hat = |s: f64, at: f64| if s == 0.0 { 1.0 - at } else { at };
        let slope = |s: f64| if s == 0.0 { -1.0 } else { 1.0 };
        let rows = (0..grid.ny)
            .map(|j| {
                let (hx, hy) = (grid.hx, grid.hy(j));
                let (mut gx, mut gy) = ([[0.0; 4]; 4], [[0.0; 4]; 4]);
                for (g, (xi, eta)) in gauss
                    .iter()
                    .flat_map(|xi| gauss.iter().map(move |eta| (*xi, *eta)))
                    .enumerate()
                {
                    for a in 0..4 {
                        gx[g][a] = slope(sx[a]) / hx * hat(sy[a], eta);
                        gy[g][a] = hat(sx[a], xi) * slope(sy[a]) / hy;
                    }
                }
                (gx, gy, 0.25 * hx * hy)
            })
            .collect();
        let centres = (0..grid.ny)
            .map(|j| {
                let (hx, hy) = (grid.hx, grid.hy(j));
                let cx = std::array::from_fn(|a| slope(sx[a]) / hx * 0.5);
                let cy = std::array::from_fn(|a| 0.5 * slope(sy[a]) / hy);
                (cx, cy)
            })
            .collect();
        let mut cells = Vec::with_capacity(grid.cells());
        for j in 0..grid.ny {
            for i in 0..grid.nx {
                let nodes = grid.cell_nodes(i, j);
                // Unknowns fit in u32: a scene has at most MAX_PLANE_UNKNOWNS of them.
                let unknown = |d: usize| index[d].map_or(CLAMPED, |k| k as u32);
                cells.push(std::array::from_fn(|l| unknown(2 * nodes[l / 2] + l % 2)));
            }
        }
        Self {
            nx: grid.nx,
            ny: grid.ny,
            material,
            rule,
            rows,
            centres,
            cells,
        }
    }

    /// `|x|²_K` for `x` on the unknowns (clamped degrees of freedom 0).
    pub fn quad(&self, x: &[f64]) -> f64 {
        self.quad_pair(|k| x[k], |_| 0.0).0
    }

    /// `(|x|²_K, |y|²_K)` in one pass over the cells, `x(k)`, `y(k)` the values of unknown
    /// `k` (each sum in the order of a pass of its own: the same bits).
    pub fn quad_pair(&self, x: impl Fn(usize) -> f64, y: impl Fn(usize) -> f64) -> (f64, f64) {
        // The λ taken at the Gauss points: all of it (full), none (selective: at the centre,
        // with four times the Gauss weight, `hx hy`).
        let selective = self.rule == Integration::Selective;
        let mu = self.material.mu;
        let lam = if selective { 0.0 } else { self.material.lambda };
        let strains = |ux: [f64; 4], uy: [f64; 4], gx: &[f64; 4], gy: &[f64; 4]| {
            let (mut exx, mut eyy, mut gxy) = (0.0, 0.0, 0.0);
            for a in 1..4 {
                let (dx, dy) = (ux[a] - ux[0], uy[a] - uy[0]);
                exx += gx[a] * dx;
                eyy += gy[a] * dy;
                gxy += gy[a] * dx + gx[a] * dy;
            }
            (exx, eyy, gxy)
        };
        let density = |ux: [f64; 4], uy: [f64; 4], gx: &[f64; 4], gy: &[f64; 4]| {
            let (exx, eyy, gxy) = strains(ux, uy, gx, gy);
            let tr = exx + eyy;
            lam * tr * tr + mu * (2.0 * (exx * exx + eyy * eyy) + gxy * gxy)
        };
        let volume = |ux: [f64; 4], uy: [f64; 4], (cx, cy): &([f64; 4], [f64; 4])| {
            let (exx, eyy, _) = strains(ux, uy, cx, cy);
            let tr = exx + eyy;
            4.0 * self.material.lambda * tr * tr
        };
        let (mut total_x, mut total_y) = (0.0, 0.0);
        for j in 0..self.ny {
            let (gx, gy, weight) = &self.rows[j];
            let (mut row_x, mut row_y) = (0.0, 0.0);
            for cell in &self.cells[j * self.nx..(j + 1) * self.nx] {
                let (xx, xy) = (gather(cell, &x, 0), gather(cell, &x, 1));
                let (yx, yy) = (gather(cell, &y, 0), gather(cell, &y, 1));
                for g in 0..4 {
                    row_x += density(xx, xy, &gx[g], &gy[g]);
                    row_y += density(yx, yy, &gx[g], &gy[g]);
                }
                if selective {
                    row_x += volume(xx, xy, &self.centres[j]);
                    row_y += volume(yx, yy, &self.centres[j]);
                }
            }
            total_x += weight * row_x;
            total_y += weight * row_y;
        }
        (total_x, total_y)
    }
}

/// Component `c` of `f` at a cell's four nodes (0 where clamped).
#[inline(always)]
fn gather(cell: &[u32; 8], f: &impl Fn(usize) -> f64, c: usize) -> [f64; 4] {
    std::array::from_fn(|a| match cell[2 * a + c] {
        CLAMPED => 0.0,
        k => f(k as usize),
    })
}

/// The sums of the energy identity ([`EnergySums`]), after `u += z` (`u = u^{n+1}`), with `w`
/// the previous increment: `zᵀMz` and `F·(z + w)` in one pass over the pattern, the `K`-forms
/// cell by cell.
pub fn measure(
    pattern: &Pattern,
    mass: &[f64],
    forms: &StrainForms,
    u: &[f64],
    z: &[f64],
    w: &[f64],
    force: Option<&[f64]>,
) -> EnergySums {
    let mut s = EnergySums::default();
    for r in 0..pattern.n {
        let mut mz = 0.0;
        for k in pattern.row_ptr[r]..pattern.row_ptr[r + 1] {
            mz += mass[k] * z[pattern.cols[k]];
        }
        s.kinetic += z[r] * mz;
        if let Some(f) = force {
            s.work += f[r] * (z[r] + w[r]);
        }
    }
    (s.potential, s.viscous) = forms.quad_pair(|k| u[k], |k| z[k] + w[k]);
    s
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::plane::matrices::assemble;

    /// The cell form and `xᵀKx` are the same sum in a different order: relative round-off of
    /// sums of a few thousand terms of one sign (K is positive semi-definite).
    const FORM_TOL: f64 = 1e-12;
    /// A rotation on top of a translation of 1e3: strains of the rounding of `1e3 ± y`
    /// (≈ 1e-13 / h), squared and summed over the body, far below this.
    const ROTATION_FORM_TOL: f64 = 1e-20;
    /// The same rotation with `λ = 900` instead of 1.3: the strains' round-off squared times
    /// `λ`, about 700 times [`ROTATION_FORM_TOL`]'s case, rounded up to a power of ten.
    const SELECTIVE_ROTATION_FORM_TOL: f64 = 1e-17;

    #[test]
    fn strain_forms_equal_the_stiffness_form_and_vanish_on_rigid_motions() {
        let grid = Grid::new(1.5, 0.5, 9, 4, 3.0);
        let material = Material {
            lambda: 1.3,
            mu: 0.4,
            density: 1.0,
        };
        let full = assemble(&grid, material);
        // Left edge clamped.
        let mut index = vec![None; grid.dofs()];
        let mut next = 0;
        for (d, i) in index.iter_mut().enumerate() {
            if grid.position(d / 2).0 != 0 {
                *i = Some(next);
                next += 1;
            }
        }
        let (pattern, from) = full.pattern.restrict(&index);
        let k: Vec<f64> = from.iter().map(|&f| full.stiffness[f]).collect();
        let forms = StrainForms::new(&grid, material, &index);
        let x: Vec<f64> = (0..next)
            .map(|i| ((i * 37) % 11) as f64 / 11.0 - 0.4)
            .collect();
        let (a, b) = (forms.quad(&x), pattern.quad(&k, &x));
        assert!((a - b).abs() <= FORM_TOL * b, "{a} {b}");
        // A rotation of the free body: the cell form gives round-off of the strains squared.
        let all: Vec<Option<usize>> = (0..grid.dofs()).map(Some).collect();
        let free = StrainForms::new(&grid, material, &all);
        let r: Vec<f64> = (0..grid.dofs())
            .map(|d| {
                let (x, y) = grid.point(d / 2);
                if d % 2 == 0 { 1e3 - y } else { 1e3 + x }
            })
            .collect();
        assert!(free.quad(&r) <= ROTATION_FORM_TOL, "{}", free.quad(&r));
        // Selective integration: the forms follow K's rule (a mismatch is of the order of the
        // λ term, far above round-off: the full forms against the selective K fail).
        use crate::plane::matrices::assemble_with;
        let stiff = Material {
            lambda: 900.0,
            ..material
        };
        let sel = assemble_with(&grid, stiff, Integration::Selective);
        let k: Vec<f64> = from.iter().map(|&f| sel.stiffness[f]).collect();
        let forms = StrainForms::with_rule(&grid, stiff, &index, Integration::Selective);
        let (a, b) = (forms.quad(&x), pattern.quad(&k, &x));
        assert!((a - b).abs() <= FORM_TOL * b, "{a} {b}");
        let full_forms = StrainForms::new(&grid, stiff, &index);
        assert!((full_forms.quad(&x) - b).abs() > 1e-3 * b);
        let free = StrainForms::with_rule(&grid, stiff, &all, Integration::Selective);
        assert!(
            free.quad(&r) <= SELECTIVE_ROTATION_FORM_TOL,
            "{}",
            free.quad(&r)
        );
    }
}
