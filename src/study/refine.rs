//! A scene of either body as the refinement study and the comparison of solvers use it
//! ([`StudyScene`]): how it refines, runs, and measures an error given at every degree of
//! freedom of its mesh (the discrete L2 norm and H1 seminorm of the error's interpolant).

use crate::bar::Simulation;
use crate::bar::closed_form::{self, ClosedForm};
use crate::plane::PlaneSimulation;
use crate::plane::body::PlaneBody;
use crate::scene::plane::PlaneScene;
use crate::scene::{Scene, SolverSpec};
use crate::scheme::{Body, RunError, Scheme};

/// A scene the studies refine and run.
pub trait StudyScene: Clone + Send + Sync {
    type Body: Body;
    /// Sets the scene's run up and takes the start-up step.
    fn simulation(&self) -> Result<Scheme<Self::Body>, RunError>;
    fn steps(&self) -> usize;
    fn dt(&self) -> f64;
    /// The mesh spacing `h` that refinement halves (the bar's `Δx`, the plane's cell width).
    fn spacing(&self) -> f64;
    /// Elements (cells) of the mesh.
    fn elements(&self) -> usize;
    /// The scene `2^level` times finer in space, with `Δt = ratio · h`.
    fn refined(&self, level: u32, ratio: f64) -> Self;
    /// Its `[solver]` table.
    fn solver_mut(&mut self) -> &mut SolverSpec;
    /// The nodes along `x` and along `y` ([`Body::lattice`]).
    fn lattice(&self) -> [usize; 2];
    /// Degrees of freedom per node.
    fn components(&self) -> usize;
    /// The L2 norm and the H1 seminorm of the continuous piecewise-linear (bilinear)
    /// interpolant of `e`, given at every degree of freedom.
    fn norms(&self, e: &[f64]) -> (f64, f64);
    /// Why refining the scene does not give nested meshes (so that the nodes of a coarse
    /// level are nodes of every finer one), if it does not.
    fn not_nested(&self) -> Option<String> {
        None
    }
    /// The closed-form solution of the built-in scene `name`, when it has one.
    fn closed_form(&self, _name: &str) -> Option<Box<dyn ClosedForm>> {
        None
    }
}

/// Trapezoidal weights on a uniform mesh.
pub fn l2_norm(e: &[f64], dx: f64) -> f64 {
    let n = e.len();
    let mut s = 0.0;
    for (i, v) in e.iter().enumerate() {
        let w = if i == 0 || i + 1 == n { 0.5 } else { 1.0 };
        s += w * v * v;
    }
    (s * dx).sqrt()
}

/// `|e|_{H1}` of the P1 interpolant on a uniform mesh.
pub fn h1_seminorm(e: &[f64], dx: f64) -> f64 {
    (e.windows(2).map(|w| (w[1] - w[0]).powi(2)).sum::<f64>() / dx).sqrt()
}

impl StudyScene for Scene {
    type Body = crate::bar::BarBody;

    fn simulation(&self) -> Result<Simulation, RunError> {
        Simulation::new(self)
    }

    fn steps(&self) -> usize {
        Scene::steps(self)
    }

    fn dt(&self) -> f64 {
        self.time.step
    }

    fn spacing(&self) -> f64 {
        self.dx()
    }

    fn elements(&self) -> usize {
        self.mesh.elements as usize
    }

    fn refined(&self, level: u32, ratio: f64) -> Self {
        let mut s = Scene::refined(self, level);
        s.time.step = ratio * s.dx();
        s
    }

    fn solver_mut(&mut self) -> &mut SolverSpec {
        &mut self.solver
    }

    fn lattice(&self) -> [usize; 2] {
        [self.mesh.elements as usize + 1, 1]
    }

    fn components(&self) -> usize {
        1
    }

    fn norms(&self, e: &[f64]) -> (f64, f64) {
        (l2_norm(e, self.dx()), h1_seminorm(e, self.dx()))
    }

    fn closed_form(&self, name: &str) -> Option<Box<dyn ClosedForm>> {
        closed_form::for_scene(name, self)
    }
}

impl StudyScene for PlaneScene {
    type Body = PlaneBody;

    fn simulation(&self) -> Result<PlaneSimulation, RunError> {
        PlaneSimulation::new(self)
    }

    fn steps(&self) -> usize {
        PlaneScene::steps(self)
    }

    fn dt(&self) -> f64 {
        self.time.step
    }

    fn spacing(&self) -> f64 {
        self.plane.width / self.mesh.nx as f64
    }

    fn elements(&self) -> usize {
        (self.mesh.nx * self.mesh.ny) as usize
    }

