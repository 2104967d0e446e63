//! Lemke's complementary pivoting method for the dense, non-symmetric LCP `w = M x + q >= 0,
//! x >= 0, xᵀw = 0` (`N × N`; the frictional contact problem of [`crate::step::condensed_lemke`]), with
//! the lexicographic ratio test, which visits no almost-complementary basis twice, so the method
//! ends after finitely many pivots, on a solution or on a ray (Cottle, Pang & Stone, *The Linear
//! Complementarity Problem*, §4.4 and §4.9). Revised form: `B⁻¹` of the current basis, dense,
//! updated by one elimination per pivot and re-inverted after `N` pivots; the answer is refined
//! once against the basis' own columns. Warm start: each call first tries the previous call's
//! complementary basis as it is, then Lemke from it with the covering vector `d = B·1`; should
//! that end on a ray or pass its pivot limit, Lemke from the slack basis with `d = 1`, whose
//! termination on a solution `docs/friction.md#termination` proves for
//! the frictional LCP. Allocates nothing after set-up.

/// A dense LCP that was not solved.
#[derive(Clone, Debug, PartialEq, thiserror::Error)]
pub enum LemkeError {
    /// No positive entry in the entering column: the method ended on a secondary ray.
    #[error("Lemke's method ended on a ray after {pivots} pivots (no solution reached)")]
    Ray { pivots: u32 },
    /// The guard on the number of pivots (finite termination makes it unreachable in exact
    /// arithmetic).
    #[error("Lemke's method did not terminate in {pivots} pivots")]
    PivotLimit { pivots: u32 },
    /// The data or the answer is not finite.
    #[error("the complementarity problem has non-finite data or answer")]
    NonFinite,
    /// The final basis' answer is negative beyond round-off (an ill-conditioned basis).
    #[error("Lemke's final basis gives a negative variable {value:e} (tolerance {tolerance:e})")]
    Infeasible { value: f64, tolerance: f64 },
}

/// Entries of the pivot column at most this many ulps of its largest entry count as zero: they
/// are at the round-off of `B⁻¹ a`, and pivoting on them would divide by noise.
pub const PIVOT_ULPS: f64 = 65_536.0;
/// Ratios and lexicographic entries within this many ulps of the least are ties, and so are
/// basic values within it of 0 (a value that small is 0 in the tableau's round-off).
pub const LEMKE_ULPS: f64 = 256.0;
/// Runs of Lemke's method per call beyond the stored basis: a run, and one more from where it
/// ended should the refined answer of the first be a round-off away from feasible.
const RUNS: usize = 2;

/// Where a run of Lemke's method starts.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum Start {
    /// From the stored complementary basis with `d = B·1`.
    Warm,
    /// From the slack basis `B = I` with `d = 1`.
    Cold,
}

/// What one call did.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct LemkeOutcome {
    /// Pivots made (0: the stored basis was feasible as it was).
    pub pivots: u32,
    /// Whether the warm Lemke run gave up and the cold one was made.
    pub restarted: bool,
}

/// Lemke's method for one `M`, solved for many `q`. The tableau is `w − M x − d x₀ = q`; its
/// variables are numbered `w_i` → `i`, `x_i` → `N + i`, the artificial `x₀` → `2N`.
#[derive(Clone, Debug)]
pub struct Lemke {
    n: usize,
    /// `M` stored by columns (`m_cols[j * n + i] = M_ij`).
    m_cols: Vec<f64>,
    /// `max_i Σ_j |M_ij|`.
    m_norm: f64,
    /// `B⁻¹`, row `r` belonging to the basic variable `basis[r]`.
    binv: Vec<f64>,
    basis: Vec<usize>,
    /// The values of the basic variables.
    b: Vec<f64>,
    /// The pivot column `B⁻¹ a`, the covering vector, scratch.
    y: Vec<f64>,
    d: Vec<f64>,
    column: Vec<f64>,
    rho: Vec<f64>,
    ties: Vec<usize>,
    /// Work space of the re-inversion: `B` and the row order of its elimination.
    work: Vec<f64>,
    order: Vec<usize>,
    pivots_since_inversion: usize,
    /// Per run of Lemke's method, the bases it visited as sets (tests only).
    #[cfg(test)]
    visited: Vec<Vec<Vec<usize>>>,
    /// The most rows tied at a ratio test (tests only).
    #[cfg(test)]
    most_ties: usize,
}

