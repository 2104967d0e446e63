//! The optimised twin of the thermal energy terms' sums (`ThermalBody::quads`, node by node in
//! order) on the uniform mesh: over the elements between interior nodes, `Σ θ_k²`,
//! `Σ θ_k θ_k+1`, `Σ (θ̄_k+1 − θ̄_k)²` and `Σ Q_k θ̄_k` (`θ̄ = θ − ½ dθ`) in four lanes, scaled
//! once by the interior coefficients by the caller, compiled for AVX where the CPU has it
//! ([`dispatch::run`]). Agrees with the plain sums to round-off (another summation order).

use crate::linalg::dispatch;

/// Lanes of the sums: the element from interior node `k` adds into lane `k mod LANES`.
const LANES: usize = 4;

/// `[Σ θ_k², Σ θ_k θ_k+1, Σ (θ̄_k+1 − θ̄_k)², Σ Q_k θ̄_k]` over `k = 0..len − 1` of the
/// interior nodes' `θ` and `dθ` (`q`: `Q` at the same nodes, or empty without a source),
/// each summed in [`LANES`] lanes added at the end in a fixed order.
pub(crate) fn interior_sums(theta: &[f64], dtheta: &[f64], q: &[f64]) -> [f64; 4] {
    let lanes = if q.is_empty() {
        dispatch::run(Sums::<false> { theta, dtheta, q })
    } else {
        dispatch::run(Sums::<true> { theta, dtheta, q })
    };
    lanes.map(|[a, b, c, d]| (a + b) + (c + d))
}

/// The loop of [`interior_sums`], for [`dispatch::run`] (the same operations in the same
/// order on either path: the same bits).
struct Sums<'a, const SOURCE: bool> {
    theta: &'a [f64],
    dtheta: &'a [f64],
    q: &'a [f64],
}

impl<const SOURCE: bool> dispatch::Kernel for Sums<'_, SOURCE> {
    type Output = [[f64; LANES]; 4];

    #[inline(always)]
    fn call(self) -> Self::Output {
        let n = self.theta.len();
        let mut acc = [[0.0; LANES]; 4];
        if n < 2 {
            return acc;
        }
        let (theta, dtheta) = (self.theta, &self.dtheta[..n]);
        let q = if SOURCE { &self.q[..n] } else { &[][..] };
        // Whole blocks of LANES elements, lane by lane (vectorised), then the rest. No closure
        // is called per element (one would be compiled for the baseline only); `from_fn`'s is
        // inlined into the block, which the compiler vectorises (an index loop it did not).
        let elements = n - 1;
        let blocks = elements / LANES;
        for b in 0..blocks {
            let k0 = b * LANES;
            let x: &[f64; LANES + 1] = theta[k0..k0 + LANES + 1].try_into().expect("5 entries");
            let d: &[f64; LANES + 1] = dtheta[k0..k0 + LANES + 1].try_into().expect("5 entries");
            let y: [f64; LANES + 1] = std::array::from_fn(|l| x[l] - 0.5 * d[l]);
            for l in 0..LANES {
                acc[0][l] += x[l] * x[l];
                acc[1][l] += x[l] * x[l + 1];
                acc[2][l] += (y[l + 1] - y[l]) * (y[l + 1] - y[l]);
                if SOURCE {
                    acc[3][l] += q[k0 + l] * y[l];
                }
            }
        }
        for k in blocks * LANES..elements {
            let l = k % LANES;
            let (xk, xn) = (theta[k], theta[k + 1]);
            let (yk, yn) = (xk - 0.5 * dtheta[k], xn - 0.5 * dtheta[k + 1]);
            acc[0][l] += xk * xk;
            acc[1][l] += xk * xn;
            acc[2][l] += (yn - yk) * (yn - yk);
            if SOURCE {
                acc[3][l] += q[k] * yk;
            }
        }
        acc
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::linalg::dispatch::Kernel;

    /// The dispatched path (AVX where the CPU has it) has the bits of the loop as built, for
    /// every tail length, with and without a source.
    #[test]
    fn the_dispatched_sums_have_the_bits_of_the_baseline_loop() {
        for n in [0usize, 1, 2, 3, 4, 5, 6, 9, 10, 101] {
            let theta: Vec<f64> = (0..n).map(|k| (0.3 * k as f64).sin() + 0.1).collect();
            let dtheta: Vec<f64> = (0..n).map(|k| 1e-3 * (0.7 * k as f64).cos()).collect();
            let q: Vec<f64> = (0..n).map(|k| 0.01 * k as f64 - 0.2).collect();
            let lanes = |a: [[f64; LANES]; 4]| a.map(|[a, b, c, d]| (a + b) + (c + d));
            let bits = |v: [f64; 4]| v.map(f64::to_bits);
            let plain = Sums::<false> {
                theta: &theta,
                dtheta: &dtheta,
                q: &[],
            }
            .call();
            let sourced = Sums::<true> {
                theta: &theta,
                dtheta: &dtheta,
                q: &q,
            }
            .call();
            assert_eq!(
                bits(interior_sums(&theta, &dtheta, &[])),
                bits(lanes(plain)),
                "n {n}"
            );
            assert_eq!(
                bits(interior_sums(&theta, &dtheta, &q)),
                bits(lanes(sourced)),
                "n {n}"
            );
        }
    }
}
