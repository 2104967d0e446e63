//! The penalty law (normal compliance `ε r_k = (lo_k − s_k z_{i_k})⁺`) for any number of
//! constraints, without the dense `S` of [`crate::step::CondensedLcp`]: the step problem is
//! the minimisation of the convex, piecewise quadratic
//! `f(z) = ½ zᵀCz − bᵀz + 1/(2ε) Σ_k ((lo_k − s_k z_{i_k})⁺)²`, solved by a damped semismooth
//! Newton iteration on the sparse system. With the active set `A` (the constraints whose
//! compliance is compressed) `f` is the quadratic `q_A`, whose minimiser solves
//! `(C + D_A/ε) z = b + Σ_{k∈A} s_k lo_k e_{i_k}/ε` (`D_A` diagonal: one constraint per
//! unknown), factorised on `C`'s pattern without a new analysis and only when `A` changes
//! (warm start: the last step's set). The iteration ends on the minimiser of `q_A` whose own
//! active set is `A`, the minimiser of `f`, to the solve's round-off; a Newton step that does
//! not end there and does not decrease `f` enough is halved (Armijo). Memory: the numeric
//! factor of `C + D_A/ε` in place of `C`'s, and its work space.

use crate::linalg::cholesky::SparseCholesky;
use crate::linalg::sparse::Pattern;
use crate::linalg::system::SparseSystem;
use crate::step::law::Law;
use crate::step::solver::Constraints;
use crate::step::{SetupError, SolveInfo, StepFailure, StepSolver};

/// Newton iterations allowed in one step (each one solve, and a factorisation when the active
/// set changed): far above the few a step takes.
pub const MAX_NEWTON_ITERATIONS: u32 = 200;
/// Halvings of a Newton step before the iteration gives up.
const MAX_HALVINGS: u32 = 60;
/// Armijo's sufficient-decrease constant.
const ARMIJO: f64 = 1e-4;

/// The sparse penalty solver.
pub struct SemismoothPenalty {
    pattern: Pattern,
    /// `C` and `C + D_A/ε` on the pattern.
    c: Vec<f64>,
    work: Vec<f64>,
    /// The factor of `C + D_A/ε` for `A = factored`.
    factor: SparseCholesky,
    factored: Vec<bool>,
    constraints: Constraints,
    /// The position of `(i_k, i_k)` in the pattern.
    diagonal: Vec<usize>,
    epsilon: f64,
    /// The active set of the iterate, and of the quadratic it minimises.
    active: Vec<bool>,
    /// Work vectors: the minimiser of a quadratic, the Newton direction, a trial point, `C x`.
    newton: Vec<f64>,
    direction: Vec<f64>,
    point: Vec<f64>,
    cz: Vec<f64>,
}

/// `lo_k − s_k z_{i_k}`: the compression of constraint `k` (positive: active).
#[inline(always)]
fn compression(constraints: &Constraints, k: usize, lower: &[f64], z: &[f64]) -> f64 {
    lower[k] - constraints.directions[k] * z[constraints.unknowns[k]]
}

/// The step problem's `f` and its data.
struct Objective<'a> {
    pattern: &'a Pattern,
    c: &'a [f64],
    constraints: &'a Constraints,
    epsilon: f64,
    rhs: &'a [f64],
    lower: &'a [f64],
}

impl Objective<'_> {
    /// `f(z)`, with `C z` into `cz`.
    fn value(&self, z: &[f64], cz: &mut [f64]) -> f64 {
        self.pattern.mul_into(self.c, z, cz);
        let mut f = 0.0;
        for ((zi, ci), bi) in z.iter().zip(cz.iter()).zip(self.rhs) {
            f += zi * (0.5 * ci - bi);
        }
        let mut p = 0.0;
        for k in 0..self.constraints.len() {
            let g = compression(self.constraints, k, self.lower, z).max(0.0);
            p += g * g;
        }
        f + 0.5 * p / self.epsilon
    }

    /// `∇f(z)·d` from `cz = C z`.
    fn slope(&self, z: &[f64], cz: &[f64], d: &[f64]) -> f64 {
        let mut g = 0.0;
        for ((ci, bi), di) in cz.iter().zip(self.rhs).zip(d) {
            g += (ci - bi) * di;
        }
        for k in 0..self.constraints.len() {
            let (i, s) = (self.constraints.unknowns[k], self.constraints.directions[k]);
            let r = Law::penalty_reaction(
                compression(self.constraints, k, self.lower, z),
                self.epsilon,
            );
            g -= r * s * d[i];
        }
        g
    }
}

