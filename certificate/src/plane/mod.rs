//! The plane body's certificate (VERIFICATION.md, "Plane body"): the matrices' properties, the
//! energy identity on every built-in plane scene and the manufactured one, the bar as an exact
//! special case, and the observed order of the manufactured solution. The tests
//! (`tests/plane.rs`, `src/plane/*`) assert on the same computations.
//!
//! The plane's other certificates, each a section of VERIFICATION.md: [`contact`] ("Plane
//! contact"), [`symmetry`] (mirrored and turned scenes), [`locking`] ("No locking") and
//! [`moving`] ("Moving obstacles", on both bodies). Its friction is [`crate::friction`].

pub mod contact;
pub mod locking;
pub mod moving;
pub mod symmetry;

use std::fmt::Write;
use viscobar::bar::Simulation;
use viscobar::internals::linalg::cholesky::SparseCholesky;
use viscobar::internals::plane::matrices::{Material, assemble};
use viscobar::internals::plane::mesh::Grid;
use viscobar::internals::scene::schema::number_text;
use viscobar::output::run_plane_in_memory;
use viscobar::plane::PlaneSimulation;
use viscobar::plane::closed_form::Manufactured;
use viscobar::scene::plane::{
    Body, EdgeCondition, EdgeSpec, Edges, PLANE_BUILTIN, PlaneInitial, PlaneLoad, PlaneMesh,
    PlaneScene, Vector, plane_builtin_text,
};
use viscobar::scene::{Condition, Scene};
use viscobar::scheme::RunError;
use viscobar::study::converge::ConvergeError;

/// The grids of the matrix table: `(nx, ny, y_grading)`.
pub const MATRIX_GRIDS: [(usize, usize, f64); 3] = [(4, 2, 1.0), (16, 8, 3.0), (64, 16, 0.2)];
/// The material of the matrix table (λ ≠ 0, ρ ≠ 1, so nothing cancels by accident).
pub const MATRIX_MATERIAL: Material = Material {
    lambda: 1.7,
    mu: 0.6,
    density: 2.5,
};
/// Width and height of the matrix table's body.
pub const MATRIX_BODY: (f64, f64) = (2.0, 0.5);

/// The properties of `M` and `K` on one grid.
#[derive(Clone, Copy, Debug)]
pub struct MatrixCheck {
    pub nx: usize,
    pub ny: usize,
    pub y_grading: f64,
    pub dofs: usize,
    /// Both bitwise symmetric.
    pub symmetric: bool,
    /// `1ᵀ M_c 1 / (ρWH)` for `c = x, y`.
    pub mass_ratio: [f64; 2],
    /// A sparse Cholesky of `M` succeeded.
    pub mass_positive_definite: bool,
    /// `‖K r‖∞ / (‖K‖∞ ‖r‖∞)` for the translations in x, y and the rotation `(−y, x)`.
    pub kernel: [f64; 3],
}

