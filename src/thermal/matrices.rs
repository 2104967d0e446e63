//! The thermal bar's matrices on the bar's mesh: the P1 mass `M_θ` and stiffness `K_θ` of the
//! temperature (every node), the coupling `G_ij = ∫ ψ_j φ_i'` (displacement row `i`,
//! temperature column `j`), the temperature's step matrix `H_χ = M_θ + Δt κ/2 K_θ + Δt h/2 χ`
//! on its unknowns, and the coupled step matrix `[[C, −γ/2 G], [−γ/2 Gᵀ, −H_χ]]` in the
//! node-by-node interleaved order that keeps it banded. Derivation: `docs/thermal.md`.

use crate::bar::matrices::{MatrixVariant, mass, stiffness};
use crate::linalg::banded::SymBanded;
use crate::linalg::tridiag::SymTridiag;

/// Half-bandwidth of the interleaved coupled matrix: `u_i` couples with `θ_{i+1}` three
/// positions on.
pub const BAND: usize = 3;

/// `G_ij = ∫ ψ_j φ_i'` on a uniform mesh of `nodes` nodes: `−½` for `j = i + 1`, `½` for
/// `j = i − 1`, and on the diagonal `−½` at the left end, `½` at the right end, 0 inside.
#[inline(always)]
pub fn coupling_entry(i: usize, j: usize, nodes: usize) -> f64 {
    if j == i + 1 {
        -0.5
    } else if j + 1 == i {
        0.5
    } else if i == j && i == 0 {
        -0.5
    } else if i == j && i + 1 == nodes {
        0.5
    } else {
        0.0
    }
}

/// The layout of the thermal bar's unknowns and its temperature matrices.
#[derive(Clone, Debug)]
pub struct ThermalMatrices {
    /// All nodes, `J + 2`.
    pub nodes: usize,
    pub dt: f64,
    /// `κ`, `γ`.
    pub kappa: f64,
    pub gamma: f64,
    /// The displacement's unknowns: nodes `u_first..u_first + n_u` (block `0..n_u`).
    pub u_first: usize,
    pub n_u: usize,
    /// The temperature's unknowns: nodes `t_first..t_first + n_t` (block `n_u..n_u + n_t`;
    /// fixed-temperature ends removed).
    pub t_first: usize,
    pub n_t: usize,
    /// `M_θ` and `K_θ` on every node.
    pub mass: SymTridiag,
    pub stiffness: SymTridiag,
    /// The exchange ends' nodes and coefficients `h`, in the order of the exchange state's bits.
    pub exchange: Vec<(usize, f64)>,
}

impl ThermalMatrices {
    /// The matrices of a bar of `nodes` nodes, spacing `dx`: displacement unknowns from
    /// `u_first` (`n_u` of them), fixed temperatures at `[left, right]`, exchange ends.
    #[allow(clippy::too_many_arguments)]
    pub fn new(
        nodes: usize,
        dx: f64,
        dt: f64,
        (kappa, gamma): (f64, f64),
        (u_first, n_u): (usize, usize),
        fixed: [bool; 2],
        exchange: Vec<(usize, f64)>,
    ) -> Self {
        let t_first = usize::from(fixed[0]);
        let t_last = nodes - 1 - usize::from(fixed[1]);
        Self {
            nodes,
            dt,
            kappa,
            gamma,
            u_first,
            n_u,
            t_first,
            n_t: (t_last + 1).saturating_sub(t_first),
            mass: mass(MatrixVariant::Consistent, nodes, dx),
            stiffness: stiffness(MatrixVariant::Consistent, nodes, dx),
            exchange,
        }
    }

    /// The block index of the temperature unknown at `node`, if it is one.
    #[inline(always)]
    pub fn theta_unknown(&self, node: usize) -> Option<usize> {
        (node >= self.t_first && node < self.t_first + self.n_t)
            .then(|| self.n_u + node - self.t_first)
    }

    /// The block index of the displacement unknown at `node`, if it is one.
    #[inline(always)]
    pub fn u_unknown(&self, node: usize) -> Option<usize> {
        (node >= self.u_first && node < self.u_first + self.n_u).then(|| node - self.u_first)
    }

    /// `M_θ + s κ K_θ + s h χ` on the temperature's unknowns (`s = Δt/2` for the step,
    /// `Δt/4` for the start-up's half step), exchange end `e` counted when bit `e` of `mask`
    /// is set.
    pub fn heat_matrix(&self, s: f64, mask: usize) -> SymTridiag {
        let last = self.t_first + self.n_t - 1;
        let mut h = SymTridiag::combine(1.0, &self.mass, s * self.kappa, &self.stiffness)
            .sub(self.t_first, last);
        let mut diag = std::mem::take(&mut h.diag);
        for (e, &(node, coefficient)) in self.exchange.iter().enumerate() {
            if mask & (1 << e) != 0 {
                diag[node - self.t_first] += s * coefficient;
            }
        }
        SymTridiag::new(diag, std::mem::take(&mut h.off))
    }

