//! Exact solutions shipped with the built-in test scenes (in the manner of russell_ode's test
//! problems): each is the solution of the continuous problem, against which the discrete one is
//! measured at the nodes.

use crate::scene::Scene;

/// An exact solution `u(x, t)`.
pub trait ClosedForm {
    fn displacement(&self, x: f64, t: f64) -> f64;
    /// Kinetic plus elastic energy `½∫u_t² + ½∫u_x²` (the scheme's `E`), where derived here.
    fn energy(&self, _t: f64) -> Option<f64> {
        None
    }
    /// The contact intervals of the left end that start before `t_end` (clipped to it), where
    /// derived here.
    fn contact_intervals(&self, _t_end: f64) -> Option<Vec<[f64; 2]>> {
        None
    }
}

/// Free-free Kelvin–Voigt bar in mode `k`: `u = A(t) cos(kπx/L)` with
/// `A'' + α ω² A' + ω² A = 0`, `ω = kπ/L`, `A(0) = 1`, `A'(0) = 0` (separation of variables in
/// `u_tt − u_xx − α u_xxt = 0`; the mode satisfies `u_x = 0` at both ends).
#[derive(Clone, Copy, Debug)]
pub struct Modal {
    pub length: f64,
    pub alpha: f64,
    pub k: u32,
}

impl Modal {
    /// Modal amplitude `A(t)`: under-, critically or over-damped oscillator.
    pub fn amplitude(&self, t: f64) -> f64 {
        let w = self.k as f64 * std::f64::consts::PI / self.length;
        let g = 0.5 * self.alpha * w * w; // decay rate
        let disc = w * w - g * g;
        if disc > 0.0 {
            let wd = disc.sqrt();
            (-g * t).exp() * ((wd * t).cos() + g / wd * (wd * t).sin())
        } else if disc == 0.0 {
            (-g * t).exp() * (1.0 + g * t)
        } else {
            let s = (-disc).sqrt();
            let (l1, l2) = (-g + s, -g - s);
            (l1 * (l2 * t).exp() - l2 * (l1 * t).exp()) / (l1 - l2)
        }
    }
}

/// Step used to differentiate the modal amplitude for the energy: central differences,
/// truncation ~h² and round-off ~1e-16/h, both below 1e-9 relative.
const AMPLITUDE_DIFF_STEP: f64 = 1e-5;

impl ClosedForm for Modal {
    fn displacement(&self, x: f64, t: f64) -> f64 {
        let w = self.k as f64 * std::f64::consts::PI / self.length;
        self.amplitude(t) * (w * x).cos()
    }
    /// `u = A cos(wx)`: `E = ¼ L (A'² + w² A²)`.
    fn energy(&self, t: f64) -> Option<f64> {
        let w = self.k as f64 * std::f64::consts::PI / self.length;
        let h = AMPLITUDE_DIFF_STEP;
        let da = (self.amplitude(t + h) - self.amplitude(t - h)) / (2.0 * h);
        let a = self.amplitude(t);
        Some(0.25 * self.length * (da * da + w * w * a * a))
    }
}

/// Elastic bar on `[0, L]` moving rigidly at `−v0` onto an obstacle `a0` below its left end,
/// right end free: `u = max(−v0 min(t, t1 + x), v0 (t − 2t1 − 2L))`, `t1 = a0/v0`. Contact on
/// `[t1, t1 + 2L]` with reaction `v0`.
#[derive(Clone, Copy, Debug)]
pub struct Impact {
    pub length: f64,
    pub gap: f64,
    pub speed: f64,
}

impl Impact {
    pub fn contact_start(&self) -> f64 {
        self.gap / self.speed
    }
    pub fn contact_end(&self) -> f64 {
        self.contact_start() + 2.0 * self.length
    }
}

impl ClosedForm for Impact {
    fn displacement(&self, x: f64, t: f64) -> f64 {
        let (v0, t1, l) = (self.speed, self.contact_start(), self.length);
        (-v0 * t.min(t1 + x)).max(v0 * (t - 2.0 * t1 - 2.0 * l))
    }
    /// Elastic, and the obstacle does no work (`u(0)` is fixed while in contact): `½ v0² L`.
    fn energy(&self, _t: f64) -> Option<f64> {
        Some(0.5 * self.speed * self.speed * self.length)
    }
    fn contact_intervals(&self, t_end: f64) -> Option<Vec<[f64; 2]>> {
        Some(clip(&[[self.contact_start(), self.contact_end()]], t_end))
    }
}

