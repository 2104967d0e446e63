//! The thermal bar as a [`Body`] of the scheme: the state is `[u | θ]`, the bar's displacement
//! `u^n` on its unknowns followed by the temperature `θ^{n−1/2}` on the nodes whose temperature
//! is not fixed. Its kernels are the bar's on the displacement block (so the scheme's energy
//! sums are the bar's) and the coupled ones where the step needs them: the right-hand side and
//! the step matrix `[[C, −γ/2 G], [−γ/2 Gᵀ, −H_χ]]` ([`crate::thermal::matrices`]). The hooks
//! evaluate the boundary data of each step and whether its heat step is implicit Euler
//! ([`crate::thermal::smoothing`]), the start-up half step of `θ` and the thermal terms of
//! the energy identity. Derivation: `docs/thermal.md`.

use crate::bar::BarBody;
use crate::linalg::kernels::ldlt::Ldlt;
use crate::scene::SceneError;
use crate::scene::heat::{EndHeat, HeatExpressions};
use crate::scheme::RunError;
use crate::scheme::body::{Body, EnergySums, FullMassRows, HeatTerms};
use crate::scheme::certify::{MAX_IDENTITY_BOUND, THERMAL_IDENTITY_TOL, conditioned_bound};
use crate::thermal::heat_rows;
use crate::thermal::matrices::{ThermalMatrices, heat_weight};
use crate::thermal::smoothing::{Smoothing, jumps_within, profile_jumps, starts_with_a_jump};
use crate::thermal::solver::{ImplicitFlag, exchange_state};

/// An exchange end: its node, constraint, coefficient `h` and `θ_obs(t)`. Its gap is the
/// contact set's (moved with its obstacle), read off the step's bounds.
#[derive(Clone, Debug)]
pub struct ExchangeEnd {
    pub node: usize,
    /// Index into the bar's constraints (the order of the step's bounds).
    pub constraint: usize,
    pub coefficient: f64,
    pub obstacle: crate::scene::expr::Expression,
}

/// A fixed-temperature end: its node and `θ_end(t)`.
#[derive(Clone, Debug)]
pub struct FixedEnd {
    pub node: usize,
    pub value: crate::scene::expr::Expression,
    /// `θ_end(t_{n−1/2})` and `θ_end(t_{n+1/2})` of the step being taken, and `θ_w` there,
    /// `old + w (new − old)` (`w` the step's weight, [`heat_weight`]).
    pub old: f64,
    pub new: f64,
    pub weighted: f64,
}

/// The bar with a temperature.
pub struct ThermalBody {
    pub(crate) bar: BarBody,
    pub(crate) m: ThermalMatrices,
    pub(crate) exchange: Vec<ExchangeEnd>,
    pub(crate) fixed: Vec<FixedEnd>,
    source: Option<crate::scene::expr::Expression>,
    /// `Q^n = M_θ q(·, t_n)` on every node (empty without a source).
    q: Vec<f64>,
    /// `q(x_j, t_n)` (scratch).
    q_nodal: Vec<f64>,
    /// The exchange state of the step (bit `e`: exchange end `e` in contact with `u^n`) and
    /// `θ_obs(t_n)` of each exchange end.
    mask: usize,
    theta_obs: [f64; 2],
    /// Which heat steps are implicit Euler, whether the step being taken is, and whether the
    /// initial temperature disagrees with a fixed end's value at `t = 0`.
    smoothing: Smoothing,
    implicit: bool,
    start_jump: bool,
}

/// `name(t)` finite, or the scene error naming `key`.
fn eval_t(e: &crate::scene::expr::Expression, x: f64, t: f64, key: &str) -> Result<f64, RunError> {
    let v = e.eval(x, t)?;
    if v.is_finite() {
        Ok(v)
    } else {
        Err(crate::scene::error::invalid(key, v, "must be finite at every node and time").into())
    }
}

