//! Plane scene files (TOML): a Kelvin–Voigt body in plane strain on `(0, W) × (0, H)`, its four
//! edges, initial data and load (two components each, expressions in `x`, `y` and, for the
//! load, `t`), the graded mesh, the time step, the contact solver (`[solver]`, the bar's
//! keys) and the output. A scene file has `[bar]` or `[plane]`, never both ([`load_any`] tells
//! them apart). Unknown keys are refused, as for the bar.

use crate::scene::error::invalid;
use crate::scene::expr::Expression;
use crate::scene::heat::ThermalCondition;
use crate::scene::output::{OutputSampling, OutputSpec};
use crate::scene::schema::{
    GIB, MAX_STEPS, Scene, Time, available_memory_bytes, check_time_grid, number_or_expression,
    number_text, positive, toml_syntax, with_overrides,
};
/// The built-in plane scenes (kept beside the bar's list in `scene::schema`).
pub use crate::scene::schema::{PLANE_BUILTIN, plane_builtin_text};
use crate::scene::solver::{SolverMethod, SolverSpec};
use crate::scene::{SceneError, builtin_names, builtin_text};
use serde::{Deserialize, Serialize};
use std::path::Path;

/// A plane scene as read from TOML (see [`PlaneScene::validate`]).
#[derive(Clone, Debug, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct PlaneScene {
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub description: Option<String>,
    pub plane: Body,
    #[serde(default)]
    pub edges: Edges,
    #[serde(default)]
    pub initial: PlaneInitial,
    #[serde(default)]
    pub load: PlaneLoad,
    pub mesh: PlaneMesh,
    pub time: Time,
    /// The step solver: the bar's `[solver]` table, keys and defaults. Without Signorini
    /// edges the method is still the one named, as for the bar: `osqp` runs OSQP on the
    /// unconstrained step problem, `exact` and `penalty` are the one sparse solve.
    #[serde(default)]
    pub solver: SolverSpec,
    /// The bar's `[output]` table, keys and defaults.
    #[serde(default)]
    pub output: OutputSpec,
    /// The temperature (`[heat]`, checked by `crate::scene::plane_heat`); absent: the body
    /// has none.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub heat: Option<PlaneHeat>,
}

/// The `[plane]` table: geometry and material.
#[derive(Clone, Debug, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Body {
    /// `W > 0`.
    pub width: f64,
    /// `H > 0`.
    pub height: f64,
    /// Lamé `λ`, with `λ + μ > 0` (the plane-strain energy is then positive definite).
    pub lambda: f64,
    /// Lamé `μ > 0`.
    pub mu: f64,
    /// `ρ > 0` (default 1), mass per unit area.
    #[serde(default = "one_f64")]
    pub density: f64,
    /// Kelvin–Voigt `α >= 0` (default 0): `σ = A ε(u) + α A ε(u_t)`.
    #[serde(default)]
    pub viscosity: f64,
    /// How `K` is integrated (default `full`); `selective` takes the `λ` term at the cell
    /// centre, so that a nearly incompressible body does not lock.
    #[serde(default, skip_serializing_if = "Integration::is_full")]
    pub integration: Integration,
}

/// `[plane] integration`: the quadrature of the stiffness `K` (and of its energy forms).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum Integration {
    /// Every term at the 2 × 2 Gauss points: exact on rectangles; locks as `λ/μ → ∞`.
    #[default]
    Full,
    /// Selective reduced integration: `λ div u div v` at the cell centre (one point),
    /// `2μ ε(u):ε(v)` at 2 × 2 (Hughes, *The Finite Element Method*, §4.5).
    Selective,
}

impl Integration {
    fn is_full(&self) -> bool {
        *self == Integration::Full
    }

    /// `full` or `selective`, as in the scene.
    pub fn name(self) -> &'static str {
        match self {
            Integration::Full => "full",
            Integration::Selective => "selective",
        }
    }
}

fn one_f64() -> f64 {
    1.0
}

/// The condition on an edge.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum EdgeCondition {
    /// Zero traction.
    #[default]
    Free,
    /// `u = 0` (both components).
    Clamped,
    /// A rigid flat obstacle parallel to the edge at distance `gap(s)` outside the body: at
    /// every node of the edge `u·n <= g(s)`, `n` the outward normal, with a reaction `r >= 0`
    /// along `−n` and `r (g − u·n) = 0` (the physical convention; the bar keeps the talk's
    /// lower bounds). Zero traction where there is no contact.
    Signorini,
}