/// [`MatrixCheck`] of the grid `nx × ny` graded by `y_grading`.
pub fn matrix_check(nx: usize, ny: usize, y_grading: f64) -> MatrixCheck {
    let (w, h) = MATRIX_BODY;
    let grid = Grid::new(w, h, nx, ny, y_grading);
    let m = assemble(&grid, MATRIX_MATERIAL);
    let p = &m.pattern;
    let mut symmetric = true;
    for r in 0..p.n {
        for k in p.row_ptr[r]..p.row_ptr[r + 1] {
            let c = p.cols[k];
            let kt =
                p.row_ptr[c] + p.cols[p.row_ptr[c]..p.row_ptr[c + 1]].partition_point(|&x| x < r);
            symmetric &= m.mass[k].to_bits() == m.mass[kt].to_bits()
                && m.stiffness[k].to_bits() == m.stiffness[kt].to_bits();
        }
    }
    let total = MATRIX_MATERIAL.density * w * h;
    let mass_ratio = [0, 1].map(|c| {
        let e: Vec<f64> = (0..grid.dofs()).map(|d| f64::from(d % 2 == c)).collect();
        p.quad(&m.mass, &e) / total
    });
    let mass_positive_definite = SparseCholesky::new(p, &m.mass, "M").is_ok();
    let norm = (0..p.n)
        .map(|r| {
            (p.row_ptr[r]..p.row_ptr[r + 1])
                .map(|k| m.stiffness[k].abs())
                .sum::<f64>()
        })
        .fold(0.0, f64::max);
    type Motion = fn(f64, f64) -> (f64, f64);
    let motions: [Motion; 3] = [|_, _| (1.0, 0.0), |_, _| (0.0, 1.0), |x, y| (-y, x)];
    let kernel = motions.map(|f| {
        let mut r = vec![0.0; grid.dofs()];
        for node in 0..grid.nodes() {
            let (x, y) = grid.point(node);
            (r[2 * node], r[2 * node + 1]) = f(x, y);
        }
        let mut kr = vec![0.0; grid.dofs()];
        p.mul_into(&m.stiffness, &r, &mut kr);
        let inf = |v: &[f64]| v.iter().fold(0.0f64, |a, x| a.max(x.abs()));
        inf(&kr) / (norm * inf(&r))
    });
    MatrixCheck {
        nx,
        ny,
        y_grading,
        dofs: grid.dofs(),
        symmetric,
        mass_ratio,
        mass_positive_definite,
        kernel,
    }
}

/// The manufactured scene of the identity table (forced, viscous, λ ≠ 0, clamped, graded).
pub fn manufactured_identity_scene() -> PlaneScene {
    Manufactured::default().scene(16, 8, 3.0, 0.0625, 1.0)
}

/// The scenes of the identity table: the built-in plane scenes and the manufactured one.
pub fn identity_scenes() -> Vec<(String, PlaneScene)> {
    let mut scenes: Vec<(String, PlaneScene)> = PLANE_BUILTIN
        .iter()
        .map(|(n, _)| {
            let text = plane_builtin_text(n).expect("listed");
            let scene = PlaneScene::from_toml(text, &[]).expect("built-in plane scenes are valid");
            (n.to_string(), scene)
        })
        .collect();
    scenes.push(("manufactured".into(), manufactured_identity_scene()));
    scenes
}

/// The plane scene of a bar scene: `λ = 0`, `μ = ½`, `ρ = 1`, data `(f, 0)`, the bar's end
/// conditions on the left and right edges (free or clamped), free top and bottom, `ny` rows
/// graded by `y_grading`; a Signorini left end `u(0) >= −a` becomes the left edge's
/// `−ux <= a` (outward normal `−x`: the same bound). `None` for a bar whose right end is
/// Signorini (the bar's lower bound there is not an edge obstacle of the plane) or with an
/// obstacle under every node.
pub fn plane_of_bar(bar: &Scene, height: f64, ny: u64, y_grading: f64) -> Option<PlaneScene> {
    let edge = |c: Condition, gap: Option<f64>, left: bool| match c {
        Condition::Free => Some(EdgeSpec::default()),
        Condition::Clamped => Some(EdgeSpec::plain(EdgeCondition::Clamped)),
        Condition::Signorini if left => Some(EdgeSpec::signorini(&number_text(gap?))),
        Condition::Signorini => None,
    };
    if bar.obstacle.is_some() {
        return None;
    }
    let pair = |s: &str| Vector([s.to_string(), "0".into()]);
    Some(PlaneScene {
        description: None,
        plane: Body {
            width: bar.bar.length,
            height,
            lambda: 0.0,
            mu: 0.5,
            density: 1.0,
            viscosity: bar.bar.viscosity,
            integration: Default::default(),
        },
        edges: Edges {
            left: edge(bar.left.condition, bar.left.constant_gap(), true)?,
            right: edge(bar.right.condition, bar.right.constant_gap(), false)?,
            bottom: EdgeSpec::default(),
            top: EdgeSpec::default(),
        },
        initial: PlaneInitial {
            displacement: pair(&bar.initial.displacement),
            velocity: pair(&bar.initial.velocity),
        },
        load: PlaneLoad {
            density: bar.load.density.as_deref().map(pair),
        },
        mesh: PlaneMesh {
            nx: bar.mesh.elements,
            ny,
            y_grading,
        },
        time: bar.time.clone(),
        solver: Default::default(),
        output: Default::default(),
        heat: None,
    })
}

