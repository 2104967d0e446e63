//! Scene files (TOML): the bar, its ends, initial data, load, mesh, time step, solver and output.
//!
//! The keys are the public interface; unknown keys are refused so that a typo such as
//! `viscocity` is an error, not a silently ignored setting.

use crate::scene::SceneError;
use crate::scene::error::invalid;
use crate::scene::expr::Expression;
pub(crate) use crate::scene::expr::number_or_expression;
pub use crate::scene::expr::number_text;
use crate::scene::output::{OutputSampling, OutputSpec};
use crate::scene::solver::SolverSpec;
use serde::{Deserialize, Serialize};
use std::path::Path;

/// Which pair of matrices a scene uses.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum MatrixVariant {
    /// `M = Δx/6 · tridiag(1, 4, 1)` with end diagonals `Δx/3`;
    /// `R = 1/Δx · tridiag(−1, 2, −1)` with end diagonals `1/Δx`.
    #[default]
    Consistent,
    /// The entries as printed in the talk (inconsistent; for diagnosis only).
    TalkPrinted,
}

/// The mass matrix of a scene (`[bar] mass`), beside the stiffness it shares with every
/// variant; see [`crate::bar::matrices::mass_matrix`] for the entries and
/// `docs/mass-variants.md` for the derivation.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum MassVariant {
    /// The P1 (consistent) mass matrix, the talk's scheme.
    #[default]
    Consistent,
    /// No mass at the Signorini end nodes, their mass moved to the two nearest nodes so that
    /// the total mass and the first moment are kept (Khenous, Laborde & Renard 2008).
    Redistributed,
    /// The row sums of the consistent matrix on the diagonal.
    Lumped,
}

impl MassVariant {
    /// All variants, in the order of the documentation.
    pub const ALL: [MassVariant; 3] = [
        MassVariant::Consistent,
        MassVariant::Redistributed,
        MassVariant::Lumped,
    ];

    /// The scene key's value: `consistent`, `redistributed`, `lumped`.
    pub fn name(self) -> &'static str {
        match self {
            MassVariant::Consistent => "consistent",
            MassVariant::Redistributed => "redistributed",
            MassVariant::Lumped => "lumped",
        }
    }

    /// Parses a scene key's value (the names of [`MassVariant::name`]).
    pub fn parse(text: &str) -> Option<MassVariant> {
        Self::ALL.into_iter().find(|v| v.name() == text.trim())
    }
}

/// Fewest elements a bar with one redistributed Signorini end may have: the two nodes that take
/// the end's mass must be inner nodes (see [`crate::bar::matrices::mass_matrix`]).
pub const REDISTRIBUTED_MIN_ELEMENTS_ONE_END: u64 = 3;
/// Fewest elements with two redistributed Signorini ends: the two modifications may not touch
/// (with 5 elements the two reduced diagonals `Δx/6` are neighbours and `M` is indefinite).
pub const REDISTRIBUTED_MIN_ELEMENTS_TWO_ENDS: u64 = 6;

/// A scene as read from TOML, before validation (see [`Scene::validate`]).
#[derive(Clone, Debug, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Scene {
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub description: Option<String>,
    pub bar: Bar,
    pub left: EndSpec,
    pub right: EndSpec,
    #[serde(default)]
    pub initial: Initial,
    #[serde(default)]
    pub load: Load,
    /// Distributed Signorini: an obstacle `u(x) >= -g(x)` under every node.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub obstacle: Option<Obstacle>,
    /// The temperature (`[heat]`, [`crate::scene::heat`]); absent: the bar has none.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub heat: Option<crate::scene::heat::Heat>,
    pub mesh: Mesh,
    pub time: Time,
    #[serde(default)]
    pub solver: SolverSpec,
    #[serde(default)]
    pub output: OutputSpec,
}

#[derive(Clone, Debug, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Bar {
    pub length: f64,
    /// Kelvin–Voigt viscosity `alpha >= 0`.
    #[serde(default)]
    pub viscosity: f64,
    #[serde(default)]
    pub matrices: MatrixVariant,
    /// The mass matrix (default consistent); not written when consistent, so that the TOML of
    /// a talk scene reads as before.
    #[serde(default, skip_serializing_if = "is_consistent")]
    pub mass: MassVariant,
}

fn is_consistent(m: &MassVariant) -> bool {
    *m == MassVariant::Consistent
}

