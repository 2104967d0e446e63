//! The plane body's temperature: `θ_t − κ Δθ + γ div u_t = q`, Q1 on the body's mesh at the
//! half steps, stepped after each mechanical step (with `γ > 0` the step's displacement
//! problem has `θ` eliminated, [`crate::plane::coupling`], and the heat step follows from its
//! answer): Crank–Nicolson, or implicit Euler where the data are not smooth
//! (the thermal bar's Rannacher start, [`crate::thermal::smoothing`]). Edges are insulated,
//! held at a temperature, or exchange heat with their obstacle where in contact (lumped on the
//! edge's nodes); the friction work of each frictional node enters it as nodal heat, the
//! share `η` of its edge. Each contact state's matrix is factorised once, when first met.
//! Derivation and the thermal terms of the energy identity: docs/thermal.md, "The plane body".

use std::sync::Arc;
use std::sync::atomic::{AtomicBool, Ordering};

use crate::linalg::cholesky::SparseCholesky;
use crate::linalg::sparse::Pattern;
use crate::plane::coupling::{CoupledParts, CouplingMatrix, HeatStepMatrix};
use crate::plane::mesh::Grid;
use crate::plane::normals::Normal;
use crate::scene::expr::Expression;
use crate::scene::heat::EndHeat;
use crate::scene::plane_heat::PlaneHeatExpressions;
use crate::scheme::body::{HeatOutputs, HeatTerms};
use crate::scheme::{RunError, in_contact};
use crate::step::{Constraints, Friction};
use crate::thermal::smoothing::{Smoothing, jumps_within, profile_jumps, starts_with_a_jump};
use crate::thermal::solver::ImplicitFlag;

/// A node held at its edge's temperature: the node, its edge and coordinate `s`.
#[derive(Clone, Copy, Debug)]
struct FixedNode {
    node: usize,
    edge: usize,
    s: f64,
}

/// A node of an exchange edge: the node, its contact constraint, its trapezoid share of the
/// edge and the edge.
#[derive(Clone, Copy, Debug)]
struct ExchangeNode {
    node: usize,
    constraint: usize,
    weight: f64,
    edge: usize,
}

/// The factor of one step matrix `(M + c A_χ)` on the unknown temperatures: its exchange
/// state `χ` and `c = wτ` (`Δt` an implicit Euler step, `Δt/2` a Crank–Nicolson one or the
/// start-up's implicit half step, `Δt/4` the start-up's Crank–Nicolson half step).
struct StepFactor {
    chi: Vec<bool>,
    c: f64,
    factor: SparseCholesky,
}

/// The coupling `γ > 0`: `G`, the step's thermal load on the displacement and the heat the
/// displacement's divergence takes, and the frictional heat lagged by one step (docs/thermal.md,
/// "The plane body").
struct Coupled {
    gamma: f64,
    g: CouplingMatrix,
    /// Whether the step is an implicit Euler step, for the step solver.
    implicit: ImplicitFlag,
    /// `γ G θ̂ + γ w G_F B⁻¹ (r_F − γ/2 G_Fᵀ w)` on the displacement unknowns.
    load: Vec<f64>,
    /// `γ/2 Gᵀ δ` on every node.
    heating: Vec<f64>,
    /// Each frictional node's share of the previous step's `D_f`.
    lagged: Vec<f64>,
    /// Scratch on the displacement unknowns, on every node and on the unknown temperatures.
    delta: Vec<f64>,
    nodal: Vec<f64>,
    unknown: Vec<f64>,
}