impl Lemke {
    /// Set-up for `M` given row-major (`m[i * n + j] = M_ij`); the stored basis is the slack one.
    pub fn new(m: &[f64], n: usize) -> Self {
        assert_eq!(m.len(), n * n, "M must be n x n");
        let mut m_cols = vec![0.0; n * n];
        for i in 0..n {
            for j in 0..n {
                m_cols[j * n + i] = m[i * n + j];
            }
        }
        let m_norm = (0..n)
            .map(|i| m[i * n..(i + 1) * n].iter().map(|v| v.abs()).sum::<f64>())
            .fold(0.0, f64::max);
        let mut this = Self {
            n,
            m_cols,
            m_norm,
            binv: vec![0.0; n * n],
            basis: vec![0; n],
            b: vec![0.0; n],
            y: vec![0.0; n],
            d: vec![0.0; n],
            column: vec![0.0; n],
            rho: vec![0.0; n],
            ties: Vec::with_capacity(n + 1),
            work: vec![0.0; n * n],
            order: vec![0; n],
            pivots_since_inversion: 0,
            #[cfg(test)]
            visited: Vec::new(),
            #[cfg(test)]
            most_ties: 0,
        };
        this.reset();
        this
    }

    /// `N`.
    pub fn dim(&self) -> usize {
        self.n
    }

    /// Forgets the warm start: the slack basis `B = I`.
    pub fn reset(&mut self) {
        let n = self.n;
        self.binv.fill(0.0);
        for i in 0..n {
            self.binv[i * n + i] = 1.0;
            self.basis[i] = i;
        }
        self.pivots_since_inversion = 0;
    }

    /// Whether `x_i` is basic in the stored complementary basis (else `w_i` is).
    pub fn x_basic(&self, i: usize) -> bool {
        self.basis.contains(&(self.n + i))
    }

    /// `w = M x + q`.
    pub fn slack_into(&self, q: &[f64], x: &[f64], w: &mut [f64]) {
        let n = self.n;
        w.copy_from_slice(q);
        for (j, &xj) in x.iter().enumerate() {
            if xj != 0.0 {
                for (wi, m) in w.iter_mut().zip(&self.m_cols[j * n..(j + 1) * n]) {
                    *wi += m * xj;
                }
            }
        }
    }

    /// `M_ij`.
    pub fn entry(&self, i: usize, j: usize) -> f64 {
        self.m_cols[j * self.n + i]
    }

    /// The column `a_v` of variable `v` in `B x_B = q`: `e_i` for `w_i`, `−M e_j` for `x_j`,
    /// `−d` for `x₀`, into `out`.
    fn column_of(&self, v: usize, out: &mut [f64]) {
        let n = self.n;
        if v < n {
            out.fill(0.0);
            out[v] = 1.0;
        } else if v < 2 * n {
            let j = v - n;
            for (o, m) in out.iter_mut().zip(&self.m_cols[j * n..(j + 1) * n]) {
                *o = -m;
            }
        } else {
            for (o, d) in out.iter_mut().zip(&self.d) {
                *o = -d;
            }
        }
    }

    /// `y = B⁻¹ a_v`.
    fn pivot_column(&mut self, v: usize) {
        let n = self.n;
        if v < n {
            for r in 0..n {
                self.y[r] = self.binv[r * n + v];
            }
            return;
        }
        let mut column = std::mem::take(&mut self.column);
        self.column_of(v, &mut column);
        for r in 0..n {
            let row = &self.binv[r * n..(r + 1) * n];
            self.y[r] = row.iter().zip(&column).map(|(a, c)| a * c).sum();
        }
        self.column = column;
    }

    /// Pivots variable `v` (column `y` already computed) into row `r`.
    fn pivot(&mut self, r: usize, v: usize) {
        let n = self.n;
        let inv = 1.0 / self.y[r];
        let (b, binv, y) = (&mut self.b, &mut self.binv, &self.y);
        for a in &mut binv[r * n..(r + 1) * n] {
            *a *= inv;
        }
        b[r] *= inv;
        let br = b[r];
        for i in (0..n).filter(|&i| i != r && y[i] != 0.0) {
            let f = y[i];
            let (row, row_r) = if i < r {
                let (head, tail) = binv.split_at_mut(r * n);
                (&mut head[i * n..(i + 1) * n], &tail[..n])
            } else {
                let (head, tail) = binv.split_at_mut(i * n);
                (&mut tail[..n], &head[r * n..(r + 1) * n])
            };
            for (a, pr) in row.iter_mut().zip(row_r) {
                *a -= f * pr;
            }
            b[i] -= f * br;
        }
        self.basis[r] = v;
        self.pivots_since_inversion += 1;
    }