impl ThermalBody {
    /// The body from the bar's and the parsed `[heat]` table (`constraints`: the bar's
    /// constrained nodes with their gaps, in the order of the bounds).
    pub fn new(
        bar: BarBody,
        (kappa, gamma): (f64, f64),
        heat: HeatExpressions,
        constraints: &[(usize, f64)],
    ) -> Result<Self, SceneError> {
        let disc = bar.discretisation();
        let (nodes, dx, dt, first, n_u) =
            (disc.nodes, disc.dx, disc.dt, disc.first, disc.unknowns());
        let HeatExpressions {
            source,
            ends,
            temperature,
        } = heat;
        let mut exchange = Vec::new();
        let mut fixed = Vec::new();
        // A jump inside the initial temperature is non-smooth data at t = 0 too.
        let xs: Vec<f64> = (0..nodes).map(|j| j as f64 * dx).collect();
        let mut start_jump = profile_jumps(|x| temperature.eval(x, 0.0).unwrap_or(f64::NAN), &xs);
        for (side, end) in ends.into_iter().enumerate() {
            let node = if side == 0 { 0 } else { nodes - 1 };
            match end {
                EndHeat::Insulated => {}
                EndHeat::Temperature(value) => {
                    // `eval` refuses a value that is not finite, naming the key.
                    let v0 = value.eval(0.0, 0.0)?;
                    let initial = temperature.eval(node as f64 * dx, 0.0)?;
                    start_jump |= starts_with_a_jump(initial, v0);
                    fixed.push(FixedEnd {
                        node,
                        value,
                        old: v0,
                        new: v0,
                        weighted: v0,
                    })
                }
                EndHeat::Exchange {
                    coefficient,
                    obstacle,
                } => {
                    let constraint = (constraints.iter())
                        .position(|&(n, _)| n == node)
                        .expect("validated: an exchange end is a Signorini end");
                    exchange.push(ExchangeEnd {
                        node,
                        constraint,
                        coefficient,
                        obstacle,
                    });
                }
            }
        }
        let is_fixed = [0, nodes - 1].map(|n| fixed.iter().any(|f| f.node == n));
        let m = ThermalMatrices::new(
            nodes,
            dx,
            dt,
            (kappa, gamma),
            (first, n_u),
            is_fixed,
            exchange.iter().map(|e| (e.node, e.coefficient)).collect(),
        );
        if m.n_t == 0 {
            return Err(SceneError::Invalid {
                field: "mesh.elements".into(),
                value: (nodes - 1).to_string(),
                allowed: "at least 2 with a fixed temperature at both ends (a node whose \
                          temperature is unknown)"
                    .into(),
            });
        }
        let ratio = kappa * dt / (dx * dx);
        let bound = conditioned_bound(THERMAL_IDENTITY_TOL, n_u + m.n_t, ratio);
        if bound > MAX_IDENTITY_BOUND {
            return Err(SceneError::Invalid {
                field: "heat.diffusivity".into(),
                value: kappa.to_string(),
                allowed: format!(
                    "the heat step's ratio κΔt/Δx² = {ratio:.1e} holds the energy identity only \
                     to {bound:.1e}, above {MAX_IDENTITY_BOUND:e}: take a smaller diffusivity \
                     or time.step"
                ),
            });
        }
        let with_source = source.is_some();
        Ok(Self {
            bar,
            m,
            exchange,
            fixed,
            source,
            q: if with_source {
                vec![0.0; nodes]
            } else {
                Vec::new()
            },
            q_nodal: if with_source {
                vec![0.0; nodes]
            } else {
                Vec::new()
            },
            mask: 0,
            theta_obs: [0.0; 2],
            smoothing: Smoothing::default(),
            implicit: false,
            start_jump,
        })
    }

    /// The flag telling the step solver whether the step being taken is implicit Euler.
    pub fn implicit_flag(&self) -> ImplicitFlag {
        self.smoothing.flag()
    }

    /// Whether the step being taken is an implicit Euler step of the heat.
    pub fn implicit_step(&self) -> bool {
        self.implicit
    }

    /// `1 − w`: `θ_w = θ^{n+1/2} − (1 − w) dθ` (½ for Crank–Nicolson, 0 for implicit Euler).
    #[inline(always)]
    fn lag(&self) -> f64 {
        1.0 - heat_weight(self.implicit)
    }

    /// `κΔt/Δx²`: the heat step's stiffness ratio, which its round-off follows.
    pub fn diffusion_ratio(&self) -> f64 {
        let d = self.bar.discretisation();
        self.m.kappa * d.dt / (d.dx * d.dx)
    }

    /// The bar's body.
    pub fn bar(&self) -> &BarBody {
        &self.bar
    }

    /// The matrices and the layout of the unknowns.
    pub fn matrices(&self) -> &ThermalMatrices {
        &self.m
    }

    /// The exchange ends' constraint indices, in the order of the exchange state's bits.
    pub fn exchange_constraints(&self) -> Vec<usize> {
        self.exchange.iter().map(|e| e.constraint).collect()
    }

    /// The exchange state of the step being taken.
    pub fn exchange_state(&self) -> usize {
        self.mask
    }

    /// `θ` at `node`: the state's where it is an unknown, the fixed end's `new` value otherwise.
    #[inline(always)]
    fn theta(&self, u: &[f64], node: usize) -> f64 {
        match self.m.theta_unknown(node) {
            Some(j) => u[j],
            None => self.fixed_at(node).map_or(0.0, |f| f.new),
        }
    }

    #[inline(always)]
    fn fixed_at(&self, node: usize) -> Option<&FixedEnd> {
        self.fixed.iter().find(|f| f.node == node)
    }

