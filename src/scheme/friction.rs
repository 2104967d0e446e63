//! The friction state of a step, for a contact set with frictional nodes: the friction
//! dissipation `D_f = −½ Σ_j r_T,j δ_j` of the energy identity (`δ_j = (u^{n+1} − u^{n−1})_{t_j}`,
//! the central slip; `= ½ Σ_j μ_j r_N,j |δ_j| >= 0` by Coulomb's law), and the frictional nodes
//! in contact that stick or slip ([`is_slipping`], one definition for every output). An
//! obstacle sliding along its edge ([`crate::scheme::Slide`]) makes the slip relative, `δ_j − v_j`, and does
//! the work `½ Σ_j r_T,j v_j`. Derivation: `docs/friction.md`.

use crate::scheme::contact::{ContactSet, in_contact};

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
            let k = f.normals[j];
            let gap = self.direction(k) * u[self.unknown(k)] + self.gaps()[k];
            let t = f.tangents[j];
            // Relative to a sliding obstacle; `− 0.0` keeps a fixed obstacle's bits.
            let delta = z[t] + w[t] - self.slide().map_or(0.0, |s| s.displacement()[j]);
            if in_contact(gap) {
                if is_slipping(delta) {
                    state.slip_nodes += 1;
                } else {
                    state.stick_nodes += 1;
                }
            }
            if dissipation {
                state.dissipation += -0.5 * r[m + j] * delta;
            }
        }
        state
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
}
