//! The friction state of a step, for a contact set with frictional nodes: the friction
//! dissipation `D_f = −½ Σ_j r_T,j δ_j` of the energy identity (`δ_j = (u^{n+1} − u^{n−1})_{t_j}`,
//! the central slip; `= ½ Σ_j μ_j r_N,j |δ_j| >= 0` by Coulomb's law), and the frictional nodes
//! in contact that stick or slip ([`is_slipping`], one definition for every output). An
//! obstacle sliding along its edge ([`crate::scheme::Slide`]) makes the slip relative,
//! `δ_j − v_j`, and does the work `½ Σ_j r_T,j v_j`. Derivation: `docs/friction.md`.

use crate::scheme::contact::{ContactSet, GroupState, in_contact};

/// A frictional node in contact slips when its central slip `|δ|` exceeds this: the exact
/// solver puts a sticking node at `δ = 0` up to the rounding of `u^{n+1} − u^{n−1}` (a few ulps
/// of the non-dimensional displacement, as [`crate::scheme::CONTACT_GAP_TOL`]).
pub const SLIP_TOL: f64 = 1e-12;

/// Whether a node with central slip `delta` slips.
#[inline(always)]
pub fn is_slipping(delta: f64) -> bool {
    delta.abs() > SLIP_TOL
}

/// The friction state of one step.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct FrictionState {
    /// `D_f` (0 when the step's energy balance is not measured).
    pub dissipation: f64,
    /// Frictional nodes in contact with `|δ| <= SLIP_TOL`, and with more.
    pub stick_nodes: usize,
    pub slip_nodes: usize,
}

impl ContactSet {
    /// The friction state of `u = u^{n+1}` (`z` its increment, `w` the one before, `r` the
    /// normal then the tangential reactions); `dissipation` also sums `D_f`.
    pub fn measure_friction(
        &self,
        (u, z, w, r): (&[f64], &[f64], &[f64], &[f64]),
        dissipation: bool,
    ) -> FrictionState {
        let (f, m) = (self.friction(), self.len());
        let mut state = FrictionState::default();
        for j in 0..f.len() {
            match self.node_state(j, (u, z, w)) {
                NodeState::Open => {}
                NodeState::Stick => state.stick_nodes += 1,
                NodeState::Slip => state.slip_nodes += 1,
            }
            if dissipation {
                state.dissipation += -0.5 * r[m + j] * self.relative_slip(j, (z, w));
            }
        }
        state
    }

    /// Each frictional node's share of the friction work over the step just taken,
    /// `out[j] = −scale r_T,j δ_j` (`δ_j` the relative slip over the increments `z` and `w`,
    /// `w = None` for the start-up's slip `u^1 − u^0`; `scale` ½ for a central slip, so that
    /// the shares sum to [`FrictionState::dissipation`] in its order). Fills as many nodes as
    /// `out` holds (none for a body that does not ask).
    pub fn friction_work_into(
        &self,
        r: &[f64],
        (z, w): (&[f64], Option<&[f64]>),
        scale: f64,
        out: &mut [f64],
    ) {
        let m = self.len();
        for (j, o) in out.iter_mut().enumerate() {
            let slip = match w {
                Some(w) => self.relative_slip(j, (z, w)),
                None => {
                    let t = self.friction().tangents[j];
                    z[t] + 0.0 - self.slide().map_or(0.0, |s| s.displacement()[j])
                }
            };
            *o = -scale * r[m + j] * slip;
        }
    }

    /// The sliding obstacles' work over the step just taken, `½ Σ_j r_T,j v_j` (`r` the normal
    /// then the tangential reactions): positive when an obstacle drags the body along its
    /// motion (0 when none slides).
    pub fn sliding_work(&self, r: &[f64]) -> f64 {
        let Some(slide) = self.slide() else {
            return 0.0;
        };
        let m = self.len();
        let mut work = 0.0;
        for (j, v) in slide.displacement().iter().enumerate() {
            work += 0.5 * r[m + j] * v;
        }
        work
    }

    /// The slip of frictional node `j` relative to its obstacle, `(z + w)_{t_j} − v_j` (`z`, `w`
    /// the step's two increments, in either order; `v_j` a sliding obstacle's displacement over
    /// them, [`crate::scheme::Slide`]; `− 0.0` keeps a fixed obstacle's bits).
    #[inline]
    pub fn relative_slip(&self, j: usize, (z, w): (&[f64], &[f64])) -> f64 {
        let t = self.friction().tangents[j];
        z[t] + w[t] - self.slide().map_or(0.0, |s| s.displacement()[j])
    }

    /// The state of frictional node `j` at `u = u^{n+1}` with its relative central slip
    /// ([`ContactSet::relative_slip`]).
    #[inline]
    pub fn node_state(&self, j: usize, (u, z, w): (&[f64], &[f64], &[f64])) -> NodeState {
        let f = self.friction();
        let k = f.normals[j];
        let gap = self.direction(k) * u[self.unknown(k)] + self.gaps()[k];
        if !in_contact(gap) {
            NodeState::Open
        } else if is_slipping(self.relative_slip(j, (z, w))) {
            NodeState::Slip
        } else {
            NodeState::Stick
        }
    }
}

/// A frictional node's state at one step; its number (`as u8`) is the VTU field
/// `friction_state`.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[repr(u8)]
pub enum NodeState {
    /// Not in contact ([`in_contact`]).
    Open = 0,
    /// In contact, `|δ| <= SLIP_TOL`.
    Stick = 1,
    /// In contact, `|δ| > SLIP_TOL` ([`is_slipping`]).
    Slip = 2,
}

impl ContactSet {
    /// Each group's `Σ_j r_T,j` (the tangential reactions `r[m + j]` of its frictional nodes)
    /// into `groups`' `tangential_reaction`; nothing without friction.
    pub fn tangential_totals(&self, r: &[f64], groups: &mut [GroupState]) {
        let (f, m) = (self.friction(), self.len());
        for (j, &k) in f.normals.iter().enumerate() {
            if let Some(g) = self.groups().iter().position(|g| g.range.contains(&k)) {
                groups[g].tangential_reaction += r[m + j];
            }
        }
    }
}