/// One edge: its condition and, for `signorini`, the gap (a number or an expression in the
/// edge's coordinate `s`: `x` along bottom and top, `y` along left and right), the Coulomb
/// friction coefficient and the obstacle's sliding speed (`crate::scene::friction`).
#[derive(Clone, Debug, Default, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct EdgeSpec {
    pub condition: EdgeCondition,
    #[serde(
        default,
        deserialize_with = "optional_expression",
        skip_serializing_if = "Option::is_none"
    )]
    pub gap: Option<String>,
    /// `μ(s) >= 0` of a Signorini edge, a number or an expression in `s` (absent: 0,
    /// frictionless).
    #[serde(
        default,
        deserialize_with = "optional_expression",
        skip_serializing_if = "Option::is_none"
    )]
    pub friction: Option<String>,
    /// The obstacle's speed along the edge's tangent, a number or an expression in `t`, of a
    /// Signorini edge with friction (absent: 0, a fixed obstacle).
    #[serde(
        default,
        deserialize_with = "optional_expression",
        skip_serializing_if = "Option::is_none"
    )]
    pub velocity: Option<String>,
}

impl EdgeSpec {
    /// A free (`Free`) or clamped edge.
    pub fn plain(condition: EdgeCondition) -> Self {
        Self {
            condition,
            gap: None,
            friction: None,
            velocity: None,
        }
    }

    /// A Signorini edge with gap `gap` (number or expression in `s`).
    pub fn signorini(gap: &str) -> Self {
        Self {
            condition: EdgeCondition::Signorini,
            gap: Some(gap.to_string()),
            friction: None,
            velocity: None,
        }
    }
}

fn optional_expression<'de, D: serde::Deserializer<'de>>(d: D) -> Result<Option<String>, D::Error> {
    number_or_expression(d).map(Some)
}

/// `[heat]` of a plane scene.
#[derive(Clone, Debug, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct PlaneHeat {
    /// `γ`: the thermal stress `−γ θ I` and the heating `γ div u_t`; 0 on the plane body.
    pub coupling: f64,
    /// `κ > 0`.
    pub diffusivity: f64,
    /// `θ(x, y, 0)` (default 0).
    #[serde(default = "zero_text", deserialize_with = "number_or_expression")]
    pub temperature: String,
    /// `q(x, y, t)` (default: no source).
    #[serde(
        default,
        skip_serializing_if = "Option::is_none",
        deserialize_with = "optional_expression"
    )]
    pub source: Option<String>,
    #[serde(default)]
    pub left: ThermalEdge,
    #[serde(default)]
    pub right: ThermalEdge,
    #[serde(default)]
    pub bottom: ThermalEdge,
    #[serde(default)]
    pub top: ThermalEdge,
}

fn zero_text() -> String {
    "0".to_string()
}

/// `heat.<edge>`: its thermal condition and, on a frictional edge, `frictional_heating`.
#[derive(Clone, Debug, Default, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct ThermalEdge {
    #[serde(default)]
    pub condition: ThermalCondition,
    /// `θ_edge(s, t)` of a `temperature` edge.
    #[serde(
        default,
        skip_serializing_if = "Option::is_none",
        deserialize_with = "optional_expression"
    )]
    pub value: Option<String>,
    /// `h >= 0` of an `exchange` edge.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub coefficient: Option<f64>,
    /// `θ_obs(t)` of an `exchange` edge (default 0).
    #[serde(
        default,
        skip_serializing_if = "Option::is_none",
        deserialize_with = "optional_expression"
    )]
    pub obstacle: Option<String>,
    /// `η`, the share of the edge's friction dissipation put into the body (default 1).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub frictional_heating: Option<f64>,
}

/// The edges in the order `left, right, bottom, top` ([`Edges::all`]).
pub const EDGE_NAMES: [&str; 4] = ["left", "right", "bottom", "top"];

/// Bytes per pair of contact normals of the exact step: the condensed matrix `S` and the
/// factor of its active block are two dense `m × m` arrays of doubles.
pub const EXACT_BYTES_PER_NORMAL_PAIR: u64 = 16;
pub use crate::step::algorithm::PENALTY_CONDENSED_MAX_NORMALS;

