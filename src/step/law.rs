//! The contact laws a step answer `(z, r)` is held to, each stated once: the audit
//! ([`crate::step::audit`]) checks exactly the conditions of the [`Law`] it is given, and a
//! solver states the law it solves by the same value. Normal laws act on the constraints
//! `s_k z_{i_k} >= lo_k`; frictional laws add one tangential reaction `r_T,j` per frictional
//! node, bounded by a threshold `g_j` and opposed to the slip `δ_j` ([`Slip`]).
//!
//! A new law is a new variant: its conditions in [`Law::threshold`] (or beside the penalty law's
//! residual), its checks and names in the audit, its bound tests in `tests/audit_bounds/`.
//! `docs/step-solvers.md#kkt-audit` and `docs/friction.md#audit` derive the audit's tolerances.

/// The slip of the frictional nodes over the step, relative to the obstacle,
/// `δ_j = (z + w)_{t_j} − v_j`: the central slip, `w` the previous increment at the tangents
/// (0 at the start-up step, whose slip is `u^1 − u^0`), less `v_j`, the obstacle's tangential
/// displacement over the same steps (0 for a fixed obstacle;
/// `docs/friction.md#sliding-obstacles`). Read by [`Slip::at`] and by the audit's slip-law
/// floor ([`Slip::scale`]).
#[derive(Clone, Copy, Debug)]
pub struct Slip<'a> {
    /// `w_j`, the previous increment at the tangents.
    pub previous: &'a [f64],
    /// `v_j`, the obstacle's tangential displacement over the two steps (zeros when fixed).
    pub obstacle: &'a [f64],
}

impl Slip<'_> {
    /// `δ_j` of node `j` whose tangential unknown is `z_t` (`− 0.0` is exact: a fixed
    /// obstacle's slip has the bits of `z_t + w_j`).
    #[inline]
    pub fn at(&self, j: usize, z_t: f64) -> f64 {
        z_t + self.previous[j] - self.obstacle[j]
    }

    /// The magnitudes added to `z_t` in [`Slip::at`], `|w_j| + |v_j|`: `δ_j` rounds to ulps
    /// of them.
    #[inline]
    pub fn scale(&self, j: usize) -> f64 {
        self.previous[j].abs() + self.obstacle[j].abs()
    }
}

/// A contact law: the conditions an answer `(z, r)` of the step problem must meet besides the
/// step equation `C z = b + Σ_k r_k s_k e_{i_k} (+ Σ_j r_T,j e_{t_j})`.
#[derive(Clone, Copy, Debug)]
pub enum Law<'a> {
    /// Signorini: `s_k z_{i_k} >= lo_k`, `r_k >= 0`, `r_k (s_k z_{i_k} − lo_k) = 0`.
    Signorini,
    /// Normal compliance (the penalty law): `ε r_k = (lo_k − s_k z_{i_k})⁺`
    /// ([`Law::penalty_reaction`]).
    Penalty { epsilon: f64 },
    /// Coulomb: Signorini on the normals, `|r_T,j| <= g_j = μ_j r_N,k_j` (the answer's own normal
    /// reaction at node `j`'s constraint `k_j`), and `g_j |δ_j| + r_T,j δ_j = 0`. The start-up
    /// step is this law with `w = 0` (the slip `u^1 − u^0`).
    Coulomb { mu: &'a [f64], slip: Slip<'a> },
    /// Tresca: as Coulomb with given thresholds `g_j`.
    Tresca {
        thresholds: &'a [f64],
        slip: Slip<'a>,
    },
}

/// What one audit is set up for, fixed for a run: the checks its report lists and, for friction,
/// the frictional nodes.
#[derive(Clone, Copy, Debug)]
pub enum LawFamily<'a> {
    /// [`Law::Signorini`].
    Signorini,
    /// [`Law::Penalty`].
    Penalty,
    /// [`Law::Coulomb`] and [`Law::Tresca`] on these frictional nodes.
    Frictional(&'a crate::step::solver::Friction),
}

impl Law<'_> {
    /// Whether the law has tangential reactions (with the frictional floors of the audit).
    pub fn is_frictional(&self) -> bool {
        matches!(self, Law::Coulomb { .. } | Law::Tresca { .. })
    }

    /// The threshold `g_j` of frictional node `j`, whose normal reaction is `r_n`: `μ_j r_n`,
    /// given, or 0 (also for the normal laws, which have no tangential reactions).
    #[inline]
    pub fn threshold(&self, j: usize, r_n: f64) -> f64 {
        match self {
            Law::Coulomb { mu, .. } => mu[j] * r_n,
            Law::Tresca { thresholds, .. } => thresholds[j],
            Law::Signorini | Law::Penalty { .. } => 0.0,
        }
    }

    /// The slip the slip law is stated in (`None`: a normal law).
    pub fn slip(&self) -> Option<&Slip<'_>> {
        match self {
            Law::Coulomb { slip, .. } | Law::Tresca { slip, .. } => Some(slip),
            _ => None,
        }
    }

    /// The penalty law's reaction `r = (lo − s z)⁺ / ε` from the compression `lo − s z`.
    #[inline]
    pub fn penalty_reaction(compression: f64, epsilon: f64) -> f64 {
        compression.max(0.0) / epsilon
    }

    /// The penalty law's residual `|ε r − (lo − s z)⁺|` at a constraint with gap `s z − lo`.
    #[inline]
    pub fn penalty_residual(epsilon: f64, r: f64, gap: f64) -> f64 {
        (epsilon * r - (-gap).max(0.0)).abs()
    }
}

/// Whether the penalty solver takes a constrained node's reaction from its gap,
/// `(lo_j − z_j)/ε`: when the spring `1/ε` (`stiffness`) is no stiffer than `C_jj`; otherwise
/// from stationarity, `(C z − b)_j` (`EndPenalty::solve_on_support`). The solver and the
/// audit, which weighs each form's round-off, share this rule.
pub fn reaction_from_gap(c_jj: f64, stiffness: f64) -> bool {
    c_jj >= stiffness
}