/// The intervals that start at or before `t_end`, the last one cut at `t_end`.
fn clip(intervals: &[[f64; 2]], t_end: f64) -> Vec<[f64; 2]> {
    intervals
        .iter()
        .filter(|iv| iv[0] <= t_end)
        .map(|iv| [iv[0], iv[1].min(t_end)])
        .collect()
}

/// The falling bar: an elastic bar (`α = 0`) on `[0, L]` under gravity, `l = −g`, released at
/// rest with `u = 0` at height `a0` above a rigid obstacle under its left end (Signorini,
/// `u(0) ≥ −a0`); right end free. The benchmark class of Doyen, Ern & Piperno, "Time-integration
/// schemes for the finite element dynamic Signorini problem", SIAM J. Sci. Comput. 33(1), 2011:
/// a bar dropped on a rigid obstacle, with an exact solution. Their data were not available to
/// us, so the data and the closed form below are ours, derived here (checked by
/// `tests/closed_forms.rs`).
///
/// With `V1 = √(2 g a0)` (impact speed) we require `m = V1/(gL)` to be an integer `≥ 3`; then
/// the motion is periodic with period `T = 4(t1 + L)`, `t1 = V1/g = mL`, and symmetric in time
/// about `T/2`: `u(x, t) = u(x, T − t)`. On `t ∈ [0, T/2]`:
///
/// 1. Free fall, `t ≤ t1`: `u = −g t²/2`; the left end reaches `−a0` at `t1` with speed `V1`.
/// 2. Contact, `τ = t − t1 ∈ [0, 2L]`: with `h(s) = V1 s + g s²/2` for `s ≥ 0`, `0` for `s < 0`,
///    `u = −a0 − V1 τ − g τ²/2 + h(τ − x) + h(τ + x − 2L)` (d'Alembert; the second wave is the
///    reflection at the free end). It solves `u_tt − u_xx = −g`, `u(0) = −a0`, `u_x(L) = 0`,
///    and the reaction `−u_x(0) = V1 + g τ > 0`. Staying in contact past `τ = 2L` would need the
///    reaction `2gL − V1 < 0` (`m ≥ 3`), so the end releases at `τ = 2L`, when the bar has the
///    shape `u = −a0 + g(x² − 2Lx)` and the uniform velocity `+V1`.
/// 3. Flight, `s = τ − 2L ∈ [0, mL]`, free–free under gravity: the mean moves as a projectile
///    and the deviation, at rest initially, is d'Alembert with even reflections at both ends:
///    `u = −a0 − gL² + V1 s − g s²/2 + (P(x − s) + P(x + s))/2`, `P(y) = g (L − d(y))²`, `d(y)`
///    the distance from `y` to the nearest multiple of `2L` (the even, `2L`-periodic extension
///    of `g(L − x)²`). At `s = 2mL` (beyond `T/2`) the state is the release state with the
///    velocity reversed (`2mL = 2V1/g` is a whole number of periods `2L` of the deviation), so
///    the second half of the period is the first, reversed: a second contact of length `2L`,
///    then the rigid rise back to rest at `u = 0`.
///
/// The left end stays off the obstacle during the flight: on `s ∈ [2kL, 2(k+1)L]`,
/// `u(0) + a0 = g s²/2 + (V1 − 2jgL) s + g(j² − 1)L²`, `j = 2k + 1`, whose minimum over the
/// interval is either at an end (`u(0) + a0 = s(V1 − g s/2) > 0` at `s = 2kL ∈ (0, 2mL)`) or,
/// when `|m − j| ≤ 1`, at `s = (2j − m)L` with value `gL²(m²/2 − (m − j)² − 1) > 0` for `m ≥ 3`.
///
/// Contact intervals: `[t1, t1 + 2L]` and `[T − t1 − 2L, T − t1]` in every period, reaction
/// `V1 + g τ` (`τ` the time since the start of the first, or until the end of the second).
/// Total energy `½∫u_t² + ½∫u_x² + g∫u = 0`, so the scheme's `E` is `−g∫u`.
#[derive(Clone, Copy, Debug)]
pub struct FallingBar {
    pub length: f64,
    pub gravity: f64,
    pub gap: f64,
}

