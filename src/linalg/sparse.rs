//! Sparse symmetric matrices stored as values on a shared CSR pattern (the plane body's `M`,
//! `K` and `C`): products, quadratic forms, and the restriction to kept rows and columns.

/// A symmetric sparsity pattern in CSR (equivalently CSC): row `r` holds the columns
/// `cols[row_ptr[r]..row_ptr[r + 1]]`, sorted.
#[derive(Clone, Debug)]
pub struct Pattern {
    pub n: usize,
    pub row_ptr: Vec<usize>,
    pub cols: Vec<usize>,
}

impl Pattern {
    /// The position of `(row, col)` in the value arrays (the pattern must hold it).
    pub fn position(&self, row: usize, col: usize) -> usize {
        let range = self.row_ptr[row]..self.row_ptr[row + 1];
        let at = self.cols[range.clone()]
            .binary_search(&col)
            .expect("the stencil holds every pair of nodes of a cell");
        range.start + at
    }

    /// Stored entries.
    pub fn nnz(&self) -> usize {
        self.cols.len()
    }

    /// `y = A x` for the values `a` on this pattern.
    pub fn mul_into(&self, a: &[f64], x: &[f64], y: &mut [f64]) {
        for (r, yr) in y.iter_mut().enumerate() {
            let mut s = 0.0;
            for k in self.row_ptr[r]..self.row_ptr[r + 1] {
                s += a[k] * x[self.cols[k]];
            }
            *yr = s;
        }
    }

    /// `xᵀ A x`.
    pub fn quad(&self, a: &[f64], x: &[f64]) -> f64 {
        let mut total = 0.0;
        for (r, xr) in x.iter().enumerate() {
            let mut s = 0.0;
            for k in self.row_ptr[r]..self.row_ptr[r + 1] {
                s += a[k] * x[self.cols[k]];
            }
            total += xr * s;
        }
        total
    }

    /// The pattern on the kept rows and columns (`keep[d]` the new index of `d`, `None` when
    /// removed) and, for each kept entry, its position in this pattern.
    pub fn restrict(&self, keep: &[Option<usize>]) -> (Pattern, Vec<usize>) {
        let n = keep.iter().flatten().count();
        let mut row_ptr = Vec::with_capacity(n + 1);
        let (mut cols, mut from) = (Vec::new(), Vec::new());
        row_ptr.push(0);
        for r in 0..self.n {
            if keep[r].is_none() {
                continue;
            }
            for k in self.row_ptr[r]..self.row_ptr[r + 1] {
                if let Some(c) = keep[self.cols[k]] {
                    cols.push(c);
                    from.push(k);
                }
            }
            row_ptr.push(cols.len());
        }
        (Pattern { n, row_ptr, cols }, from)
    }
}
