//! Volumetric locking (VERIFICATION.md, "No locking"): `[plane] integration = "selective"`
//! against `"full"`. The patch test of both rules (a linear field prescribed on the boundary of
//! a graded patch is reproduced inside), and the static tip deflection of `plane-cantilever`
//! (clamped at `x = 0`, its own weight) against Timoshenko beam theory in plane strain for `ν`
//! from 0.3 to 0.4999 at the scene's `μ`: full integration locks, selective does not.

use std::fmt::Write;
use viscobar::internals::linalg::cholesky::SparseCholesky;
use viscobar::internals::linalg::sparse::Pattern;
use viscobar::internals::plane::matrices::{Integration, Material, assemble, assemble_with};
use viscobar::internals::plane::mesh::Grid;
use viscobar::plane::PlaneDiscretisation;
use viscobar::scene::plane::{PlaneScene, plane_builtin_text};
use viscobar::scheme::RunError;

/// Poisson's ratios of the cantilever table (plane strain; `λ = 2μν/(1 − 2ν)`).
pub const POISSON_RATIOS: [f64; 6] = [0.3, 0.4, 0.45, 0.49, 0.499, 0.4999];
/// Timoshenko's shear coefficient of a rectangular section.
pub const SHEAR_COEFFICIENT: f64 = 5.0 / 6.0;
/// The band selective integration's tip deflection keeps over Timoshenko's at every `ν` of the
/// table (measured 0.973–0.993 on the scene's 64 × 8 mesh, falling slowly with `ν`: Q1's
/// bending error on 8 graded rows, and the clamped edge, which holds the section's Poisson
/// contraction; the band is 1 % wider on either side).
pub const SELECTIVE_BAND: (f64, f64) = (0.963, 1.003);
/// Full integration at `ν = 0.4999` locks: its deflection is below this share of Timoshenko's
/// (measured VERIFICATION.md's last row).
pub const LOCKED_BELOW: f64 = 0.1;
/// The energy identity's growth with `λ/μ`: the run's own bound
/// (`viscobar::scheme::certify`), measured here.
pub use viscobar::scheme::certify::LAMBDA_IDENTITY_ULPS;
/// Steps of the identity runs of the cantilever (`time.end = 4`, 80 steps).
pub const IDENTITY_RUN_END: f64 = 4.0;
/// The patch test: interior nodes reproduce a linear field to round-off, relative to its
/// largest value; the solve's error is `κ(K_II) ε`, `κ` up to about 1e5 at `λ/μ = 1e4` on the
/// graded patch, and is measured below 1e-12.
pub const PATCH_TOL: f64 = 1e-10;

/// `λ` of plane strain with Poisson's ratio `ν` and shear modulus `μ`.
pub fn lambda_of(nu: f64, mu: f64) -> f64 {
    2.0 * mu * nu / (1.0 - 2.0 * nu)
}

/// The cantilever scene (`plane-cantilever`) with `λ` for `ν` and `rule`.
pub fn cantilever_scene(nu: f64, rule: Integration) -> Result<PlaneScene, RunError> {
    let text = plane_builtin_text("plane-cantilever").expect("a built-in scene");
    let base = PlaneScene::from_toml(text, &[])?;
    let lambda = lambda_of(nu, base.plane.mu);
    Ok(PlaneScene::from_toml(
        text,
        &[
            format!("plane.lambda={lambda:?}"),
            format!("plane.integration=\"{}\"", rule.name()),
        ],
    )?)
}

/// Timoshenko's tip deflection (downwards positive) of the scene's cantilever in plane strain:
/// `w L⁴/(8 E' I) + w L²/(2 κ μ A)`, `w = q H` the weight per length, `E' = 4μ(λ+μ)/(λ+2μ)`,
/// `I = H³/12`, `A = H`.
pub fn timoshenko(scene: &PlaneScene) -> f64 {
    let (l, h, lam, mu) = (
        scene.plane.width,
        scene.plane.height,
        scene.plane.lambda,
        scene.plane.mu,
    );
    let q = -scene.load.density.as_ref().map_or(0.0, |v| {
        v.0[1].parse::<f64>().expect("the scene's load is a number")
    });
    let w = q * h;
    let e_plane = 4.0 * mu * (lam + mu) / (lam + 2.0 * mu);
    let inertia = h.powi(3) / 12.0;
    w * l.powi(4) / (8.0 * e_plane * inertia) + w * l * l / (2.0 * SHEAR_COEFFICIENT * mu * h)
}

