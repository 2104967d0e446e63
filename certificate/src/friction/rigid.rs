//! The rigid-limit closed forms of Coulomb friction (VERIFICATION.md, "Plane friction") and
//! how the plane body approaches them as it stiffens: a block at rest on a floor under gravity
//! tilted by `θ` (load `(g sin θ, −g cos θ)`) slides with acceleration `g (sin θ − μ cos θ)`
//! when `tan θ > μ` and sticks otherwise; a block launched at `v0` on a level floor stops after
//! `v0/(μ g)` having slid `v0²/(2 μ g)`. The closed forms are checked first against an
//! independent integration of the rigid block's law of motion with its stops located exactly
//! ([`rigid_motion`]); the plane runs (`plane-friction-slope`, `plane-friction-launch`, the
//! stiffness `λ = μ_L = κ` set) are then measured by the block's mass-weighted mean motion.
//! Friction acts from the start-up step on (its projection applies the rigid block's
//! deceleration over `[0, Δt/2]` exactly), so the launch's stop time and distance are measured
//! from `t = 0`.

use crate::plane::contact::{plane_error, plane_scene};
use viscobar::plane::PlaneSimulation;
use viscobar::scene::plane::PlaneScene;
use viscobar::study::converge::ConvergeError;

/// The stiffnesses `κ = λ = μ_L` of the rigid-limit table (the scenes' own: 100).
pub const STIFFNESSES: [f64; 5] = [1e1, 1e2, 1e3, 1e4, 1e5];
/// The slope scene's friction in its stick run (above `tan θ = 0.75`).
pub const STICK_FRICTION: f64 = 1.0;

/// A rigid block on a floor: tangential and normal load per unit mass `(f_t, f_n)` (`f_n > 0`
/// presses it on), Coulomb coefficient `mu`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct RigidBlock {
    pub tangential: f64,
    pub normal: f64,
    pub mu: f64,
}

impl RigidBlock {
    /// Its acceleration from rest: `f_t − μ f_n sign f_t` when `|f_t| > μ f_n`, else 0 (it
    /// sticks).
    pub fn acceleration_from_rest(&self) -> f64 {
        let (f, limit) = (self.tangential, self.mu * self.normal);
        if f.abs() > limit {
            f - limit * f.signum()
        } else {
            0.0
        }
    }

    /// Launched at `v0 > 0` with no tangential load: its stop time `v0/(μ f_n)` and distance
    /// `v0²/(2 μ f_n)`.
    pub fn launched(&self, v0: f64) -> (f64, f64) {
        let decel = self.mu * self.normal;
        (v0 / decel, v0 * v0 / (2.0 * decel))
    }
}

/// The rigid block's motion from `(x, v) = (0, v0)` up to `t_end`, integrated independently of
/// the closed forms: in each interval of length `dt` the acceleration is constant (the
/// friction force opposes the velocity, or, at rest, the load up to `μ f_n`), so `x` and `v`
/// are exact quadratics; a velocity that would change sign stops at its zero, located exactly,
/// and the rest of the interval is spent at rest or starting again. Returns the final
/// `(x, v)` and the first stop time (`None` without one).
pub fn rigid_motion(block: RigidBlock, v0: f64, dt: f64, t_end: f64) -> (f64, f64, Option<f64>) {
    let (mut t, mut x, mut v, mut stop) = (0.0, 0.0, v0, None);
    while t < t_end {
        let mut left = dt.min(t_end - t);
        while left > 0.0 {
            let a = if v != 0.0 {
                block.tangential - block.mu * block.normal * v.signum()
            } else {
                block.acceleration_from_rest()
            };
            // The time to a zero of v under this acceleration, if it comes within the interval.
            let to_zero = if v != 0.0 && a != 0.0 && (-v / a) > 0.0 {
                -v / a
            } else {
                f64::INFINITY
            };
            let h = left.min(to_zero);
            x += v * h + 0.5 * a * h * h;
            if h == to_zero {
                v = 0.0;
                stop.get_or_insert(t + (dt.min(t_end - t) - left) + h);
            } else {
                v += a * h;
            }
            left -= h;
        }
        t += dt.min(t_end - t);
    }
    (x, v, stop)
}

/// The mass-weighted mean motion of a plane run along `x`: `X = 1_xᵀ M u / m` and
/// `V = 1_xᵀ M w / (Δt m)` (`w = u^n − u^{n−1}`, so `V` is the velocity at `t_{n−1/2}`).
pub struct MeanMotion {
    weights: Vec<f64>,
    mass: f64,
}

