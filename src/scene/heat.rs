//! The `[heat]` table of a bar scene: the temperature deviation `θ` of the thermo-viscoelastic
//! bar, `θ_t − κ θ_xx + γ u_xt = q`, with the stress `u_x + α u_xt − γ θ`; its initial value,
//! source and the thermal condition of each end (insulated, a fixed temperature, or at a
//! Signorini end an exchange with the obstacle while in contact). A scene without the table
//! has no temperature. The keys are public interface; bad values are refused naming the key.

use crate::scene::SceneError;
use crate::scene::error::invalid;
use crate::scene::expr::{Expression, number_or_expression};
use serde::{Deserialize, Serialize};

/// `[heat]`: coupling, diffusivity, initial temperature, source and the ends' conditions.
#[derive(Clone, Debug, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Heat {
    /// `γ >= 0`: the thermal stress `−γ θ` and the heating `γ u_xt` by compression rate.
    pub coupling: f64,
    /// `κ > 0`.
    pub diffusivity: f64,
    /// `θ(x, 0)`, an expression in `x` (default 0).
    #[serde(default = "zero", deserialize_with = "number_or_expression")]
    pub temperature: String,
    /// `q(x, t)`, an expression (default 0: no source).
    #[serde(
        default,
        skip_serializing_if = "Option::is_none",
        deserialize_with = "optional_expression"
    )]
    pub source: Option<String>,
    /// The end at `x = 0` (default insulated).
    #[serde(default)]
    pub left: ThermalEnd,
    /// The end at `x = L` (default insulated).
    #[serde(default)]
    pub right: ThermalEnd,
}

fn zero() -> String {
    "0".to_string()
}

fn optional_expression<'de, D: serde::Deserializer<'de>>(d: D) -> Result<Option<String>, D::Error> {
    number_or_expression(d).map(Some)
}

/// The thermal condition of an end.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum ThermalCondition {
    /// `θ_x = 0`.
    #[default]
    Insulated,
    /// `θ = θ_end(t)` (`value`).
    Temperature,
    /// At a Signorini end: `∓κ θ_x = h (θ − θ_obs(t))` while the end is in contact, insulated
    /// otherwise (`coefficient` `h >= 0`, `obstacle` `θ_obs`).
    Exchange,
}

impl ThermalCondition {
    pub fn name(self) -> &'static str {
        match self {
            ThermalCondition::Insulated => "insulated",
            ThermalCondition::Temperature => "temperature",
            ThermalCondition::Exchange => "exchange",
        }
    }
}

/// `heat.left` / `heat.right`.
#[derive(Clone, Debug, Default, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct ThermalEnd {
    pub condition: ThermalCondition,
    /// `θ_end(t)` of a `temperature` end, an expression in `t`.
    #[serde(
        default,
        skip_serializing_if = "Option::is_none",
        deserialize_with = "optional_expression"
    )]
    pub value: Option<String>,
    /// `h >= 0` of an `exchange` end.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub coefficient: Option<f64>,
    /// `θ_obs(t)` of an `exchange` end, an expression in `t` (default 0).
    #[serde(
        default,
        skip_serializing_if = "Option::is_none",
        deserialize_with = "optional_expression"
    )]
    pub obstacle: Option<String>,
}

/// The parsed thermal condition of one end of the bar or one edge of the plane body.
#[derive(Clone, Debug, Default)]
pub enum EndHeat {
    #[default]
    Insulated,
    /// `θ = value(t)` (on an edge `value(s, t)`).
    Temperature(Expression),
    /// `h` and `θ_obs(t)`.
    Exchange {
        coefficient: f64,
        obstacle: Expression,
    },
}

/// The parsed `[heat]` table.
#[derive(Clone, Debug)]
pub struct HeatExpressions {
    pub temperature: Expression,
    /// `None`: no source.
    pub source: Option<Expression>,
    /// Left, right.
    pub ends: [EndHeat; 2],
}

/// Keys of an end's thermal condition; in `[left]`/`[right]` they mean a thermal end given
/// outside `[heat]` (refused by [`check_end_tables`]).
const THERMAL_END_KEYS: [&str; 3] = ["value", "coefficient", "obstacle"];