    /// Of the rows in `self.ties`, keeps those lexicographically least by `B⁻¹_i / y_i`
    /// (`y_i = 1` for every row when `unit`), column by column up to round-off, and returns the
    /// least index of what remains (the ratios `b_i / y_i` were compared by the caller).
    fn lexicographic_least(&mut self, unit: bool) -> usize {
        let n = self.n;
        let ulp = LEMKE_ULPS * f64::EPSILON;
        let mut ties = std::mem::take(&mut self.ties);
        #[cfg(test)]
        {
            self.most_ties = self.most_ties.max(ties.len());
        }
        let y = |i: usize| if unit { 1.0 } else { self.y[i] };
        for k in 0..n {
            if ties.len() <= 1 {
                break;
            }
            let ratio = |i: usize| self.binv[i * n + k] / y(i);
            let scale = |i: usize| {
                let row = &self.binv[i * n..(i + 1) * n];
                row.iter().fold(0.0f64, |a, v| a.max(v.abs())) / y(i).abs()
            };
            let least = ties.iter().map(|&i| ratio(i)).fold(f64::INFINITY, f64::min);
            ties.retain(|&i| ratio(i) <= least + ulp * scale(i));
        }
        // Round-off left several rows equal: the least index decides.
        let r = ties
            .iter()
            .copied()
            .min()
            .expect("a tie set is never empty");
        self.ties = ties;
        r
    }

    /// The value scale of the tableau for the tolerances: `‖M‖ ‖b‖ + ‖q‖`.
    fn scale(&self, q_max: f64) -> f64 {
        let b_max = self.b.iter().fold(0.0f64, |a, v| a.max(v.abs()));
        self.m_norm.max(1.0) * b_max + q_max
    }

    /// Lemke's method from the stored basis; `Ok(pivots)` on a solution (x₀ left the basis).
    fn run(&mut self, q: &[f64], start: Start, limit: u32) -> Result<u32, LemkeError> {
        let n = self.n;
        let x0 = 2 * n;
        match start {
            Start::Cold => {
                self.reset();
                self.d.fill(1.0);
                self.b.copy_from_slice(q);
            }
            Start::Warm => {
                // d = B·1, so that B⁻¹ d = 1 exactly by construction.
                self.d.fill(0.0);
                let mut column = std::mem::take(&mut self.column);
                for r in 0..n {
                    self.column_of(self.basis[r], &mut column);
                    for (d, c) in self.d.iter_mut().zip(&column) {
                        *d += c;
                    }
                }
                self.column = column;
            }
        }
        let q_max = q.iter().fold(0.0f64, |a, v| a.max(v.abs()));
        // x₀ enters: x_B = b + t·1 >= 0 from t = −min b; the leaving row is the
        // lexicographically least of (b_i, B⁻¹_i), so every row stays lexicographically positive.
        let least = self.b.iter().copied().fold(f64::INFINITY, f64::min);
        let tol = LEMKE_ULPS * f64::EPSILON * self.scale(q_max);
        let mut ties = std::mem::take(&mut self.ties);
        ties.clear();
        ties.extend((0..n).filter(|&i| self.b[i] <= least + tol));
        self.ties = ties;
        let r = self.lexicographic_least(true);
        self.y.fill(-1.0);
        let mut leaving = self.basis[r];
        self.pivot(r, x0);
        #[cfg(test)]
        {
            self.visited.push(Vec::new());
            self.record();
        }
        let mut pivots = 1u32;
        loop {
            if leaving == x0 {
                return Ok(pivots);
            }
            if pivots >= limit {
                return Err(LemkeError::PivotLimit { pivots });
            }
            let entering = if leaving < n {
                leaving + n
            } else {
                leaving - n
            };
            self.pivot_column(entering);
            let y_max = self.y.iter().fold(0.0f64, |a, v| a.max(v.abs()));
            if !y_max.is_finite() {
                return Err(LemkeError::NonFinite);
            }
            let piv_tol = PIVOT_ULPS * f64::EPSILON * y_max;
            let mut least = f64::INFINITY;
            for i in 0..n {
                if self.y[i] > piv_tol {
                    least = least.min(self.b[i].max(0.0) / self.y[i]);
                }
            }
            if !least.is_finite() {
                return Err(LemkeError::Ray { pivots });
            }
            let tol = LEMKE_ULPS * f64::EPSILON * self.scale(q_max);
            self.ties.clear();
            for i in 0..n {
                let yi = self.y[i];
                if yi > piv_tol && self.b[i].max(0.0) / yi <= least + tol / yi {
                    self.ties.push(i);
                }
            }
            // x₀ leaving on a tie ends the run on a solution at once.
            let r = match self.ties.iter().copied().find(|&i| self.basis[i] == x0) {
                Some(r) => r,
                None => self.lexicographic_least(false),
            };
            leaving = self.basis[r];
            self.pivot(r, entering);
            #[cfg(test)]
            self.record();
            pivots += 1;
        }
    }

