//! Exact solutions shipped with the built-in test scenes (in the manner of russell_ode's test
//! problems): each is the solution of the continuous problem, against which the discrete one is
//! measured at the nodes.

use crate::scene::Scene;

/// An exact solution `u(x, t)`.
pub trait ClosedForm {
    fn displacement(&self, x: f64, t: f64) -> f64;
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

impl ClosedForm for Modal {
    fn displacement(&self, x: f64, t: f64) -> f64 {
        let w = self.k as f64 * std::f64::consts::PI / self.length;
        self.amplitude(t) * (w * x).cos()
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
}

/// The closed form of a built-in scene, with its parameters read from the scene (so that
/// `--set` overrides of the length, gap, speed or viscosity are honoured). `None` for scenes
/// without one, or when overrides have made the scene leave the closed form's assumptions
/// (checked: end conditions, elastic bar where required, initial displacement at 101 points).
pub fn for_scene(name: &str, scene: &Scene) -> Option<Box<dyn ClosedForm>> {
    use crate::scene::Condition::{Clamped, Free, Signorini};
    let ends = (scene.left.condition, scene.right.condition);
    let elastic = scene.bar.viscosity == 0.0 && scene.load.density.is_none();
    let velocity0 =
        crate::expr::Expression::parse("initial.velocity", &scene.initial.velocity, false)
            .ok()?
            .eval(0.0, 0.0)
            .ok()?;
    let exact: Box<dyn ClosedForm> = match name {
        "modal" if ends == (Free, Free) && scene.load.density.is_none() => Box::new(Modal {
            length: scene.bar.length,
            alpha: scene.bar.viscosity,
            k: 2,
        }),
        "impact" if ends == (Signorini, Free) && elastic && velocity0 < 0.0 => Box::new(Impact {
            length: scene.bar.length,
            gap: scene.left.gap?,
            speed: -velocity0,
        }),
        "clamped-impact"
            if ends == (Signorini, Clamped)
                && elastic
                && scene.bar.length == 1.0
                && scene.left.gap == Some(0.0) =>
        {
            Box::new(ClampedImpact)
        }
        _ => return None,
    };
    let u0 =
        crate::expr::Expression::parse("initial.displacement", &scene.initial.displacement, false)
            .ok()?;
    let fits = (0..=100).all(|i| {
        let x = scene.bar.length * i as f64 / 100.0;
        u0.eval(x, 0.0)
            .is_ok_and(|v| (v - exact.displacement(x, 0.0)).abs() <= 1e-12)
    });
    fits.then_some(exact)
}