/// The plane body's temperature and its step.
pub struct PlaneHeat {
    kappa: f64,
    dt: f64,
    /// The least cell side.
    least_side: f64,
    /// Scalar Q1 mass and stiffness on every node (one pattern).
    pattern: Pattern,
    mass: Vec<f64>,
    stiffness: Vec<f64>,
    /// The step's matrix on the unknown temperatures (nodes not held); `free[i]` the node of
    /// unknown `i`, `keep` the reverse.
    step_matrix: HeatStepMatrix,
    free: Vec<usize>,
    keep: Vec<Option<usize>>,
    fixed: Vec<FixedNode>,
    values: [Option<Expression>; 4],
    exchange: Vec<ExchangeNode>,
    /// `h` and `θ_obs(t)` of each exchange edge.
    exchange_edges: [Option<(f64, Expression)>; 4],
    source: Option<Expression>,
    /// The node and `η` of each frictional node.
    heated: Vec<(usize, f64)>,
    points: Vec<(f64, f64)>,
    factors: Vec<StepFactor>,
    /// The step's exchange state, `θ_obs` of each exchange edge at `t_n`, and its weight.
    chi: Vec<bool>,
    theta_obs: [f64; 4],
    implicit: bool,
    /// Whether the start-up's half step is implicit Euler (the data jump at `t = 0`).
    start_implicit: bool,
    smoothing: Smoothing,
    start_jump: bool,
    /// `θ^{n−1/2}` and `θ^{n+1/2}` on every node.
    old: Vec<f64>,
    new: Vec<f64>,
    /// Scratch (every node): `Q`, the frictional heat `q`, `θ_w`, products, the right-hand
    /// side; the unknowns' increment; matrix values.
    source_load: Vec<f64>,
    heat: Vec<f64>,
    weighted: Vec<f64>,
    product: Vec<f64>,
    a_weighted: Vec<f64>,
    rhs: Vec<f64>,
    unknown: Vec<f64>,
    values_reduced: Vec<f64>,
    /// `Σ q` and `Σ (1 − η) d` of the step.
    inputs: (f64, f64),
    coupled: Option<Coupled>,
    terms: HeatTerms,
}

/// The 3 × 3 node stencil of every node: the pattern of the scalar Q1 matrices.
pub(crate) fn node_stencil(grid: &Grid) -> Pattern {
    let n = grid.nodes();
    let mut row_ptr = Vec::with_capacity(n + 1);
    let mut cols = Vec::with_capacity(9 * n);
    row_ptr.push(0);
    for node in 0..n {
        let (i, j) = grid.position(node);
        for jj in j.saturating_sub(1)..=(j + 1).min(grid.ny) {
            for ii in i.saturating_sub(1)..=(i + 1).min(grid.nx) {
                cols.push(grid.node(ii, jj));
            }
        }
        row_ptr.push(cols.len());
    }
    Pattern { n, row_ptr, cols }
}

/// The scalar Q1 mass and stiffness on the grid, cell by cell as tensor products of the P1
/// element matrices in `x` and in `y` (exact on rectangles).
pub(crate) fn assemble(grid: &Grid, pattern: &Pattern) -> (Vec<f64>, Vec<f64>) {
    let (mut mass, mut stiffness) = (vec![0.0; pattern.nnz()], vec![0.0; pattern.nnz()]);
    let m1 = |h: f64| [[h / 3.0, h / 6.0], [h / 6.0, h / 3.0]];
    let k1 = |h: f64| [[1.0 / h, -1.0 / h], [-1.0 / h, 1.0 / h]];
    for j in 0..grid.ny {
        for i in 0..grid.nx {
            let (hx, hy) = (grid.xs[i + 1] - grid.xs[i], grid.ys[j + 1] - grid.ys[j]);
            let (mx, my, kx, ky) = (m1(hx), m1(hy), k1(hx), k1(hy));
            for (a, b) in [(0, 0), (1, 0), (0, 1), (1, 1)] {
                let row = grid.node(i + a, j + b);
                for (c, d) in [(0, 0), (1, 0), (0, 1), (1, 1)] {
                    let p = pattern.position(row, grid.node(i + c, j + d));
                    mass[p] += mx[a][c] * my[b][d];
                    stiffness[p] += kx[a][c] * my[b][d] + mx[a][c] * ky[b][d];
                }
            }
        }
    }
    (mass, stiffness)
}

/// The keys the step's data are read from, `heat.<edge>.value` and `heat.<edge>.obstacle`
/// (an error names them; the step allocates nothing).
const VALUE_KEYS: [&str; 4] = [
    "heat.left.value",
    "heat.right.value",
    "heat.bottom.value",
    "heat.top.value",
];
const OBSTACLE_KEYS: [&str; 4] = [
    "heat.left.obstacle",
    "heat.right.obstacle",
    "heat.bottom.obstacle",
    "heat.top.obstacle",
];

/// `f` finite, or the error naming `key`.
fn finite(v: f64, key: &str) -> Result<f64, RunError> {
    if v.is_finite() {
        Ok(v)
    } else {
        Err(crate::scene::error::invalid(key, v, "must be finite at every node and time").into())
    }
}