    /// The current basis, as a set, into the current run's list of visited bases (tests only).
    #[cfg(test)]
    fn record(&mut self) {
        let mut basis = self.basis.clone();
        basis.sort_unstable();
        self.visited.last_mut().expect("a run").push(basis);
    }

    /// `B` of the stored basis into `work` (row-major), then `B⁻¹` into `binv` by Gauss–Jordan
    /// elimination with partial pivoting; `false` if `B` is numerically singular.
    fn invert(&mut self) -> bool {
        let n = self.n;
        let mut column = std::mem::take(&mut self.column);
        for r in 0..n {
            self.column_of(self.basis[r], &mut column);
            for (i, c) in column.iter().enumerate() {
                self.work[i * n + r] = *c;
            }
        }
        self.column = column;
        // [work | binv] ← [B | I], eliminated to [I | B⁻¹] by rows.
        self.binv.fill(0.0);
        for i in 0..n {
            self.binv[i * n + i] = 1.0;
            self.order[i] = i;
        }
        let (a, inv) = (&mut self.work, &mut self.binv);
        for c in 0..n {
            let p = (c..n)
                .max_by(|&i, &j| a[i * n + c].abs().total_cmp(&a[j * n + c].abs()))
                .expect("a column below the diagonal");
            if a[p * n + c] == 0.0 || !a[p * n + c].is_finite() {
                return false;
            }
            if p != c {
                for k in 0..n {
                    a.swap(p * n + k, c * n + k);
                    inv.swap(p * n + k, c * n + k);
                }
            }
            let pivot = 1.0 / a[c * n + c];
            for k in 0..n {
                a[c * n + k] *= pivot;
                inv[c * n + k] *= pivot;
            }
            for i in 0..n {
                let f = a[i * n + c];
                if i != c && f != 0.0 {
                    for k in 0..n {
                        a[i * n + k] -= f * a[c * n + k];
                        inv[i * n + k] -= f * inv[c * n + k];
                    }
                }
            }
        }
        // Row r of B⁻¹ belongs to basis[r]: the elimination kept that order (the swaps were
        // of equations, the unknowns stayed in place).
        self.pivots_since_inversion = 0;
        true
    }

    /// `b ← B⁻¹q`, refined once against the basis' columns; returns the largest residual of
    /// `B b = q` before the refinement.
    fn basic_values(&mut self, q: &[f64]) -> f64 {
        let n = self.n;
        for r in 0..n {
            let row = &self.binv[r * n..(r + 1) * n];
            self.b[r] = row.iter().zip(q).map(|(a, c)| a * c).sum();
        }
        self.rho.copy_from_slice(q);
        for r in 0..n {
            let v = self.basis[r];
            let br = self.b[r];
            if v < n {
                self.rho[v] -= br;
            } else {
                let j = v - n;
                for (rho, m) in self.rho.iter_mut().zip(&self.m_cols[j * n..(j + 1) * n]) {
                    *rho += m * br;
                }
            }
        }
        let residual = self.rho.iter().fold(0.0f64, |a, v| a.max(v.abs()));
        for r in 0..n {
            let row = &self.binv[r * n..(r + 1) * n];
            let c: f64 = row.iter().zip(&self.rho).map(|(a, c)| a * c).sum();
            self.b[r] += c;
        }
        residual
    }