    /// `φ_j`: `θ^{n−1/2}_j` at an unknown (from `u`), `θ_w` at a fixed end (the mean
    /// `½(old + new)` on a Crank–Nicolson step).
    #[inline(always)]
    fn phi(&self, u: &[f64], node: usize) -> f64 {
        match self.m.theta_unknown(node) {
            Some(j) => u[j],
            None => self.fixed_at(node).map_or(0.0, |f| f.weighted),
        }
    }

    /// `v` at every node from its values at the two end nodes (computed once, by the searches
    /// of [`Self::phi`] and the like) and a direct reader of the interior nodes, where both
    /// fields are unknowns: the same values, without a search per node.
    #[inline(always)]
    fn nodal(
        &self,
        v: impl Fn(usize) -> f64,
        interior: impl Fn(usize) -> f64,
    ) -> impl Fn(usize) -> f64 {
        let last = self.m.nodes - 1;
        let ends = self.ends(v);
        move |k| {
            if k == 0 {
                ends[0]
            } else if k == last {
                ends[1]
            } else {
                interior(k)
            }
        }
    }

    /// `[v(0), v(last)]`: a nodal value at the two end nodes.
    #[inline(always)]
    fn ends(&self, v: impl Fn(usize) -> f64) -> [f64; 2] {
        [v(0), v(self.m.nodes - 1)]
    }

    /// The fixed ends' increment `new − old` at `node` (0 elsewhere).
    #[inline(always)]
    fn fixed_increment(&self, node: usize) -> f64 {
        self.fixed_at(node).map_or(0.0, |f| f.new - f.old)
    }

    /// `x` at every node for a displacement-block vector (0 at clamped nodes).
    #[inline(always)]
    fn disp(&self, x: &[f64], node: usize) -> f64 {
        self.m.u_unknown(node).map_or(0.0, |i| x[i])
    }

    /// `(T v)_j` for a tridiagonal `T` on every node and `v` given node by node.
    #[inline(always)]
    fn tri_row(t: &crate::linalg::tridiag::SymTridiag, j: usize, v: impl Fn(usize) -> f64) -> f64 {
        let n = t.diag.len();
        let mut s = t.diag[j] * v(j);
        if j > 0 {
            s += t.off[j - 1] * v(j - 1);
        }
        if j + 1 < n {
            s += t.off[j] * v(j + 1);
        }
        s
    }

    /// `(G φ)_i = ∫ φ φ_i'` at node `i` for `φ` given node by node.
    #[inline(always)]
    fn g_row(&self, i: usize, v: impl Fn(usize) -> f64) -> f64 {
        let nodes = self.m.nodes;
        let mut s = 0.0;
        if i > 0 {
            s += 0.5 * (v(i - 1) + v(i));
        }
        if i + 1 < nodes {
            s -= 0.5 * (v(i) + v(i + 1));
        }
        s
    }

    /// `(Gᵀ v)_j = ∫ v_x ψ_j` at node `j` for `v` given node by node.
    #[inline(always)]
    fn gt_row(&self, j: usize, v: impl Fn(usize) -> f64) -> f64 {
        let nodes = self.m.nodes;
        let mut s = 0.0;
        if j > 0 {
            s += 0.5 * (v(j) - v(j - 1));
        }
        if j + 1 < nodes {
            s += 0.5 * (v(j + 1) - v(j));
        }
        s
    }

    /// `h_e` at the exchange end at `node` when it exchanges in this step, and its `θ_obs`.
    #[inline(always)]
    fn exchanging(&self, node: usize) -> Option<(f64, f64)> {
        (self.exchange.iter().enumerate())
            .find(|(e, x)| x.node == node && self.mask & (1 << e) != 0)
            .map(|(e, x)| (x.coefficient, self.theta_obs[e]))
    }

    /// `|x|²_M` of the temperature's mass and `|y|²_K` of its stiffness on every node in one
    /// pass, and `Q·y` with the source's `Q^n` (0 without a source): each node's terms
    /// `(M_jj x_j + 2 M_j,j+1 x_j+1) x_j` and `−K_j,j+1 (y_j+1 − y_j)²` (difference form, exact
    /// for constants), with the uniform mesh's coefficients ([`interior_coefficients`]).
    ///
    /// `x` and `y` are given by their values at the two end nodes and at the interior nodes
    /// `1..last` in order, so that the interior is one pass without a test per node.
    fn quads(
        &self,
        (x_ends, x): ([f64; 2], impl IntoIterator<Item = f64>),
        (y_ends, y): ([f64; 2], impl IntoIterator<Item = f64>),
    ) -> [f64; 3] {
        let [md, mo, ko] = self.interior_entries();
        let (mass, q) = (&self.m.mass, &self.q[..]);
        let last = mass.diag.len() - 1;
        let mut s = [0.0; 3];
        // The elements (j, j + 1) in order, the first with the end node's own mass entry.
        let (mut prev, mut d, mut j) = ((x_ends[0], y_ends[0]), mass.diag[0], 0);
        for next in x.into_iter().zip(y) {
            add_element(&mut s, (d, mo, ko), q.get(j), prev, next);
            (prev, d, j) = (next, md, j + 1);
        }
        let end = (x_ends[1], y_ends[1]);
        add_element(&mut s, (d, mo, ko), q.get(j), prev, end);
        s[0] += mass.diag[last] * end.0 * end.0;
        if let Some(q) = q.get(last) {
            s[2] += q * end.1;
        }
        s
    }

