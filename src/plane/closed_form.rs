//! A manufactured solution of the plane Kelvin–Voigt body on `(0, W) × (0, H)`, clamped on
//! all four edges, `u(x, y, t) = (cos ωt + β sin ωt) Φ(x, y)` with
//! `Φ = (a₁ sin(πx/W) sin(πy/H), a₂ sin(2πx/W) sin(2πy/H))`, and its load
//! `l = ρ u_tt − div σ`, `σ = A ε(u + α u_t)` (derivation: `docs/plane-manufactured.md`).
//! `Φ` vanishes on the boundary, so the clamped conditions hold; the unit test checks `l`
//! against finite differences of `u` and the scene's load text against `l`. [`Coupled`] adds a
//! temperature `θ = b (1 + t) sin(πx/W) sin(πy/H)` coupled by `γ` (held at 0 on the edges),
//! the load gaining `γ ∇θ` and the heat source `θ_t − κΔθ + γ div u_t`.

use crate::scene::heat::ThermalCondition;
use crate::scene::plane::{
    Body, EdgeCondition, EdgeSpec, Edges, PlaneHeat, PlaneInitial, PlaneLoad, PlaneMesh,
    PlaneScene, ThermalEdge, Vector,
};
use crate::scene::schema::Time;
use std::f64::consts::PI;

/// The manufactured problem's data.
#[derive(Clone, Copy, Debug)]
pub struct Manufactured {
    pub width: f64,
    pub height: f64,
    pub lambda: f64,
    pub mu: f64,
    pub density: f64,
    pub viscosity: f64,
    /// `ω`, `β` of `g`.
    pub omega: f64,
    pub beta: f64,
    /// Amplitudes `a₁`, `a₂`.
    pub amplitude: [f64; 2],
}

impl Default for Manufactured {
    /// The problem of the convergence test: `λ = 2 ≠ 0`, `α = 0.05 > 0`.
    fn default() -> Self {
        Self {
            width: 2.0,
            height: 1.0,
            lambda: 2.0,
            mu: 1.0,
            density: 1.0,
            viscosity: 0.05,
            omega: 3.0,
            beta: 0.5,
            amplitude: [0.1, 0.05],
        }
    }
}

/// `sin(k s)` and its first two derivatives.
fn sine(k: f64, s: f64) -> [f64; 3] {
    let (sn, cs) = (k * s).sin_cos();
    [sn, k * cs, -k * k * sn]
}

impl Manufactured {
    /// Wave numbers `[k₁x, k₁y, k₂x, k₂y]`.
    fn k(&self) -> [f64; 4] {
        [
            PI / self.width,
            PI / self.height,
            2.0 * PI / self.width,
            2.0 * PI / self.height,
        ]
    }

    /// `g, g', g''`.
    fn g(&self, t: f64) -> [f64; 3] {
        let (s, c) = (self.omega * t).sin_cos();
        let g = c + self.beta * s;
        [
            g,
            self.omega * (self.beta * c - s),
            -self.omega * self.omega * g,
        ]
    }

    /// `Φ(x, y)`.
    fn phi(&self, x: f64, y: f64) -> [f64; 2] {
        let [k1x, k1y, k2x, k2y] = self.k();
        [
            self.amplitude[0] * sine(k1x, x)[0] * sine(k1y, y)[0],
            self.amplitude[1] * sine(k2x, x)[0] * sine(k2y, y)[0],
        ]
    }

    /// `u(x, y, t)`.
    pub fn displacement(&self, x: f64, y: f64, t: f64) -> [f64; 2] {
        let g = self.g(t)[0];
        self.phi(x, y).map(|p| g * p)
    }

    /// `u_t(x, y, t)`.
    pub fn velocity(&self, x: f64, y: f64, t: f64) -> [f64; 2] {
        let g = self.g(t)[1];
        self.phi(x, y).map(|p| g * p)
    }