    fn refined(&self, level: u32, ratio: f64) -> Self {
        let mut s = PlaneScene::refined(self, level);
        s.time.step = ratio * s.spacing();
        s
    }

    fn solver_mut(&mut self) -> &mut SolverSpec {
        &mut self.solver
    }

    fn lattice(&self) -> [usize; 2] {
        [self.mesh.nx as usize + 1, self.mesh.ny as usize + 1]
    }

    fn components(&self) -> usize {
        2
    }

    /// On the uniform grid (`y_grading = 1`): the trapezoidal rule over the nodes for the L2
    /// norm (exact for the bilinear interpolant's square up to the rule's own error, as the
    /// bar's), and the 2 × 2 Gauss rule per cell for `∫|∇e|²` (exact: the gradient of a
    /// bilinear function is linear in each variable).
    fn norms(&self, e: &[f64]) -> (f64, f64) {
        let [nx, ny] = [self.mesh.nx as usize, self.mesh.ny as usize];
        let (hx, hy) = (self.spacing(), self.plane.height / ny as f64);
        let node = |i: usize, j: usize| i + j * (nx + 1);
        let end = |i: usize, n: usize| if i == 0 || i == n { 0.5 } else { 1.0 };
        let mut l2 = 0.0;
        for j in 0..=ny {
            for i in 0..=nx {
                let k = node(i, j);
                l2 += end(i, nx) * end(j, ny) * (e[2 * k] * e[2 * k] + e[2 * k + 1] * e[2 * k + 1]);
            }
        }
        let d = 0.5 / 3f64.sqrt();
        let gauss = [0.5 - d, 0.5 + d];
        let mut h1 = 0.0;
        for j in 0..ny {
            for i in 0..nx {
                let corners = [
                    node(i, j),
                    node(i + 1, j),
                    node(i, j + 1),
                    node(i + 1, j + 1),
                ];
                for c in 0..2 {
                    let [a, b, p, q] = corners.map(|k| e[2 * k + c]);
                    for &xi in &gauss {
                        for &eta in &gauss {
                            // e = a(1−ξ)(1−η) + b ξ(1−η) + p(1−ξ)η + q ξη.
                            let ex = ((b - a) * (1.0 - eta) + (q - p) * eta) / hx;
                            let ey = ((p - a) * (1.0 - xi) + (q - b) * xi) / hy;
                            h1 += 0.25 * (ex * ex + ey * ey);
                        }
                    }
                }
            }
        }
        ((l2 * hx * hy).sqrt(), (h1 * hx * hy).sqrt())
    }

    fn not_nested(&self) -> Option<String> {
        (self.mesh.y_grading != 1.0).then(|| {
            format!(
                "mesh.y_grading = {}: refined graded meshes are not nested (a coarse node is \
                 not a node of the finer meshes); refine a scene with y_grading = 1",
                self.mesh.y_grading
            )
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The plane's norms of a field constant along `y` are the bar's norms of its profile times
    /// `sqrt(H)` (the bilinear interpolant is then the P1 one in `x`), and the H1 seminorm of a
    /// linear field is exact.
    #[test]
    fn plane_norms_reduce_to_the_bar_norms_and_are_exact_on_linear_fields() {
        let (_, any) = crate::scene::load_any("plane-strip", &["mesh.y_grading=1".into()]).unwrap();
        let crate::scene::AnyScene::Plane(scene) = any else {
            unreachable!()
        };
        let [nx, ny] = scene.lattice();
        let dx = scene.spacing();
        let profile: Vec<f64> = (0..nx).map(|i| (0.7 * i as f64).sin()).collect();
        let mut e = vec![0.0; 2 * nx * ny];
        for j in 0..ny {
            for i in 0..nx {
                e[2 * (i + j * nx)] = profile[i];
            }
        }
        let (l2, h1) = scene.norms(&e);
        let root_h = scene.plane.height.sqrt();
        let close = |a: f64, b: f64| (a - b).abs() <= 1e-12 * b.abs();
        assert!(close(l2, l2_norm(&profile, dx) * root_h), "{l2}");
        assert!(close(h1, h1_seminorm(&profile, dx) * root_h), "{h1}");
        // e_y = 2x + 3y: |∇e_y|² = 13 over the area W H.
        let mut e = vec![0.0; 2 * nx * ny];
        for j in 0..ny {
            for i in 0..nx {
                let (x, y) = (
                    i as f64 * dx,
                    j as f64 * scene.plane.height / (ny - 1) as f64,
                );
                e[2 * (i + j * nx) + 1] = 2.0 * x + 3.0 * y;
            }
        }
        let area = scene.plane.width * scene.plane.height;
        assert!(close(scene.norms(&e).1, (13.0 * area).sqrt()));
    }
}