/// The edge coordinate `s` of `node` on edge `edge` (`y` on left and right, `x` on bottom and
/// top).
fn edge_coordinate(grid: &Grid, node: usize, edge: usize) -> f64 {
    let (x, y) = grid.point(node);
    if edge < 2 { y } else { x }
}

/// Whether `node` lies on edge `edge`.
fn on_edge(grid: &Grid, node: usize, edge: usize) -> bool {
    let (i, j) = grid.position(node);
    match edge {
        0 => i == 0,
        1 => i == grid.nx,
        2 => j == 0,
        _ => j == grid.ny,
    }
}

impl PlaneHeat {
    /// The temperature of a plane body on `grid` with the contact `normals`, the frictional
    /// nodes `friction` and the parsed `[heat]`; `θ^0` evaluated at every node.
    /// `mechanical` are the displacement unknowns' degrees of freedom (for `G`).
    pub fn new(
        grid: &Grid,
        (normals, friction): (&[Normal], &Friction),
        mechanical: &[usize],
        heat: PlaneHeatExpressions,
        dt: f64,
    ) -> Result<Self, RunError> {
        let pattern = node_stencil(grid);
        let (mass, stiffness) = assemble(grid, &pattern);
        let nodes = grid.nodes();
        let PlaneHeatExpressions {
            coupling,
            diffusivity,
            temperature,
            source,
            edges,
            frictional_heating,
        } = heat;
        let mut values: [Option<Expression>; 4] = Default::default();
        let mut exchange_edges: [Option<(f64, Expression)>; 4] = Default::default();
        for (k, e) in edges.into_iter().enumerate() {
            match e {
                EndHeat::Insulated => {}
                EndHeat::Temperature(v) => values[k] = Some(v),
                EndHeat::Exchange {
                    coefficient,
                    obstacle,
                } => exchange_edges[k] = Some((coefficient, obstacle)),
            }
        }
        let points: Vec<(f64, f64)> = (0..nodes).map(|n| grid.point(n)).collect();
        let mut old = Vec::with_capacity(nodes);
        for &(x, y) in &points {
            old.push(finite(temperature.eval_xy(x, y, 0.0)?, "heat.temperature")?);
        }
        // A node on two held edges takes the first in the order left, right, bottom, top.
        let mut held = vec![false; nodes];
        let mut fixed = Vec::new();
        let mut start_jump = false;
        for (edge, value) in values.iter().enumerate() {
            let Some(value) = value else { continue };
            let key = VALUE_KEYS[edge];
            for node in 0..nodes {
                if !on_edge(grid, node, edge) || held[node] {
                    continue;
                }
                held[node] = true;
                let s = edge_coordinate(grid, node, edge);
                let v0 = finite(value.eval(s, 0.0)?, key)?;
                start_jump |= starts_with_a_jump(old[node], v0);
                // A held node starts at its edge's value, as the bar's fixed end does.
                old[node] = v0;
                fixed.push(FixedNode { node, edge, s });
            }
        }
        // A jump inside the initial temperature, along a row or a column of nodes, is
        // non-smooth data at t = 0 too.
        let theta0 = |x: f64, y: f64| temperature.eval_xy(x, y, 0.0).unwrap_or(f64::NAN);
        start_jump |= (grid.ys.iter()).any(|&y| profile_jumps(|x| theta0(x, y), &grid.xs))
            || (grid.xs.iter()).any(|&x| profile_jumps(|y| theta0(x, y), &grid.ys));
        let keep: Vec<Option<usize>> = {
            let mut next = 0;
            (0..nodes)
                .map(|n| {
                    (!held[n]).then(|| {
                        next += 1;
                        next - 1
                    })
                })
                .collect()
        };
        let free: Vec<usize> = (0..nodes).filter(|&n| !held[n]).collect();
        let (reduced, from) = pattern.restrict(&keep);
        let coefficient = |edge: usize| exchange_edges[edge].as_ref().map_or(0.0, |e| e.0);
        let exchange: Vec<ExchangeNode> = (normals.iter().enumerate())
            .filter(|(_, nk)| exchange_edges[nk.edge].is_some())
            .map(|(k, nk)| ExchangeNode {
                node: nk.node,
                constraint: k,
                weight: nk.weight,
                edge: nk.edge,
            })
            .collect();
        let step_matrix = HeatStepMatrix {
            mass: from.iter().map(|&k| mass[k]).collect(),
            stiffness: from.iter().map(|&k| stiffness[k]).collect(),
            exchange: (exchange.iter())
                .map(|x| {
                    let position = keep[x.node].map(|i| reduced.position(i, i));
                    (position, coefficient(x.edge), x.weight)
                })
                .collect(),
            kappa: diffusivity,
            pattern: reduced,
        };
        let heated: Vec<(usize, f64)> = (friction.normals.iter())
            .map(|&k| (normals[k].node, frictional_heating[normals[k].edge]))
            .collect();
        let source_load = vec![0.0; if source.is_some() { nodes } else { 0 }];
        let n_free = free.len();
        let coupled = (coupling > 0.0).then(|| Coupled {
            gamma: coupling,
            g: CouplingMatrix::new(grid, &pattern, mechanical),
            implicit: Arc::new(AtomicBool::new(false)),
            load: vec![0.0; mechanical.len()],
            heating: vec![0.0; nodes],
            lagged: vec![0.0; heated.len()],
            delta: vec![0.0; mechanical.len()],
            nodal: vec![0.0; nodes],
            unknown: vec![0.0; n_free],
        });
        let sides = (grid.xs.windows(2))
            .chain(grid.ys.windows(2))
            .map(|p| p[1] - p[0]);
        Ok(Self {
            kappa: diffusivity,
            dt,
            least_side: sides.fold(f64::INFINITY, f64::min),
            values_reduced: vec![0.0; step_matrix.pattern.nnz()],
            step_matrix,
            pattern,
            mass,
            stiffness,
            free,
            keep,
            fixed,
            values,
            chi: vec![false; exchange.len()],
            exchange,
            exchange_edges,
            source,
            heated,
            points,
            factors: Vec::new(),
            theta_obs: [0.0; 4],
            implicit: false,
            start_implicit: false,
            smoothing: Smoothing::default(),
            start_jump,
            new: old.clone(),
            old,
            source_load,
            heat: vec![0.0; nodes],
            weighted: vec![0.0; nodes],
            product: vec![0.0; nodes],
            a_weighted: vec![0.0; nodes],
            rhs: vec![0.0; nodes],
            unknown: vec![0.0; n_free],
            inputs: (0.0, 0.0),
            coupled,
            terms: HeatTerms::default(),
        })
    }

