//! A dense brute-force reference for the step problem, independent of the banded code: it
//! enumerates every active set of the `k` bounds, solves each equality-constrained problem with
//! nalgebra's dense LU, keeps the feasible stationary points and returns the one with the least
//! objective. Exponential in `k`; used as an oracle in tests.

use nalgebra::{DMatrix, DVector};

/// Result of the enumeration.
#[derive(Clone, Debug)]
pub struct OracleSolution {
    pub z: Vec<f64>,
    pub reactions: Vec<f64>,
    pub objective: f64,
}

/// Largest number of bounds the oracle accepts (2^k dense solves).
pub const MAX_ORACLE_BOUNDS: usize = 16;

/// The oracle refuses problems with more than [`MAX_ORACLE_BOUNDS`] bounds.
#[derive(Clone, Copy, Debug, PartialEq, thiserror::Error)]
#[error("the brute-force oracle refuses {0} bounds (2^{0} solves); at most {MAX_ORACLE_BOUNDS}")]
pub struct TooManyBounds(pub usize);

/// `min ½ zᵀCz − bᵀz` s.t. `z[nodes[j]] >= lower[j]`, by enumeration; `C` dense SPD.
/// Feasibility of each candidate is judged with slack `tol` (round-off in the dense solve).
/// `Ok(None)` when no active set gives a feasible point (only possible through round-off).
pub fn brute_force(
    c: &DMatrix<f64>,
    b: &[f64],
    nodes: &[usize],
    lower: &[f64],
    tol: f64,
) -> Result<Option<OracleSolution>, TooManyBounds> {
    let n = b.len();
    let k = nodes.len();
    if k > MAX_ORACLE_BOUNDS {
        return Err(TooManyBounds(k));
    }
    let bv = DVector::from_column_slice(b);
    let mut best: Option<OracleSolution> = None;
    for mask in 0u32..(1 << k) {
        let active: Vec<usize> = (0..k).filter(|j| mask & (1 << j) != 0).collect();
        // KKT system [C  −E; Eᵀ 0] [z; r] = [b; lo_A] with E the selected unit columns.
        let m = n + active.len();
        let mut kkt = DMatrix::zeros(m, m);
        kkt.view_mut((0, 0), (n, n)).copy_from(c);
        let mut rhs = DVector::zeros(m);
        rhs.rows_mut(0, n).copy_from(&bv);
        for (a, &j) in active.iter().enumerate() {
            kkt[(nodes[j], n + a)] = -1.0;
            kkt[(n + a, nodes[j])] = 1.0;
            rhs[n + a] = lower[j];
        }
        let Some(sol) = kkt.lu().solve(&rhs) else {
            continue;
        };
        let z: Vec<f64> = sol.rows(0, n).iter().copied().collect();
        let feasible = (0..k).all(|j| z[nodes[j]] >= lower[j] - tol);
        if !feasible {
            continue;
        }
        let mut reactions = vec![0.0; k];
        for (a, &j) in active.iter().enumerate() {
            reactions[j] = sol[n + a];
        }
        let zv = DVector::from_column_slice(&z);
        let objective = 0.5 * zv.dot(&(c * &zv)) - bv.dot(&zv);
        if best.as_ref().is_none_or(|b| objective < b.objective) {
            best = Some(OracleSolution {
                z,
                reactions,
                objective,
            });
        }
    }
    Ok(best)
}
