//! The tensor grid of the plane body: `nx × ny` rectangular cells on `(0, W) × (0, H)`, uniform
//! in `x`, geometrically graded in `y` (cell heights `h_k = h_0 r^k`, `r^{ny−1}` = `y_grading`,
//! the ratio of the last to the first cell height).
//!
//! Nodes are numbered row by row, `node(i, j) = j (nx + 1) + i`; the degrees of freedom node
//! by node, `dof = 2 node + c` with `c = 0` for `ux`, `1` for `uy`.

/// The grid. `xs[i] = i · hx` with `hx = W / nx` (the bar's `x_i = i Δx`, the same bits), and
/// `ys` from 0 to `H` exactly.
#[derive(Clone, Debug)]
pub struct Grid {
    pub nx: usize,
    pub ny: usize,
    pub width: f64,
    pub height: f64,
    /// The cell width `W / nx`.
    pub hx: f64,
    /// `nx + 1` abscissae.
    pub xs: Vec<f64>,
    /// `ny + 1` ordinates, increasing, `ys[0] = 0`, `ys[ny] = H`.
    pub ys: Vec<f64>,
}

impl Grid {
    /// The grid of `nx × ny` cells (both at least 1), graded in `y` by `y_grading > 0` (1 =
    /// uniform, `ys[k] = k H / ny`).
    pub fn new(width: f64, height: f64, nx: usize, ny: usize, y_grading: f64) -> Self {
        let hx = width / nx as f64;
        let xs = (0..=nx).map(|i| i as f64 * hx).collect();
        let ys = if y_grading == 1.0 || ny == 1 {
            (0..=ny).map(|k| k as f64 * height / ny as f64).collect()
        } else {
            // Cell k has height h_0 r^k; the partial sums, scaled so that the last is H.
            let r = y_grading.powf(1.0 / (ny - 1) as f64);
            let mut sums = vec![0.0; ny + 1];
            for k in 0..ny {
                sums[k + 1] = sums[k] + r.powi(k as i32);
            }
            let total = sums[ny];
            let mut ys: Vec<f64> = sums.iter().map(|s| height * (s / total)).collect();
            ys[ny] = height;
            ys
        };
        Self {
            nx,
            ny,
            width,
            height,
            hx,
            xs,
            ys,
        }
    }

    /// `(nx + 1)(ny + 1)`.
    pub fn nodes(&self) -> usize {
        (self.nx + 1) * (self.ny + 1)
    }

    /// `2 · nodes`.
    pub fn dofs(&self) -> usize {
        2 * self.nodes()
    }

    /// `nx · ny`.
    pub fn cells(&self) -> usize {
        self.nx * self.ny
    }

    /// The node at column `i`, row `j`.
    pub fn node(&self, i: usize, j: usize) -> usize {
        j * (self.nx + 1) + i
    }

    /// `(i, j)` of a node.
    pub fn position(&self, node: usize) -> (usize, usize) {
        (node % (self.nx + 1), node / (self.nx + 1))
    }

    /// The coordinates of a node.
    pub fn point(&self, node: usize) -> (f64, f64) {
        let (i, j) = self.position(node);
        (self.xs[i], self.ys[j])
    }

    /// Height of cell row `j`, `ys[j + 1] − ys[j]`.
    pub fn hy(&self, j: usize) -> f64 {
        self.ys[j + 1] - self.ys[j]
    }

    /// The four nodes of cell `(i, j)`, counter-clockwise from the lower left:
    /// `(i, j), (i + 1, j), (i + 1, j + 1), (i, j + 1)`.
    pub fn cell_nodes(&self, i: usize, j: usize) -> [usize; 4] {
        [
            self.node(i, j),
            self.node(i + 1, j),
            self.node(i + 1, j + 1),
            self.node(i, j + 1),
        ]
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The graded ordinates are partial sums of a geometric series: a few ulps of H.
    const GRADING_TOL: f64 = 1e-13;

    #[test]
    fn graded_rows_have_the_asked_ratio_and_span_the_height() {
        let g = Grid::new(2.0, 0.25, 4, 5, 3.0);
        assert_eq!(g.ys[0], 0.0);
        assert_eq!(g.ys[5], 0.25);
        let ratio = g.hy(4) / g.hy(0);
        assert!((ratio - 3.0).abs() <= GRADING_TOL * 3.0 / 0.25, "{ratio}");
        let r = g.hy(1) / g.hy(0);
        for j in 1..5 {
            assert!((g.hy(j) / g.hy(j - 1) - r).abs() <= GRADING_TOL / 0.25 * 10.0);
        }
        let u = Grid::new(2.0, 1.0, 4, 4, 1.0);
        assert_eq!(u.ys, vec![0.0, 0.25, 0.5, 0.75, 1.0]);
        assert_eq!(u.xs, vec![0.0, 0.5, 1.0, 1.5, 2.0]);
        assert_eq!(u.position(u.node(3, 2)), (3, 2));
    }
}