/// The static tip deflection (downwards positive) of `scene`: `K u = F` (its load, the
/// consistent load vector), the mean of `−u_y` over the right edge (trapezoidal rule in `y`).
pub fn static_tip_deflection(scene: &PlaneScene) -> Result<f64, RunError> {
    let disc = PlaneDiscretisation::new(scene);
    let grid = &disc.grid;
    let load = scene
        .expressions()?
        .load
        .expect("the cantilever has a load");
    let mut nodal = vec![0.0; grid.dofs()];
    for node in 0..grid.nodes() {
        let (x, y) = grid.point(node);
        for c in 0..2 {
            nodal[2 * node + c] = load[c].eval_xy(x, y, 0.0)?;
        }
    }
    let full = assemble(grid, disc.material);
    let mut f_full = vec![0.0; grid.dofs()];
    full.pattern.mul_into(&full.mass, &nodal, &mut f_full);
    let mut u: Vec<f64> = disc.free.iter().map(|&d| f_full[d]).collect();
    SparseCholesky::new(&disc.pattern, &disc.stiffness, "K")?.solve_in_place(&mut u);
    let (mut area, mut sum) = (0.0, 0.0);
    for j in 0..grid.ny {
        let uy = |jj: usize| {
            let dof = 2 * grid.node(grid.nx, jj) + 1;
            disc.index[dof].map_or(0.0, |i| u[i])
        };
        let h = grid.hy(j);
        sum += 0.5 * h * (uy(j) + uy(j + 1));
        area += h;
    }
    Ok(-sum / area)
}

/// One row of the cantilever table.
#[derive(Clone, Copy, Debug)]
pub struct CantileverRow {
    pub nu: f64,
    pub lambda: f64,
    pub timoshenko: f64,
    /// Tip deflection over Timoshenko's, full and selective integration.
    pub full: f64,
    pub selective: f64,
}

/// The cantilever table over [`POISSON_RATIOS`].
pub fn cantilever_table() -> Result<Vec<CantileverRow>, RunError> {
    POISSON_RATIOS
        .iter()
        .map(|&nu| {
            let full = cantilever_scene(nu, Integration::Full)?;
            let selective = cantilever_scene(nu, Integration::Selective)?;
            let t = timoshenko(&full);
            Ok(CantileverRow {
                nu,
                lambda: full.plane.lambda,
                timoshenko: t,
                full: static_tip_deflection(&full)? / t,
                selective: static_tip_deflection(&selective)? / t,
            })
        })
        .collect()
}

/// The patch of the patch test: 5 × 4 cells on `(0, 1.5) × (0, 1)`, graded 3 in `y`.
pub fn patch_grid() -> Grid {
    Grid::new(1.5, 1.0, 5, 4, 3.0)
}