/// `[edges]`: `left` (x = 0), `right` (x = W), `bottom` (y = 0), `top` (y = H); free when absent.
#[derive(Clone, Debug, Default, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Edges {
    #[serde(default)]
    pub left: EdgeSpec,
    #[serde(default)]
    pub right: EdgeSpec,
    #[serde(default)]
    pub bottom: EdgeSpec,
    #[serde(default)]
    pub top: EdgeSpec,
}

impl Edges {
    /// `[left, right, bottom, top]`.
    pub fn all(&self) -> [&EdgeSpec; 4] {
        [&self.left, &self.right, &self.bottom, &self.top]
    }

    /// `[left, right, bottom, top]` clamped.
    pub fn clamped(&self) -> [bool; 4] {
        self.all().map(|e| e.condition == EdgeCondition::Clamped)
    }

    /// The parsed gap of each Signorini edge (`None` for the others), `[left, right, bottom,
    /// top]`; an error names `edges.<edge>.gap`.
    pub fn gaps(&self) -> Result<[Option<Expression>; 4], SceneError> {
        let mut out: [Option<Expression>; 4] = Default::default();
        for (k, e) in self.all().into_iter().enumerate() {
            let field = format!("edges.{}.gap", EDGE_NAMES[k]);
            match (e.condition, &e.gap) {
                (EdgeCondition::Signorini, Some(text)) => {
                    out[k] = Some(Expression::parse_edge(&field, text)?);
                }
                (EdgeCondition::Signorini, None) => {
                    return Err(SceneError::Invalid {
                        field,
                        value: "absent".into(),
                        allowed:
                            "an edge with condition = \"signorini\" needs its gap: a number or \
                                  an expression in s"
                                .into(),
                    });
                }
                (c, Some(text)) => {
                    return Err(SceneError::Invalid {
                        field,
                        value: text.clone(),
                        allowed: format!(
                            "a gap belongs to a Signorini edge only (this edge is {})",
                            format!("{c:?}").to_lowercase()
                        ),
                    });
                }
                (_, None) => {}
            }
        }
        Ok(out)
    }
}

/// Two components, each a number or an expression (kept as text, see [`number_text`]).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(transparent)]
pub struct Vector(#[serde(deserialize_with = "pair")] pub [String; 2]);

impl Vector {
    pub fn zero() -> Self {
        Vector(["0".into(), "0".into()])
    }
}

/// One component: a number or an expression.
struct Component(String);

impl<'de> Deserialize<'de> for Component {
    fn deserialize<D: serde::Deserializer<'de>>(d: D) -> Result<Self, D::Error> {
        number_or_expression(d).map(Component)
    }
}

fn pair<'de, D: serde::Deserializer<'de>>(d: D) -> Result<[String; 2], D::Error> {
    let v: Vec<Component> = Vec::deserialize(d)?;
    match <[Component; 2]>::try_from(v) {
        Ok([a, b]) => Ok([a.0, b.0]),
        Err(v) => Err(serde::de::Error::custom(format!(
            "expected two components [x, y], e.g. [\"0.1*cos(pi*x/2)\", \"0\"], got {}",
            v.len()
        ))),
    }
}

#[derive(Clone, Debug, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct PlaneInitial {
    /// `u(x, y, 0)`, expressions in `x` and `y`.
    #[serde(default = "Vector::zero")]
    pub displacement: Vector,
    /// `u_t(x, y, 0)`.
    #[serde(default = "Vector::zero")]
    pub velocity: Vector,
}

impl Default for PlaneInitial {
    fn default() -> Self {
        Self {
            displacement: Vector::zero(),
            velocity: Vector::zero(),
        }
    }
}

#[derive(Clone, Debug, Default, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct PlaneLoad {
    /// `l(x, y, t)`, force per unit area; absent means none.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub density: Option<Vector>,
}

#[derive(Clone, Debug, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct PlaneMesh {
    /// Cells along `x` (uniform).
    pub nx: u64,
    /// Cells along `y`.
    pub ny: u64,
    /// Last over first cell height (1 = uniform), geometric in between.
    #[serde(default = "one_f64")]
    pub y_grading: f64,
}