impl MeanMotion {
    /// The weights `M 1_x` of `sim`'s unknowns.
    pub fn of(sim: &PlaneSimulation) -> Self {
        use viscobar::scheme::Body;
        let d = sim.discretisation();
        let ones: Vec<f64> = d
            .free
            .iter()
            .map(|&dof| if dof % 2 == 0 { 1.0 } else { 0.0 })
            .collect();
        let mut weights = vec![0.0; ones.len()];
        sim.body().mass_mul(&ones, &mut weights);
        let mass = weights.iter().sum();
        Self { weights, mass }
    }

    /// The block's mass `1_xᵀ M 1_x = ρ W H`.
    pub fn mass(&self) -> f64 {
        self.mass
    }

    /// `X` of `u`.
    pub fn position(&self, u: &[f64]) -> f64 {
        self.weights.iter().zip(u).map(|(a, b)| a * b).sum::<f64>() / self.mass
    }

    /// `(X, V)` of `sim`'s current state.
    pub fn of_state(&self, sim: &PlaneSimulation) -> (f64, f64) {
        let s = sim.state();
        (self.position(s.u), self.position(s.w) * s.scale)
    }
}

/// The closed form of the slope scene (its load and friction) and of the launch scene.
fn slope_block(scene: &PlaneScene) -> Result<RigidBlock, ConvergeError> {
    let load = scene
        .expressions()?
        .load
        .expect("the slope scene has a load");
    let [ft, fy] = load.map(|e| e.eval_xy(0.0, 0.0, 0.0).unwrap_or(f64::NAN));
    Ok(RigidBlock {
        tangential: ft / scene.plane.density,
        normal: -fy / scene.plane.density,
        mu: scene.edges.bottom.constant_friction().unwrap_or(0.0),
    })
}

/// One row of the rigid-limit table.
#[derive(Clone, Copy, Debug, Default)]
pub struct RigidRow {
    pub stiffness: f64,
    /// Slope, slipping: the mean acceleration `(V_{N−1/2} − V_{1/2}) / (t_{N−1/2} − t_{1/2})`,
    /// its closed form and relative error.
    pub slope_acceleration: f64,
    pub slope_exact: f64,
    pub slope_error: f64,
    /// Slope, sticking (`μ = STICK_FRICTION`): the mean velocity over the run's second half,
    /// `|X_N − X_{N/2}| / (t_N − t_{N/2})`, over the frictionless block's final velocity `f_t T`.
    pub stick_velocity: f64,
    /// Launch: the time from `t = 0` to the first zero of `V` (linear between half-steps),
    /// the distance from the mean position at `t = 0` to the end, and their relative errors.
    pub stop_time: f64,
    pub stop_error: f64,
    pub distance: f64,
    pub distance_error: f64,
    /// The largest identity residual of the three runs.
    pub identity: f64,
}

/// `scene` with `λ = μ_L = kappa`.
fn stiffened(scene: &PlaneScene, kappa: f64) -> PlaneScene {
    let mut s = scene.clone();
    s.plane.lambda = kappa;
    s.plane.mu = kappa;
    s
}

/// The mean motion `(t, X, V)` of a run after each step.
pub type MeanHistory = Vec<(f64, f64, f64)>;

/// Runs `scene` and returns the mean motion `(t, X, V)` after each step (`V` at `t − Δt/2`),
/// from the start-up step on, with the largest identity residual.
pub fn mean_history(scene: &PlaneScene) -> Result<(MeanHistory, f64), ConvergeError> {
    let prepared = PlaneSimulation::prepare(scene).map_err(plane_error)?;
    let (u0, v0) = (prepared.state().u.to_vec(), prepared.state().w.to_vec());
    let mut sim = prepared.start().map_err(plane_error)?;
    let mean = MeanMotion::of(&sim);
    // At t = 0 the state's `w` is the initial velocity itself.
    let mut out = vec![(0.0, mean.position(&u0), mean.position(&v0))];
    let (x, v) = mean.of_state(&sim);
    out.push((sim.time(), x, v));
    let mut identity = 0.0f64;
    for _ in 1..scene.steps() {
        let r = sim.step().map_err(plane_error)?;
        identity = identity.max(r.identity_residual);
        let (x, v) = mean.of_state(&sim);
        out.push((sim.time(), x, v));
    }
    Ok((out, identity))
}