impl Heat {
    /// Checks every key against its range and against the bar's ends (`mechanical`: left,
    /// right, each its `condition` name and whether it is a Signorini end); the error names
    /// the key.
    pub fn validate(
        &self,
        mechanical: [(&str, bool); 2],
        obstacle: bool,
    ) -> Result<HeatExpressions, SceneError> {
        check_material(self.coupling, self.diffusivity)?;
        if obstacle {
            return Err(SceneError::Invalid {
                field: "obstacle.gap".into(),
                value: "(set)".into(),
                allowed: "a bar with [heat] takes Signorini conditions at its ends only; an \
                          obstacle under every node is not supported with a temperature"
                    .into(),
            });
        }
        let temperature = Expression::parse("heat.temperature", &self.temperature, false)?;
        let source = match &self.source {
            Some(text) => Some(Expression::parse("heat.source", text, true)?),
            None => None,
        };
        let left = self.left.validate("left", mechanical[0])?;
        let right = self.right.validate("right", mechanical[1])?;
        Ok(HeatExpressions {
            temperature,
            source,
            ends: [left, right],
        })
    }
}

/// `heat.coupling` `γ >= 0` and `heat.diffusivity` `κ > 0`, both finite (the bar's and the
/// plane's `[heat]`).
pub(crate) fn check_material(coupling: f64, diffusivity: f64) -> Result<(), SceneError> {
    if !(coupling.is_finite() && coupling >= 0.0) {
        return Err(invalid(
            "heat.coupling",
            coupling,
            "must be a finite number >= 0",
        ));
    }
    if !(diffusivity.is_finite() && diffusivity > 0.0) {
        return Err(invalid(
            "heat.diffusivity",
            diffusivity,
            "must be a finite number > 0",
        ));
    }
    Ok(())
}

/// The keys of one thermal condition `condition` of a `what` (`end` or `edge`): `value` only on
/// a `temperature` one, `coefficient` and `obstacle` only on an `exchange` one (`given`: whether
/// each of the three is set); `key(k)` names a key in an error.
pub(crate) fn check_condition_keys(
    condition: ThermalCondition,
    [value, coefficient, obstacle]: [bool; 3],
    what: &str,
    key: &dyn Fn(&str) -> String,
) -> Result<(), SceneError> {
    let only = |k: &str, needs: &str| SceneError::Invalid {
        field: key(k),
        value: "(set)".into(),
        allowed: format!(
            "only a `{needs}` {what} has `{k}` (this {what} is `{}`)",
            condition.name()
        ),
    };
    if value && condition != ThermalCondition::Temperature {
        return Err(only("value", "temperature"));
    }
    if condition != ThermalCondition::Exchange {
        if coefficient {
            return Err(only("coefficient", "exchange"));
        }
        if obstacle {
            return Err(only("obstacle", "exchange"));
        }
    }
    Ok(())
}

/// An `exchange` condition's coefficient `h >= 0` (required; `key` names it).
pub(crate) fn exchange_coefficient(
    h: Option<f64>,
    what: &str,
    key: &str,
) -> Result<f64, SceneError> {
    let h = h.ok_or_else(|| SceneError::Invalid {
        field: key.into(),
        value: "missing".into(),
        allowed: format!("an `exchange` {what} needs its coefficient h >= 0"),
    })?;
    if !(h.is_finite() && h >= 0.0) {
        return Err(invalid(key, h, "must be a finite number >= 0"));
    }
    Ok(h)
}