/// How far `V1/(gL)` may be from an integer and still count as one: a few ulps of the square
/// root and the division (the built-in data give an exact 3).
const WHOLE_RATIO_TOL: f64 = 1e-12;

impl FallingBar {
    /// The closed form, or `None` when the data leave its assumptions (positive length, gravity
    /// and gap, `V1/(gL)` an integer `≥ 3`).
    pub fn new(length: f64, gravity: f64, gap: f64) -> Option<Self> {
        let fb = Self {
            length,
            gravity,
            gap,
        };
        let m = fb.impact_speed() / (gravity * length);
        let ok = length > 0.0
            && gravity > 0.0
            && gap > 0.0
            && m.is_finite()
            && m >= 3.0 - WHOLE_RATIO_TOL
            && (m - m.round()).abs() <= WHOLE_RATIO_TOL * m;
        ok.then_some(fb)
    }
    /// `V1 = √(2 g a0)`.
    pub fn impact_speed(&self) -> f64 {
        (2.0 * self.gravity * self.gap).sqrt()
    }
    /// `t1 = V1/g`, the end of the free fall.
    pub fn fall_time(&self) -> f64 {
        self.impact_speed() / self.gravity
    }
    /// `T = 4(t1 + L)`.
    pub fn period(&self) -> f64 {
        4.0 * (self.fall_time() + self.length)
    }
    /// The phase at `t`, folded into the first half period `[0, T/2]` by periodicity and time
    /// symmetry.
    fn phase(&self, t: f64) -> Phase {
        let p = self.period();
        let r = t.rem_euclid(p);
        let t = if r > 0.5 * p { p - r } else { r };
        let tau = t - self.fall_time();
        if tau <= 0.0 {
            Phase::Fall(t)
        } else if tau <= 2.0 * self.length {
            Phase::Contact(tau)
        } else {
            Phase::Flight(tau - 2.0 * self.length)
        }
    }
    /// `−u_x(0, t)`: the contact force per unit section on the obstacle.
    pub fn reaction(&self, t: f64) -> f64 {
        match self.phase(t) {
            Phase::Contact(tau) => self.impact_speed() + self.gravity * tau,
            _ => 0.0,
        }
    }
    /// `∫_0^L u(x, t) dx`, in closed form (integrals of the phases' polynomials).
    pub fn integral(&self, t: f64) -> f64 {
        let (l, g, a0, v1) = (self.length, self.gravity, self.gap, self.impact_speed());
        match self.phase(t) {
            Phase::Fall(t) => -0.5 * g * t * t * l,
            // ∫h(τ − x) + ∫h(τ + x − 2L) = H(τ) − H(τ − 2L), H' = h, H(τ − 2L) = 0.
            Phase::Contact(tau) => {
                -a0 * l - l * (v1 * tau + 0.5 * g * tau * tau)
                    + 0.5 * v1 * tau * tau
                    + g * tau * tau * tau / 6.0
            }
            // The deviation has mean zero; the mean of the release shape is −2gL²/3.
            Phase::Flight(s) => -a0 * l + l * (-2.0 * g * l * l / 3.0 + v1 * s - 0.5 * g * s * s),
        }
    }
}

/// Where [`FallingBar`] is in its first half period, with the time since the phase began.
enum Phase {
    Fall(f64),
    Contact(f64),
    Flight(f64),
}

impl ClosedForm for FallingBar {
    fn displacement(&self, x: f64, t: f64) -> f64 {
        let (l, g, a0, v1) = (self.length, self.gravity, self.gap, self.impact_speed());
        match self.phase(t) {
            Phase::Fall(t) => -0.5 * g * t * t,
            Phase::Contact(tau) => {
                let h = |s: f64| {
                    if s > 0.0 {
                        v1 * s + 0.5 * g * s * s
                    } else {
                        0.0
                    }
                };
                -a0 - v1 * tau - 0.5 * g * tau * tau + h(tau - x) + h(tau + x - 2.0 * l)
            }
            Phase::Flight(s) => {
                let p = |y: f64| {
                    let d = (y - 2.0 * l * (y / (2.0 * l)).round()).abs();
                    g * (l - d) * (l - d)
                };
                -a0 - g * l * l + v1 * s - 0.5 * g * s * s + 0.5 * (p(x - s) + p(x + s))
            }
        }
    }
    fn energy(&self, t: f64) -> Option<f64> {
        Some(-self.gravity * self.integral(t))
    }
    fn contact_intervals(&self, t_end: f64) -> Option<Vec<[f64; 2]>> {
        let (p, t1, c) = (self.period(), self.fall_time(), 2.0 * self.length);
        let periods = (t_end / p).floor().max(0.0) as usize + 1;
        let all: Vec<[f64; 2]> = (0..periods)
            .flat_map(|k| {
                let o = k as f64 * p;
                [[o + t1, o + t1 + c], [o + p - t1 - c, o + p - t1]]
            })
            .collect();
        Some(clip(&all, t_end))
    }
}

