//! The thermal bar's coupled step matrix `A_χ = [[C, −γ/2 G], [−γ/2 Gᵀ, −H_χ]]` as the exact
//! end solver sees it ([`EndSystem`]): vectors in the body's block layout `[u | θ]`, the matrix
//! node by node (blocks `(u_i, θ_i)`, [`ThermalMatrices::coupled`]) with its block `LDLᵀ`
//! (by default its twisted twin, [`crate::linalg::kernels::block_tridiag_fast`]), and
//! one more factor per non-empty set of active ends (their displacement rows and columns
//! replaced by identity ones), all formed once per exchange state. `A_χ` is quasi-definite,
//! not positive definite; what the enumeration needs holds all the same: `E A_χ⁻¹ Eᵀ` on
//! displacement unknowns is the inverse's block `(C + γ²/4 G H_χ⁻¹ Gᵀ)⁻¹`, positive definite,
//! so the contact step stays an exact convex LCP (`docs/thermal.md`).

use crate::linalg::kernels::block_tridiag::{BlockLdlt, BlockTridiag, SingularBlock};
use crate::linalg::kernels::block_tridiag_fast::TwistedBlockLdlt;
use crate::linalg::tridiag::SymTridiag;
use crate::step::end_enumeration::EndSystem;
use crate::step::schur::{constraint_rows, row_product};
use crate::thermal::matrices::{ThermalMatrices, coupling_entry, heat_weight};

/// A block factor: the plain sweep, or its twisted twin.
#[derive(Clone, Debug)]
enum Factor {
    Plain(BlockLdlt),
    Twisted(Box<TwistedBlockLdlt>),
}

impl Factor {
    fn new(a: &BlockTridiag, twisted: bool) -> Result<Self, SingularBlock> {
        Ok(match twisted {
            true => Self::Twisted(Box::new(TwistedBlockLdlt::factor(a)?)),
            false => Self::Plain(BlockLdlt::factor(a)?),
        })
    }
}

/// The coupled step matrix of one exchange state with its factors, for the end enumeration.
#[derive(Clone, Debug)]
pub struct CoupledEnds {
    /// The block `LDLᵀ` of `A_χ`, and at index `mask − 1` that of `A_χ` with the displacement
    /// rows and columns of the active ends in `mask` replaced by identity ones.
    factor: Factor,
    reduced: Vec<Factor>,
    /// The first nodes of the displacement and the temperature unknowns.
    firsts: [usize; 2],
    /// The constrained displacement unknowns (at most two), the rows of `C` there
    /// ([`constraint_rows`]) and `−w γ G_ij` with the temperature's position `j` (`w` the
    /// step's weight, [`heat_weight`]).
    unknowns: Vec<usize>,
    rows: [[f64; 3]; 2],
    theta: [Vec<(usize, f64)>; 2],
    n_u: usize,
    /// `n_u + n_t`.
    dim: usize,
    /// The forward sweep of a solve, node by node.
    scratch: Vec<[f64; 2]>,
}

impl CoupledEnds {
    /// `A_χ` of exchange state `mask` (`c`: the bar's `C`), in its implicit Euler form when
    /// `implicit` ([`ThermalMatrices::coupled`]), constrained at the displacement unknowns
    /// `unknowns` (at most two); solved by the twisted twin of the block factor when `twisted`
    /// ([`crate::linalg::kernels::block_tridiag_fast`]).
    pub fn new(
        m: &ThermalMatrices,
        c: &SymTridiag,
        state: (usize, bool),
        unknowns: &[usize],
        twisted: bool,
    ) -> Result<Self, SingularBlock> {
        let nodes: Vec<usize> = unknowns.iter().map(|&i| i + m.u_first).collect();
        let factor = Factor::new(&m.coupled(c, state, &[]), twisted)?;
        let reduced = (1u8..(1 << nodes.len()))
            .map(|active| {
                let subset: Vec<usize> = (nodes.iter().enumerate())
                    .filter(|&(j, _)| active & (1 << j) != 0)
                    .map(|(_, &node)| node)
                    .collect();
                Factor::new(&m.coupled(c, state, &subset), twisted)
            })
            .collect::<Result<Vec<_>, _>>()?;
        let weight = heat_weight(state.1);
        let theta = [0, 1].map(|j| {
            let Some(&node) = nodes.get(j) else {
                return Vec::new();
            };
            (node.saturating_sub(1)..=(node + 1).min(m.nodes - 1))
                .filter_map(|t| {
                    let g = coupling_entry(node, t, m.nodes);
                    let k = m.theta_unknown(t)?;
                    (g != 0.0).then_some((k, -weight * m.gamma * g))
                })
                .collect()
        });
        Ok(Self {
            factor,
            reduced,
            firsts: [m.u_first, m.t_first],
            unknowns: unknowns.to_vec(),
            rows: constraint_rows(c, unknowns),
            theta,
            n_u: m.n_u,
            dim: m.n_u + m.n_t,
            scratch: vec![[0.0; 2]; m.nodes],
        })
    }

    /// `x ← F⁻¹ x` in the block layout by the factor `F`, the sweep carried by `y`.
    fn solve(&mut self, mask: u8, x: &mut [f64]) {
        let factor = match mask {
            0 => &self.factor,
            _ => &self.reduced[mask as usize - 1],
        };
        let (u, t) = x.split_at_mut(self.n_u);
        let [fu, ft] = self.firsts;
        match factor {
            Factor::Plain(f) => f.solve_fields([(u, fu), (t, ft)], &mut self.scratch),
            Factor::Twisted(f) => f.solve_fields([(u, fu), (t, ft)]),
        }
    }
}

impl EndSystem for CoupledEnds {
    fn solve_into(&mut self, b: &[f64], x: &mut [f64]) {
        x.copy_from_slice(b);
        self.solve(0, x);
    }

    fn solve_reduced_in_place(&mut self, mask: u8, x: &mut [f64]) {
        self.solve(mask, x);
    }

    /// The neighbouring displacements off the active set, and the temperatures coupled to it.
    fn move_to_rhs(&self, j: usize, v: f64, mask: u8, x: &mut [f64]) {
        let i = self.unknowns[j];
        let is_active = |k: usize| {
            (0..self.unknowns.len()).any(|a| mask & (1 << a) != 0 && self.unknowns[a] == k)
        };
        let [left, right, _] = self.rows[j];
        if i > 0 && !is_active(i - 1) {
            x[i - 1] -= left * v;
        }
        if i + 1 < self.n_u && !is_active(i + 1) {
            x[i + 1] -= right * v;
        }
        for &(k, a) in &self.theta[j] {
            x[k] -= a * v;
        }
    }

    /// `(C z_u)_i` in the bar's difference form, then the coupling to the temperatures.
    fn row_product(&self, j: usize, z: &[f64]) -> f64 {
        let mut s = row_product(self.rows[j], self.unknowns[j], &z[..self.n_u]);
        for &(k, a) in &self.theta[j] {
            s += a * z[k];
        }
        s
    }

    fn schur_complement(&mut self) -> [[f64; 2]; 2] {
        let mut schur = [[0.0; 2]; 2];
        let mut column = vec![0.0; self.dim];
        for (a, i) in self.unknowns.clone().into_iter().enumerate() {
            column.fill(0.0);
            column[i] = 1.0;
            self.solve(0, &mut column);
            for (b, &k) in self.unknowns.iter().enumerate() {
                schur[a][b] = column[k];
            }
        }
        let s = 0.5 * (schur[0][1] + schur[1][0]);
        (schur[0][1], schur[1][0]) = (s, s);
        schur
    }
}