    /// `κΔt/h²`, `h` the least cell side: the heat step's conditioning, part of the identity's
    /// round-off bound.
    pub fn diffusion_ratio(&self) -> f64 {
        self.kappa * self.dt / (self.least_side * self.least_side)
    }

    /// The latest temperature at `node`: `θ^{n−1/2}` while the scheme holds `u^n` (`θ^0`
    /// before the start-up).
    pub fn temperature(&self, node: usize) -> f64 {
        self.new[node]
    }

    /// `γ θ` at `node` (the latest temperature), the thermal stress's size; `None` uncoupled.
    pub fn thermal_stress(&self, node: usize) -> Option<f64> {
        self.coupled.as_ref().map(|c| c.gamma * self.new[node])
    }

    /// `½ |θ^{n+1/2}|²_M`.
    pub fn energy(&self) -> f64 {
        0.5 * self.pattern.quad(&self.mass, &self.new)
    }

    /// The heat balance a run reports: the heat content, frictional heating where some node is
    /// frictional, heat to the obstacles where some such node's edge has `η < 1`.
    pub fn outputs(&self) -> HeatOutputs {
        HeatOutputs {
            heat_content: true,
            frictional_heating: !self.heated.is_empty(),
            obstacle_heating: self.heated.iter().any(|&(_, eta)| eta < 1.0),
        }
    }

    /// The thermal terms of the last heat step.
    pub fn terms(&self) -> HeatTerms {
        self.terms
    }

    /// The start-up's record: `½|θ^{1/2}|²_M` and its heat inputs (its half step takes no
    /// part in an identity).
    pub fn start_up_terms(&self) -> HeatTerms {
        let t = self.terms;
        HeatTerms {
            energy: t.energy,
            frictional_heating: t.frictional_heating,
            obstacle_heating: t.obstacle_heating,
            heat_content: t.heat_content,
            ..Default::default()
        }
    }