/// The rigid-limit row at stiffness `kappa`.
pub fn rigid_row(kappa: f64) -> Result<RigidRow, ConvergeError> {
    let slope = stiffened(&plane_scene("plane-friction-slope", &[])?, kappa);
    let launch = stiffened(&plane_scene("plane-friction-launch", &[])?, kappa);
    let dt = slope.time.step;
    let mut row = RigidRow {
        stiffness: kappa,
        ..RigidRow::default()
    };
    // Slope, slipping.
    let block = slope_block(&slope)?;
    let (h, id) = mean_history(&slope)?;
    row.slope_exact = block.acceleration_from_rest();
    let (first, last) = (h[1], h[h.len() - 1]);
    row.slope_acceleration = (last.2 - first.2) / (last.0 - first.0);
    row.slope_error = (row.slope_acceleration - row.slope_exact).abs() / row.slope_exact;
    row.identity = id;
    // Slope, sticking.
    let mut stick = slope.clone();
    stick.edges.bottom.friction = Some(STICK_FRICTION.to_string());
    let (h, id) = mean_history(&stick)?;
    let (mid, last) = (h[h.len() / 2], h[h.len() - 1]);
    let mean_velocity = (last.1 - mid.1).abs() / (last.0 - mid.0);
    row.stick_velocity = mean_velocity / (block.tangential * last.0);
    row.identity = row.identity.max(id);
    // Launch.
    let v0 = launch_velocity(&launch)?;
    let block = slope_block(&launch)?;
    let (stop, distance) = block.launched(v0);
    let (h, id) = mean_history(&launch)?;
    row.identity = row.identity.max(id);
    let start = h[0].1;
    let crossing = h.windows(2).skip(1).find(|w| w[0].2 > 0.0 && w[1].2 <= 0.0);
    row.stop_time = crossing.map_or(f64::INFINITY, |w| {
        let (ta, tb) = (w[0].0 - 0.5 * dt, w[1].0 - 0.5 * dt);
        ta + (tb - ta) * w[0].2 / (w[0].2 - w[1].2)
    });
    row.stop_error = (row.stop_time - stop).abs() / stop;
    row.distance = h[h.len() - 1].1 - start;
    row.distance_error = (row.distance - distance).abs() / distance;
    Ok(row)
}

/// The launch scene's initial velocity (uniform, along x).
fn launch_velocity(scene: &PlaneScene) -> Result<f64, ConvergeError> {
    scene.expressions()?.velocity[0]
        .eval_xy(0.0, 0.0, 0.0)
        .map_err(|e| ConvergeError::BadInput(e.to_string()))
}

/// The rigid-limit table over [`STIFFNESSES`].
pub fn rigid_table() -> Result<Vec<RigidRow>, ConvergeError> {
    STIFFNESSES.iter().map(|&k| rigid_row(k)).collect()
}

/// The closed forms against the independent integration ([`rigid_motion`], `dt = 1e-3`), for
/// the scenes' blocks: `(slope acceleration, stick velocity, stop time, distance)` as the
/// largest relative (stick: absolute) difference.
pub fn closed_form_self_test() -> Result<[f64; 4], ConvergeError> {
    let slope = slope_block(&plane_scene("plane-friction-slope", &[])?)?;
    let launch_scene = plane_scene("plane-friction-launch", &[])?;
    let launch = slope_block(&launch_scene)?;
    let v0 = launch_velocity(&launch_scene)?;
    let (dt, t_end) = (1e-3, 3.0);
    let (_, v, _) = rigid_motion(slope, 0.0, dt, t_end);
    let a = slope.acceleration_from_rest();
    let slope_diff = (v / t_end - a).abs() / a;
    let stick = RigidBlock {
        mu: STICK_FRICTION,
        ..slope
    };
    let (x, v, _) = rigid_motion(stick, 0.0, dt, t_end);
    let stick_diff = x
        .abs()
        .max(v.abs())
        .max(stick.acceleration_from_rest().abs());
    let (stop, distance) = launch.launched(v0);
    let (x, v, t_stop) = rigid_motion(launch, v0, dt, 1.5 * stop);
    let stop_diff = (t_stop.unwrap_or(f64::INFINITY) - stop).abs() / stop;
    let distance_diff = ((x - distance).abs() / distance).max(v.abs());
    Ok([slope_diff, stick_diff, stop_diff, distance_diff])
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The integration is exact for piecewise constant acceleration: only round-off of a few
    /// thousand additions separates it from the closed forms.
    const SELF_TEST_TOL: f64 = 1e-12;

    #[test]
    fn the_integration_reproduces_textbook_cases_independently() {
        // A block sliding to rest on a level floor, v0 = 3, μ g = 1.5: stops at 2 after 3.
        let b = RigidBlock {
            tangential: 0.0,
            normal: 3.0,
            mu: 0.5,
        };
        let (x, v, stop) = rigid_motion(b, 3.0, 0.07, 5.0);
        assert!((stop.unwrap() - 2.0).abs() < SELF_TEST_TOL, "{stop:?}");
        assert!((x - 3.0).abs() < SELF_TEST_TOL && v == 0.0, "{x} {v}");
        // A wrong formula would fail: v0²/(μ g) is 6, not 3.
        assert!((x - 6.0).abs() > 1.0);
        let scene = closed_form_self_test().unwrap();
        assert!(scene.iter().all(|d| *d < SELF_TEST_TOL), "{scene:?}");
    }
}