    /// `LΦ = div A ε(Φ)`.
    fn l_phi(&self, x: f64, y: f64) -> [f64; 2] {
        let [k1x, k1y, k2x, k2y] = self.k();
        let [a1, a2] = self.amplitude;
        let (x1, y1, x2, y2) = (sine(k1x, x), sine(k1y, y), sine(k2x, x), sine(k2y, y));
        let (lam, mu) = (self.lambda, self.mu);
        [
            a1 * ((lam + 2.0 * mu) * x1[2] * y1[0] + mu * x1[0] * y1[2])
                + a2 * (lam + mu) * x2[1] * y2[1],
            a2 * (mu * x2[2] * y2[0] + (lam + 2.0 * mu) * x2[0] * y2[2])
                + a1 * (lam + mu) * x1[1] * y1[1],
        ]
    }

    /// `l = ρ g'' Φ − (g + α g') LΦ`.
    pub fn load(&self, x: f64, y: f64, t: f64) -> [f64; 2] {
        let [g, gp, gpp] = self.g(t);
        let (phi, lphi) = (self.phi(x, y), self.l_phi(x, y));
        [0, 1].map(|c| self.density * gpp * phi[c] - (g + self.viscosity * gp) * lphi[c])
    }

    /// The load as scene expressions in `x`, `y`, `t` (the formula of [`Manufactured::load`]
    /// written out; numbers as `{:?}`, which read back to the same doubles).
    pub fn load_text(&self) -> [String; 2] {
        let [k1x, k1y, k2x, k2y] = self.k();
        let [a1, a2] = self.amplitude;
        let (lam, mu, w, b) = (self.lambda, self.mu, self.omega, self.beta);
        let g = format!("(cos({w:?}*t) + {b:?}*sin({w:?}*t))");
        let gp = format!("({w:?}*({b:?}*cos({w:?}*t) - sin({w:?}*t)))");
        let s = |k: f64, v: &str| format!("sin({k:?}*{v})");
        let c = |k: f64, v: &str| format!("cos({k:?}*{v})");
        let phi = [
            format!("{a1:?}*{}*{}", s(k1x, "x"), s(k1y, "y")),
            format!("{a2:?}*{}*{}", s(k2x, "x"), s(k2y, "y")),
        ];
        let l2m = lam + 2.0 * mu;
        let lphi = [
            format!(
                "({:?}*{}*{} + {:?}*{}*{} + {:?}*{}*{})",
                -a1 * l2m * k1x * k1x,
                s(k1x, "x"),
                s(k1y, "y"),
                -a1 * mu * k1y * k1y,
                s(k1x, "x"),
                s(k1y, "y"),
                a2 * (lam + mu) * k2x * k2y,
                c(k2x, "x"),
                c(k2y, "y"),
            ),
            format!(
                "({:?}*{}*{} + {:?}*{}*{} + {:?}*{}*{})",
                -a2 * mu * k2x * k2x,
                s(k2x, "x"),
                s(k2y, "y"),
                -a2 * l2m * k2y * k2y,
                s(k2x, "x"),
                s(k2y, "y"),
                a1 * (lam + mu) * k1x * k1y,
                c(k1x, "x"),
                c(k1y, "y"),
            ),
        ];
        let rho_w2 = -self.density * w * w;
        [0, 1].map(|i| {
            format!(
                "{rho_w2:?}*{g}*{} - ({g} + {:?}*{gp})*{}",
                phi[i], self.viscosity, lphi[i]
            )
        })
    }