    /// Solves `w = M x + q >= 0 ⊥ x >= 0` into `x`, warm-started from the previous call's
    /// basis (after a failed call, from the slack basis). Basic values within round-off of 0
    /// are set to 0; `w = Mx + q` is [`Lemke::slack_into`]. Allocates nothing.
    pub fn solve(&mut self, q: &[f64], x: &mut [f64]) -> Result<LemkeOutcome, LemkeError> {
        let result = self.solve_from_stored(q, x);
        if result.is_err() {
            self.reset();
        }
        result
    }

    fn solve_from_stored(&mut self, q: &[f64], x: &mut [f64]) -> Result<LemkeOutcome, LemkeError> {
        let n = self.n;
        assert!(q.len() == n && x.len() == n);
        if !q.iter().all(|v| v.is_finite()) {
            return Err(LemkeError::NonFinite);
        }
        let q_max = q.iter().fold(0.0f64, |a, v| a.max(v.abs()));
        let mut outcome = LemkeOutcome::default();
        // The stored basis as it is; then at most two runs of Lemke's method, each from the
        // basis the last one ended on (a run can end a round-off away from feasible).
        for attempt in 0..=RUNS {
            let tol = self.refined_values(q, q_max);
            let worst = self.b.iter().copied().fold(f64::INFINITY, f64::min);
            if worst >= -tol {
                break;
            }
            if !worst.is_finite() {
                return Err(LemkeError::NonFinite);
            }
            if attempt == RUNS {
                return Err(LemkeError::Infeasible {
                    value: worst,
                    tolerance: tol,
                });
            }
            let warm = self.basis.iter().enumerate().any(|(r, &v)| v != r);
            let result = if warm {
                self.run(q, Start::Warm, n as u32 + 10)
            } else {
                Err(LemkeError::Ray { pivots: 0 })
            };
            outcome.pivots += match result {
                Ok(p) => p,
                Err(LemkeError::NonFinite) => return Err(LemkeError::NonFinite),
                Err(LemkeError::Ray { pivots } | LemkeError::PivotLimit { pivots }) => {
                    outcome.restarted |= warm;
                    pivots + self.run(q, Start::Cold, 50 * n as u32 + 100)?
                }
                Err(e) => return Err(e),
            };
            if self.pivots_since_inversion >= n.max(8) && !self.invert() {
                return Err(LemkeError::NonFinite);
            }
        }
        x.fill(0.0);
        for r in 0..n {
            let v = self.basis[r];
            if (n..2 * n).contains(&v) {
                x[v - n] = self.b[r].max(0.0);
            }
        }
        Ok(outcome)
    }

    /// The basic values of the stored basis ([`Lemke::basic_values`]; again after a fresh
    /// inversion when the first residual is beyond round-off), and the tolerance below which
    /// a negative one is round-off: [`LEMKE_ULPS`] ε times the tableau's scale and the basis'
    /// condition `‖B⁻¹‖∞ (1 + ‖M‖∞)`.
    fn refined_values(&mut self, q: &[f64], q_max: f64) -> f64 {
        let n = self.n;
        let residual = self.basic_values(q);
        let round_off = LEMKE_ULPS * f64::EPSILON * self.scale(q_max);
        if (residual > round_off || residual.is_nan()) && self.invert() {
            self.basic_values(q);
        }
        let inverse = (0..n)
            .map(|r| {
                self.binv[r * n..(r + 1) * n]
                    .iter()
                    .map(|v| v.abs())
                    .sum::<f64>()
            })
            .fold(0.0, f64::max);
        LEMKE_ULPS * f64::EPSILON * self.scale(q_max) * inverse * (1.0 + self.m_norm)
    }
}