/// A clamped–free bar, viscous, under a load varying in x and t: the second bar of the
/// special-case check (the first is the built-in `modal`, free–free).
pub const CLAMPED_BAR: &str = r#"
[bar]
length = 1.5
viscosity = 0.02
[left]
condition = "clamped"
[right]
condition = "free"
[initial]
displacement = "0.1*sin(pi*x/3)"
velocity = "0.05*x"
[load]
density = "sin(3*t)*(1 + x)"
[mesh]
elements = 48
[time]
step = 0.02
end = 3.0
"#;

/// Height, rows and grading of the plane body that stands for a bar.
pub const BAR_CASE_BODY: (f64, u64, f64) = (0.3, 3, 4.0);

/// The bar special case: over every step, `max |ux(x_i, y_j) − u_i|`, `max |uy|` and the bar's
/// `max |u|`; with a Signorini left end, `max_k |r_k − ω_k r_bar|` over the left edge's nodes
/// (`ω_k` the node's trapezoid share of the edge) and the bar's `max r`.
#[derive(Clone, Copy, Debug)]
pub struct BarCase {
    pub steps: usize,
    pub max_ux_deviation: f64,
    pub max_uy: f64,
    pub max_u: f64,
    pub max_reaction_deviation: f64,
    pub max_reaction: f64,
    /// Steps with the bar in contact (`r > 0`).
    pub contact_steps: usize,
}

/// Runs `bar` and its plane counterpart ([`plane_of_bar`], [`BAR_CASE_BODY`]) step by step.
pub fn bar_case(bar: &Scene) -> Result<BarCase, ConvergeError> {
    let (height, ny, grading) = BAR_CASE_BODY;
    let plane = plane_of_bar(bar, height, ny, grading)
        .ok_or_else(|| ConvergeError::BadInput("the bar has contact".into()))?;
    let mut b = Simulation::new(bar)?;
    let mut p = PlaneSimulation::new(&plane).map_err(plane_error)?;
    let grid = p.discretisation().grid.clone();
    let mut out = BarCase {
        steps: bar.steps(),
        max_ux_deviation: 0.0,
        max_uy: 0.0,
        max_u: 0.0,
        max_reaction_deviation: 0.0,
        max_reaction: 0.0,
        contact_steps: 0,
    };
    let compare = |b: &Simulation, p: &PlaneSimulation, out: &mut BarCase| {
        if !p.contact().is_empty() {
            let rb = b.reactions()[0];
            out.max_reaction = out.max_reaction.max(rb);
            out.contact_steps += usize::from(rb > 0.0);
            for (nk, r) in p.body().normals().iter().zip(p.reactions()) {
                let d = (r - nk.weight * rb).abs();
                out.max_reaction_deviation = out.max_reaction_deviation.max(d);
            }
        }
        let (ub, up) = (b.displacement_dofs(), p.displacement_dofs());
        assert_eq!(ub.len(), grid.nx + 1, "one plane column per bar node");
        for node in 0..grid.nodes() {
            let i = grid.position(node).0;
            out.max_ux_deviation = out.max_ux_deviation.max((up[2 * node] - ub[i]).abs());
            out.max_uy = out.max_uy.max(up[2 * node + 1].abs());
        }
        out.max_u = ub.iter().fold(out.max_u, |a, v| a.max(v.abs()));
    };
    compare(&b, &p, &mut out);
    for _ in 1..bar.steps() {
        b.step()?;
        p.step().map_err(plane_error)?;
        compare(&b, &p, &mut out);
    }
    Ok(out)
}