    /// The step from `t_n` (`n = 0` the start-up): the exchange state read off the step's
    /// bounds `lower`, `θ_obs(t_n)`, and whether the heat step is implicit Euler. With `γ > 0`
    /// also the step's data and the displacement's thermal load
    /// ([`PlaneHeat::thermal_load`]; `w_old = u^n − u^{n−1}`).
    pub fn prepare(&mut self, n: usize, lower: &[f64], w_old: &[f64]) -> Result<(), RunError> {
        let t = n as f64 * self.dt;
        for (k, e) in self.exchange_edges.iter().enumerate() {
            if let Some((_, obstacle)) = e {
                self.theta_obs[k] = finite(obstacle.eval(0.0, t)?, OBSTACLE_KEYS[k])?;
            }
        }
        // An exchange switching on or off (on at t = 0: in contact from the start) is a jump
        // of its flux; at t = 0 so is an edge temperature that disagrees with θ^0.
        let mut jump = n == 0 && self.start_jump;
        for (chi, x) in self.chi.iter_mut().zip(&self.exchange) {
            let contact = in_contact(-lower[x.constraint]);
            jump |= contact != *chi || (n == 0 && contact);
            *chi = contact;
        }
        if n > 0 {
            let (t_old, t_new) = self.half_steps(n);
            for f in &self.fixed {
                let value = self.values[f.edge]
                    .as_ref()
                    .expect("a held edge has a value");
                if !value.depends_on_t() {
                    continue;
                }
                let at = |t: f64| finite(value.eval(f.s, t)?, VALUE_KEYS[f.edge]);
                let (a, b) = (at(t_old)?, at(t_new)?);
                jump |= jumps_within(at, (t_old, t_new), (a, b))?;
                if jump {
                    break;
                }
            }
        }
        let implicit = self.smoothing.schedule(n, jump);
        // The start-up's half step is its own; its projection takes Crank–Nicolson's `S`.
        (self.implicit, self.start_implicit) = match n {
            0 => (false, implicit),
            _ => (implicit, self.start_implicit),
        };
        let Some(mut coupled) = self.coupled.take() else {
            return Ok(());
        };
        coupled.implicit.store(self.implicit, Ordering::Relaxed);
        let lagged = std::mem::take(&mut coupled.lagged);
        self.heat_inputs(&lagged);
        coupled.lagged = lagged;
        let result = self.begin(n).and_then(|()| match n {
            0 => Ok(()),
            _ => self.coupled_load(n, &mut coupled, w_old),
        });
        self.coupled = Some(coupled);
        result
    }

    /// `γ G θ̂ + γ w G_F B⁻¹ (r_F − γ/2 G_Fᵀ w_old)`, `θ̂` the step's `θ^{n−1/2}` with the held
    /// nodes at `θ_w`: the displacement's thermal load once `ζ_F` is eliminated.
    fn coupled_load(&mut self, n: usize, c: &mut Coupled, w_old: &[f64]) -> Result<(), RunError> {
        let (_, w) = self.weights(n);
        c.nodal.copy_from_slice(&self.old);
        for f in &self.fixed {
            let (a, b) = (self.old[f.node], self.new[f.node]);
            c.nodal[f.node] = a + w * (b - a);
        }
        c.g.mul_into(&c.nodal, c.gamma, &mut c.load);
        c.g.transpose_mul_into(w_old, 0.5 * c.gamma, &mut c.nodal);
        for (u, &node) in c.unknown.iter_mut().zip(&self.free) {
            *u = self.rhs[node] - c.nodal[node];
        }
        let index = self.factor_index(w * self.dt)?;
        self.factors[index].factor.solve_in_place(&mut c.unknown);
        c.nodal.fill(0.0);
        for (u, &node) in c.unknown.iter().zip(&self.free) {
            c.nodal[node] = *u;
        }
        c.g.mul_into(&c.nodal, c.gamma * w, &mut c.delta);
        for (l, d) in c.load.iter_mut().zip(&c.delta) {
            *l += d;
        }
        Ok(())
    }

    /// The displacement's thermal load of the step being taken (`γ > 0`; `None` uncoupled).
    pub fn thermal_load(&self) -> Option<&[f64]> {
        self.coupled.as_ref().map(|c| &c.load[..])
    }

    /// `γ G θ^0` (`γ > 0`; after the start-up's `prepare`): the thermal stress in the start-up's
    /// Taylor step.
    pub fn initial_thermal_force(&self, out: &mut [f64]) -> bool {
        match &self.coupled {
            Some(c) => {
                c.g.mul_into(&self.old, c.gamma, out);
                true
            }
            None => false,
        }
    }

