//! The admissible set `K_h` and the contact state of a step, for every body.
//!
//! Constraint `k` keeps the gap `s_k u_{i_k} + g_k >= 0`: unknown `i_k`, the direction `s_k = ±1`
//! in which the obstacle pushes, and `g_k` (the bar's `u >= −a` is `s = +1`, `g = a`; a plane
//! edge's `u·n <= g` is `s = −σ` for the outward normal `n = σ e_c`). Its reaction `r_k >= 0`
//! pushes along `s_k e_{i_k}`. One definition of "in contact" serves every body and output:
//! [`in_contact`]. The constraints form named groups (an end of the bar, an edge of the plane,
//! the bar's whole obstacle), whose contact episodes the outputs report. An obstacle may move
//! ([`GapMotion`]): its gaps `g_k(t)` are then set before each step's bounds; a frictional
//! edge's obstacle may slide along the edge ([`Slide`]), moved on at the same time.

use crate::scene::{Expression, SceneError};
use crate::scheme::slide::Slide;
use crate::step::{Constraints, Friction};
use std::ops::Range;

/// A constraint is in contact when its gap is at most this: the exact solvers put an active
/// node on its obstacle up to the rounding of `u^n + z` (a few ulps of `|u|`, which the
/// non-dimensional scheme keeps of order one).
pub const CONTACT_GAP_TOL: f64 = 1e-12;

/// Whether a constraint with gap `s u + g` is in contact.
#[inline(always)]
pub fn in_contact(gap: f64) -> bool {
    gap <= CONTACT_GAP_TOL
}

/// At most this many groups: the plane's four edges (the bar has two ends and its obstacle).
pub const MAX_GROUPS: usize = 4;

/// Where the constraints sit along their end, edge or obstacle (the coordinate `s` of the
/// contact extent).
#[derive(Clone, Debug, PartialEq)]
pub enum Positions {
    /// `s_k = (first + k) · spacing`: the bar's nodes.
    Grid { first: usize, spacing: f64 },
    /// `s_k` given.
    List(Vec<f64>),
}

/// Named constraints whose contact episodes are reported together.
#[derive(Clone, Debug, PartialEq)]
pub struct Group {
    /// `left`, `right` (ends or edges), `bottom`, `top`, `obstacle`.
    pub name: &'static str,
    pub range: Range<usize>,
}

/// The contact state of one group at one step.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct GroupState {
    /// Constraints in contact ([`in_contact`]).
    pub contact_nodes: usize,
    /// `s` of the first and the last constraint in contact (`NaN` when none).
    pub extent: [f64; 2],
    /// The least gap (the gap, for a single constraint).
    pub min_gap: f64,
    /// `Σ r_k`.
    pub reaction: f64,
    /// `−½ Σ r_k s_k (u^{n+1} − u^{n−1})_{i_k}`, its share of the contact dissipation (0 when
    /// the step's energy balance is not measured).
    pub dissipation: f64,
    /// `Σ_j r_T,j` over the group's frictional nodes, each along its tangent `t_j` (0 without
    /// friction; [`ContactSet::tangential_totals`]).
    pub tangential_reaction: f64,
}

/// The constraints of a run: gaps, unknowns, directions, positions and groups.
#[derive(Clone, Debug)]
pub struct ContactSet {
    gaps: Vec<f64>,
    /// `i_k`; empty when `i_k = k` (an obstacle under every unknown).
    unknowns: Vec<usize>,
    /// `s_k`; empty when every `s_k = +1`.
    directions: Vec<f64>,
    positions: Positions,
    groups: Vec<Group>,
    /// The obstacles that move, if any ([`ContactSet::with_motion`]).
    motion: Option<Box<GapMotion>>,
    /// The frictional nodes (none without friction), [`crate::scheme::friction`].
    friction: Friction,
    /// The obstacles that slide along their edges, if any ([`ContactSet::with_slide`]).
    slide: Option<Box<Slide>>,
}

/// One constraint whose obstacle moves: `g_k(t) = min(law(s, t), cap)`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct MovingGap {
    /// The constraint `k`.
    pub constraint: usize,
    /// Its law, an index into [`GapMotion`]'s laws.
    pub law: usize,
    /// The first argument of the law: the edge coordinate `s` (0 for a bar's end).
    pub s: f64,
    /// A fixed bound the gap never exceeds (a bar's obstacle under a moving end; `+∞` else).
    pub cap: f64,
}