/// The LCP by enumeration of all `2^N` complementary bases (tests, `N <= 12`): the first basis,
/// in the order of the masks, whose answer meets the conditions to `tol` (`x` for the `x`
/// basic in it, `w = M x + q`); `None` when none does.
pub fn enumerate(m: &[f64], q: &[f64], tol: f64) -> Option<Vec<f64>> {
    let n = q.len();
    assert!(n <= 12, "enumeration of 2^n bases");
    for mask in 0u32..(1 << n) {
        let idx: Vec<usize> = (0..n).filter(|k| mask >> k & 1 == 1).collect();
        let a = idx.len();
        let maa = nalgebra::DMatrix::from_fn(a, a, |i, j| m[idx[i] * n + idx[j]]);
        let qa = nalgebra::DVector::from_fn(a, |i, _| -q[idx[i]]);
        let xa = if a == 0 {
            qa
        } else {
            match maa.lu().solve(&qa) {
                Some(x) => x,
                None => continue,
            }
        };
        let mut x = vec![0.0; n];
        for (i, &k) in idx.iter().enumerate() {
            x[k] = xa[i];
        }
        let ok = (0..n).all(|k| {
            let w = q[k] + (0..n).map(|j| m[k * n + j] * x[j]).sum::<f64>();
            x[k] >= -tol && w >= -tol
        });
        if ok {
            return Some(x);
        }
    }
    None
}

#[cfg(test)]
mod tests {
    use super::*;
    use proptest::prelude::*;

    /// Complementarity, signs and `w = Mx + q` of an answer, relative to `‖M‖‖x‖ + ‖q‖`: a row
    /// of `M x + q` from a refined basic solution of a well-conditioned basis (condition below
    /// about 1e3 here) rounds to a few hundred ulps of that scale at most.
    const KKT_TOL: f64 = 1e-11;

    fn check(m: &[f64], q: &[f64], x: &[f64]) {
        let n = q.len();
        let m_norm = (0..n)
            .map(|i| m[i * n..(i + 1) * n].iter().map(|v| v.abs()).sum::<f64>())
            .fold(0.0, f64::max);
        let x_max = x.iter().fold(0.0f64, |a, v| a.max(v.abs()));
        let q_max = q.iter().fold(0.0f64, |a, v| a.max(v.abs()));
        let tol = KKT_TOL * (m_norm * x_max + q_max).max(f64::MIN_POSITIVE);
        for k in 0..n {
            let w = q[k] + (0..n).map(|j| m[k * n + j] * x[j]).sum::<f64>();
            assert!(x[k] >= 0.0 && w >= -tol, "signs at {k}: x {} w {w}", x[k]);
            assert!((x[k] * w).abs() <= tol * x[k].max(1.0), "x w at {k}");
        }
    }

    /// The frictional LCP of a random SPD `S` on `m` normals, the first `p` with friction
    /// `mu` (the structure of [`crate::step::condensed_lemke`] at scale 1): rows and columns `N`
    /// (`0..m`), `β⁺`, `β⁻`, `λ` (`p` each).
    fn friction_lcp(m: usize, p: usize, seed: &[f64], mu: f64) -> Vec<f64> {
        let k = m + p;
        let b = |i: usize, j: usize| seed[(i * k + j) % seed.len()];
        let s = |i: usize, j: usize| {
            (0..k).map(|l| b(l, i) * b(l, j)).sum::<f64>() + if i == j { 0.3 } else { 0.0 }
        };
        let n = m + 3 * p;
        let mut a = vec![0.0; n * n];
        // The signed copies of row (or column) i of S: N, β⁺ (+1) and β⁻ (−1).
        let copies = |i: usize| -> Vec<(usize, f64)> {
            if i < m {
                vec![(i, 1.0)]
            } else {
                vec![(i, 1.0), (i + p, -1.0)]
            }
        };
        for i in 0..k {
            for j in 0..k {
                for &(row, si) in &copies(i) {
                    for &(col, sj) in &copies(j) {
                        a[row * n + col] = si * sj * s(i, j);
                    }
                }
            }
        }
        for l in 0..p {
            let (plus, minus, lambda) = (m + l, m + p + l, m + 2 * p + l);
            a[plus * n + lambda] = 1.0;
            a[minus * n + lambda] = 1.0;
            a[lambda * n + l] = mu;
            a[lambda * n + plus] = -1.0;
            a[lambda * n + minus] = -1.0;
        }
        a
    }