    /// `y += (γ²/4) G_F B⁻¹ G_Fᵀ x` with the start-up's Crank–Nicolson `B`: `S x − C x` of the
    /// step solver's start-up state (`γ > 0`; nothing uncoupled).
    pub fn add_schur_product(&mut self, x: &[f64], y: &mut [f64]) -> Result<(), RunError> {
        let Some(mut c) = self.coupled.take() else {
            return Ok(());
        };
        c.g.transpose_mul_into(x, 1.0, &mut c.nodal);
        for (u, &node) in c.unknown.iter_mut().zip(&self.free) {
            *u = c.nodal[node];
        }
        let result = self.factor_index(0.5 * self.dt);
        if let Ok(index) = result {
            self.factors[index].factor.solve_in_place(&mut c.unknown);
            c.nodal.fill(0.0);
            for (u, &node) in c.unknown.iter().zip(&self.free) {
                c.nodal[node] = *u;
            }
            c.g.mul_into(&c.nodal, 0.25 * c.gamma * c.gamma, &mut c.delta);
            for (yi, d) in y.iter_mut().zip(&c.delta) {
                *yi += d;
            }
        }
        self.coupled = Some(c);
        result.map(|_| ())
    }

    /// The parts of the coupled step solver (`γ > 0`): `C` on `c_pattern`, `G_F`, `B`'s parts,
    /// the constraints and frictional nodes; the exchange nodes' constraints, in the order of a
    /// state's entries, and the flag of the implicit steps.
    pub fn coupled_solver_parts(
        &self,
        (c_pattern, c): (&Pattern, &[f64]),
        constraints: &Constraints,
        friction: &Friction,
    ) -> Option<(CoupledParts, Vec<usize>, ImplicitFlag)> {
        let coupled = self.coupled.as_ref()?;
        let parts = CoupledParts {
            c_pattern: c_pattern.clone(),
            c: c.to_vec(),
            g: coupled.g.restrict_columns(&self.keep),
            heat: self.step_matrix.clone(),
            gamma: coupled.gamma,
            dt: self.dt,
            constraints: constraints.clone(),
            friction: friction.clone(),
        };
        let exchange = self.exchange.iter().map(|x| x.constraint).collect();
        Some((parts, exchange, coupled.implicit.clone()))
    }

    /// `t_{n−1/2}` and `t_{n+1/2}` of step `n` (`0` and `Δt/2` for the start-up).
    fn half_steps(&self, n: usize) -> (f64, f64) {
        let dt = self.dt;
        if n == 0 {
            (0.0, 0.5 * dt)
        } else {
            ((2 * n - 1) as f64 * 0.5 * dt, (2 * n + 1) as f64 * 0.5 * dt)
        }
    }

    /// `y ← A_χ x = κ K x + h X χ x` on every node.
    fn apply_a(&self, x: &[f64], y: &mut [f64]) {
        self.pattern.mul_into(&self.stiffness, x, y);
        for yi in y.iter_mut() {
            *yi *= self.kappa;
        }
        for (x_e, &chi) in self.exchange.iter().zip(&self.chi) {
            if chi {
                let h = self.coefficient(x_e.edge);
                y[x_e.node] += h * x_e.weight * x[x_e.node];
            }
        }
    }

    /// The factor of `(M + c A_χ)` on the unknown temperatures (`c = wτ`) in the step's exchange
    /// state, made when first met.
    fn factor_index(&mut self, c: f64) -> Result<usize, RunError> {
        if let Some(i) = (self.factors.iter()).position(|f| f.c == c && f.chi == self.chi) {
            return Ok(i);
        }
        (self.step_matrix).values(&self.chi, c, &mut self.values_reduced);
        let factor = SparseCholesky::new(
            &self.step_matrix.pattern,
            &self.values_reduced,
            "the heat step",
        )?;
        self.factors.push(StepFactor {
            chi: self.chi.clone(),
            c,
            factor,
        });
        Ok(self.factors.len() - 1)
    }