/// The two bars of the special case: `modal` and [`CLAMPED_BAR`].
pub fn bar_case_scenes() -> Vec<(&'static str, Scene)> {
    let (_, modal) = viscobar::scene::load("modal", &[]).expect("built-in");
    let clamped = Scene::from_toml(CLAMPED_BAR, &[]).expect("valid");
    vec![("modal", modal), ("clamped", clamped)]
}

/// A viscous bar pushed by a load onto an obstacle at its left end, free at its right: the
/// contact bar of the special case beside the built-in `impact` (elastic, no load). It
/// arrives with speed 0.5 at the obstacle 0.05 away, is held there by the load and leaves
/// when the load turns.
pub const CONTACT_BAR: &str = r#"
[bar]
length = 1.0
viscosity = 0.05
[left]
condition = "signorini"
gap = 0.05
[right]
condition = "free"
[initial]
displacement = "0"
velocity = "-0.5"
[load]
density = "-0.6*cos(1.5*t)*(1 - x/2)"
[mesh]
elements = 50
[time]
step = 0.01
end = 4.0
"#;

/// The bars with contact of the special case: `impact` and [`CONTACT_BAR`].
pub fn bar_contact_case_scenes() -> Vec<(&'static str, Scene)> {
    let (_, impact) = viscobar::scene::load("impact", &[]).expect("built-in");
    let loaded = Scene::from_toml(CONTACT_BAR, &[]).expect("valid");
    vec![("impact", impact), ("loaded-contact", loaded)]
}

/// Cells along x of the manufactured levels (`nx × nx/2` cells, `Δt = h/2`).
pub const MANUFACTURED_LEVELS: [u64; 4] = [16, 32, 64, 128];
/// Grading of the manufactured meshes (a fixed ratio: a smooth mapping as h → 0).
pub const MANUFACTURED_GRADING: f64 = 1.5;
/// End time of the manufactured runs.
pub const MANUFACTURED_END: f64 = 0.5;

/// One level of the manufactured study.
#[derive(Clone, Copy, Debug)]
pub struct Level {
    pub nx: u64,
    pub h: f64,
    pub unknowns: usize,
    pub steps: usize,
    /// `‖u_h(T) − I_h u(T)‖_{L2} = sqrt(eᵀ M e)`.
    pub l2_error: f64,
}

/// The manufactured solution on `nx × nx/2` cells, `Δt = h/2`, to [`MANUFACTURED_END`].
pub fn manufactured_level(nx: u64) -> Result<Level, ConvergeError> {
    let m = Manufactured::default();
    let h = m.width / nx as f64;
    let scene = m.scene(nx, nx / 2, MANUFACTURED_GRADING, h / 2.0, MANUFACTURED_END);
    let mut sim = PlaneSimulation::new(&scene).map_err(plane_error)?;
    for _ in 1..scene.steps() {
        sim.step().map_err(plane_error)?;
    }
    let d = sim.discretisation();
    let t = sim.time();
    let e: Vec<f64> = d
        .free
        .iter()
        .zip(sim.displacement())
        .map(|(&dof, u)| {
            let (x, y) = d.grid.point(dof / 2);
            u - m.displacement(x, y, t)[dof % 2]
        })
        .collect();
    Ok(Level {
        nx,
        h,
        unknowns: d.unknowns(),
        steps: scene.steps(),
        l2_error: d.pattern.quad(&d.mass, &e).sqrt(),
    })
}

/// Least-squares slope of `ln error` against `ln h`.
pub fn observed_order(levels: &[Level]) -> f64 {
    let pts: Vec<(f64, f64)> = levels.iter().map(|l| (l.h.ln(), l.l2_error.ln())).collect();
    let n = pts.len() as f64;
    let mx = pts.iter().map(|p| p.0).sum::<f64>() / n;
    let my = pts.iter().map(|p| p.1).sum::<f64>() / n;
    pts.iter().map(|p| (p.0 - mx) * (p.1 - my)).sum::<f64>()
        / pts.iter().map(|p| (p.0 - mx).powi(2)).sum::<f64>()
}