    /// `θ_w` at `node` (`θ̄` on a Crank–Nicolson step): `θ^{n+1/2} − (1 − w) dθ` from the
    /// state `u` and the increment `z` at an unknown, `θ_w` of the step's two values at a
    /// fixed end.
    #[inline(always)]
    fn theta_bar(&self, u: &[f64], z: &[f64], node: usize) -> f64 {
        match self.m.theta_unknown(node) {
            Some(j) => u[j] - self.lag() * z[j],
            None => self.fixed_at(node).map_or(0.0, |f| f.weighted),
        }
    }

    /// [`Self::quads`] of `θ^{n+1/2}` and `θ̄` ([`Self::theta_bar`]) from the state `u` and the
    /// increment `z`: `[|θ|²_M, |θ̄|²_K, Q·θ̄]`.
    fn energy_quads(&self, u: &[f64], z: &[f64]) -> [f64; 3] {
        let (m, n_u) = (&self.m, self.m.n_u);
        let interior = 1 - m.t_first..m.nodes - 1 - m.t_first;
        let (theta, dtheta) = (&u[n_u..][interior.clone()], &z[n_u..][interior]);
        let lag = self.lag();
        self.quads(
            (self.ends(|k| self.theta(u, k)), theta.iter().copied()),
            (
                self.ends(|k| self.theta_bar(u, z, k)),
                theta.iter().zip(dtheta).map(|(t, dt)| t - lag * dt),
            ),
        )
    }

    /// `[M_jj, M_j,j+1, K_j,j+1]` of the interior rows ([`interior_coefficients`]).
    fn interior_entries(&self) -> [f64; 3] {
        let ([md, mo], [_, ko]) = (
            interior_coefficients(&self.m.mass),
            interior_coefficients(&self.m.stiffness),
        );
        [md, mo, ko]
    }

    /// The `θ` block of the right-hand side over the temperature's unknowns: the heat rows
    /// times `−Δt` (`s = Δt`), or the start-up's half step (`s = Δt/2`) without the sign;
    /// with `coupling = Some(b_u)` (`γ ≠ 0`), also the displacement rows' `+= γ G φ`, read
    /// off the same nodes.
    fn heat_rhs(
        &self,
        u: &[f64],
        w_u: &[f64],
        (s, sign): (f64, f64),
        b_theta: &mut [f64],
        coupling: Option<&mut [f64]>,
    ) {
        let m = &self.m;
        let (kappa, gamma) = (m.kappa, m.gamma);
        let theta = &u[m.n_u..];
        let phi = self.nodal(|k| self.phi(u, k), |k| theta[k - m.t_first]);
        let disp = self.nodal(|k| self.disp(w_u, k), |k| w_u[k - m.u_first]);
        // Rows whose stencil reaches an end node by the general reads; the others below.
        let interior = 2..m.nodes.saturating_sub(2).max(2);
        let t_end = m.t_first + b_theta.len();
        for j in (m.t_first..interior.start.min(t_end)).chain(interior.end..t_end) {
            let mut r = -s * kappa * Self::tri_row(&m.stiffness, j, &phi);
            if !self.q.is_empty() {
                r += s * self.q[j];
            }
            if let Some((h, obs)) = self.exchanging(j) {
                r -= s * h * (self.phi(u, j) - obs);
            }
            if gamma != 0.0 {
                r -= 0.5 * gamma * self.gt_row(j, &disp);
            }
            if !self.fixed.is_empty() {
                r -= Self::tri_row(&m.mass, j, |k| self.fixed_increment(k));
            }
            b_theta[j - m.t_first] = sign * r;
        }
        let mut coupling = coupling;
        if let Some(bu) = coupling.as_deref_mut() {
            let u_end = m.u_first + bu.len();
            for node in (m.u_first..interior.start.min(u_end)).chain(interior.end..u_end) {
                bu[node - m.u_first] += gamma * self.g_row(node, &phi);
            }
        }
        if interior.is_empty() {
            return;
        }
        // The interior rows, the same formulas on the nodes `j − 1, j, j + 1` read directly
        // (no exchange, no fixed end there), with the interior coefficients of `K_θ`.
        let rows = interior.clone();
        let b = &mut b_theta[rows.start - m.t_first..rows.end - m.t_first];
        let theta = &theta[rows.start - 1 - m.t_first..rows.end + 1 - m.t_first];
        let w = &w_u[rows.start - 1 - m.u_first..rows.end + 1 - m.u_first];
        let [kd, ko] = interior_coefficients(&m.stiffness);
        let q = if self.q.is_empty() {
            &[][..]
        } else {
            &self.q[rows.clone()]
        };
        let n = b.len();
        let bu = coupling.map(|bu| &mut bu[interior.start - m.u_first..interior.end - m.u_first]);
        heat_rows::HeatRows {
            row: heat_rows::HeatRow {
                a: -s * kappa,
                kd,
                ko,
                c: 0.5 * gamma,
            },
            s,
            gamma,
            sign,
            th: &theta[..n + 2],
            w: &w[..n + 2],
            q,
            b,
            bu,
        }
        .run();
    }
}