    /// The scene: all edges clamped, `nx × ny` cells graded by `y_grading`, `Δt`, end `T`.
    pub fn scene(&self, nx: u64, ny: u64, y_grading: f64, dt: f64, end: f64) -> PlaneScene {
        let [k1x, k1y, k2x, k2y] = self.k();
        let [a1, a2] = self.amplitude;
        let clamped = EdgeSpec::plain(EdgeCondition::Clamped);
        let field = |a: f64| {
            [
                format!("{a:?}*{a1:?}*sin({k1x:?}*x)*sin({k1y:?}*y)"),
                format!("{a:?}*{a2:?}*sin({k2x:?}*x)*sin({k2y:?}*y)"),
            ]
        };
        PlaneScene {
            description: Some("Manufactured solution (plane::closed_form).".into()),
            plane: Body {
                width: self.width,
                height: self.height,
                lambda: self.lambda,
                mu: self.mu,
                density: self.density,
                viscosity: self.viscosity,
                integration: Default::default(),
            },
            edges: Edges {
                left: clamped.clone(),
                right: clamped.clone(),
                bottom: clamped.clone(),
                top: clamped,
            },
            initial: PlaneInitial {
                displacement: Vector(field(self.g(0.0)[0])),
                velocity: Vector(field(self.g(0.0)[1])),
            },
            load: PlaneLoad {
                density: Some(Vector(self.load_text())),
            },
            mesh: PlaneMesh { nx, ny, y_grading },
            time: Time { step: dt, end },
            solver: Default::default(),
            output: Default::default(),
            heat: None,
        }
    }
}

/// The manufactured solution with a coupled temperature: [`Manufactured`]'s `u` and
/// `θ = b (1 + t) sin(k₁ₓx) sin(k₁ᵧy)`, `γ`, `κ`.
#[derive(Clone, Copy, Debug)]
pub struct Coupled {
    pub mechanics: Manufactured,
    /// `γ`, `κ`, `b`.
    pub coupling: f64,
    pub diffusivity: f64,
    pub amplitude: f64,
}

impl Default for Coupled {
    /// `γ = 0.8`, `κ = 0.3`, `b = 0.5` on [`Manufactured::default`].
    fn default() -> Self {
        Self {
            mechanics: Manufactured::default(),
            coupling: 0.8,
            diffusivity: 0.3,
            amplitude: 0.5,
        }
    }
}

impl Coupled {
    /// `θ(x, y, t)`.
    pub fn temperature(&self, x: f64, y: f64, t: f64) -> f64 {
        let [k1x, k1y, _, _] = self.mechanics.k();
        self.amplitude * (1.0 + t) * (k1x * x).sin() * (k1y * y).sin()
    }

    /// `l + γ ∇θ` and `q = θ_t − κ Δθ + γ div u_t` as scene expressions.
    pub fn texts(&self) -> ([String; 2], String) {
        let m = &self.mechanics;
        let [k1x, k1y, k2x, k2y] = m.k();
        let [a1, a2] = m.amplitude;
        let (g, b, kappa) = (self.coupling, self.amplitude, self.diffusivity);
        let (w, beta) = (m.omega, m.beta);
        let [lx, ly] = m.load_text();
        let load = [
            format!(
                "{lx} + {:?}*(1 + t)*cos({k1x:?}*x)*sin({k1y:?}*y)",
                g * b * k1x
            ),
            format!(
                "{ly} + {:?}*(1 + t)*sin({k1x:?}*x)*cos({k1y:?}*y)",
                g * b * k1y
            ),
        ];
        let gp = format!("({w:?}*({beta:?}*cos({w:?}*t) - sin({w:?}*t)))");
        let laplacian = kappa * (k1x * k1x + k1y * k1y);
        let source = format!(
            "{b:?}*sin({k1x:?}*x)*sin({k1y:?}*y)*(1 + {laplacian:?}*(1 + t)) + {g:?}*{gp}*\
             ({:?}*cos({k1x:?}*x)*sin({k1y:?}*y) + {:?}*sin({k2x:?}*x)*cos({k2y:?}*y))",
            a1 * k1x,
            a2 * k2y
        );
        (load, source)
    }