    /// The heat step `θ^{n−1/2} → θ^{n+1/2}` after the mechanical step from `t_n`
    /// (`n = 0`: `θ^0 → θ^{1/2}`, a Crank–Nicolson half step, implicit Euler where the data
    /// jump at `t = 0`), with frictional node `j`'s
    /// share `friction_work[j]` of `D_f` and the step's displacement increments
    /// `(z, w)` (`w = None` at the start-up); records the step's thermal terms. With `γ > 0`
    /// the step's data were set by [`PlaneHeat::prepare`], the frictional heat is the previous
    /// step's, and the heat rows take `γ/2 Gᵀ (z + w)`.
    pub fn step(
        &mut self,
        n: usize,
        (z, w_old): (&[f64], Option<&[f64]>),
        friction_work: &[f64],
    ) -> Result<(), RunError> {
        let Some(mut coupled) = self.coupled.take() else {
            self.heat_inputs(friction_work);
            self.begin(n)?;
            return self.finish(n);
        };
        // γ/2 Gᵀ δ, δ = z + w (z at the start-up), leaves the unknown rows' right-hand side.
        for (d, (i, zi)) in coupled.delta.iter_mut().zip(z.iter().enumerate()) {
            *d = zi + w_old.map_or(0.0, |w| w[i]);
        }
        let half = 0.5 * coupled.gamma;
        (coupled.g).transpose_mul_into(&coupled.delta, half, &mut coupled.heating);
        for (r, h) in self.rhs.iter_mut().zip(&coupled.heating) {
            *r -= h;
        }
        coupled.lagged.copy_from_slice(friction_work);
        self.coupled = Some(coupled);
        self.finish(n)
    }

    /// `q_j = η_j d_j` at each frictional node from its share `d_j` of `D_f`, and their sums.
    fn heat_inputs(&mut self, friction_work: &[f64]) {
        self.heat.fill(0.0);
        let (mut heating, mut obstacle) = (0.0, 0.0);
        for (&(node, eta), &d) in self.heated.iter().zip(friction_work) {
            self.heat[node] += eta * d;
            heating += eta * d;
            obstacle += (1.0 - eta) * d;
        }
        self.inputs = (heating, obstacle);
    }

    /// `τ` and `w` of step `n`'s heat step.
    fn weights(&self, n: usize) -> (f64, f64) {
        if n == 0 {
            (0.5 * self.dt, if self.start_implicit { 1.0 } else { 0.5 })
        } else if self.implicit {
            (self.dt, 1.0)
        } else {
            (self.dt, 0.5)
        }
    }

    /// The step's data: `θ^{n−1/2}` moved to `old`, the held nodes' `θ^{n+1/2}`, and the right-
    /// hand side `τ (Q + h X χ θ_obs − A θ^{n−1/2}) + q − (M + wτ A) ζ_held` on every node.
    fn begin(&mut self, n: usize) -> Result<(), RunError> {
        std::mem::swap(&mut self.old, &mut self.new);
        let (tau, w) = self.weights(n);
        let t_n = n as f64 * self.dt;
        let (_, t_new) = self.half_steps(n);
        // θ^{n+1/2} at the held nodes; the others start from θ^{n−1/2}.
        self.new.copy_from_slice(&self.old);
        for f in &self.fixed {
            let value = self.values[f.edge]
                .as_ref()
                .expect("a held edge has a value");
            self.new[f.node] = finite(value.eval(f.s, t_new)?, VALUE_KEYS[f.edge])?;
        }
        // The source Q = M q(·, t_n).
        if let Some(source) = &self.source {
            for (node, &(x, y)) in self.points.iter().enumerate() {
                self.weighted[node] = finite(source.eval_xy(x, y, t_n)?, "heat.source")?;
            }
            self.pattern
                .mul_into(&self.mass, &self.weighted, &mut self.source_load);
        }
        let mut product = std::mem::take(&mut self.product);
        self.apply_a(&self.old, &mut product);
        self.product = product;
        for (node, r) in self.rhs.iter_mut().enumerate() {
            let q = self.source_load.get(node).copied().unwrap_or(0.0);
            *r = tau * (q - self.product[node]) + self.heat[node];
        }
        for (x_e, &chi) in self.exchange.iter().zip(&self.chi) {
            if chi {
                let h = self.coefficient(x_e.edge);
                self.rhs[x_e.node] += tau * h * x_e.weight * self.theta_obs[x_e.edge];
            }
        }
        // ζ on every node (held nodes' increments; 0 at the unknowns for now), in `weighted`.
        for (z, (a, b)) in self.weighted.iter_mut().zip(self.old.iter().zip(&self.new)) {
            *z = b - a;
        }
        for &node in &self.free {
            self.weighted[node] = 0.0;
        }
        if !self.fixed.is_empty() {
            self.pattern
                .mul_into(&self.mass, &self.weighted, &mut self.product);
            for (r, p) in self.rhs.iter_mut().zip(&self.product) {
                *r -= p;
            }
            let zeta = std::mem::take(&mut self.weighted);
            let mut product = std::mem::take(&mut self.product);
            self.apply_a(&zeta, &mut product);
            for (r, p) in self.rhs.iter_mut().zip(&product) {
                *r -= w * tau * p;
            }
            (self.weighted, self.product) = (zeta, product);
        }
        Ok(())
    }