    proptest! {
        #![proptest_config(ProptestConfig::with_cases(200))]
        #[test]
        fn lemke_solves_random_frictional_lcps_warm_and_cold(
            m in 1usize..4,
            p_frac in 0.0f64..1.0,
            seed in prop::collection::vec(-1.0f64..1.0, 1..30),
            qs in prop::collection::vec(-2.0f64..2.0, 24),
            mu in 0.0f64..2.0,
        ) {
            let p = ((m as f64 * p_frac).round() as usize).min(m);
            let a = friction_lcp(m, p, &seed, mu);
            let n = m + 3 * p;
            let mut lemke = Lemke::new(&a, n);
            let mut x = vec![0.0; n];
            // Three right-hand sides in a row: the second and third start warm.
            for q in qs.chunks_exact(8).take(3) {
                let mut qv = vec![0.0; n];
                qv[..m].copy_from_slice(&q[..m]);
                for l in 0..p {
                    qv[m + l] = q[4 + l];
                    qv[m + p + l] = -q[4 + l];
                }
                lemke.solve(&qv, &mut x).unwrap();
                check(&a, &qv, &x);
                // Cone and slip law in the answer's own terms.
                for l in 0..p {
                    let rt = x[m + l] - x[m + p + l];
                    prop_assert!(rt.abs() <= mu * x[l] + 1e-9 * (1.0 + x[l]));
                }
            }
        }

        #[test]
        fn lemke_matches_enumeration_on_p_matrices(
            n in 1usize..7,
            seed in prop::collection::vec(-1.0f64..1.0, 1..49),
            q in prop::collection::vec(-2.0f64..2.0, 6),
        ) {
            // A non-symmetric P-matrix: SPD plus a skew part; the solution is unique.
            let b = |i: usize, j: usize| seed[(i * n + j) % seed.len()];
            let mut a = vec![0.0; n * n];
            for i in 0..n {
                for j in 0..n {
                    a[i * n + j] = (0..n).map(|k| b(k, i) * b(k, j)).sum::<f64>()
                        + 0.5 * (b(i, j) - b(j, i));
                }
                a[i * n + i] += 0.2;
            }
            let q = &q[..n];
            let mut x = vec![0.0; n];
            Lemke::new(&a, n).solve(q, &mut x).unwrap();
            check(&a, q, &x);
            let xe = enumerate(&a, q, 1e-12).unwrap();
            let scale = xe.iter().fold(1.0f64, |s, v| s.max(v.abs()));
            for k in 0..n {
                prop_assert!((x[k] - xe[k]).abs() <= 1e-9 * scale, "{k}: {} {}", x[k], xe[k]);
            }
        }
    }

    #[test]
    fn degenerate_cases_and_the_warm_start() {
        // q >= 0: x = 0 without a pivot.
        let a = vec![2.0, -1.0, -1.0, 2.0];
        let mut l = Lemke::new(&a, 2);
        let mut x = [1.0; 2];
        assert_eq!(l.solve(&[1.0, 0.0], &mut x).unwrap().pivots, 0);
        assert_eq!(x, [0.0; 2]);
        // Both active, then the same q again: the stored basis is feasible, no pivot.
        let q = [-1.0, -1.0];
        assert!(l.solve(&q, &mut x).unwrap().pivots > 0);
        check(&a, &q, &x);
        assert_eq!(l.solve(&q, &mut x).unwrap().pivots, 0);
        assert!(l.x_basic(0) && l.x_basic(1));
        // A zero matrix with q = (−1, 0): no solution, a ray.
        let mut z = Lemke::new(&[0.0; 4], 2);
        assert!(matches!(
            z.solve(&[-1.0, 0.0], &mut x),
            Err(LemkeError::Ray { .. })
        ));
        // Non-finite data.
        assert_eq!(
            Lemke::new(&a, 2).solve(&[f64::NAN, 0.0], &mut x),
            Err(LemkeError::NonFinite)
        );
        // A degenerate frictional problem: a node pressed straight down (q_T = 0, q_λ = 0).
        let f = friction_lcp(1, 1, &[0.5, 0.2, -0.3], 0.5);
        let q = [-1.0, 0.0, 0.0, 0.0];
        let mut x = [0.0; 4];
        Lemke::new(&f, 4).solve(&q, &mut x).unwrap();
        check(&f, &q, &x);
        assert!(x[0] > 0.0);
    }