/// Boundary condition at one end of the bar.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum Condition {
    /// `0 <= u + a ⊥ reaction >= 0` (a lower bound `u >= -a`, at either end, as in the talk).
    Signorini,
    /// Zero stress.
    Free,
    /// `u = 0`.
    Clamped,
}

#[derive(Clone, Debug, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct EndSpec {
    pub condition: Condition,
    /// The gap `a` of a Signorini end (constraint `u(end) >= -a`): a number, or an expression
    /// in `t` (an obstacle moving along the bar; `a(0) >= 0`, later values of either sign).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub gap: Option<GapValue>,
}

impl EndSpec {
    /// An end with `condition` and, for a Signorini end, the constant gap `gap`.
    pub fn new(condition: Condition, gap: Option<f64>) -> Self {
        Self {
            condition,
            gap: gap.map(GapValue::Number),
        }
    }

    /// The gap when it is a number (`None` when absent or an expression in `t`).
    pub fn constant_gap(&self) -> Option<f64> {
        match self.gap {
            Some(GapValue::Number(v)) => Some(v),
            _ => None,
        }
    }

    /// The gap `a(t)` as an expression in `t` for the scene field `field` (`None` when absent).
    pub fn gap_expression(&self, field: &str) -> Result<Option<Expression>, SceneError> {
        match &self.gap {
            None => Ok(None),
            Some(GapValue::Number(v)) if !v.is_finite() => {
                Err(invalid(field, *v, "must be a finite number >= 0"))
            }
            Some(GapValue::Number(v)) => Expression::parse_time(field, &number_text(*v)).map(Some),
            Some(GapValue::Expression(text)) => Expression::parse_time(field, text).map(Some),
        }
    }
}

#[derive(Clone, Debug, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Initial {
    /// `u(x, 0)`, an expression in `x` (a number is kept as its text, see [`number_text`]).
    #[serde(default = "zero", deserialize_with = "number_or_expression")]
    pub displacement: String,
    /// `u_t(x, 0)`, an expression in `x` (a number is kept as its text).
    #[serde(default = "zero", deserialize_with = "number_or_expression")]
    pub velocity: String,
}

impl Default for Initial {
    fn default() -> Self {
        Self {
            displacement: zero(),
            velocity: zero(),
        }
    }
}

fn zero() -> String {
    "0".to_string()
}

#[derive(Clone, Debug, Default, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Load {
    /// `l(x, t)`, force per unit length; absent means no load (a number is kept as its text).
    #[serde(
        default,
        skip_serializing_if = "Option::is_none",
        deserialize_with = "optional_number_or_expression"
    )]
    pub density: Option<String>,
}

/// The obstacle under the whole bar (the talk's "distributed Signorini conditions").
#[derive(Clone, Debug, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Obstacle {
    /// `g(x)`: a number or an expression in `x`; the constraint is `u(x_i) >= -g(x_i)` at every
    /// node (combined with a Signorini end's own gap by taking the tighter bound).
    pub gap: GapValue,
}

/// A number or an expression (in `x` for the obstacle, in `t` for an end).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(untagged)]
pub enum GapValue {
    Number(f64),
    Expression(String),
}

impl GapValue {
    /// As an expression for the scene field `field`.
    pub fn expression(&self, field: &str) -> Result<Expression, SceneError> {
        match self {
            GapValue::Number(v) if !v.is_finite() => Err(invalid(field, *v, "must be finite")),
            GapValue::Number(v) => Expression::parse(field, &number_text(*v), false),
            GapValue::Expression(text) => Expression::parse(field, text, false),
        }
    }
}

fn optional_number_or_expression<'de, D: serde::Deserializer<'de>>(
    d: D,
) -> Result<Option<String>, D::Error> {
    number_or_expression(d).map(Some)
}

#[derive(Clone, Debug, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Mesh {
    /// Number of elements `J + 1`.
    pub elements: u64,
}

#[derive(Clone, Debug, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Time {
    /// `dt > 0`.
    pub step: f64,
    /// Final time `T`; the run takes `round(T / dt)` steps (see [`Scene::steps`]).
    pub end: f64,
}

/// Largest accepted element count: the run holds about 20 vectors of this length.
pub const MAX_ELEMENTS: u64 = 100_000_000;
/// Memory per node of a run: about 40 vectors of f64 (state, products, matrices, factors,
/// solver columns, output buffers) with a margin for the solver's own work space.
pub const BYTES_PER_NODE: u64 = 512;
pub(crate) const GIB: f64 = (1u64 << 30) as f64;