/// Elastic bar on `[0, 1]`, clamped at 1, Signorini with gap 0 at 0, released at rest from
/// `(1 − x)/2`. Period 3; with `τ = t mod 3`, `s = τ − ⌊τ⌋`:
/// `τ ∈ [0,1)`: `(1 − max(x, s))/2`; `[1,2)`: `−min(x, s, 1−x, 1−s)/2`; `[2,3)`: `min(s, 1−x)/2`.
/// Energy `1/8` (conserved: the contact at `x = 0` is with zero velocity jump).
#[derive(Clone, Copy, Debug)]
pub struct ClampedImpact;

impl ClosedForm for ClampedImpact {
    fn displacement(&self, x: f64, t: f64) -> f64 {
        let tau = t.rem_euclid(3.0);
        let s = tau - tau.floor();
        if tau < 1.0 {
            (1.0 - x.max(s)) / 2.0
        } else if tau < 2.0 {
            -x.min(s).min(1.0 - x).min(1.0 - s) / 2.0
        } else {
            s.min(1.0 - x) / 2.0
        }
    }
    /// Released at rest from `(1 − x)/2`: `½ ∫ u_x² = 1/8`, conserved.
    fn energy(&self, _t: f64) -> Option<f64> {
        Some(0.125)
    }
}

/// A manufactured solution with a load that depends on `x` and `t`, no contact:
/// `u = cos(2t) cos(kx)`, `k = π/L`, on a free-free bar (`u_x = 0` at both ends for all `t`).
/// Its load `l = u_tt − u_xx − α u_xxt = ((k² − 4) cos 2t − 2αk² sin 2t) cos kx` is the only
/// closed form in the certificate whose load varies in both `x` and `t`, so it is the one that
/// sees where in time the scheme evaluates `F^n` (at `t_n`; at `t_{n+1}` the error is first
/// order).
#[derive(Clone, Copy, Debug)]
pub struct ForcedMode {
    pub length: f64,
    pub alpha: f64,
}

impl ForcedMode {
    fn k(&self) -> f64 {
        std::f64::consts::PI / self.length
    }
    /// The load density `l(x, t)` that makes `u` a solution.
    pub fn load(&self, x: f64, t: f64) -> f64 {
        let k = self.k();
        ((k * k - 4.0) * (2.0 * t).cos() - 2.0 * self.alpha * k * k * (2.0 * t).sin())
            * (k * x).cos()
    }
    /// The load written in the scene grammar (README, "Expressions"), for scenes built in code.
    pub fn load_expression(&self) -> String {
        let (k, a) = (self.k(), self.alpha);
        format!("(({k:e})^2 - 4)*cos(2*t)*cos({k:e}*x) - 2*{a:e}*({k:e})^2*sin(2*t)*cos({k:e}*x)")
    }
}

impl ClosedForm for ForcedMode {
    fn displacement(&self, x: f64, t: f64) -> f64 {
        (2.0 * t).cos() * (self.k() * x).cos()
    }
    /// `E = ½∫u_t² + ½∫u_x² = ¼L (4 sin² 2t + k² cos² 2t)`.
    fn energy(&self, t: f64) -> Option<f64> {
        let (s, c, k) = ((2.0 * t).sin(), (2.0 * t).cos(), self.k());
        Some(0.25 * self.length * (4.0 * s * s + k * k * c * c))
    }
}

/// Largest difference, relative to `1 + |l|`, between a scene's load and [`ForcedMode::load`]
/// that still counts as the same load: the scene's text rounds `π` and its products once more.
const LOAD_MATCH_TOL: f64 = 1e-12;