    /// Solves `q` with `lemke` (warm from its stored basis): no run of the call visits a basis
    /// twice, and the call ends on a solution; returns the most rows tied at a ratio test.
    fn solve_without_revisiting(lemke: &mut Lemke, m: &[f64], q: &[f64]) -> usize {
        lemke.visited.clear();
        lemke.most_ties = 0;
        let mut x = vec![0.0; q.len()];
        let outcome = lemke.solve(q, &mut x);
        for (k, run) in lemke.visited.iter().enumerate() {
            for (i, basis) in run.iter().enumerate() {
                let again = run[..i].iter().position(|b| b == basis);
                assert!(
                    again.is_none(),
                    "run {k} visits the basis {basis:?} at pivots {} and {} (q = {q:?})",
                    again.unwrap_or(0) + 1,
                    i + 1
                );
            }
        }
        assert!(outcome.is_ok(), "{outcome:?} (q = {q:?})");
        check(m, q, &x);
        lemke.most_ties
    }

    /// Eight nodes pressed straight down onto a floor, with friction and no tangential drive
    /// (`q_T = 0`, `q_λ = 0`): every normal ties at `x₀`'s entry and the tangential rows tie at
    /// the ratio 0. Cold, then warm through other presses (some nodes just touching, `q_N = 0`)
    /// and back: Lemke's method ends on a solution without visiting a basis twice in any run.
    #[test]
    fn lemke_ends_without_revisiting_a_basis_on_a_degenerate_frictional_lcp() {
        use crate::step::condensed_lemke::stewart_trinkle_matrix;
        use crate::step::solver::Friction;
        let (m, mu) = (8usize, 0.5);
        let k = 2 * m;
        // S = GᵀG + I/2 on the normals then the tangents: SPD, coupled (as E C⁻¹ Eᵀ is).
        let g = |i: usize, j: usize| ((7 * i + 3 * j) % 11) as f64 / 11.0 - 0.45;
        let mut s = vec![0.0; k * k];
        for i in 0..k {
            for j in 0..k {
                s[i * k + j] = (0..k).map(|l| g(l, i) * g(l, j)).sum::<f64>();
            }
            s[i * k + i] += 0.5;
        }
        let friction = Friction {
            normals: (0..m).collect(),
            tangents: (m..k).collect(),
            coefficients: vec![mu; m],
        };
        let sigma = (0..k).map(|i| s[i * k + i]).fold(0.0, f64::max);
        let a = stewart_trinkle_matrix(&s, m, &friction, sigma);
        let n = m + 3 * m;
        let pressed = |down: &[f64]| {
            let mut q = vec![0.0; n];
            q[..m].copy_from_slice(down);
            q
        };
        let straight = pressed(&[-1.0; 8]);
        let touching = pressed(&[-1.0, 0.0, -1.0, 0.0, -2.0, -2.0, 0.0, -1.0]);
        let mut lemke = Lemke::new(&a, n);
        let mut most = 0;
        for q in [&straight, &touching, &straight, &touching] {
            most = most.max(solve_without_revisiting(&mut lemke, &a, q));
        }
        most = most.max(solve_without_revisiting(
            &mut Lemke::new(&a, n),
            &a,
            &touching,
        ));
        // The ties the lexicographic rule breaks: all eight normals at x₀'s entry.
        assert!(most >= m, "most rows tied {most}");
    }

    /// Two degenerate LCPs on which the plain ratio test, ties broken by row order, cycles;
    /// built here and run in exact (rational) arithmetic: `q = −1` ties every row at `x₀`'s
    /// entry and later ratios tie at 0. `M₁` (ties to the least row) and `M₂` (to the greatest)
    /// return to their second basis at the eighth pivot and go round a cycle of six bases for
    /// ever; the lexicographic rule reaches the solution `x = (⅓, ⅓, ⅓)` in 4 and 6 pivots.
    /// Both are P-matrices (unique solution, on which Lemke's method must end).
    #[test]
    fn lemke_does_not_cycle_where_the_plain_ratio_test_does() {
        let m1 = [1.0, 2.0, 0.0, 0.0, 1.0, 2.0, 2.0, 0.0, 1.0];
        let m2 = [1.0, 0.0, 2.0, 2.0, 1.0, 0.0, 0.0, 2.0, 1.0];
        let q = [-1.0; 3];
        for m in [m1, m2] {
            let ties = solve_without_revisiting(&mut Lemke::new(&m, 3), &m, &q);
            assert_eq!(ties, 3, "every row ties at x₀'s entry");
            let mut x = [0.0; 3];
            Lemke::new(&m, 3).solve(&q, &mut x).unwrap();
            for xi in x {
                assert!((xi - 1.0 / 3.0).abs() <= KKT_TOL, "{x:?}");
            }
        }
    }
}