/// Adds the element `(j, j + 1)`'s terms to the sums of [`ThermalBody::quads`]:
/// `(d x_j + 2 M_j,j+1 x_j+1) x_j`, `−K_j,j+1 (y_j+1 − y_j)²` and `Q_j y_j`.
#[inline(always)]
fn add_element(
    s: &mut [f64; 3],
    (d, mo, ko): (f64, f64, f64),
    q: Option<&f64>,
    (xj, yj): (f64, f64),
    (xn, yn): (f64, f64),
) {
    s[0] += (d * xj + 2.0 * mo * xn) * xj;
    s[1] += -ko * ((yn - yj) * (yn - yj));
    if let Some(q) = q {
        s[2] += q * yj;
    }
}

/// `[A_jj, A_j,j+1]` of the interior rows of a P1 matrix on the uniform mesh: every interior
/// diagonal entry and every off-diagonal one is the same number
/// ([`crate::bar::matrices::stiffness`]).
fn interior_coefficients(a: &crate::linalg::tridiag::SymTridiag) -> [f64; 2] {
    debug_assert!(
        a.uniform().is_some(),
        "the thermal matrices are built on a uniform mesh"
    );
    [
        a.diag[1.min(a.diag.len() - 1)],
        a.off.first().copied().unwrap_or(0.0),
    ]
}

impl Body for ThermalBody {
    /// [`conditioned_bound`] of the mechanical `C` and of the heat step, whose stiffness ratio
    /// is `κΔt/Δx²` ([`ThermalBody::diffusion_ratio`]).
    fn identity_tolerance(&self) -> f64 {
        let condition = self.bar.condition() + self.diffusion_ratio();
        conditioned_bound(THERMAL_IDENTITY_TOL, self.unknowns(), condition)
    }

    const NAME: &'static str = "bar";
    fn has_temperature(&self) -> bool {
        true
    }

    fn unknowns(&self) -> usize {
        self.m.n_u + self.m.n_t
    }

    fn dt(&self) -> f64 {
        self.bar.dt()
    }

    fn viscosity(&self) -> f64 {
        self.bar.viscosity()
    }

    /// The bar's right-hand side plus `γ G φ` on the displacement, the heat rows times `−Δt`
    /// on the temperature, `−2Δt` on an implicit Euler step (`docs/thermal.md`).
    fn rhs_into(&self, u: &[f64], w: &[f64], force: Option<&[f64]>, b: &mut [f64]) {
        let n_u = self.m.n_u;
        let (bu, bt) = b.split_at_mut(n_u);
        let force = force.map(|f| &f[..n_u]);
        self.bar.rhs_into(&u[..n_u], &w[..n_u], force, bu);
        let coupling = (self.m.gamma != 0.0).then_some(bu);
        self.heat_rhs(u, &w[..n_u], (self.dt(), -1.0), bt, coupling);
        if self.implicit {
            bt.iter_mut().for_each(|b| *b *= 2.0);
        }
    }

    fn energy_sums(&self, u: &[f64], z: &[f64], w: &[f64], force: Option<&[f64]>) -> EnergySums {
        let n = self.m.n_u;
        let force = force.map(|f| &f[..n]);
        self.bar.energy_sums(&u[..n], &z[..n], &w[..n], force)
    }

    fn stiffness_form(&self, x: &[f64]) -> f64 {
        self.bar.stiffness_form(&x[..self.m.n_u])
    }

    fn stiffness_form_of_difference(&self, u: &[f64], w: &[f64]) -> f64 {
        let n = self.m.n_u;
        self.bar.stiffness_form_of_difference(&u[..n], &w[..n])
    }

    fn mass_form(&self, x: &[f64]) -> f64 {
        self.bar.mass_form(&x[..self.m.n_u])
    }

    fn mass_mul(&self, x: &[f64], y: &mut [f64]) {
        let n = self.m.n_u;
        self.bar.mass_mul(&x[..n], &mut y[..n]);
        y[n..].fill(0.0);
    }