/// Obstacles moving along their normals: the gaps `g_k(t)` of some constraints, evaluated
/// at every step (no allocation), and the gaps of the two steps before, for the obstacle's
/// work `W = −½ Σ_k r_k (g_k^{n+1} − g_k^{n−1})` in the energy identity
/// ([docs/moving-obstacles.md](../../docs/moving-obstacles.md)).
#[derive(Clone, Debug)]
pub struct GapMotion {
    laws: Vec<Expression>,
    moving: Vec<MovingGap>,
    /// `g^{n−1}` and `g^n` of every constraint (`g^{n+1}` is the set's own `gaps`).
    earlier: Vec<f64>,
    previous: Vec<f64>,
}

impl GapMotion {
    /// The moving constraints `moving` with their `laws` (expressions in `s` and `t`); `None`
    /// when nothing moves.
    pub fn new(laws: Vec<Expression>, moving: Vec<MovingGap>) -> Option<Self> {
        (!moving.is_empty()).then(|| Self {
            laws,
            moving,
            earlier: Vec::new(),
            previous: Vec::new(),
        })
    }

    /// The moving constraints.
    pub fn moving(&self) -> &[MovingGap] {
        &self.moving
    }

    /// `g_k(t)` of a moving constraint.
    pub fn gap_at(&self, m: &MovingGap, t: f64) -> Result<f64, SceneError> {
        Ok(self.laws[m.law].eval(m.s, t)?.min(m.cap))
    }
}

/// The sums of one pass over some constraints.
struct Pass {
    min_gap: f64,
    min_reaction: f64,
    max_comp: f64,
    total: f64,
    dissipation: f64,
    count: usize,
    first: usize,
    last: usize,
}

impl Pass {
    fn new() -> Self {
        Self {
            min_gap: f64::INFINITY,
            min_reaction: f64::INFINITY,
            max_comp: 0.0,
            total: 0.0,
            dissipation: 0.0,
            count: 0,
            first: 0,
            last: 0,
        }
    }

    /// Adds constraint `k` with its gap and reaction (the sums but the dissipation).
    #[inline(always)]
    fn add(&mut self, k: usize, gap: f64, reaction: f64) {
        self.total += reaction;
        self.min_gap = min_of(self.min_gap, gap);
        self.min_reaction = min_of(self.min_reaction, reaction);
        self.max_comp = max_of(self.max_comp, (gap * reaction).abs());
        if in_contact(gap) {
            if self.count == 0 {
                self.first = k;
            }
            self.last = k;
            self.count += 1;
        }
    }
}

/// `m.min(x)` for a running minimum `m` that is never NaN: a NaN `x` is ignored and a tie
/// keeps `m`, as `f64::min` does here.
#[inline(always)]
fn min_of(m: f64, x: f64) -> f64 {
    if x < m { x } else { m }
}

/// [`min_of`] for a running maximum.
#[inline(always)]
fn max_of(m: f64, x: f64) -> f64 {
    if x > m { x } else { m }
}

/// `(u^{n+1}, z, w, r)`: the state after a step, its increment, the one before and the
/// reactions.
type State<'a> = (&'a [f64], &'a [f64], &'a [f64], &'a [f64]);

impl ContactSet {
    /// Constraints with gaps `gaps`, at unknowns `unknowns` (empty: `i_k = k`) in directions
    /// `directions` (empty: all `+1`), placed at `positions`, reported in `groups`.
    pub fn new(
        gaps: Vec<f64>,
        unknowns: Vec<usize>,
        directions: Vec<f64>,
        positions: Positions,
        groups: Vec<Group>,
    ) -> Self {
        assert!(unknowns.is_empty() || unknowns.len() == gaps.len());
        assert!(directions.is_empty() || directions.len() == gaps.len());
        assert!(groups.len() <= MAX_GROUPS);
        Self {
            gaps,
            unknowns,
            directions,
            positions,
            groups,
            motion: None,
            friction: Friction::default(),
            slide: None,
        }
    }

    /// The set with its obstacles moving by `motion` (the gaps given to [`ContactSet::new`]
    /// are those at `t = 0`); `None` keeps them fixed.
    pub fn with_motion(mut self, motion: Option<GapMotion>) -> Self {
        self.motion = motion.map(|mut m| {
            m.earlier = self.gaps.clone();
            m.previous = self.gaps.clone();
            Box::new(m)
        });
        self
    }