/// The patch test of `rule` with Lamé `lambda` (μ = 0.6): the linear field
/// `u = (0.1 + 0.3x − 0.2y, −0.05 + 0.1x + 0.4y)` prescribed at the boundary nodes, `K_II u_I =
/// −K_IB u_B` solved for the interior; the largest interior error over the field's largest
/// value.
pub fn patch_test(rule: Integration, lambda: f64) -> Result<f64, RunError> {
    let grid = patch_grid();
    let material = Material {
        lambda,
        mu: 0.6,
        density: 1.0,
    };
    let m = assemble_with(&grid, material, rule);
    let field = |x: f64, y: f64| [0.1 + 0.3 * x - 0.2 * y, -0.05 + 0.1 * x + 0.4 * y];
    let mut exact = vec![0.0; grid.dofs()];
    let mut boundary = vec![0.0; grid.dofs()];
    let mut index = vec![None; grid.dofs()];
    let mut next = 0;
    for node in 0..grid.nodes() {
        let (i, j) = grid.position(node);
        let (x, y) = grid.point(node);
        let on_boundary = i == 0 || j == 0 || i == grid.nx || j == grid.ny;
        for c in 0..2 {
            exact[2 * node + c] = field(x, y)[c];
            if on_boundary {
                boundary[2 * node + c] = field(x, y)[c];
            } else {
                index[2 * node + c] = Some(next);
                next += 1;
            }
        }
    }
    let mut kb = vec![0.0; grid.dofs()];
    m.pattern.mul_into(&m.stiffness, &boundary, &mut kb);
    let (pattern, from): (Pattern, Vec<usize>) = m.pattern.restrict(&index);
    let k: Vec<f64> = from.iter().map(|&f| m.stiffness[f]).collect();
    let mut u = vec![0.0; next];
    for (d, i) in index.iter().enumerate() {
        if let Some(i) = i {
            u[*i] = -kb[d];
        }
    }
    SparseCholesky::new(&pattern, &k, "K_II")?.solve_in_place(&mut u);
    let scale = exact.iter().fold(0.0f64, |a, v| a.max(v.abs()));
    let mut worst = 0.0f64;
    for (d, i) in index.iter().enumerate() {
        if let Some(i) = i {
            worst = worst.max((u[*i] - exact[d]).abs() / scale);
        }
    }
    Ok(worst)
}

/// `λ` of the patch tests: moderate and nearly incompressible (`λ/μ ≈ 1.7e4`).
pub const PATCH_LAMBDAS: [f64; 2] = [1.7, 1e4];

/// The worst patch-test error of each rule over [`PATCH_LAMBDAS`]: `[full, selective]`.
pub fn patch_worst() -> Result<[f64; 2], RunError> {
    let mut w = [0.0f64; 2];
    for (k, rule) in [Integration::Full, Integration::Selective]
        .into_iter()
        .enumerate()
    {
        for lambda in PATCH_LAMBDAS {
            w[k] = w[k].max(patch_test(rule, lambda)?);
        }
    }
    Ok(w)
}

/// The generated block `locking`: the patch tests and the cantilever table.
pub fn markdown() -> Result<String, RunError> {
    let [pf, ps] = patch_worst()?;
    let mut md = format!(
        "Patch test (5 × 4 cells graded 3, λ = 1.7 and 1e4, μ = 0.6; max interior error / max \
         abs(u)): full {pf:.1e}, selective {ps:.1e}.\n\n"
    );
    md.push_str(
        "| ν | λ (μ = 0.5) | Timoshenko tip deflection | full / Timoshenko | selective / Timoshenko |\n|---|---|---|---|---|\n",
    );
    let table = cantilever_table()?;
    for r in &table {
        let _ = writeln!(
            md,
            "| {} | {:.6} | {:.5} | {:.4} | {:.4} |",
            r.nu, r.lambda, r.timoshenko, r.full, r.selective
        );
    }
    let (lo, hi) = table.iter().fold((f64::INFINITY, 0.0f64), |(lo, hi), r| {
        (lo.min(r.selective), hi.max(r.selective))
    });
    let _ = writeln!(
        md,
        "\nSelective integration over Timoshenko: {lo:.4} to {hi:.4} over the table (band \
         `SELECTIVE_BAND` = {:?}).",
        SELECTIVE_BAND
    );
    Ok(md)
}

/// The largest identity residual of the cantilever at `ν` with `rule` (to
/// [`IDENTITY_RUN_END`]), over its bound `PLANE_IDENTITY_TOL + LAMBDA_IDENTITY_ULPS ε λ/μ`.
pub fn identity_ratio(nu: f64, rule: Integration) -> Result<f64, RunError> {
    let mut scene = cantilever_scene(nu, rule)?;
    scene.time.end = IDENTITY_RUN_END;
    let (records, _, _) = viscobar::output::run_plane_in_memory("cantilever", &scene)?;
    let worst = (records.iter().skip(1))
        .map(|r| r.identity_residual)
        .fold(0.0, f64::max);
    let bound = crate::tolerances::PLANE_IDENTITY_TOL
        + LAMBDA_IDENTITY_ULPS * f64::EPSILON * scene.plane.lambda / scene.plane.mu;
    Ok(worst / bound)
}