/// A plane failure in a verification study: a scene error is bad input, anything else a failed
/// run (exit 1).
fn plane_error(e: RunError) -> ConvergeError {
    match e {
        RunError::Scene(s) => ConvergeError::Scene(s),
        other => ConvergeError::Run(other),
    }
}

/// The generated block of VERIFICATION.md's "Plane body" section (id `plane`).
pub fn markdown() -> Result<String, ConvergeError> {
    let mut md = String::from(
        "| grid (nx × ny, y_grading) | dofs | M, K bitwise symmetric | 1ᵀM_x1 / ρWH − 1 | 1ᵀM_y1 / ρWH − 1 | M positive definite | ‖K t_x‖ | ‖K t_y‖ | ‖K rot‖ |\n|---|---|---|---|---|---|---|---|---|\n",
    );
    for (nx, ny, g) in MATRIX_GRIDS {
        let c = matrix_check(nx, ny, g);
        let _ = writeln!(
            md,
            "| {nx} × {ny}, {g} | {} | {} | {:.1e} | {:.1e} | {} | {:.1e} | {:.1e} | {:.1e} |",
            c.dofs,
            c.symmetric,
            c.mass_ratio[0] - 1.0,
            c.mass_ratio[1] - 1.0,
            c.mass_positive_definite,
            c.kernel[0],
            c.kernel[1],
            c.kernel[2]
        );
    }
    md.push_str(
        "\n| scene | unknowns | steps | max identity residual | max energy rise / E^{1/2} |\n|---|---|---|---|---|\n",
    );
    for (name, scene) in identity_scenes() {
        let (_, s, _) = run_plane_in_memory(&name, &scene).map_err(plane_error)?;
        let rise = s
            .max_energy_rise
            .map_or_else(|| "(forced)".to_string(), |r| format!("{r:.1e}"));
        let _ = writeln!(
            md,
            "| {name} | {} | {} | {:.1e} | {rise} |",
            s.unknowns, s.steps, s.max_identity_residual
        );
    }
    md.push_str(
        "\n| bar scene | steps | plane rows (y_grading) | max abs(ux − u) / max abs(u) | max abs(uy) / max abs(u) |\n|---|---|---|---|---|\n",
    );
    for (name, bar) in bar_case_scenes() {
        let c = bar_case(&bar)?;
        let _ = writeln!(
            md,
            "| {name} | {} | {} ({}) | {:.1e} | {:.1e} |",
            c.steps,
            BAR_CASE_BODY.1,
            BAR_CASE_BODY.2,
            c.max_ux_deviation / c.max_u,
            c.max_uy / c.max_u
        );
    }
    md.push_str(
        "\n| nx × ny | h | unknowns | steps | L2 error at T | order |\n|---|---|---|---|---|---|\n",
    );
    let levels = MANUFACTURED_LEVELS
        .iter()
        .map(|&nx| manufactured_level(nx))
        .collect::<Result<Vec<_>, _>>()?;
    for (k, l) in levels.iter().enumerate() {
        let order = if k == 0 {
            "–".to_string()
        } else {
            let p = &levels[k - 1];
            format!("{:.3}", (p.l2_error / l.l2_error).ln() / (p.h / l.h).ln())
        };
        let _ = writeln!(
            md,
            "| {} × {} | {} | {} | {} | {:.3e} | {order} |",
            l.nx,
            l.nx / 2,
            l.h,
            l.unknowns,
            l.steps,
            l.l2_error
        );
    }
    let _ = writeln!(
        md,
        "\nLeast-squares order over the {} levels: {:.3}.",
        levels.len(),
        observed_order(&levels)
    );
    Ok(md)
}