    /// Whether an obstacle moves.
    pub fn is_moving(&self) -> bool {
        self.motion.is_some()
    }

    /// The motion of the obstacles, if any.
    pub fn motion(&self) -> Option<&GapMotion> {
        self.motion.as_deref()
    }

    /// Moves the obstacles to `t = t_{n+1}` before the bounds of the step to it: `g^{n−1} ←
    /// g^n ← g^{n+1} ← g(t)`. Does nothing (and allocates nothing) when no obstacle moves; an
    /// error names the gap's field and the point where it is not finite.
    pub fn advance_gaps(&mut self, t: f64) -> Result<(), SceneError> {
        if let Some(slide) = self.slide.as_deref_mut() {
            slide.advance(t)?;
        }
        let Some(motion) = self.motion.as_deref_mut() else {
            return Ok(());
        };
        std::mem::swap(&mut motion.earlier, &mut motion.previous);
        motion.previous.copy_from_slice(&self.gaps);
        for m in &motion.moving {
            self.gaps[m.constraint] = motion.laws[m.law].eval(m.s, t)?.min(m.cap);
        }
        Ok(())
    }

    /// `g_k^{n+1} − g_k^{n−1}` (0 for a fixed obstacle).
    #[inline(always)]
    fn gap_change(&self, k: usize) -> f64 {
        self.motion
            .as_deref()
            .map_or(0.0, |m| self.gaps[k] - m.earlier[k])
    }

    /// The obstacles' work over the step just taken, `W = −½ Σ_k r_k (g_k^{n+1} − g_k^{n−1})`:
    /// positive when an obstacle pushing on the body advances into it (0 without motion).
    pub fn obstacle_work(&self, r: &[f64]) -> f64 {
        let Some(motion) = self.motion.as_deref() else {
            return 0.0;
        };
        let mut work = 0.0;
        for m in &motion.moving {
            let k = m.constraint;
            work += -0.5 * r[k] * (self.gaps[k] - motion.earlier[k]);
        }
        work
    }

    /// The same constraints with Coulomb friction at the nodes of `friction`.
    pub fn with_friction(mut self, friction: Friction) -> Self {
        self.friction = friction;
        self
    }

    /// The frictional nodes (empty without friction).
    pub fn friction(&self) -> &Friction {
        &self.friction
    }

    /// The same constraints with the frictional nodes' obstacles sliding by `slide` (moved on
    /// by [`ContactSet::advance_gaps`]); `None` keeps them fixed.
    pub fn with_slide(mut self, slide: Option<Slide>) -> Self {
        self.slide = slide.map(Box::new);
        self
    }

    /// The sliding obstacles, if any.
    pub fn slide(&self) -> Option<&Slide> {
        self.slide.as_deref()
    }

    /// Whether an obstacle slides along its edge.
    pub fn is_sliding(&self) -> bool {
        self.slide.is_some()
    }

    /// Reactions of a step: one per constraint, then one tangential per frictional node.
    pub fn reaction_len(&self) -> usize {
        self.len() + self.friction.len()
    }

    /// No constraint.
    pub fn none() -> Self {
        Self::new(
            Vec::new(),
            Vec::new(),
            Vec::new(),
            Positions::List(Vec::new()),
            Vec::new(),
        )
    }

    /// `m`.
    pub fn len(&self) -> usize {
        self.gaps.len()
    }

    pub fn is_empty(&self) -> bool {
        self.gaps.is_empty()
    }

    /// `i_k`.
    #[inline(always)]
    pub fn unknown(&self, k: usize) -> usize {
        if self.unknowns.is_empty() {
            k
        } else {
            self.unknowns[k]
        }
    }

    /// `s_k`.
    #[inline(always)]
    pub fn direction(&self, k: usize) -> f64 {
        if self.directions.is_empty() {
            1.0
        } else {
            self.directions[k]
        }
    }

    /// `g_k`.
    pub fn gaps(&self) -> &[f64] {
        &self.gaps
    }

    /// `s` of constraint `k`.
    pub fn position(&self, k: usize) -> f64 {
        match &self.positions {
            Positions::Grid { first, spacing } => (first + k) as f64 * spacing,
            Positions::List(s) => s[k],
        }
    }

    pub fn groups(&self) -> &[Group] {
        &self.groups
    }

    /// The constraints as the step solvers take them (set-up).
    pub fn constraints(&self) -> Constraints {
        let m = self.len();
        Constraints {
            unknowns: (0..m).map(|k| self.unknown(k)).collect(),
            directions: (0..m).map(|k| self.direction(k)).collect(),
        }
    }