/// `MemAvailable` from /proc/meminfo, or 24 GiB (this project's machines) where unreadable.
pub(crate) fn available_memory_bytes() -> u64 {
    std::fs::read_to_string("/proc/meminfo")
        .ok()
        .and_then(|t| {
            t.lines()
                .find(|l| l.starts_with("MemAvailable:"))
                .and_then(|l| l.split_whitespace().nth(1))
                .and_then(|kb| kb.parse::<u64>().ok())
        })
        .map_or(24 << 30, |kb| kb * 1024)
}

/// Largest accepted number of time steps.
pub const MAX_STEPS: u64 = 1_000_000_000;

/// Built-in scenes, embedded from `scenes/*.toml`.
pub const BUILTIN: &[(&str, &str)] = &[
    ("modal", include_str!("../../scenes/modal.toml")),
    ("forced-mode", include_str!("../../scenes/forced-mode.toml")),
    ("impact", include_str!("../../scenes/impact.toml")),
    ("falling-bar", include_str!("../../scenes/falling-bar.toml")),
    (
        "clamped-impact",
        include_str!("../../scenes/clamped-impact.toml"),
    ),
    (
        "viscous-contact",
        include_str!("../../scenes/viscous-contact.toml"),
    ),
    ("both-ends", include_str!("../../scenes/both-ends.toml")),
    (
        "both-ends-forced",
        include_str!("../../scenes/both-ends-forced.toml"),
    ),
    ("one-end", include_str!("../../scenes/one-end.toml")),
    (
        "one-end-forced",
        include_str!("../../scenes/one-end-forced.toml"),
    ),
    ("distributed", include_str!("../../scenes/distributed.toml")),
    (
        "distributed-forced",
        include_str!("../../scenes/distributed-forced.toml"),
    ),
];

/// Built-in scenes of the bar with a temperature (`[heat]`), embedded from `scenes/*.toml`
/// (listed apart from [`BUILTIN`], whose users run the bar without one).
pub const THERMAL_BUILTIN: &[(&str, &str)] = &[
    (
        "heated-expansion",
        include_str!("../../scenes/heated-expansion.toml"),
    ),
    (
        "thermal-impact",
        include_str!("../../scenes/thermal-impact.toml"),
    ),
];

/// Built-in plane scenes, embedded from `scenes/*.toml` (listed apart from the bar's
/// [`crate::scene::BUILTIN`], whose users expect bar scenes).
pub const PLANE_BUILTIN: &[(&str, &str)] = &[
    ("plane-strip", include_str!("../../scenes/plane-strip.toml")),
    (
        "plane-cantilever",
        include_str!("../../scenes/plane-cantilever.toml"),
    ),
    (
        "plane-tilted-drop",
        include_str!("../../scenes/plane-tilted-drop.toml"),
    ),
    (
        "plane-curved-obstacle",
        include_str!("../../scenes/plane-curved-obstacle.toml"),
    ),
    (
        "plane-block-drop",
        include_str!("../../scenes/plane-block-drop.toml"),
    ),
    (
        "plane-friction-tilted-drop",
        include_str!("../../scenes/plane-friction-tilted-drop.toml"),
    ),
    (
        "plane-friction-slope",
        include_str!("../../scenes/plane-friction-slope.toml"),
    ),
    (
        "plane-friction-launch",
        include_str!("../../scenes/plane-friction-launch.toml"),
    ),
    (
        "plane-friction-stick-slip",
        include_str!("../../scenes/plane-friction-stick-slip.toml"),
    ),
    ("plane-brake", include_str!("../../scenes/plane-brake.toml")),
];

/// The TOML text of a built-in plane scene.
pub fn plane_builtin_text(name: &str) -> Option<&'static str> {
    PLANE_BUILTIN
        .iter()
        .find(|(n, _)| *n == name)
        .map(|(_, t)| *t)
}

/// The names of the built-in scenes, in order.
pub fn builtin_names() -> Vec<&'static str> {
    BUILTIN.iter().map(|(n, _)| *n).collect()
}