    fn stiffness_mul(&self, x: &[f64], y: &mut [f64]) {
        let n = self.m.n_u;
        self.bar.stiffness_mul(&x[..n], &mut y[..n]);
        y[n..].fill(0.0);
    }

    /// `[[C, −γ/2 G], [−γ/2 Gᵀ, −H_χ]] x` with the step's exchange state, or on an implicit
    /// Euler step `[[C, −γ G], [−γ Gᵀ, −2(M_θ + Δt κ K_θ + Δt h χ)]] x`.
    fn step_matrix_mul(&mut self, x: &[f64], y: &mut [f64]) -> Result<(), RunError> {
        let m = &self.m;
        let weight = heat_weight(self.implicit);
        let (n_u, gamma, s, scale) = (m.n_u, m.gamma, weight * self.dt(), 2.0 * weight);
        let (xu, xt) = x.split_at(n_u);
        let theta = |k: usize| m.theta_unknown(k).map_or(0.0, |j| x[j]);
        let (yu, yt) = y.split_at_mut(n_u);
        self.bar.step_matrix_mul(xu, yu)?;
        for (i, yi) in yu.iter_mut().enumerate() {
            *yi -= weight * gamma * self.g_row(m.u_first + i, theta);
        }
        for (jt, yj) in yt.iter_mut().enumerate() {
            let j = m.t_first + jt;
            let mut h = Self::tri_row(&m.mass, j, theta)
                + s * m.kappa * Self::tri_row(&m.stiffness, j, theta);
            if let Some((coefficient, _)) = self.exchanging(j) {
                h += s * coefficient * xt[jt];
            }
            *yj = -(scale * h) - weight * gamma * self.gt_row(j, |k| self.disp(xu, k));
        }
        Ok(())
    }

    fn solve_mass(&self, a: &mut [f64]) -> Result<(), RunError> {
        let n = self.m.n_u;
        self.bar.solve_mass(&mut a[..n])?;
        a[n..].fill(0.0);
        Ok(())
    }

    fn full_mass_rows(&self) -> FullMassRows {
        let mut rows = self.bar.full_mass_rows();
        let n = self.m.n_u;
        Box::new(move |x, out| {
            let k = n.min(out.len());
            rows(x, &mut out[..k]);
            out[k..].fill(0.0);
        })
    }

    fn nodes(&self) -> usize {
        self.bar.nodes()
    }

    fn elements(&self) -> usize {
        self.bar.elements()
    }

    fn lattice(&self) -> [usize; 2] {
        self.bar.lattice()
    }

    fn components(&self) -> usize {
        1
    }

    fn point(&self, node: usize) -> (f64, Option<f64>) {
        self.bar.point(node)
    }

    fn unknown_of(&self, dof: usize) -> Option<usize> {
        self.bar.unknown_of(dof)
    }

    /// The exchange state read off the step's bounds by `exchange_state`, as the step solver
    /// reads it (the gaps of `u^n` against the obstacles where the step puts them),
    /// `θ_obs(t_n)`, the fixed ends' `θ_end(t_{n∓1/2})` and the source's `Q^n`. Allocates
    /// nothing.
    fn prepare_step(&mut self, n: usize, lower: &[f64], _w_old: &[f64]) -> Result<(), RunError> {
        let dt = self.dt();
        let t = n as f64 * dt;
        for (e, x) in self.exchange.iter().enumerate() {
            let key = if x.node == 0 {
                "heat.left.obstacle"
            } else {
                "heat.right.obstacle"
            };
            self.theta_obs[e] = eval_t(&x.obstacle, 0.0, t, key)?;
        }
        let mask = exchange_state(lower, self.exchange.iter().map(|x| x.constraint));
        // An exchange switching on or off (on at t = 0: in contact from the start) is a jump
        // of its end's flux; at t = 0 so is a sudden end temperature.
        let mut jump = mask != self.mask || (n == 0 && self.start_jump);
        self.mask = mask;
        let (t_old, t_new) = if n == 0 {
            (0.0, 0.5 * dt)
        } else {
            ((2 * n - 1) as f64 * 0.5 * dt, (2 * n + 1) as f64 * 0.5 * dt)
        };
        for f in &mut self.fixed {
            let key = if f.node == 0 {
                "heat.left.value"
            } else {
                "heat.right.value"
            };
            f.old = eval_t(&f.value, 0.0, t_old, key)?;
            f.new = eval_t(&f.value, 0.0, t_new, key)?;
            let value = |t: f64| eval_t(&f.value, 0.0, t, key);
            jump |= n > 0 && jumps_within(value, (t_old, t_new), (f.old, f.new))?;
        }
        self.implicit = self.smoothing.schedule(n, jump);
        for f in &mut self.fixed {
            f.weighted = match self.implicit {
                true => f.new,
                false => 0.5 * (f.old + f.new),
            };
        }
        if let Some(source) = &self.source {
            let dx = self.bar.discretisation().dx;
            for (j, q) in self.q_nodal.iter_mut().enumerate() {
                *q = eval_t(source, j as f64 * dx, t, "heat.source")?;
            }
            self.m.mass.mul_into(&self.q_nodal, &mut self.q);
        }
        Ok(())
    }