    /// The interleaved order: position `k` holds block index `order[k]` (node by node, the
    /// displacement before the temperature).
    pub fn interleaved_order(&self) -> Vec<usize> {
        let mut order = Vec::with_capacity(self.n_u + self.n_t);
        for node in 0..self.nodes {
            order.extend(self.u_unknown(node));
            order.extend(self.theta_unknown(node));
        }
        order
    }

    /// The coupled step matrix `[[C, −γ/2 G], [−γ/2 Gᵀ, −H_χ]]` (`c`: the bar's `C`) in the
    /// interleaved order ([`ThermalMatrices::interleaved_order`]).
    pub fn coupled(&self, c: &SymTridiag, mask: usize) -> SymBanded<BAND> {
        let order = self.interleaved_order();
        let mut position = vec![0; order.len()];
        for (k, &b) in order.iter().enumerate() {
            position[b] = k;
        }
        let mut a = SymBanded::zeros(order.len());
        for i in 0..self.n_u {
            a.add(position[i], position[i], c.diag[i]);
            if i + 1 < self.n_u {
                a.add(position[i], position[i + 1], c.off[i]);
            }
        }
        let h = self.heat_matrix(0.5 * self.dt, mask);
        for j in 0..self.n_t {
            let p = position[self.n_u + j];
            a.add(p, p, -h.diag[j]);
            if j + 1 < self.n_t {
                a.add(p, position[self.n_u + j + 1], -h.off[j]);
            }
        }
        for iu in 0..self.n_u {
            let node = self.u_first + iu;
            for tnode in node.saturating_sub(1)..=(node + 1).min(self.nodes - 1) {
                let g = coupling_entry(node, tnode, self.nodes);
                if let (Some(jt), true) = (self.theta_unknown(tnode), g != 0.0) {
                    a.add(position[iu], position[jt], -0.5 * self.gamma * g);
                }
            }
        }
        a
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// `G 1` is `∫ φ_i'`: `−1` at the left end, `+1` at the right, 0 inside; and `Gᵀ` applied
    /// to a linear displacement is `∫ u_x ψ_j`, the nodal mass of the constant slope.
    #[test]
    fn coupling_integrates_the_shape_function_derivatives() {
        for nodes in [2usize, 3, 9] {
            let dx = 1.0 / (nodes - 1) as f64;
            for i in 0..nodes {
                let row: f64 = (0..nodes).map(|j| coupling_entry(i, j, nodes)).sum();
                let expected = if i == 0 {
                    -1.0
                } else if i + 1 == nodes {
                    1.0
                } else {
                    0.0
                };
                assert_eq!(row, expected, "nodes {nodes}, row {i}");
            }
            for j in 0..nodes {
                // u = x: ∫ 1 · ψ_j = dx (dx/2 at the ends).
                let gt: f64 = (0..nodes)
                    .map(|i| coupling_entry(i, j, nodes) * i as f64 * dx)
                    .sum();
                let expected = if j == 0 || j + 1 == nodes {
                    dx / 2.0
                } else {
                    dx
                };
                assert!(
                    (gt - expected).abs() <= 4.0 * f64::EPSILON,
                    "{gt} vs {expected}"
                );
            }
        }
    }

    /// The coupled matrix in the interleaved order is quasi-definite: symmetric, with as many
    /// positive pivots as displacement unknowns.
    #[test]
    fn the_coupled_matrix_has_the_inertia_of_its_blocks() {
        use crate::linalg::banded::BandedLdlt;
        let nodes = 11;
        let dx = 0.1;
        let dt = 0.05;
        for (fixed, u_first, n_u) in [
            ([false, false], 0, 11),
            ([false, true], 0, 10),
            ([true, false], 1, 10),
        ] {
            let m = ThermalMatrices::new(
                nodes,
                dx,
                dt,
                (0.3, 2.0),
                (u_first, n_u),
                fixed,
                vec![(0, 5.0)].into_iter().filter(|_| !fixed[0]).collect(),
            );
            let um = mass(MatrixVariant::Consistent, nodes, dx).sub(u_first, u_first + n_u - 1);
            let uk =
                stiffness(MatrixVariant::Consistent, nodes, dx).sub(u_first, u_first + n_u - 1);
            let c = SymTridiag::combine(1.0 / (dt * dt), &um, 0.5 + 0.1 / (2.0 * dt), &uk);
            for mask in 0..=usize::from(!fixed[0]) {
                let a = m.coupled(&c, mask);
                let f = BandedLdlt::factor(&a).unwrap();
                assert_eq!(f.inertia(), (m.n_u, m.n_t));
            }
        }
    }
}