    /// [`Manufactured::scene`] with the coupled load and `[heat]`: `θ^0`, the source, every
    /// edge held at 0.
    pub fn scene(&self, nx: u64, ny: u64, y_grading: f64, dt: f64, end: f64) -> PlaneScene {
        let mut scene = self.mechanics.scene(nx, ny, y_grading, dt, end);
        let [k1x, k1y, _, _] = self.mechanics.k();
        let (load, source) = self.texts();
        scene.description = Some("Coupled manufactured solution (plane::closed_form).".into());
        scene.load.density = Some(Vector(load));
        let held = ThermalEdge {
            condition: ThermalCondition::Temperature,
            value: Some("0".into()),
            ..Default::default()
        };
        scene.heat = Some(PlaneHeat {
            coupling: self.coupling,
            diffusivity: self.diffusivity,
            temperature: format!("{:?}*sin({k1x:?}*x)*sin({k1y:?}*y)", self.amplitude),
            source: Some(source),
            left: held.clone(),
            right: held.clone(),
            bottom: held.clone(),
            top: held,
        });
        scene
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::scene::expr::Expression;

    /// Finite-difference step: nested central differences (stress, then its divergence) have
    /// truncation `O(h²)` ≈ 1e-8 of the fourth derivatives and round-off ≈ ε|u|/h² ≈ 1e-9.
    const FD_STEP: f64 = 1e-4;
    /// Relative agreement of the derived load with the finite differences (both errors above,
    /// times the wave numbers' powers up to (2π)⁴ ≈ 1.6e3).
    const FD_TOL: f64 = 1e-5;
    /// The load text evaluates the same formula in a different order: a few ulps.
    const TEXT_TOL: f64 = 1e-13;
    /// `sin(π)`, `sin(2π)` round to about 1e-16, times amplitudes of 0.1 and less.
    const BOUNDARY_TOL: f64 = 1e-16;

    /// `ρ u_tt − div σ(u + α u_t)` by finite differences of [`Manufactured::displacement`].
    fn residual_load(m: &Manufactured, x: f64, y: f64, t: f64) -> [f64; 2] {
        let h = FD_STEP;
        // Kelvin–Voigt: σ(u) + α σ(u_t) = σ(v), v = u + α u_t (u_t by differences too).
        let v = |x: f64, y: f64| {
            let (p, q) = (m.displacement(x, y, t + h), m.displacement(x, y, t - h));
            let u = m.displacement(x, y, t);
            [0, 1].map(|c| u[c] + m.viscosity * (p[c] - q[c]) / (2.0 * h))
        };
        let stress = |x: f64, y: f64| {
            let dx = [0, 1].map(|c| (v(x + h, y)[c] - v(x - h, y)[c]) / (2.0 * h));
            let dy = [0, 1].map(|c| (v(x, y + h)[c] - v(x, y - h)[c]) / (2.0 * h));
            let div = dx[0] + dy[1];
            let shear = m.mu * (dy[0] + dx[1]);
            // (σ_xx, σ_yy, σ_xy)
            [
                m.lambda * div + 2.0 * m.mu * dx[0],
                m.lambda * div + 2.0 * m.mu * dy[1],
                shear,
            ]
        };
        let (sxp, sxm) = (stress(x + h, y), stress(x - h, y));
        let (syp, sym) = (stress(x, y + h), stress(x, y - h));
        let div = [
            (sxp[0] - sxm[0]) / (2.0 * h) + (syp[2] - sym[2]) / (2.0 * h),
            (sxp[2] - sxm[2]) / (2.0 * h) + (syp[1] - sym[1]) / (2.0 * h),
        ];
        let (p, q, u) = (
            m.displacement(x, y, t + h),
            m.displacement(x, y, t - h),
            m.displacement(x, y, t),
        );
        [0, 1].map(|c| m.density * (p[c] - 2.0 * u[c] + q[c]) / (h * h) - div[c])
    }

    #[test]
    fn derived_load_matches_finite_differences_and_the_load_text() {
        let m = Manufactured::default();
        let text = m.load_text();
        let exprs = text
            .clone()
            .map(|t| Expression::parse_plane("load.density", &t, true).unwrap());
        let mut scale = 0.0f64;
        let mut worst_fd = 0.0f64;
        let mut worst_text = 0.0f64;
        for (x, y, t) in [
            (0.3, 0.2, 0.1),
            (1.1, 0.7, 0.45),
            (1.7, 0.55, 1.3),
            (0.9, 0.35, 0.0),
        ] {
            let exact = m.load(x, y, t);
            let fd = residual_load(&m, x, y, t);
            for c in 0..2 {
                scale = scale.max(exact[c].abs());
                worst_fd = worst_fd.max((exact[c] - fd[c]).abs());
                worst_text = worst_text.max((exact[c] - exprs[c].eval_xy(x, y, t).unwrap()).abs());
            }
        }
        assert!(worst_fd <= FD_TOL * scale, "{worst_fd:e} vs {scale:e}");
        assert!(
            worst_text <= TEXT_TOL * scale,
            "{worst_text:e} vs {scale:e}"
        );
        // The boundary: Φ vanishes on every edge (clamped data are exact).
        for s in [0.0, 0.37, 1.0] {
            for [x, y] in [
                [0.0, s],
                [m.width, s],
                [s * m.width, 0.0],
                [s * m.width, m.height],
            ] {
                let u = m.displacement(x, y, 0.3);
                assert!(
                    u[0].abs() <= BOUNDARY_TOL && u[1].abs() <= BOUNDARY_TOL,
                    "{x} {y} {u:?}"
                );
            }
        }
    }

    /// `θ_t − κΔθ + γ div u_t` and `γ ∇θ` by central differences of [`Coupled`]'s fields
    /// against its texts (less the mechanical load, checked above): truncation `O(h²)` of
    /// third and fourth derivatives of size up to (2π)⁴ ≈ 1.6e3 and round-off ε/h², as above.
    #[test]
    fn coupled_source_and_load_match_finite_differences() {
        let c = Coupled::default();
        let (load, source) = c.texts();
        let parse = |t: &str| Expression::parse_plane("heat.source", t, true).unwrap();
        let (q, l) = (parse(&source), load.map(|t| parse(&t)));
        let mechanical = c.mechanics.load_text().map(|t| parse(&t));
        let h = FD_STEP;
        let (mut worst, mut scale) = (0.0f64, 0.0f64);
        for (x, y, t) in [(0.3, 0.2, 0.1), (1.1, 0.7, 0.45), (1.7, 0.55, 1.3)] {
            let th = |x: f64, y: f64, t: f64| c.temperature(x, y, t);
            let u = |x: f64, y: f64, t: f64| c.mechanics.displacement(x, y, t);
            let theta_t = (th(x, y, t + h) - th(x, y, t - h)) / (2.0 * h);
            let lap = (th(x + h, y, t) + th(x - h, y, t) + th(x, y + h, t) + th(x, y - h, t)
                - 4.0 * th(x, y, t))
                / (h * h);
            let div = |t: f64| {
                (u(x + h, y, t)[0] - u(x - h, y, t)[0] + u(x, y + h, t)[1] - u(x, y - h, t)[1])
                    / (2.0 * h)
            };
            let div_t = (div(t + h) - div(t - h)) / (2.0 * h);
            let expected = theta_t - c.diffusivity * lap + c.coupling * div_t;
            let grad = [
                (th(x + h, y, t) - th(x - h, y, t)) / (2.0 * h),
                (th(x, y + h, t) - th(x, y - h, t)) / (2.0 * h),
            ];
            worst = worst.max((q.eval_xy(x, y, t).unwrap() - expected).abs());
            scale = scale.max(expected.abs());
            for k in 0..2 {
                let thermal =
                    l[k].eval_xy(x, y, t).unwrap() - mechanical[k].eval_xy(x, y, t).unwrap();
                worst = worst.max((thermal - c.coupling * grad[k]).abs());
            }
        }
        assert!(worst <= FD_TOL * scale, "{worst:e} vs {scale:e}");
    }
}
