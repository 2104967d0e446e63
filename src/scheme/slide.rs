//! Obstacles sliding along their edges' tangents (a belt, a brake disc): the discrete position
//! of each and its displacement over a step's slip interval, which the frictional step and the
//! friction state read ([`crate::scheme::friction`]). Derivation: `docs/friction.md`.

use crate::scene::{Expression, SceneError};

/// Obstacles sliding along their edges' tangents at the speeds `V'(t)` of some laws (one per
/// sliding edge). The discrete position is the trapezoidal rule,
/// `V^{n+1} = V^n + Δt (V'(t_n) + V'(t_{n+1}))/2`, `V^0 = 0`, and the slip of a step reads the
/// displacement over its interval, `v_j = V^{n+1} − V^{n−1}`, summed from the two increments
/// (`V^1 − V^0` at the start-up step); no allocation per step
/// ([docs/friction.md](../../docs/friction.md#sliding-obstacles)).
#[derive(Clone, Debug)]
pub struct Slide {
    laws: Vec<Expression>,
    /// The law of each frictional node (`None`: its obstacle is fixed).
    law_of_node: Vec<Option<usize>>,
    dt: f64,
    /// Per law: `V'(t_n)` (the last evaluated), `V^n − V^{n−1}`, `V^{n+1} − V^{n−1}`.
    speed: Vec<f64>,
    increment: Vec<f64>,
    span: Vec<f64>,
    /// Steps taken (0, 1, more): the start-up's span is its one increment.
    advanced: usize,
    /// `v_j` of each frictional node.
    displacement: Vec<f64>,
}

impl Slide {
    /// Obstacles moving at the speeds `laws` (expressions in `t`), frictional node `j` on the
    /// obstacle `law_of_node[j]`, with time step `dt`; `None` when no node's obstacle slides.
    /// An error names the law's field when its speed at `t = 0` is not finite.
    pub fn new(
        laws: Vec<Expression>,
        law_of_node: Vec<Option<usize>>,
        dt: f64,
    ) -> Result<Option<Self>, SceneError> {
        if law_of_node.iter().all(Option::is_none) {
            return Ok(None);
        }
        let speed = (laws.iter().map(|l| l.eval(0.0, 0.0))).collect::<Result<Vec<_>, _>>()?;
        let n = laws.len();
        Ok(Some(Self {
            displacement: vec![0.0; law_of_node.len()],
            laws,
            law_of_node,
            dt,
            speed,
            increment: vec![0.0; n],
            span: vec![0.0; n],
            advanced: 0,
        }))
    }

    /// Moves the obstacles on to `t = t_{n+1}`: `V^{n+1} − V^n` from the speeds at `t_n` and
    /// `t`, the span of the step's slip, and `v_j`. An error names the law's field and `t`
    /// where a speed is not finite.
    pub fn advance(&mut self, t: f64) -> Result<(), SceneError> {
        let half = 0.5 * self.dt;
        for (l, law) in self.laws.iter().enumerate() {
            let speed = law.eval(0.0, t)?;
            let increment = half * (self.speed[l] + speed);
            self.span[l] = if self.advanced == 0 {
                increment
            } else {
                self.increment[l] + increment
            };
            (self.speed[l], self.increment[l]) = (speed, increment);
        }
        self.advanced += 1;
        for (v, law) in self.displacement.iter_mut().zip(&self.law_of_node) {
            *v = law.map_or(0.0, |l| self.span[l]);
        }
        Ok(())
    }

    /// `v_j`, the tangential displacement of each frictional node's obstacle over the step's
    /// slip interval (0 on a fixed obstacle).
    pub fn displacement(&self) -> &[f64] {
        &self.displacement
    }
}