/// Viscous contact, manufactured: a Kelvin–Voigt bar (`α > 0`) on `[0, L]`,
/// Signorini at `x = 0` with gap `a0`, free at `x = L`, with the exact solution
/// `u(x, t) = g(t) + h(t) w(x)`, `w = sin(kx)/k`, `k = π/(2L)` (so `w(0) = 0`, `w'(0) = 1`,
/// `w'(L) = 0`, `w'' = −k² w`), under the load `l = u_tt − u_xx − α u_xxt` it defines.
/// Derivation and choices: [docs/viscous-contact.md](../../docs/viscous-contact.md). In short:
///
/// - `u(0, t) = g(t)`, `s(0, t) = u_x + α u_xt = h + α h'`, `s(L, t) = 0`.
/// - `g = −a0 + a0 ((t1 − t)⁺/t1)³ + a0 ((t − t2)⁺/t1)³`: released at `g(0) = 0` with
///   velocity `−3a0/t1`, on the obstacle exactly on `[t1, t2]`, `C²` at both joins.
/// - The stress at the obstacle `σ(t) = s(0, t)` is `−P sin²(π(t − t1)/(t2 − t1))` on
///   `[t1, t2]` and `0` outside (`C¹`), and `h` solves `α h' + h = σ`, `h(0) = h0`:
///   `h = h0 e^{−t/α} + (1/α)∫_{t1}^t e^{−(t−τ)/α} σ(τ) dτ` (the integral in closed form; after
///   `t2` its value at `t2` decays as `e^{−(t−t2)/α}`); so `h ∈ C²`. `h0 ≠ 0` keeps the bar
///   moving when it lands (with `h0 = 0` it is at rest at `t1` and the energy identity's
///   relative residual is round-off over an energy of 1e-29).
/// - Load: `l = g'' + q(t) w(x)`, `q = h'' + k² σ`, `h' = (σ − h)/α`,
///   `h'' = (σ' − h')/α`.
/// - Complementarity: gap `g + a0 ≥ 0`, zero exactly on `[t1, t2]`; reaction `−σ ≥ 0`, zero
///   outside.
#[derive(Clone, Copy, Debug)]
pub struct ViscousContact {
    pub length: f64,
    pub alpha: f64,
    pub gap: f64,
    /// The contact window `[t1, t2]`, `0 < t1 < t2`.
    pub t1: f64,
    pub t2: f64,
    /// `P > 0`: the peak reaction, `−σ((t1 + t2)/2)`.
    pub pulse: f64,
    /// `h0 = h(0)`: the initial shape `h0 w(x)` and velocity `g'(0) − (h0/α) w(x)`.
    pub initial_amplitude: f64,
}

impl ViscousContact {
    /// `k = π/(2L)`.
    pub fn wavenumber(&self) -> f64 {
        0.5 * std::f64::consts::PI / self.length
    }
    /// The shape `w(x) = sin(kx)/k`.
    pub fn shape(&self, x: f64) -> f64 {
        let k = self.wavenumber();
        (k * x).sin() / k
    }
    /// `(g, g', g'')` at `t`.
    pub fn rigid(&self, t: f64) -> [f64; 3] {
        let c = self.gap / self.t1.powi(3);
        let (before, after) = ((self.t1 - t).max(0.0), (t - self.t2).max(0.0));
        [
            -self.gap + c * (before.powi(3) + after.powi(3)),
            3.0 * c * (after * after - before * before),
            6.0 * c * (before + after),
        ]
    }
    /// `ω = 2π/(t2 − t1)`: `sin²(π τ/T) = (1 − cos ωτ)/2`.
    fn omega(&self) -> f64 {
        2.0 * std::f64::consts::PI / (self.t2 - self.t1)
    }
    /// `(σ, σ')`: the stress `s(0, t)` and its rate.
    pub fn stress(&self, t: f64) -> [f64; 2] {
        if t <= self.t1 || t >= self.t2 {
            return [0.0, 0.0];
        }
        let (w, tau) = (self.omega(), t - self.t1);
        [
            -0.5 * self.pulse * (1.0 - (w * tau).cos()),
            -0.5 * self.pulse * w * (w * tau).sin(),
        ]
    }
    /// `h(t)`: the free decay of `h0` plus the response to `σ` (0 before the window, the
    /// convolution on it, its decay after it).
    pub fn amplitude(&self, t: f64) -> f64 {
        let a = self.alpha;
        let on_window = |tau: f64| {
            let (w, e) = (self.omega(), (-tau / a).exp());
            let resonance = 1.0 + a * a * w * w;
            -0.5 * self.pulse
                * ((1.0 - e) - ((w * tau).cos() + a * w * (w * tau).sin() - e) / resonance)
        };
        let free = self.initial_amplitude * (-t / a).exp();
        free + if t <= self.t1 {
            0.0
        } else if t <= self.t2 {
            on_window(t - self.t1)
        } else {
            on_window(self.t2 - self.t1) * (-(t - self.t2) / a).exp()
        }
    }
    /// `(h, h', h'')` from `α h' + h = σ`.
    pub fn amplitude_rates(&self, t: f64) -> [f64; 3] {
        let h = self.amplitude(t);
        let [s, ds] = self.stress(t);
        let dh = (s - h) / self.alpha;
        [h, dh, (ds - dh) / self.alpha]
    }
    /// The load `l(x, t) = g'' + (h'' + k² σ) w(x)`.
    pub fn load(&self, x: f64, t: f64) -> f64 {
        let k = self.wavenumber();
        let [_, _, ddh] = self.amplitude_rates(t);
        self.rigid(t)[2] + (ddh + k * k * self.stress(t)[0]) * self.shape(x)
    }
    /// `u_t(x, t) = g' + h' w`.
    pub fn velocity(&self, x: f64, t: f64) -> f64 {
        self.rigid(t)[1] + self.amplitude_rates(t)[1] * self.shape(x)
    }
    /// `−s(0, t) = −σ(t) ≥ 0`: the obstacle's reaction.
    pub fn reaction(&self, t: f64) -> f64 {
        -self.stress(t)[0]
    }
}