impl SemismoothPenalty {
    /// The solver of the penalty law with compliance `epsilon > 0` for `system`'s `C` (its
    /// factor is the one of `A = ∅`).
    pub fn new(
        system: SparseSystem,
        constraints: Constraints,
        epsilon: f64,
    ) -> Result<Self, SetupError> {
        if !(epsilon.is_finite() && epsilon > 0.0) {
            return Err(crate::step::SettingsError::new(
                "epsilon",
                epsilon,
                "must be a finite number > 0",
            )
            .into());
        }
        let SparseSystem {
            pattern,
            values,
            factor,
        } = system;
        let m = constraints.len();
        let diagonal = (constraints.unknowns.iter())
            .map(|&i| pattern.position(i, i))
            .collect();
        let n = pattern.n;
        Ok(Self {
            work: values.clone(),
            c: values,
            pattern,
            factor,
            factored: vec![false; m],
            constraints,
            diagonal,
            epsilon,
            active: vec![false; m],
            newton: vec![0.0; n],
            direction: vec![0.0; n],
            point: vec![0.0; n],
            cz: vec![0.0; n],
        })
    }

    /// The minimiser of `q_A` for `A = active` into `newton` (refactorising when `A` changed).
    fn minimise_quadratic(&mut self, rhs: &[f64], lower: &[f64]) -> Result<(), StepFailure> {
        if self.active != self.factored {
            self.work.copy_from_slice(&self.c);
            let inv = 1.0 / self.epsilon;
            for (k, &at) in self.diagonal.iter().enumerate() {
                if self.active[k] {
                    self.work[at] += inv;
                }
            }
            self.factor
                .refactor(&self.pattern, &self.work, "C + D/ε")
                .map_err(|_| StepFailure::NonFinite)?;
            self.factored.copy_from_slice(&self.active);
        }
        let out = &mut self.newton;
        out.copy_from_slice(rhs);
        let (unknowns, signs) = (&self.constraints.unknowns, &self.constraints.directions);
        for (k, lo) in lower.iter().enumerate() {
            if self.active[k] {
                out[unknowns[k]] += signs[k] * lo / self.epsilon;
            }
        }
        self.factor.solve_in_place(out);
        Ok(())
    }

    /// Sets `active` to the active set of `z`; returns whether it changed.
    fn update_active(&mut self, lower: &[f64], z: &[f64]) -> bool {
        let mut changed = false;
        for k in 0..self.constraints.len() {
            let a = compression(&self.constraints, k, lower, z) > 0.0;
            changed |= a != self.active[k];
            self.active[k] = a;
        }
        changed
    }
}

impl StepSolver for SemismoothPenalty {
    fn name(&self) -> &'static str {
        "penalty"
    }

    /// The damped semismooth Newton iteration from the last step's active set; allocates
    /// nothing (a factorisation when the active set changes).
    fn solve(
        &mut self,
        rhs: &[f64],
        lower: &[f64],
        z: &mut [f64],
        reactions: &mut [f64],
    ) -> Result<SolveInfo, StepFailure> {
        // z: the minimiser of q_A for the last step's A.
        self.minimise_quadratic(rhs, lower)?;
        z.copy_from_slice(&self.newton);
        let mut minimiser = true;
        let mut iterations = 1;
        loop {
            let changed = self.update_active(lower, z);
            if minimiser && !changed {
                break;
            }
            if iterations >= MAX_NEWTON_ITERATIONS {
                return Err(StepFailure::IterationLimit { iterations });
            }
            iterations += 1;
            self.minimise_quadratic(rhs, lower)?;
            if !self.newton.iter().all(|v| v.is_finite()) {
                return Err(StepFailure::NonFinite);
            }
            // The minimiser of q_A whose own active set is A: the answer (no line search, whose
            // comparisons of f would be round-off this close to the minimum).
            if (0..self.constraints.len()).all(|k| {
                (compression(&self.constraints, k, lower, &self.newton) > 0.0) == self.active[k]
            }) {
                z.copy_from_slice(&self.newton);
                break;
            }
            let f = Objective {
                pattern: &self.pattern,
                c: &self.c,
                constraints: &self.constraints,
                epsilon: self.epsilon,
                rhs,
                lower,
            };
            let f0 = f.value(z, &mut self.cz);
            for ((d, n), zi) in self.direction.iter_mut().zip(&self.newton).zip(z.iter()) {
                *d = n - zi;
            }
            let slope = f.slope(z, &self.cz, &self.direction);
            // The full step first: the Newton point itself (its bits, not z + d); then halved.
            let mut alpha = 1.0;
            let mut halvings = 0;
            self.point.copy_from_slice(&self.newton);
            while slope < 0.0 && f.value(&self.point, &mut self.cz) > f0 + ARMIJO * alpha * slope {
                halvings += 1;
                if halvings > MAX_HALVINGS {
                    return Err(StepFailure::IterationLimit { iterations });
                }
                alpha *= 0.5;
                for ((p, zi), d) in self.point.iter_mut().zip(z.iter()).zip(&self.direction) {
                    *p = zi + alpha * d;
                }
            }
            z.copy_from_slice(&self.point);
            minimiser = alpha == 1.0;
        }
        for (k, r) in reactions.iter_mut().enumerate() {
            *r = Law::penalty_reaction(compression(&self.constraints, k, lower, z), self.epsilon);
        }
        Ok(SolveInfo { iterations })
    }
}
