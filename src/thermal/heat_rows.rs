//! The interior rows of the thermal bar's right-hand side as one streaming loop
//! ([`HeatRows`]): the heat rows and the coupling's `+= γ G φ` on the displacement rows, on
//! the uniform mesh's coefficients, the same operations in the same order as the general rows
//! of `ThermalBody::heat_rhs`.

/// The interior heat rows `−sκ (K_θ θ)_j − γ/2 (Gᵀ w)_j` (with `s Q_j` between them when
/// there is a source) and the coupling's `+= γ (G φ)_i`, with their arguments ([`HeatRows::run`]).
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

impl HeatRows<'_> {
    /// Writes the rows: one loop per case, so that each runs without a test per row.
    pub(crate) fn run(self) {
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