    /// `lo_k = −g_k − s_k u_{i_k}`: the bounds `s_k z_{i_k} >= lo_k` of the increment from `u`.
    pub fn lower_bounds_into(&self, u: &[f64], lower: &mut [f64]) {
        for (k, lo) in lower.iter_mut().enumerate() {
            *lo = -self.gaps[k] - self.direction(k) * u[self.unknown(k)];
        }
    }

    /// The gaps `s_k u_{i_k} + g_k` of the state `u`.
    pub fn gaps_into(&self, u: &[f64], out: &mut [f64]) {
        for (k, o) in out.iter_mut().enumerate() {
            *o = self.direction(k) * u[self.unknown(k)] + self.gaps[k];
        }
    }

    /// One pass over constraints `range` of `u = u^{n+1}` with reactions `r`; with
    /// `dissipation`, also `−½ Σ r_k (s_k (z + w)_{i_k} + g_k^{n+1} − g_k^{n−1})`,
    /// `z + w = u^{n+1} − u^{n−1}`. Fixed lower bounds at `i_k = k` (an obstacle under every
    /// node) take [`ContactSet::pass_plain`], the same sums without the lookups of `i_k`, `s_k`
    /// and the motion.
    fn pass(&self, range: Range<usize>, state: State<'_>, dissipation: bool) -> Pass {
        let plain = self.unknowns.is_empty() && self.directions.is_empty() && !self.is_moving();
        match (plain, dissipation) {
            (true, true) => self.pass_plain::<true>(range, state),
            (true, false) => self.pass_plain::<false>(range, state),
            (false, true) => self.pass_general::<true>(range, state),
            (false, false) => self.pass_general::<false>(range, state),
        }
    }

    /// [`ContactSet::pass`] reading `i_k`, `s_k` and `g_k^{n+1} − g_k^{n−1}` per constraint.
    #[inline(always)]
    fn pass_general<const DISSIPATION: bool>(
        &self,
        range: Range<usize>,
        (u, z, w, r): State<'_>,
    ) -> Pass {
        let mut p = Pass::new();
        for k in range {
            let (l, s) = (self.unknown(k), self.direction(k));
            let gap = s * u[l] + self.gaps[k];
            let reaction = r[k];
            p.add(k, gap, reaction);
            if DISSIPATION {
                let change = self.gap_change(k);
                p.dissipation += if change == 0.0 {
                    -0.5 * reaction * s * (z[l] + w[l])
                } else {
                    -0.5 * reaction * (s * (z[l] + w[l]) + change)
                };
            }
        }
        p
    }

    /// [`ContactSet::pass_general`] for `i_k = k`, `s_k = 1` and fixed gaps: the same operations
    /// (`1 · x` is `x`), over slices zipped in one loop without index checks.
    #[inline(always)]
    fn pass_plain<const DISSIPATION: bool>(
        &self,
        range: Range<usize>,
        (u, z, w, r): State<'_>,
    ) -> Pass {
        let mut p = Pass::new();
        let (u, g, r) = (
            &u[range.clone()],
            &self.gaps[range.clone()],
            &r[range.clone()],
        );
        let (z, w) = (&z[range.clone()], &w[range.clone()]);
        let rows = u.iter().zip(g).zip(r).zip(z.iter().zip(w));
        for (k, (((&u, &g), &reaction), (&z, &w))) in range.zip(rows) {
            let gap = u + g;
            p.add(k, gap, reaction);
            if DISSIPATION {
                p.dissipation += -0.5 * reaction * (z + w);
            }
        }
        p
    }

    /// The group state of a pass.
    fn group_state(&self, p: &Pass) -> GroupState {
        GroupState {
            contact_nodes: p.count,
            extent: if p.count > 0 {
                [self.position(p.first), self.position(p.last)]
            } else {
                [f64::NAN, f64::NAN]
            },
            min_gap: p.min_gap,
            reaction: p.total,
            dissipation: p.dissipation,
            tangential_reaction: 0.0,
        }
    }