    /// The Taylor increment's thermal stress `Δt²/2 M⁻¹ γ G θ^0`, then `θ^{1/2} − θ^0` by a
    /// half step with the displacement's Taylor increment in the coupling, Crank–Nicolson's
    /// `(M + Δt/4 (κK + hχ)) Δθ = Δt/2 (Q − κKφ − hχ(θ^0 − θ_obs)) − γ/2 Gᵀ z_u` or, where
    /// the data jump at `t = 0`, implicit Euler's, `Δt/2` in place of `Δt/4`.
    fn complete_start_up(
        &self,
        u0: &[f64],
        _v0: &[f64],
        increment: &mut [f64],
    ) -> Result<(), RunError> {
        let (n_u, gamma, dt) = (self.m.n_u, self.m.gamma, self.dt());
        let (zu, zt) = increment.split_at_mut(n_u);
        if gamma != 0.0 {
            // The thermal stress in the Taylor step's acceleration: Δt²/2 M⁻¹ γ G θ^0.
            let theta0 = |k: usize| match self.m.theta_unknown(k) {
                Some(j) => u0[j],
                None => self.fixed_at(k).map_or(0.0, |f| f.old),
            };
            let mut a: Vec<f64> = (0..n_u)
                .map(|i| gamma * self.g_row(self.m.u_first + i, theta0))
                .collect();
            self.bar.solve_mass(&mut a)?;
            for (z, ai) in zu.iter_mut().zip(&a) {
                *z += 0.5 * dt * dt * ai;
            }
        }
        self.heat_rhs(u0, zu, (0.5 * dt, 1.0), zt, None);
        // Implicit Euler's `Δt/2 (κK + hχ)` over the half step, Crank–Nicolson's half of it.
        let s = if self.implicit { 0.5 * dt } else { 0.25 * dt };
        let h = self.m.heat_matrix((1.0, s), self.mask);
        if !zt.is_empty() {
            Ldlt::factor(&h)
                .map_err(|e| {
                    RunError::Scene(SceneError::Invalid {
                        field: "heat.diffusivity".into(),
                        value: self.m.kappa.to_string(),
                        allowed: format!("the temperature's start-up matrix is not definite: {e}"),
                    })
                })?
                .solve_in_place(zt);
        }
        Ok(())
    }

    fn heat_energy(&self, u: &[f64]) -> Option<f64> {
        let theta = &u[self.m.n_u..];
        let t_first = self.m.t_first;
        let x = theta[1 - t_first..self.m.nodes - 1 - t_first]
            .iter()
            .copied();
        let ends = self.ends(|k| self.theta(u, k));
        Some(0.5 * self.quads((ends, x.clone()), (ends, x))[0])
    }

    /// `½|θ^{n+1/2}|²_M`, `Δt κ |θ_w|²_K`, the exchange and the supply (source and the heat let
    /// in at the fixed ends: the residual of their heat rows), all with the step's `θ_w`, and
    /// an implicit Euler step's numerical dissipation `(w − ½)|θ^{n+1/2} − θ^{n−1/2}|²_M`.
    fn heat_terms(&self, u: &[f64], z: &[f64], w: &[f64]) -> Option<HeatTerms> {
        let m = &self.m;
        let dt = self.dt();
        let n_u = m.n_u;
        let bar_theta = |k: usize| self.theta_bar(u, z, k);
        let [mass, stiffness, source] = self.energy_quads(u, z);
        let energy = 0.5 * mass;
        let dissipation = dt * m.kappa * stiffness;
        let mut exchange = 0.0;
        for (e, x) in self.exchange.iter().enumerate() {
            if self.mask & (1 << e) != 0 {
                let tb = bar_theta(x.node);
                exchange += dt * x.coefficient * (tb - self.theta_obs[e]) * tb;
            }
        }
        let mut supply = dt * source;
        let dtheta = |k: usize| match m.theta_unknown(k) {
            Some(i) => z[i],
            None => self.fixed_increment(k),
        };
        for f in &self.fixed {
            let j = f.node;
            let delta = |k: usize| self.disp(&z[..n_u], k) + self.disp(&w[..n_u], k);
            let mut rho = Self::tri_row(&m.mass, j, dtheta)
                + dt * m.kappa * Self::tri_row(&m.stiffness, j, bar_theta)
                + 0.5 * m.gamma * self.gt_row(j, delta);
            if !self.q.is_empty() {
                rho -= dt * self.q[j];
            }
            supply += bar_theta(j) * rho;
        }
        // (w − ½)|dθ|²_M on every node: ½|dθ|²_M on an implicit Euler step, 0 otherwise.
        let smoothing = match self.implicit {
            true => {
                let sum: f64 = (0..m.nodes)
                    .map(|j| dtheta(j) * Self::tri_row(&m.mass, j, dtheta))
                    .sum();
                (heat_weight(true) - 0.5) * sum
            }
            false => 0.0,
        };
        Some(HeatTerms {
            energy,
            dissipation,
            exchange,
            supply,
            smoothing,
            ..Default::default()
        })
    }

