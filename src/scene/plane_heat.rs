//! Checks the `[heat]` table of a plane scene ([`crate::scene::plane::PlaneHeat`]): the temperature
//! `θ_t − κ Δθ + γ div u_t = q` (the stress gains `−γθI`), its initial
//! value (an expression in `x`, `y`), source (in `x`, `y`, `t`), and per edge (`left`, `right`,
//! `bottom`, `top`) the bar's thermal conditions: insulated (the default), a fixed temperature
//! `value` (in the edge's coordinate `s` and `t`) or, on a Signorini edge, an exchange with
//! the obstacle while in contact; on a frictional edge, `frictional_heating = η` (0 ≤ η ≤ 1,
//! default 1) is the share of the friction dissipation that enters the body as heat. Errors
//! name the key. Scheme: docs/thermal.md, "The plane body".

use crate::scene::SceneError;
use crate::scene::error::invalid;
use crate::scene::expr::Expression;
use crate::scene::heat::{
    EndHeat, ThermalCondition, check_condition_keys, check_material, exchange_coefficient,
};
use crate::scene::plane::{EDGE_NAMES, EdgeCondition, Edges, PlaneHeat, ThermalEdge};

/// The parsed `[heat]` of a plane scene.
#[derive(Clone, Debug)]
pub struct PlaneHeatExpressions {
    /// `γ`.
    pub coupling: f64,
    pub diffusivity: f64,
    /// `θ(x, y, 0)`.
    pub temperature: Expression,
    pub source: Option<Expression>,
    /// `left, right, bottom, top`.
    pub edges: [EndHeat; 4],
    /// `η` of each edge (1 where not given; read on frictional edges only).
    pub frictional_heating: [f64; 4],
}

impl PlaneHeat {
    /// The edges' tables in the order `left, right, bottom, top`.
    pub fn edges(&self) -> [&ThermalEdge; 4] {
        [&self.left, &self.right, &self.bottom, &self.top]
    }

    /// Checks every key against its range and against the mechanical edges; the error names
    /// the key.
    pub fn validate(&self, edges: &Edges) -> Result<PlaneHeatExpressions, SceneError> {
        check_material(self.coupling, self.diffusivity)?;
        let temperature = Expression::parse_plane("heat.temperature", &self.temperature, false)?;
        let source = match &self.source {
            Some(text) => Some(Expression::parse_plane("heat.source", text, true)?),
            None => None,
        };
        let frictions = edges.frictions()?;
        let mut parsed: [EndHeat; 4] = Default::default();
        let mut eta = [1.0; 4];
        for (k, spec) in self.edges().into_iter().enumerate() {
            let mechanical = edges.all()[k];
            parsed[k] = spec.validate(k, mechanical.condition)?;
            if let Some(value) = spec.frictional_heating {
                let key = format!("heat.{}.frictional_heating", EDGE_NAMES[k]);
                if frictions[k].is_none() {
                    return Err(SceneError::Invalid {
                        field: key,
                        value: value.to_string(),
                        allowed: format!(
                            "frictional heating belongs to an edge with friction \
                             (`edges.{}.friction` is absent or 0)",
                            EDGE_NAMES[k]
                        ),
                    });
                }
                if !(0.0..=1.0).contains(&value) {
                    return Err(invalid(&key, value, "must be a number in [0, 1]"));
                }
                eta[k] = value;
            }
        }
        Ok(PlaneHeatExpressions {
            coupling: self.coupling,
            diffusivity: self.diffusivity,
            temperature,
            source,
            edges: parsed,
            frictional_heating: eta,
        })
    }
}

impl ThermalEdge {
    fn validate(&self, edge: usize, mechanical: EdgeCondition) -> Result<EndHeat, SceneError> {
        let key = |k: &str| format!("heat.{}.{k}", EDGE_NAMES[edge]);
        let given = [
            self.value.is_some(),
            self.coefficient.is_some(),
            self.obstacle.is_some(),
        ];
        check_condition_keys(self.condition, given, "edge", &key)?;
        match self.condition {
            ThermalCondition::Insulated => Ok(EndHeat::Insulated),
            ThermalCondition::Temperature => {
                let text = self.value.as_ref().ok_or_else(|| SceneError::Invalid {
                    field: key("value"),
                    value: "missing".into(),
                    allowed: "a `temperature` edge needs its temperature, an expression in s and t"
                        .into(),
                })?;
                Ok(EndHeat::Temperature(Expression::parse_edge(
                    &key("value"),
                    text,
                )?))
            }
            ThermalCondition::Exchange => {
                if mechanical != EdgeCondition::Signorini {
                    return Err(SceneError::Invalid {
                        field: key("condition"),
                        value: "\"exchange\"".into(),
                        allowed: format!(
                            "an exchange with the obstacle needs a signorini edge \
                             (`edges.{}.condition` is \"{}\")",
                            EDGE_NAMES[edge],
                            format!("{mechanical:?}").to_lowercase()
                        ),
                    });
                }
                let h = exchange_coefficient(self.coefficient, "edge", &key("coefficient"))?;
                let text = self.obstacle.as_deref().unwrap_or("0");
                let obstacle = Expression::parse_edge(&key("obstacle"), text)?;
                if obstacle.depends_on_x() {
                    return Err(SceneError::Invalid {
                        field: key("obstacle"),
                        value: format!("\"{text}\""),
                        allowed: "the obstacle's temperature is an expression in t alone".into(),
                    });
                }
                Ok(EndHeat::Exchange {
                    coefficient: h,
                    obstacle,
                })
            }
        }
    }
}