    /// The contact state of `u = u^{n+1}` (`z` its increment, `w` the one before, `r` the
    /// reactions) into `state`; with `dissipation` also the contact dissipation
    /// `D = −½ Σ_k r_k (s_k (u^{n+1} − u^{n−1})_{i_k} + g_k^{n+1} − g_k^{n−1})`, returned (0
    /// without); `g^{n+1} − g^{n−1} = 0` for a fixed obstacle.
    pub fn measure(
        &self,
        (u, z, w, r): (&[f64], &[f64], &[f64], &[f64]),
        dissipation: bool,
        state: &mut ContactState,
    ) -> f64 {
        let m = self.len();
        let all = self.pass(0..m, (u, z, w, r), dissipation);
        for (g, group) in self.groups.iter().enumerate() {
            state.groups[g] = if group.range == (0..m) {
                self.group_state(&all)
            } else if group.range.len() == 1 {
                // One constraint: its own values, not a sum from zero (the bits of −0.0).
                let k = group.range.start;
                let (l, s) = (self.unknown(k), self.direction(k));
                let gap = s * u[l] + self.gaps[k];
                let contact = in_contact(gap);
                let position = if contact { self.position(k) } else { f64::NAN };
                GroupState {
                    contact_nodes: usize::from(contact),
                    extent: [position, position],
                    min_gap: gap,
                    reaction: r[k],
                    dissipation: if dissipation && self.gap_change(k) != 0.0 {
                        -0.5 * r[k] * (s * (z[l] + w[l]) + self.gap_change(k))
                    } else if dissipation {
                        -0.5 * r[k] * s * (z[l] + w[l])
                    } else {
                        0.0
                    },
                    tangential_reaction: 0.0,
                }
            } else {
                self.group_state(&self.pass(group.range.clone(), (u, z, w, r), dissipation))
            };
        }
        self.tangential_totals(r, &mut state.groups);
        let empty = m == 0;
        state.total_reaction = all.total;
        state.min_gap = if empty { 0.0 } else { all.min_gap };
        state.min_reaction = if empty { 0.0 } else { all.min_reaction };
        state.max_complementarity = all.max_comp;
        state.contact_nodes = all.count;
        all.dissipation
    }
}

/// The contact state of one step, over all constraints and per group.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct ContactState {
    /// `Σ_k r_k`: the total contact force.
    pub total_reaction: f64,
    /// The least gap, the least reaction and the largest `|gap · reaction|` (0 without
    /// constraints).
    pub min_gap: f64,
    pub min_reaction: f64,
    pub max_complementarity: f64,
    /// Constraints in contact.
    pub contact_nodes: usize,
    /// Per group of [`ContactSet::groups`], in its order.
    pub groups: [GroupState; MAX_GROUPS],
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The plain pass against the general one on the same constraints with `i_k = k` and
    /// `s_k = 1` spelled out, bit for bit: gaps and reactions of both signs, zeros, gaps within
    /// the contact tolerance, NaN.
    #[test]
    fn plain_pass_has_the_bits_of_the_general_pass() {
        let m = 50;
        let value = |i: usize, a: f64| (a * i as f64).sin();
        let gaps: Vec<f64> = (0..m)
            .map(|k| if k % 5 == 0 { 0.0 } else { value(k, 0.3) })
            .collect();
        let grid = || Positions::Grid {
            first: 0,
            spacing: 0.1,
        };
        let set = ContactSet::new(gaps.clone(), Vec::new(), Vec::new(), grid(), Vec::new());
        let spelled = ContactSet::new(gaps, (0..m).collect(), vec![1.0; m], grid(), Vec::new());
        let u: Vec<f64> = (0..m)
            .map(|k| {
                if k % 3 == 0 {
                    -set.gaps[k]
                } else {
                    value(k, 0.7)
                }
            })
            .collect();
        let (z, w): (Vec<f64>, Vec<f64>) = (0..m).map(|k| (value(k, 1.1), value(k, 1.9))).unzip();
        let mut r: Vec<f64> = (0..m).map(|k| value(k, 2.3).max(0.0)).collect();
        r[7] = -0.0;
        r[11] = f64::NAN;
        let state = (&u[..], &z[..], &w[..], &r[..]);
        let fields = |p: Pass| {
            let sums = [
                p.min_gap,
                p.min_reaction,
                p.max_comp,
                p.total,
                p.dissipation,
            ];
            (sums.map(f64::to_bits), [p.count, p.first, p.last])
        };
        for range in [0..m, 3..17, 9..10, 20..20] {
            for dissipation in [true, false] {
                let plain = set.pass(range.clone(), state, dissipation);
                let general = spelled.pass(range.clone(), state, dissipation);
                assert_eq!(fields(plain), fields(general), "{range:?}");
            }
        }
    }
}