    fn temperature(&self, u: &[f64], node: usize) -> Option<f64> {
        Some(self.theta(u, node))
    }
}

#[cfg(test)]
mod tests {
    use crate::Scene;
    use crate::scheme::Body;
    use crate::thermal::ThermalSimulation;

    /// Two summation orders of `n` terms: each sum carries at most about `n ε` of the sum of
    /// its terms' magnitudes.
    fn sum_tol(n: usize) -> f64 {
        4.0 * n as f64 * f64::EPSILON
    }

    /// The energy terms' element sums (`quads`, in difference form) equal the matrix products
    /// `θ·Mθ`, `θ̄·Kθ̄` and `Q·θ̄` computed row by row from the assembled matrices, on meshes of 1
    /// to 60 elements, insulated, fixed and exchanging ends, with and without a source.
    #[test]
    fn the_energy_terms_are_the_matrix_products() {
        for elements in [1usize, 2, 3, 4, 5, 6, 7, 8, 9, 60] {
            for (left, source) in [
                (
                    "{ condition = \"exchange\", coefficient = 2.0, obstacle = \"1\" }",
                    "0",
                ),
                ("{ condition = \"temperature\", value = \"0.3\" }", "1 + x"),
                ("{ condition = \"insulated\" }", "2"),
            ] {
                let text = format!(
                    "[bar]\nlength = 1.0\nviscosity = 0.1\n[left]\ncondition = \"signorini\"\n\
                     gap = 0.0\n[right]\ncondition = \"clamped\"\n[initial]\n\
                     displacement = \"0\"\nvelocity = \"0\"\n[heat]\ncoupling = 0.1\n\
                     diffusivity = 0.05\ntemperature = \"1\"\nsource = \"{source}\"\n\
                     left = {left}\nright = {{ condition = \"temperature\", value = \"0.5\" }}\n\
                     [mesh]\nelements = {elements}\n[time]\nstep = 0.01\nend = 0.1\n"
                );
                let sim = ThermalSimulation::new(&Scene::from_toml(&text, &[]).unwrap());
                if elements == 1 && left.contains("temperature") {
                    // Both temperatures fixed, none unknown: refused, naming the mesh.
                    let error = sim.err().expect("refused").to_string();
                    assert!(error.contains("mesh.elements"), "{error}");
                    continue;
                }
                let sim = sim.unwrap();
                let body = sim.body();
                let (n_u, m) = (body.m.n_u, &body.m);
                let mut u = vec![0.0; body.unknowns()];
                let mut z = vec![0.0; body.unknowns()];
                for (k, (uk, zk)) in u[n_u..].iter_mut().zip(&mut z[n_u..]).enumerate() {
                    (*uk, *zk) = (1.1 + (0.7 * k as f64).sin(), 1e-2 * (1.3 * k as f64).cos());
                }
                let plain = body.energy_quads(&u, &z);
                let bar_theta = |k: usize| body.theta_bar(&u, &z, k);
                let x: Vec<f64> = (0..m.nodes).map(|k| body.theta(&u, k)).collect();
                let y: Vec<f64> = (0..m.nodes).map(bar_theta).collect();
                let (mut mx, mut ky) = (vec![0.0; m.nodes], vec![0.0; m.nodes]);
                m.mass.mul_into(&x, &mut mx);
                m.stiffness.mul_into(&y, &mut ky);
                // The product and the sum of its terms' magnitudes.
                let dot = |a: &[f64], b: &[f64]| {
                    let terms = a.iter().zip(b).map(|(a, b)| a * b);
                    (terms.clone().sum::<f64>(), terms.map(f64::abs).sum::<f64>())
                };
                let products = [dot(&x, &mx), dot(&y, &ky), dot(&body.q, &y)];
                for (a, (b, magnitude)) in plain.into_iter().zip(products) {
                    assert!(
                        (a - b).abs() <= sum_tol(m.nodes) * magnitude,
                        "{elements} elements, left {left}, source {source}: {a} vs {b}"
                    );
                }
                assert_eq!(plain[2] == 0.0, source == "0", "the source term is summed");
            }
        }
    }
}