impl ClosedForm for ViscousContact {
    fn displacement(&self, x: f64, t: f64) -> f64 {
        self.rigid(t)[0] + self.amplitude(t) * self.shape(x)
    }
    /// `u_t = g' + h' w`, `u_x = h cos(kx)`, with `∫w = 1/k²`, `∫w² = L/(2k²)`,
    /// `∫cos²(kx) = L/2`.
    fn energy(&self, t: f64) -> Option<f64> {
        let (l, k) = (self.length, self.wavenumber());
        let [_, dg, _] = self.rigid(t);
        let [h, dh, _] = self.amplitude_rates(t);
        let kinetic = l * dg * dg + 2.0 * dg * dh / (k * k) + dh * dh * l / (2.0 * k * k);
        Some(0.5 * kinetic + 0.25 * h * h * l)
    }
    fn contact_intervals(&self, t_end: f64) -> Option<Vec<[f64; 2]>> {
        Some(clip(&[[self.t1, self.t2]], t_end))
    }
}

/// The contact window, peak reaction and `h0` of the built-in `viscous-contact` scene (its
/// description; the load expression there is written for these, `L = 1`, `α = 0.1`,
/// `a0 = 0.25`, and [`for_scene`] checks it against [`ViscousContact::load`]).
pub const VISCOUS_CONTACT_WINDOW: [f64; 2] = [0.5, 1.5];
pub const VISCOUS_CONTACT_PULSE: f64 = 1.0;
pub const VISCOUS_CONTACT_INITIAL_AMPLITUDE: f64 = -0.2;
/// Load sample points per direction at which the scene's expression must equal the closed
/// form's load (an `(x, t)` grid over the bar and the run).
const LOAD_CHECK_POINTS: usize = 41;
/// Relative agreement of the scene's load expression with [`ViscousContact::load`]: the same
/// formula, evaluated in another order (terms up to `100 |h| ~ 100`), so a few hundred ulps.
const LOAD_CHECK_RTOL: f64 = 1e-12;