/// Largest accepted number of unknowns: the factor of `C` takes about 1 GB at 1e6 (measured,
/// `docs/sparse-cholesky.md`), growing faster than linearly.
pub const MAX_PLANE_UNKNOWNS: u64 = 2_000_000;
/// Memory per unknown of a plane run: the factor (about 110 values per unknown at 1e6, 8 bytes
/// each, plus its symbolic part) and some 30 vectors; a margin over the measured 1 GB at 1e6.
pub const PLANE_BYTES_PER_UNKNOWN: u64 = 2048;
/// Largest `y_grading` (or smallest, inverted): beyond, the thinnest cells make C needlessly
/// ill-conditioned.
pub const MAX_Y_GRADING: f64 = 1e6;

/// A scene of either kind.
#[derive(Clone, Debug)]
pub enum AnyScene {
    Bar(Box<Scene>),
    Plane(Box<PlaneScene>),
}

/// Reads a bar or plane scene by built-in name or path, applies `key=value` overrides and
/// validates; returns its name (built-in name or file stem). A file with both `[bar]` and
/// `[plane]`, or neither, is refused naming both.
pub fn load_any(
    name_or_path: &str,
    overrides: &[String],
) -> Result<(String, AnyScene), SceneError> {
    if let Some(text) = builtin_text(name_or_path) {
        let scene = Scene::from_toml(text, overrides)?;
        return Ok((name_or_path.into(), AnyScene::Bar(Box::new(scene))));
    }
    if let Some(text) = plane_builtin_text(name_or_path) {
        let scene = PlaneScene::from_toml(text, overrides)?;
        return Ok((name_or_path.into(), AnyScene::Plane(Box::new(scene))));
    }
    let path = Path::new(name_or_path);
    if !path.is_file() {
        let mut names = builtin_names();
        names.extend(crate::scene::thermal_builtin_names());
        names.extend(PLANE_BUILTIN.iter().map(|(n, _)| *n));
        return Err(SceneError::UnknownScene {
            name: name_or_path.to_string(),
            builtins: names.join(", "),
        });
    }
    let text = std::fs::read_to_string(path).map_err(|source| SceneError::Read {
        path: path.to_path_buf(),
        source,
    })?;
    let stem = path
        .file_stem()
        .map_or("scene".into(), |s| s.to_string_lossy().into_owned());
    Ok((stem, any_from_toml(&text, overrides)?))
}

/// A scene of either kind from TOML text, told apart by its `[bar]` or `[plane]` table.
pub fn any_from_toml(text: &str, overrides: &[String]) -> Result<AnyScene, SceneError> {
    let table: toml::Table = toml::from_str(text)
        .map_err(|e| SceneError::Syntax(e.to_string().trim_end().to_string()))?;
    match (table.contains_key("bar"), table.contains_key("plane")) {
        (true, false) => Ok(AnyScene::Bar(Box::new(Scene::from_toml(text, overrides)?))),
        (false, true) => Ok(AnyScene::Plane(Box::new(PlaneScene::from_toml(
            text, overrides,
        )?))),
        (both, _) => Err(SceneError::Invalid {
            field: "bar, plane".into(),
            value: if both { "both given" } else { "neither given" }.into(),
            allowed: "a scene has a [bar] table (the bar) or a [plane] table (the plane body), \
                      exactly one of them"
                .into(),
        }),
    }
}

impl PlaneScene {
    /// Parses TOML text, applies `key=value` overrides (as for the bar) and validates.
    pub fn from_toml(text: &str, overrides: &[String]) -> Result<Self, SceneError> {
        let table: toml::Table = toml::from_str(text).map_err(toml_syntax)?;
        let table = crate::scene::schema::overridden(table, overrides)?;
        let scene: PlaneScene = with_overrides(table, &[])?;
        scene.validate()?;
        Ok(scene)
    }

    /// The scene as TOML text.
    pub fn to_toml(&self) -> String {
        toml::to_string(self).expect("a scene always serialises")
    }