impl ThermalEnd {
    fn validate(&self, side: &str, mechanical: (&str, bool)) -> Result<EndHeat, SceneError> {
        let key = |k: &str| format!("heat.{side}.{k}");
        let given = [
            self.value.is_some(),
            self.coefficient.is_some(),
            self.obstacle.is_some(),
        ];
        check_condition_keys(self.condition, given, "end", &key)?;
        match self.condition {
            ThermalCondition::Insulated => Ok(EndHeat::Insulated),
            ThermalCondition::Temperature => {
                let text = self.value.as_ref().ok_or_else(|| SceneError::Invalid {
                    field: key("value"),
                    value: "missing".into(),
                    allowed: "a `temperature` end needs its temperature, an expression in t".into(),
                })?;
                Ok(EndHeat::Temperature(in_t_only(&key("value"), text)?))
            }
            ThermalCondition::Exchange => {
                if !mechanical.1 {
                    return Err(SceneError::Invalid {
                        field: key("condition"),
                        value: "\"exchange\"".into(),
                        allowed: format!(
                            "an exchange with the obstacle needs a signorini end (`{side}.condition` \
                             is \"{}\")",
                            mechanical.0
                        ),
                    });
                }
                let h = exchange_coefficient(self.coefficient, "end", &key("coefficient"))?;
                let text = self.obstacle.as_deref().unwrap_or("0");
                Ok(EndHeat::Exchange {
                    coefficient: h,
                    obstacle: in_t_only(&key("obstacle"), text)?,
                })
            }
        }
    }
}

/// An end's temperature, `θ_end(t)` or `θ_obs(t)`: an expression in `t` alone (an end is a
/// point, so an `x` in it would be read at one node only); one in `x` is refused naming `key`.
fn in_t_only(key: &str, text: &str) -> Result<Expression, SceneError> {
    let e = Expression::parse(key, text, true)?;
    if e.depends_on_x() {
        return Err(SceneError::Invalid {
            field: key.into(),
            value: format!("\"{text}\""),
            allowed: "an end's temperature is an expression in t alone (the end is a point): \
                      write it without x"
                .into(),
        });
    }
    Ok(e)
}

/// A scene table (after overrides, before it is read) whose `[left]` or `[right]` holds a
/// thermal end's key, or whose `[heat]` names ends without its own required keys: refused
/// naming the key, with where the thermal end belongs.
pub fn check_end_tables(table: &toml::Table) -> Result<(), SceneError> {
    let heat = table.get("heat").and_then(toml::Value::as_table);
    for side in ["left", "right"] {
        let Some(end) = table.get(side).and_then(toml::Value::as_table) else {
            continue;
        };
        let thermal_condition = end
            .get("condition")
            .and_then(toml::Value::as_str)
            .filter(|c| ["insulated", "temperature", "exchange"].contains(c));
        let key = THERMAL_END_KEYS
            .iter()
            .find(|k| end.contains_key(**k))
            .map(|k| k.to_string())
            .or(thermal_condition.map(|_| "condition".to_string()));
        if let Some(key) = key {
            let value = end.get(&key).map_or("?".into(), ToString::to_string);
            return Err(SceneError::Invalid {
                field: format!("{side}.{key}"),
                value,
                allowed: format!(
                    "a thermal end condition belongs in the [heat] table, as \
                     `heat.{side} = {{ condition = ... }}`{}",
                    if heat.is_none() {
                        "; this scene has no [heat] table (a bar without one has no temperature)"
                    } else {
                        ""
                    }
                ),
            });
        }
    }
    if let Some(heat) = heat {
        for required in ["coupling", "diffusivity"] {
            if !heat.contains_key(required) {
                let ends: Vec<&str> = ["left", "right"]
                    .into_iter()
                    .filter(|s| heat.contains_key(*s))
                    .collect();
                let why = if ends.is_empty() {
                    "the [heat] table needs `coupling` (γ >= 0) and `diffusivity` (κ > 0)".into()
                } else {
                    format!(
                        "thermal ends ({}) belong to a body with a temperature: the [heat] table \
                         needs `coupling` (γ >= 0) and `diffusivity` (κ > 0)",
                        ends.iter()
                            .map(|s| format!("heat.{s}"))
                            .collect::<Vec<_>>()
                            .join(", ")
                    )
                };
                return Err(SceneError::Invalid {
                    field: format!("heat.{required}"),
                    value: "missing".into(),
                    allowed: why,
                });
            }
        }
    }
    Ok(())
}

/// Memory per node a temperature adds to a bar's run: the coupled step matrix and its banded
/// factor for each exchange state (up to four), the temperature in the scheme's vectors and
/// the heat data, about 100 doubles with a margin.
pub const HEAT_BYTES_PER_NODE: u64 = 1024;