/// The closed form of a built-in scene, with its parameters read from the scene (so that
/// `--set` overrides of the length, gap, speed, gravity or viscosity are honoured). `None` for
/// scenes without one, or when overrides have made the scene leave the closed form's
/// assumptions (checked: end conditions, no distributed obstacle, elastic bar and load where
/// required, a uniform initial velocity, initial displacement at 101 points).
pub fn for_scene(name: &str, scene: &Scene) -> Option<Box<dyn ClosedForm>> {
    use crate::scene::Condition::{Clamped, Free, Signorini};
    use crate::scene::expr::Expression;
    let ends = (scene.left.condition, scene.right.condition);
    let unloaded = scene.load.density.is_none();
    let elastic = scene.bar.viscosity == 0.0 && unloaded;
    let velocity = Expression::parse("initial.velocity", &scene.initial.velocity, false).ok()?;
    // Every closed form here but the manufactured one starts from a uniform velocity.
    if (velocity.depends_on_x() && name != "viscous-contact") || scene.obstacle.is_some() {
        return None;
    }
    let velocity0 = velocity.eval(0.0, 0.0).ok()?;
    let exact: Box<dyn ClosedForm> = match name {
        "modal" if ends == (Free, Free) && unloaded && velocity0 == 0.0 => Box::new(Modal {
            length: scene.bar.length,
            alpha: scene.bar.viscosity,
            k: 2,
        }),
        "impact" if ends == (Signorini, Free) && elastic && velocity0 < 0.0 => Box::new(Impact {
            length: scene.bar.length,
            gap: scene.left.constant_gap()?,
            speed: -velocity0,
        }),
        "clamped-impact"
            if ends == (Signorini, Clamped)
                && elastic
                && velocity0 == 0.0
                && scene.bar.length == 1.0
                && scene.left.constant_gap() == Some(0.0) =>
        {
            Box::new(ClampedImpact)
        }
        "forced-mode" if ends == (Free, Free) && velocity0 == 0.0 => {
            let exact = ForcedMode {
                length: scene.bar.length,
                alpha: scene.bar.viscosity,
            };
            let load =
                Expression::parse("load.density", scene.load.density.as_ref()?, true).ok()?;
            let matches = (0..=20).all(|i| {
                (0..=20).all(|j| {
                    let (x, t) = (scene.bar.length * i as f64 / 20.0, 0.3 * j as f64);
                    let want = exact.load(x, t);
                    load.eval(x, t)
                        .is_ok_and(|v| (v - want).abs() <= LOAD_MATCH_TOL * (1.0 + want.abs()))
                })
            });
            if !matches {
                return None;
            }
            Box::new(exact)
        }
        "falling-bar"
            if ends == (Signorini, Free) && scene.bar.viscosity == 0.0 && velocity0 == 0.0 =>
        {
            let load =
                Expression::parse("load.density", scene.load.density.as_ref()?, true).ok()?;
            if load.depends_on_x() || load.depends_on_t() {
                return None;
            }
            let gravity = -load.eval(0.0, 0.0).ok()?;
            Box::new(FallingBar::new(
                scene.bar.length,
                gravity,
                scene.left.constant_gap()?,
            )?)
        }
        "viscous-contact" if ends == (Signorini, Free) && scene.bar.viscosity > 0.0 => {
            let [t1, t2] = VISCOUS_CONTACT_WINDOW;
            let vc = ViscousContact {
                length: scene.bar.length,
                alpha: scene.bar.viscosity,
                gap: scene.left.constant_gap()?,
                t1,
                t2,
                pulse: VISCOUS_CONTACT_PULSE,
                initial_amplitude: VISCOUS_CONTACT_INITIAL_AMPLITUDE,
            };
            let load =
                Expression::parse("load.density", scene.load.density.as_ref()?, true).ok()?;
            let n = LOAD_CHECK_POINTS - 1;
            let end = scene.time.end;
            let same_load = (0..=n).all(|i| {
                (0..=n).all(|j| {
                    let (x, t) = (vc.length * i as f64 / n as f64, end * j as f64 / n as f64);
                    let exact = vc.load(x, t);
                    load.eval(x, t)
                        .is_ok_and(|v| (v - exact).abs() <= LOAD_CHECK_RTOL * exact.abs().max(1.0))
                })
            });
            let same_velocity = (0..=100).all(|i| {
                let x = vc.length * i as f64 / 100.0;
                velocity
                    .eval(x, 0.0)
                    .is_ok_and(|v| (v - vc.velocity(x, 0.0)).abs() <= 1e-12)
            });
            if !(same_load && same_velocity) {
                return None;
            }
            Box::new(vc)
        }
        _ => return None,
    };
    let u0 = Expression::parse("initial.displacement", &scene.initial.displacement, false).ok()?;
    let fits = (0..=100).all(|i| {
        let x = scene.bar.length * i as f64 / 100.0;
        u0.eval(x, 0.0)
            .is_ok_and(|v| (v - exact.displacement(x, 0.0)).abs() <= 1e-12)
    });
    fits.then_some(exact)
}