    /// Checks every field; the error names the field, the value and what is allowed.
    pub fn validate(&self) -> Result<(), SceneError> {
        let p = &self.plane;
        positive("plane.width", p.width)?;
        positive("plane.height", p.height)?;
        positive("plane.mu", p.mu)?;
        positive("plane.density", p.density)?;
        if !(p.lambda.is_finite() && p.lambda + p.mu > 0.0) {
            return Err(invalid(
                "plane.lambda",
                p.lambda,
                "must be a finite number with lambda + mu > 0 (plane strain)",
            ));
        }
        if !(p.viscosity.is_finite() && p.viscosity >= 0.0) {
            return Err(invalid(
                "plane.viscosity",
                p.viscosity,
                "must be a finite number >= 0",
            ));
        }
        let g = self.mesh.y_grading;
        if !(g.is_finite() && (1.0 / MAX_Y_GRADING..=MAX_Y_GRADING).contains(&g)) {
            return Err(invalid(
                "mesh.y_grading",
                g,
                &format!(
                    "must lie between {} and {MAX_Y_GRADING}",
                    1.0 / MAX_Y_GRADING
                ),
            ));
        }
        for (field, n) in [("mesh.nx", self.mesh.nx), ("mesh.ny", self.mesh.ny)] {
            if n < 1 {
                return Err(invalid(field, n as f64, "must be >= 1"));
            }
        }
        let unknowns = self.unknowns();
        if unknowns == 0 {
            return Err(SceneError::Invalid {
                field: "mesh.nx".into(),
                value: self.mesh.nx.to_string(),
                allowed: "with these clamped edges no node is free to move: refine the mesh".into(),
            });
        }
        if unknowns > MAX_PLANE_UNKNOWNS {
            return Err(SceneError::Invalid {
                field: "mesh.nx".into(),
                value: self.mesh.nx.to_string(),
                allowed: format!(
                    "the mesh has {unknowns} unknowns, more than the {MAX_PLANE_UNKNOWNS} accepted"
                ),
            });
        }
        let needed = unknowns.saturating_mul(PLANE_BYTES_PER_UNKNOWN);
        let available = available_memory_bytes();
        if needed > available {
            return Err(SceneError::Invalid {
                field: "mesh.nx".into(),
                value: self.mesh.nx.to_string(),
                allowed: format!(
                    "a run this size needs about {:.1} GiB, more than the {:.1} GiB available",
                    needed as f64 / GIB,
                    available as f64 / GIB
                ),
            });
        }
        positive("time.step", self.time.step)?;
        positive("time.end", self.time.end)?;
        if self.time.end / self.time.step > MAX_STEPS as f64 {
            return Err(SceneError::Invalid {
                field: "time.end".into(),
                value: self.time.end.to_string(),
                allowed: format!("time.end / time.step must lie between 1 and {MAX_STEPS}"),
            });
        }
        check_time_grid(self.time.step, self.time.end)?;
        self.output.validate()?;
        self.solver.validate()?;
        self.expressions()?;
        self.edges.gaps()?;
        self.validate_friction()?;
        if let Some(heat) = &self.heat {
            heat.validate(&self.edges)?;
            if self.solver.method != SolverMethod::Exact {
                return Err(SceneError::Invalid {
                    field: "solver.method".into(),
                    value: self.solver.method.name().into(),
                    allowed: "a plane scene with [heat] takes the exact step solver (\"exact\")"
                        .into(),
                });
            }
        }
        let m = self.contact_normals();
        if self.solver.method == SolverMethod::Exact {
            let dense = m
                .saturating_mul(m)
                .saturating_mul(EXACT_BYTES_PER_NORMAL_PAIR);
            if needed.saturating_add(dense) > available {
                return Err(SceneError::Invalid {
                    field: "edges".into(),
                    value: format!("{m} contact normals"),
                    allowed: format!(
                        "the exact step's dense S = E C^-1 E^T and the factor of its active \
                         block take {EXACT_BYTES_PER_NORMAL_PAIR} m^2 = {dense} bytes ({:.1} \
                         GiB) beside the run's {:.1} GiB, more than the {:.1} GiB available: \
                         use solver.method = \"penalty\" or \"osqp\" (no dense matrix), or \
                         coarsen the Signorini edges' mesh",
                        dense as f64 / GIB,
                        needed as f64 / GIB,
                        available as f64 / GIB
                    ),
                });
            }
        }
        Ok(())
    }

