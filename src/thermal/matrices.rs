//! The thermal bar's matrices on the bar's mesh: the P1 mass `M_θ` and stiffness `K_θ` of the
//! temperature (every node), the coupling `G_ij = ∫ ψ_j φ_i'` (displacement row `i`,
//! temperature column `j`), the temperature's step matrix `H_χ = M_θ + Δt κ/2 K_θ + Δt h/2 χ`
//! on its unknowns, and the coupled step matrix `[[C, −γ/2 G], [−γ/2 Gᵀ, −H_χ]]` node by node,
//! block-tridiagonal with blocks of order 2; an implicit Euler step's
//! `[[C, −γ G], [−γ Gᵀ, −2(M_θ + Δt κ K_θ + Δt h χ)]]` beside it. Derivation: `docs/thermal.md`.

use crate::bar::matrices::{MatrixVariant, mass, stiffness};
use crate::linalg::kernels::block_tridiag::BlockTridiag;
use crate::linalg::tridiag::SymTridiag;

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

/// The weight `w` of the temperature in a heat step, `θ_w = θ^{n−1/2} + w (θ^{n+1/2} −
/// θ^{n−1/2})`: `½` (Crank–Nicolson), `1` (implicit Euler, `implicit`).
#[inline(always)]
pub fn heat_weight(implicit: bool) -> f64 {
    if implicit { 1.0 } else { 0.5 }
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

    /// `a M_θ + s κ K_θ + s h χ` on the temperature's unknowns (`a = 1, s = Δt/2` for the
    /// Crank–Nicolson step, `a = 2, s = 2Δt` for an implicit Euler step, `a = 1, s = Δt/2`
    /// for the start-up's implicit half step), exchange end `e` counted when bit `e` of `mask`
    /// is set.
    pub fn heat_matrix(&self, (a, s): (f64, f64), mask: usize) -> SymTridiag {
        let last = self.t_first + self.n_t - 1;
        let mut h = SymTridiag::combine(a, &self.mass, s * self.kappa, &self.stiffness)
            .sub(self.t_first, last);
        let mut diag = std::mem::take(&mut h.diag);
        for (e, &(node, coefficient)) in self.exchange.iter().enumerate() {
            if mask & (1 << e) != 0 {
                diag[node - self.t_first] += s * coefficient;
            }
        }
        SymTridiag::new(diag, std::mem::take(&mut h.off))
    }

    /// The heat block of a step: `H_χ` for Crank–Nicolson, `2(M_θ + Δt κ K_θ + Δt h χ)` for
    /// an implicit Euler step (`implicit`), the heat rows then scaled by `−2Δt` so that the
    /// coupled matrix stays symmetric (`docs/thermal.md`).
    pub fn step_heat_matrix(&self, mask: usize, implicit: bool) -> SymTridiag {
        match implicit {
            false => self.heat_matrix((1.0, 0.5 * self.dt), mask),
            true => self.heat_matrix((2.0, 2.0 * self.dt), mask),
        }
    }

    /// The coupled step matrix `[[C, −γ/2 G], [−γ/2 Gᵀ, −H_χ]]` (`c`: the bar's `C`) node by
    /// node, or with `implicit` its implicit Euler form `[[C, −γ G], [−γ Gᵀ, −2(M_θ + Δt κ K_θ
    /// + Δt h χ)]]`, block `i` holding `(u_i, θ_i)`: a node without a displacement unknown (clamped),
    /// or one of `identity` (an active constraint's node), has the row and column of `u_i`
    /// replaced by identity ones; a node without a temperature unknown (fixed) a row and
    /// column `−1` on the diagonal, 0 elsewhere, so a solve leaves 0 there.
    pub fn coupled(
        &self,
        c: &SymTridiag,
        (mask, implicit): (usize, bool),
        identity: &[usize],
    ) -> BlockTridiag {
        let h = self.step_heat_matrix(mask, implicit);
        let u = |node: usize| self.u_unknown(node).filter(|_| !identity.contains(&node));
        let t = |node: usize| self.theta_unknown(node).map(|j| j - self.n_u);
        let weight = heat_weight(implicit);
        let g = |i: usize, j: usize| -weight * self.gamma * coupling_entry(i, j, self.nodes);
        let mut a = BlockTridiag::zeros(self.nodes);
        for node in 0..self.nodes {
            let d = &mut a.diag[node];
            d[0][0] = u(node).map_or(1.0, |i| c.diag[i]);
            d[1][1] = t(node).map_or(-1.0, |j| -h.diag[j]);
            if u(node).is_some() && t(node).is_some() {
                (d[0][1], d[1][0]) = (g(node, node), g(node, node));
            }
            if node == 0 {
                continue;
            }
            let (prev, e) = (node - 1, &mut a.lower[node]);
            if let (Some(i), Some(_)) = (u(node), u(prev)) {
                e[0][0] = c.off[i - 1];
            }
            if let (Some(_), Some(_)) = (u(node), t(prev)) {
                e[0][1] = g(node, prev);
            }
            if let (Some(_), Some(_)) = (t(node), u(prev)) {
                e[1][0] = g(prev, node);
            }
            if let (Some(j), Some(_)) = (t(node), t(prev)) {
                e[1][1] = -h.off[j - 1];
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

    /// The coupled matrix node by node is quasi-definite: as many positive pivots as
    /// displacement unknowns (and padding rows of clamped nodes), by the block factor and by
    /// the banded `LDLᵀ` of the same matrix, with and without identity rows at the ends, in
    /// its Crank–Nicolson and its implicit Euler form.
    #[test]
    fn the_coupled_matrix_has_the_inertia_of_its_blocks() {
        use crate::linalg::kernels::banded::BandedLdlt;
        use crate::linalg::kernels::block_tridiag::BlockLdlt;
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
            let states = (0..=usize::from(!fixed[0])).flat_map(|m| [(m, false), (m, true)]);
            for state in states {
                for identity in [&[][..], &[nodes - 1][..]] {
                    let a = m.coupled(&c, state, identity);
                    let banded = a.to_banded();
                    let expected = (nodes, nodes);
                    assert_eq!(BlockLdlt::factor(&a).unwrap().inertia(), expected);
                    assert_eq!(BandedLdlt::factor(&banded).unwrap().inertia(), expected);
                }
            }
        }
    }
}