    /// Solves the unknown rows of the right-hand side `begin` made, checks `θ^{n+1/2}` finite and
    /// records the step's thermal terms.
    fn finish(&mut self, n: usize) -> Result<(), RunError> {
        let (tau, w) = self.weights(n);
        let index = self.factor_index(w * tau)?;
        for (u, &node) in self.unknown.iter_mut().zip(&self.free) {
            *u = self.rhs[node];
        }
        self.factors[index].factor.solve_in_place(&mut self.unknown);
        for (u, &node) in self.unknown.iter().zip(&self.free) {
            self.new[node] = self.old[node] + u;
        }
        if self.new.iter().any(|v| !v.is_finite()) {
            return Err(RunError::Step {
                step: n + 1,
                time: (n + 1) as f64 * self.dt,
                solver: "heat".into(),
                failure: crate::step::StepFailure::NonFinite,
            });
        }
        self.measure(tau, w, self.inputs);
        Ok(())
    }

    /// The thermal terms of the step just taken (docs/thermal.md, "The plane body").
    fn measure(&mut self, tau: f64, w: f64, (heating, obstacle): (f64, f64)) {
        // ζ in `product`, θ_w in `weighted`.
        for (node, z) in self.product.iter_mut().enumerate() {
            *z = self.new[node] - self.old[node];
            self.weighted[node] = self.old[node] + w * *z;
        }
        let smoothing = (w - 0.5) * self.pattern.quad(&self.mass, &self.product);
        // The held rows' residuals ρ = M ζ + τ (A θ_w − h X χ θ_obs − Q) − q: M ζ in `rhs`,
        // A θ_w in `a_weighted`.
        self.pattern
            .mul_into(&self.mass, &self.product, &mut self.rhs);
        let mut a_weighted = std::mem::take(&mut self.a_weighted);
        self.apply_a(&self.weighted, &mut a_weighted);
        let mut exchange = 0.0;
        for (x_e, &chi) in self.exchange.iter().zip(&self.chi) {
            if chi {
                let theta = self.weighted[x_e.node];
                let h = self.coefficient(x_e.edge);
                exchange += tau * h * x_e.weight * (theta - self.theta_obs[x_e.edge]) * theta;
            }
        }
        let dissipation = tau * self.kappa * self.pattern.quad(&self.stiffness, &self.weighted);
        let mut supply = 0.0;
        for (q, t) in self.source_load.iter().zip(&self.weighted) {
            supply += tau * q * t;
        }
        for f in &self.fixed {
            let node = f.node;
            let mut rho = self.rhs[node] + tau * a_weighted[node];
            for (x_e, &chi) in self.exchange.iter().zip(&self.chi) {
                if chi && x_e.node == node {
                    let h = self.coefficient(x_e.edge);
                    rho -= tau * h * x_e.weight * self.theta_obs[x_e.edge];
                }
            }
            rho -= tau * self.source_load.get(node).copied().unwrap_or(0.0) + self.heat[node];
            if let Some(c) = &self.coupled {
                rho += c.heating[node];
            }
            supply += self.weighted[node] * rho;
        }
        let mut frictional_supply = 0.0;
        for (q, t) in self.heat.iter().zip(&self.weighted) {
            frictional_supply += q * t;
        }
        // 1ᵀ M θ^{n+1/2}.
        self.pattern
            .mul_into(&self.mass, &self.new, &mut a_weighted);
        let heat_content = a_weighted.iter().sum();
        self.a_weighted = a_weighted;
        self.terms = HeatTerms {
            energy: self.energy(),
            dissipation,
            exchange,
            supply,
            smoothing,
            frictional_supply,
            frictional_heating: heating,
            obstacle_heating: obstacle,
            heat_content,
        };
    }

    /// `h` of exchange edge `edge`.
    fn coefficient(&self, edge: usize) -> f64 {
        self.exchange_edges[edge].as_ref().map_or(0.0, |e| e.0)
    }
}