    /// Contact normals `m`: one per node of each Signorini edge, the nodes of a clamped edge
    /// excepted (a corner shared by two Signorini edges has two, one per component).
    pub fn contact_normals(&self) -> u64 {
        let [l, r, b, t] = self.edges.clamped();
        let (nx, ny) = (self.mesh.nx + 1, self.mesh.ny + 1);
        let along_y = ny.saturating_sub(u64::from(b) + u64::from(t));
        let along_x = nx.saturating_sub(u64::from(l) + u64::from(r));
        self.edges
            .all()
            .iter()
            .enumerate()
            .filter(|(_, e)| e.condition == EdgeCondition::Signorini)
            .map(|(k, _)| if k < 2 { along_y } else { along_x })
            .sum()
    }

    /// The parsed expressions: initial displacement and velocity, and the load (if any).
    pub fn expressions(&self) -> Result<PlaneExpressions, SceneError> {
        let vector =
            |name: &str, v: &Vector, allow_t: bool| -> Result<[Expression; 2], SceneError> {
                let f =
                    |c: usize| Expression::parse_plane(&format!("{name}[{c}]"), &v.0[c], allow_t);
                Ok([f(0)?, f(1)?])
            };
        Ok(PlaneExpressions {
            displacement: vector("initial.displacement", &self.initial.displacement, false)?,
            velocity: vector("initial.velocity", &self.initial.velocity, false)?,
            load: match &self.load.density {
                Some(v) => Some(vector("load.density", v, true)?),
                None => None,
            },
        })
    }

    /// Unknowns: two per node not on a clamped edge.
    pub fn unknowns(&self) -> u64 {
        let [l, r, b, t] = self.edges.clamped();
        let columns = (self.mesh.nx + 1).saturating_sub(u64::from(l) + u64::from(r));
        let rows = (self.mesh.ny + 1).saturating_sub(u64::from(b) + u64::from(t));
        2u64.saturating_mul(columns).saturating_mul(rows)
    }

    /// Number of time steps, `T / Δt` rounded (a whole number, see `check_time_grid`).
    pub fn steps(&self) -> usize {
        (self.time.end / self.time.step).round() as usize
    }

    /// The sampling of the profile file ([`OutputSpec::sampling`] on the grid's nodes).
    pub fn output_sampling(&self) -> OutputSampling {
        let lattice = [self.mesh.nx + 1, self.mesh.ny + 1];
        self.output.sampling(self.steps() as u64, lattice)
    }

    /// The scene with `2^level` times as many cells in each direction and a step `2^level`
    /// times smaller.
    pub fn refined(&self, level: u32) -> PlaneScene {
        let mut s = self.clone();
        s.mesh.nx = self.mesh.nx << level;
        s.mesh.ny = self.mesh.ny << level;
        s.time.step = self.time.step / f64::from(1u32 << level);
        s
    }
}

/// The parsed expressions of a plane scene; component 0 is `x`, 1 is `y`.
#[derive(Clone, Debug)]
pub struct PlaneExpressions {
    pub displacement: [Expression; 2],
    pub velocity: [Expression; 2],
    pub load: Option<[Expression; 2]>,
}

/// A number as a plane component (the text [`number_text`] keeps).
pub fn component(v: f64) -> String {
    number_text(v)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn every_builtin_plane_scene_loads_and_both_or_neither_table_is_refused() {
        for (name, _) in PLANE_BUILTIN {
            let (n, s) = load_any(name, &[]).unwrap();
            assert_eq!(&n, name);
            assert!(matches!(s, AnyScene::Plane(_)));
        }
        let strip = plane_builtin_text("plane-strip").unwrap();
        let both = format!("{strip}\n[bar]\nlength = 1.0\n");
        let e = any_from_toml(&both, &[]).unwrap_err().to_string();
        assert!(e.contains("both") && e.contains("[plane]"), "{e}");
        let e = any_from_toml("[mesh]\nnx = 2\n", &[])
            .unwrap_err()
            .to_string();
        assert!(e.contains("neither"), "{e}");
        // Numbers are accepted as components; y is a variable.
        let s = PlaneScene::from_toml(strip, &["initial.displacement=[0.5, \"y*x\"]".to_string()])
            .unwrap();
        assert_eq!(
            s.initial.displacement.0,
            ["0.5".to_string(), "y*x".to_string()]
        );
        let e = PlaneScene::from_toml(strip, &["initial.velocity=[\"t\", \"0\"]".into()])
            .unwrap_err()
            .to_string();
        assert!(
            e.contains("initial.velocity[0]") && e.contains("x and y only"),
            "{e}"
        );
    }
}