/// The TOML text of a built-in bar scene, with or without a temperature ([`BUILTIN`],
/// [`THERMAL_BUILTIN`]).
pub fn builtin_text(name: &str) -> Option<&'static str> {
    BUILTIN
        .iter()
        .chain(THERMAL_BUILTIN)
        .find(|(n, _)| *n == name)
        .map(|(_, t)| *t)
}

/// The names of the built-in scenes with a temperature, in order.
pub fn thermal_builtin_names() -> Vec<&'static str> {
    THERMAL_BUILTIN.iter().map(|(n, _)| *n).collect()
}

/// A plane scene given where only bar scenes are taken (`converge`, `compare`, `figures`).
fn plane_not_here(name: &str) -> SceneError {
    SceneError::Invalid {
        field: "plane".into(),
        value: name.to_string(),
        allowed: "a plane scene: only `viscobar run` takes plane scenes (this command takes \
                  bar scenes)"
            .into(),
    }
}

/// Reads a scene by built-in name or path, applies `key=value` overrides, and returns its name
/// (the built-in name or the file stem) and the validated scene.
pub fn load(name_or_path: &str, overrides: &[String]) -> Result<(String, Scene), SceneError> {
    let (name, text) = match builtin_text(name_or_path) {
        Some(t) => (name_or_path.to_string(), t.to_string()),
        None if plane_builtin_text(name_or_path).is_some() => {
            return Err(plane_not_here(name_or_path));
        }
        None => {
            let path = Path::new(name_or_path);
            if !path.is_file() {
                let mut names = builtin_names();
                names.extend(thermal_builtin_names());
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
            (stem, text)
        }
    };
    let scene = Scene::from_toml(&text, overrides)?;
    Ok((name, scene))
}

impl Scene {
    /// Parses TOML text, applies `key=value` overrides and validates. An override's key is
    /// `section.field` (or `section.table.field`, e.g. `edges.bottom.gap`); its value is read
    /// as a TOML value (`0.1`, `"x*(1 - x)"`, `true`), and a value that is not valid TOML (a
    /// bare word such as `osqp`) is taken as a string. A number
    /// is accepted wherever an expression is (`initial.displacement = 0.1`, in the file or
    /// through `--set`), kept as its text ([`number_text`]).
    pub fn from_toml(text: &str, overrides: &[String]) -> Result<Self, SceneError> {
        let table: toml::Table = toml::from_str(text).map_err(toml_syntax)?;
        if table.contains_key("plane") && !table.contains_key("bar") {
            return Err(plane_not_here("this scene"));
        }
        let table = overridden(table, overrides)?;
        crate::scene::heat::check_end_tables(&table)?;
        let scene: Scene = table.try_into().map_err(toml_syntax)?;
        scene.validate()?;
        Ok(scene)
    }

    /// The scene as TOML text.
    pub fn to_toml(&self) -> String {
        toml::to_string(self).expect("a scene always serialises")
    }

    /// Checks every field; the error names the field, the value and what is allowed.
    pub fn validate(&self) -> Result<(), SceneError> {
        if self.output.format == crate::scene::OutputFormat::Vtu {
            return Err(SceneError::Invalid {
                field: "output.format".into(),
                value: "\"vtu\"".into(),
                allowed: "ParaView output is the plane body's (its mesh, stress tensor and \
                          contact along its edges); a bar writes its profiles as \"csv\" or \
                          \"npy\""
                    .into(),
            });
        }
        positive("bar.length", self.bar.length)?;
        if !(self.bar.viscosity.is_finite() && self.bar.viscosity >= 0.0) {
            return Err(invalid(
                "bar.viscosity",
                self.bar.viscosity,
                "must be a finite number >= 0",
            ));
        }
        for (side, end) in [("left", &self.left), ("right", &self.right)] {
            let field = format!("{side}.gap");
            match (end.condition, &end.gap) {
                (Condition::Signorini, None) => {
                    return Err(SceneError::Invalid {
                        field,
                        value: "missing".into(),
                        allowed: "a signorini end needs a finite gap >= 0 (a number, or an \
                                  expression in t)"
                            .into(),
                    });
                }
                (Condition::Signorini, Some(_)) => {
                    let a = end.gap_expression(&field)?.expect("given").eval(0.0, 0.0)?;
                    if a < 0.0 {
                        return Err(invalid(
                            &field,
                            a,
                            "must be a finite number >= 0 (at t = 0)",
                        ));
                    }
                }
                (Condition::Free | Condition::Clamped, Some(a)) => {
                    return Err(SceneError::Invalid {
                        field,
                        value: match a {
                            GapValue::Number(v) => v.to_string(),
                            GapValue::Expression(text) => format!("\"{text}\""),
                        },
                        allowed: "only a signorini end has a gap".into(),
                    });
                }
                _ => {}
            }
        }
        let elements = self.mesh.elements;
        let clamped = [&self.left, &self.right]
            .iter()
            .filter(|e| e.condition == Condition::Clamped)
            .count() as u64;
        if !(1..=MAX_ELEMENTS).contains(&elements) || elements < clamped {
            return Err(SceneError::Invalid {
                field: "mesh.elements".into(),
                value: elements.to_string(),
                allowed: format!(
                    "must be between {} and {MAX_ELEMENTS} (at least one node must be free to move)",
                    clamped.max(1)
                ),
            });
        }
        let needed = self.estimated_bytes();
        let available = available_memory_bytes();
        if needed > available {
            return Err(SceneError::Invalid {
                field: "mesh.elements".into(),
                value: elements.to_string(),
                allowed: format!(
                    "a run this size needs about {:.1} GiB, more than the {:.1} GiB available",
                    needed as f64 / GIB,
                    available as f64 / GIB
                ),
            });
        }
        positive("time.step", self.time.step)?;
        positive("time.end", self.time.end)?;
        let steps = self.time.end / self.time.step;
        if steps > MAX_STEPS as f64 {
            return Err(SceneError::Invalid {
                field: "time.end".into(),
                value: self.time.end.to_string(),
                allowed: format!("time.end / time.step must lie between 1 and {MAX_STEPS}"),
            });
        }
        self.validate_mass()?;
        check_time_grid(self.time.step, self.time.end)?;
        self.solver.validate()?;
        self.output.validate()?;
        Expression::parse("initial.displacement", &self.initial.displacement, false)?;
        Expression::parse("initial.velocity", &self.initial.velocity, false)?;
        if let Some(d) = &self.load.density {
            Expression::parse("load.density", d, true)?;
        }
        if let Some(o) = &self.obstacle {
            o.gap.expression("obstacle.gap")?;
        }
        if let Some(heat) = &self.heat {
            heat.validate(self.thermal_view(), self.obstacle.is_some())?;
        }
        Ok(())
    }

    /// `bar.mass` against the other keys: the talk's printed matrices are a diagnostic of their
    /// own; redistribution needs a node-free obstacle and enough elements.
    fn validate_mass(&self) -> Result<(), SceneError> {
        let mass = self.bar.mass;
        if mass == MassVariant::Consistent {
            return Ok(());
        }
        if self.bar.matrices == MatrixVariant::TalkPrinted {
            return Err(SceneError::Invalid {
                field: "bar.mass".into(),
                value: format!("\"{}\"", mass.name()),
                allowed: "only \"consistent\" goes with `bar.matrices` = \"talk-printed\" \
                          (the talk's printed entries are a diagnostic of their own)"
                    .into(),
            });
        }
        if mass != MassVariant::Redistributed {
            return Ok(());
        }
        if self.obstacle.is_some() {
            return Err(SceneError::Invalid {
                field: "bar.mass".into(),
                value: "\"redistributed\"".into(),
                allowed: "cannot go with an obstacle (`obstacle.gap`): every node would be a \
                          contact node and none would keep mass; use \"consistent\" or \
                          \"lumped\""
                    .into(),
            });
        }
        let ends = self.signorini_ends().len() as u64;
        let least = match ends {
            0 => 0,
            1 => REDISTRIBUTED_MIN_ELEMENTS_ONE_END,
            _ => REDISTRIBUTED_MIN_ELEMENTS_TWO_ENDS,
        };
        if self.mesh.elements < least {
            return Err(SceneError::Invalid {
                field: "mesh.elements".into(),
                value: self.mesh.elements.to_string(),
                allowed: format!(
                    "must be at least {least} with `bar.mass` = \"redistributed\" and {ends} \
                     signorini end(s) (the end's mass goes to its two nearest inner nodes, \
                     and two ends' changes may not touch)"
                ),
            });
        }
        Ok(())
    }

    /// Each end's `condition` name and whether it is a Signorini end, as `[heat]` checks its
    /// thermal ends against them.
    pub fn thermal_view(&self) -> [(&'static str, bool); 2] {
        [&self.left, &self.right].map(|e| {
            let name = match e.condition {
                Condition::Signorini => "signorini",
                Condition::Free => "free",
                Condition::Clamped => "clamped",
            };
            (name, e.condition == Condition::Signorini)
        })
    }

    /// Memory a run of this scene needs, estimated before anything is allocated (a bar with a
    /// temperature: [`crate::scene::heat::HEAT_BYTES_PER_NODE`] more per node).
    pub fn estimated_bytes(&self) -> u64 {
        let per_node = BYTES_PER_NODE
            + self
                .heat
                .as_ref()
                .map_or(0, |_| crate::scene::heat::HEAT_BYTES_PER_NODE);
        (self.mesh.elements + 1).saturating_mul(per_node)
    }

    /// The scene with `2^level` times as many elements and a step `2^level` times smaller
    /// (dx and dt refined together, exactly, as in every refinement study here).
    pub fn refined(&self, level: u32) -> Scene {
        let mut s = self.clone();
        s.mesh.elements = self.mesh.elements << level;
        s.time.step = self.time.step / f64::from(1u32 << level);
        s
    }

    /// Number of elements `J + 1`.
    pub fn elements(&self) -> usize {
        self.mesh.elements as usize
    }

    /// `Δx = L / (J + 1)`.
    pub fn dx(&self) -> f64 {
        self.bar.length / self.mesh.elements as f64
    }

    /// Number of time steps: `T / dt` rounded to the nearest integer, so the run ends at
    /// `steps · dt`, which differs from `T` by at most `dt / 2`.
    pub fn steps(&self) -> usize {
        (self.time.end / self.time.step).round() as usize
    }

    /// The sampling of the profile file ([`OutputSpec::sampling`] on the bar's line of nodes).
    pub fn output_sampling(&self) -> OutputSampling {
        self.output
            .sampling(self.steps() as u64, [self.elements() as u64 + 1, 1])
    }

    /// The Signorini ends as `(side, gap)`, left first; the gap at `t = 0` (a validated scene's
    /// gaps evaluate; one that does not is left out, as [`Scene::validate`] refuses it).
    pub fn signorini_ends(&self) -> Vec<(Side, f64)> {
        let end = |side: Side| {
            if side == Side::Left {
                &self.left
            } else {
                &self.right
            }
        };
        self.moving_ends()
            .into_iter()
            .filter_map(|(side, a)| {
                let a0 = end(side).constant_gap().or_else(|| a.eval(0.0, 0.0).ok())?;
                Some((side, a0))
            })
            .collect()
    }

    /// Whether a Signorini end's gap depends on `t` (an end obstacle that moves).
    pub fn has_moving_ends(&self) -> bool {
        self.moving_ends().iter().any(|(_, a)| a.depends_on_t())
    }

    /// The Signorini ends as `(side, a(t))`, left first (a constant gap as a constant
    /// expression); ends whose gap does not parse are left out ([`Scene::validate`] refuses
    /// them).
    pub fn moving_ends(&self) -> Vec<(Side, Expression)> {
        let mut v = Vec::new();
        for (side, end) in [(Side::Left, &self.left), (Side::Right, &self.right)] {
            if end.condition == Condition::Signorini
                && let Ok(Some(a)) = end.gap_expression(&format!("{}.gap", side.name()))
            {
                v.push((side, a));
            }
        }
        v
    }
}

/// An end of the bar.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize)]
#[serde(rename_all = "lowercase")]
pub enum Side {
    Left,
    Right,
}

impl Side {
    pub fn name(self) -> &'static str {
        match self {
            Side::Left => "left",
            Side::Right => "right",
        }
    }
}

/// How far `time.end / time.step` may miss a whole number of steps, relative to it: decimal
/// inputs such as `0.005` carry binary round-off (a few ulps, ~1e-15 relative, in the ratio), and
/// steps typed to 10 digits (`0.3333333333` for 1/3) stay within 1e-10; below `1/MAX_STEPS` a
/// tenth of a step is still caught at the largest step count.
pub const TIME_GRID_TOL: f64 = 1e-10;

/// Significant digits of the suggested `time.end` and `time.step` values (enough to divide to
/// within [`TIME_GRID_TOL`], few enough to read).
const SUGGESTION_DIGITS: usize = 12;

/// `time.step` must divide `time.end` (up to [`TIME_GRID_TOL`]): the run then ends at
/// `time.end` exactly instead of at the nearest multiple of the step. Refused otherwise, with
/// the nearest valid ends for this step and the nearest valid steps for this end.
pub(crate) fn check_time_grid(step: f64, end: f64) -> Result<(), SceneError> {
    let ratio = end / step;
    let n = ratio.round();
    if n >= 1.0 && (ratio - n).abs() <= TIME_GRID_TOL * n {
        return Ok(());
    }
    // Rounded to SUGGESTION_DIGITS significant digits and printed in the shortest form.
    let short = |x: f64| {
        format!("{x:.prec$e}", prec = SUGGESTION_DIGITS - 1)
            .parse::<f64>()
            .map_or_else(|_| x.to_string(), |r| r.to_string())
    };
    let plural = |n: f64| if n == 1.0 { "step" } else { "steps" };
    let (below, above) = (ratio.floor(), ratio.ceil());
    let candidates: Vec<f64> = [below, above].into_iter().filter(|k| *k >= 1.0).collect();
    let ends: Vec<String> = candidates
        .iter()
        .map(|k| format!("time.end = {} ({k} {})", short(k * step), plural(*k)))
        .collect();
    let steps: Vec<String> = candidates
        .iter()
        .rev()
        .map(|k| format!("time.step = {} ({k} {})", short(end / k), plural(*k)))
        .collect();
    Err(SceneError::Invalid {
        field: "time.step".into(),
        value: step.to_string(),
        allowed: format!(
            "does not divide `time.end` = {end} (time.end / time.step = {}, not a whole number \
             of steps; the run would end at a multiple of the step, not at time.end); \
             nearest valid ends for this step: {}; nearest valid steps for this end: {}",
            short(ratio),
            ends.join(" or "),
            steps.join(" or ")
        ),
    })
}

pub(crate) fn positive(field: &str, value: f64) -> Result<(), SceneError> {
    if value.is_finite() && value > 0.0 {
        Ok(())
    } else {
        Err(invalid(field, value, "must be a finite number > 0"))
    }
}

/// A TOML error as the scene's syntax error.
pub(crate) fn toml_syntax(e: toml::de::Error) -> SceneError {
    SceneError::Syntax(e.to_string().trim_end().to_string())
}

/// `table` with the `key=value` overrides applied, read as a scene of type `T` (not yet
/// validated): the bar's and the plane's parsing share it.
pub(crate) fn with_overrides<T: serde::de::DeserializeOwned>(
    table: toml::Table,
    overrides: &[String],
) -> Result<T, SceneError> {
    overridden(table, overrides)?
        .try_into()
        .map_err(toml_syntax)
}

/// `table` with the `key=value` overrides applied.
pub(crate) fn overridden(
    mut table: toml::Table,
    overrides: &[String],
) -> Result<toml::Table, SceneError> {
    for assignment in overrides {
        apply_override(&mut table, assignment)?;
    }
    Ok(table)
}

pub(crate) fn apply_override(table: &mut toml::Table, assignment: &str) -> Result<(), SceneError> {
    let fail = |reason: &str| SceneError::Override {
        assignment: assignment.to_string(),
        reason: reason.to_string(),
    };
    let (key, raw) = assignment
        .split_once('=')
        .ok_or_else(|| fail("expected key=value, e.g. time.step=0.001"))?;
    let (key, raw) = (key.trim(), raw.trim());
    let value = match toml::from_str::<toml::Table>(&format!("v = {raw}")) {
        Ok(mut t) => t.remove("v").expect("parsed key"),
        Err(_) => toml::Value::String(raw.to_string()),
    };
    let parts: Vec<&str> = key.split('.').collect();
    if parts.len() < 2 || parts.iter().any(|p| p.is_empty()) {
        return Err(fail(
            "the key must be section.field (or section.table.field), e.g. bar.viscosity or \
             edges.bottom.gap",
        ));
    }
    // Each part but the last names a table (inline or not), made when absent.
    let (field, tables) = parts.split_last().expect("at least two parts");
    let mut section = table;
    for (depth, name) in tables.iter().enumerate() {
        let entry = section
            .entry(name.to_string())
            .or_insert_with(|| toml::Value::Table(toml::Table::new()));
        section = entry
            .as_table_mut()
            .ok_or_else(|| fail(&format!("`{}` is not a table", parts[..=depth].join("."))))?;
    }
    section.insert(field.to_string(), value);
    Ok(())
}
