//! The interior rows of the thermal bar's right-hand side as one streaming kernel
//! ([`HeatRows`]): the heat rows and the coupling's `+= γ G φ` on the displacement rows, on
//! the uniform mesh's coefficients, compiled for AVX where the CPU has it
//! ([`dispatch::run`]: the same operations in the same order, the same bits).

use crate::linalg::kernels::dispatch;

/// The interior heat rows `−sκ (K_θ θ)_j − γ/2 (Gᵀ w)_j` (with `s Q_j` between them when
/// there is a source) and the coupling's `+= γ (G φ)_i`, for [`dispatch::run`]:
/// compiled for AVX where the CPU has it, the same operations in the same order.
pub(crate) struct HeatRows<'a> {
    pub(crate) row: HeatRow,
    pub(crate) s: f64,
    pub(crate) gamma: f64,
    pub(crate) sign: f64,
    pub(crate) th: &'a [f64],
    pub(crate) w: &'a [f64],
    pub(crate) q: &'a [f64],
    pub(crate) b: &'a mut [f64],
    pub(crate) bu: Option<&'a mut [f64]>,
}

/// The coefficients of an interior heat row: `a = −sκ`, `K_jj`, `K_j,j+1`, `c = γ/2`.
#[derive(Clone, Copy)]
pub(crate) struct HeatRow {
    pub(crate) a: f64,
    pub(crate) kd: f64,
    pub(crate) ko: f64,
    pub(crate) c: f64,
}

impl HeatRow {
    /// `−sκ (K_θ θ)_j` from `θ_j−1, θ_j, θ_j+1` at `th[j..j + 3]`.
    #[inline(always)]
    fn heat(self, th: &[f64], j: usize) -> f64 {
        self.a * (self.kd * th[j + 1] + self.ko * th[j] + self.ko * th[j + 2])
    }

    /// `γ/2 (Gᵀ w)_j` from `w[j..j + 3]`.
    #[inline(always)]
    fn coupled(self, w: &[f64], j: usize) -> f64 {
        self.c * (0.5 * (w[j + 1] - w[j]) + 0.5 * (w[j + 2] - w[j + 1]))
    }
}

impl dispatch::Kernel for HeatRows<'_> {
    type Output = ();

    /// One loop per case, so that each runs without a test per row; no closure (one would be
    /// compiled for the baseline only).
    #[inline(always)]
    fn call(self) {
        let Self {
            row,
            s,
            gamma,
            sign,
            th,
            w,
            q,
            b,
            bu,
        } = self;
        let n = b.len();
        let (th, w) = (&th[..n + 2], &w[..n + 2]);
        match (q.is_empty(), row.c == 0.0) {
            (true, true) => {
                for (j, bj) in b.iter_mut().enumerate() {
                    *bj = sign * row.heat(th, j);
                }
            }
            (true, false) => {
                for (j, bj) in b.iter_mut().enumerate() {
                    *bj = sign * (row.heat(th, j) - row.coupled(w, j));
                }
            }
            (false, true) => {
                for (j, (bj, qj)) in b.iter_mut().zip(q).enumerate() {
                    *bj = sign * (row.heat(th, j) + s * qj);
                }
            }
            (false, false) => {
                for (j, (bj, qj)) in b.iter_mut().zip(q).enumerate() {
                    *bj = sign * ((row.heat(th, j) + s * qj) - row.coupled(w, j));
                }
            }
        }
        // `+= γ (G φ)_i` on the same nodes.
        if let Some(bu) = bu {
            for (i, bi) in bu[..n].iter_mut().enumerate() {
                *bi += gamma * (0.5 * (th[i] + th[i + 1]) - 0.5 * (th[i + 1] + th[i + 2]));
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::linalg::kernels::dispatch::Kernel;

    /// The heat rows run through `dispatch::run` (AVX where the CPU has it) have the bits of
    /// the loop as built, in each case (with or without a source, with or without coupling).
    #[test]
    fn the_dispatched_heat_rows_have_the_bits_of_the_baseline_loop() {
        let n = 37;
        let th: Vec<f64> = (0..n + 2).map(|k| (0.3 * k as f64).sin() + 0.2).collect();
        let w: Vec<f64> = (0..n + 2).map(|k| 1e-3 * (0.9 * k as f64).cos()).collect();
        let source: Vec<f64> = (0..n).map(|k| 0.01 * k as f64 - 0.1).collect();
        for (q, gamma) in [
            (&[][..], 0.0),
            (&[][..], 0.3),
            (&source[..], 0.0),
            (&source[..], 0.3),
        ] {
            let rows = |b: &mut [f64], bu: &mut [f64], dispatched: bool| {
                let kernel = HeatRows {
                    row: HeatRow {
                        a: -0.01 * 0.05,
                        kd: 2.0 * n as f64,
                        ko: -(n as f64),
                        c: 0.5 * gamma,
                    },
                    s: 0.01,
                    gamma,
                    sign: -1.0,
                    th: &th,
                    w: &w,
                    q,
                    b,
                    bu: (gamma != 0.0).then_some(bu),
                };
                if dispatched {
                    dispatch::run(kernel)
                } else {
                    kernel.call()
                }
            };
            let (mut b0, mut bu0) = (vec![0.0; n], vec![0.5; n]);
            let (mut b1, mut bu1) = (b0.clone(), bu0.clone());
            rows(&mut b0, &mut bu0, false);
            rows(&mut b1, &mut bu1, true);
            let bits = |v: &[f64]| v.iter().map(|x| x.to_bits()).collect::<Vec<_>>();
            assert_eq!(bits(&b0), bits(&b1), "q {}, γ {gamma}", q.len());
            assert_eq!(bits(&bu0), bits(&bu1), "q {}, γ {gamma}", q.len());
        }
    }
}
