//! `history.csv`: one row per step, the same columns for both bodies. The energy identity's
//! terms (empty on steps whose identity was not measured), then per group of constraints its
//! contact state (a single constraint: `gap_G,reaction_G`; a set: the constraints in contact,
//! the extent `s` of the contact, the least gap and the total reaction, and for an edge with
//! frictional nodes `tangential_reaction_G`, their tangential total), then the iterations.
//! Optional columns follow `identity_residual` ([`OptionalColumns`]): `obstacle_work` when an
//! obstacle moves; with friction, the friction dissipation `D_f` (empty when not measured) and
//! the frictional nodes that stick and slip; `sliding_work` when an obstacle slides; for a bar
//! with a temperature, the identity's thermal terms.

use crate::output::text::{push_time, push_value};
use crate::scheme::StepRecord;
use crate::scheme::body::HeatOutputs;
use crate::scheme::contact::{ContactSet, Group, MAX_GROUPS};
use std::io::Write;

/// The columns of every run.
const ENERGY_COLUMNS: &str =
    "step,t,energy,work,viscous_dissipation,contact_dissipation,identity_residual";

/// The column of a run whose obstacles move.
const OBSTACLE_COLUMN: &str = ",obstacle_work";
/// The columns of a run with friction.
const FRICTION_COLUMNS: &str = ",friction_dissipation,stick_nodes,slip_nodes";
/// The column of a run whose obstacles slide along their edges.
const SLIDING_COLUMN: &str = ",sliding_work";
/// The thermal terms of a bar with a temperature.
const THERMAL_COLUMNS: &str =
    ",thermal_energy,thermal_dissipation,exchange,heat_supply,smoothing_dissipation";

/// Which optional columns a run writes after `identity_residual`.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct OptionalColumns {
    /// An obstacle moves: `obstacle_work`.
    pub moving: bool,
    /// Some edge has friction: `friction_dissipation`, `stick_nodes`, `slip_nodes`.
    pub friction: bool,
    /// An obstacle slides along its edge: `sliding_work`.
    pub sliding: bool,
    /// The body has a temperature: `thermal_energy`, `thermal_dissipation`, `exchange`,
    /// `heat_supply`, `smoothing_dissipation`.
    pub thermal: bool,
    /// The heat balance of a body that reports one: `heat_content`, `frictional_supply`,
    /// `frictional_heating`, `heat_to_obstacle` ([`HeatOutputs`]).
    pub heat: HeatOutputs,
    /// The groups, in order, with frictional nodes: `tangential_reaction_G` after
    /// `reaction_G`.
    pub tangential: [bool; MAX_GROUPS],
}

impl OptionalColumns {
    /// The columns of a run with the constraints `contact`, of a body with a temperature or
    /// not.
    pub fn of(contact: &ContactSet, thermal: bool, heat: HeatOutputs) -> Self {
        let mut tangential = [false; MAX_GROUPS];
        for &k in &contact.friction().normals {
            if let Some(g) = contact.groups().iter().position(|g| g.range.contains(&k)) {
                tangential[g] = true;
            }
        }
        Self {
            moving: contact.is_moving(),
            friction: !contact.friction().is_empty(),
            sliding: contact.is_sliding(),
            thermal,
            heat,
            tangential,
        }
    }
}

/// The header line for a run with the contact `groups` and the `optional` columns.
pub fn header(groups: &[Group], optional: OptionalColumns) -> String {
    let mut h = String::from(ENERGY_COLUMNS);
    if optional.moving {
        h.push_str(OBSTACLE_COLUMN);
    }
    if optional.friction {
        h.push_str(FRICTION_COLUMNS);
    }
    if optional.sliding {
        h.push_str(SLIDING_COLUMN);
    }
    if optional.thermal {
        h.push_str(THERMAL_COLUMNS);
    }
    if optional.heat.heat_content {
        h.push_str(",heat_content");
    }
    if optional.heat.frictional_heating {
        h.push_str(",frictional_supply,frictional_heating");
    }
    if optional.heat.obstacle_heating {
        h.push_str(",heat_to_obstacle");
    }
    for (g, tangential) in groups.iter().zip(optional.tangential) {
        let n = g.name;
        if g.range.len() == 1 {
            h.push_str(&format!(",gap_{n},reaction_{n}"));
        } else {
            h.push_str(&format!(
                ",contact_nodes_{n},contact_s_min_{n},contact_s_max_{n},min_gap_{n},reaction_{n}"
            ));
        }
        if tangential {
            h.push_str(&format!(",tangential_reaction_{n}"));
        }
    }
    h.push_str(",iterations\n");
    h
}

/// Appends the row of `r` (`row` is cleared first); `groups` and `optional` as in the header.
pub fn row(r: &StepRecord, groups: &[Group], optional: OptionalColumns, row: &mut Vec<u8>) {
    row.clear();
    write!(row, "{},", r.step).expect("writing to a vector");
    push_time(r.time, row);
    for v in [
        r.energy,
        r.work,
        r.viscous_dissipation,
        r.contact_dissipation,
        r.identity_residual,
    ] {
        row.push(b',');
        // Not measured ([output] diagnostics_every): empty cells, not zeros.
        if r.measured {
            push_value(v, row);
        }
    }
    if optional.moving {
        row.push(b',');
        if r.measured {
            push_value(r.obstacle_work, row);
        }
    }
    if optional.friction {
        row.push(b',');
        if r.measured {
            push_value(r.friction_dissipation, row);
        }
        write!(row, ",{},{}", r.stick_nodes, r.slip_nodes).expect("writing to a vector");
    }
    if optional.sliding {
        row.push(b',');
        if r.measured {
            push_value(r.sliding_work, row);
        }
    }
    if optional.thermal {
        let h = r.heat.unwrap_or_default();
        for v in [h.energy, h.dissipation, h.exchange, h.supply, h.smoothing] {
            row.push(b',');
            if r.measured {
                push_value(v, row);
            }
        }
    }
    // The heat balance is kept at every step (the identity's term only where measured).
    let h = r.heat.unwrap_or_default();
    if optional.heat.heat_content {
        row.push(b',');
        push_value(h.heat_content, row);
    }
    if optional.heat.frictional_heating {
        row.push(b',');
        if r.measured {
            push_value(h.frictional_supply, row);
        }
        row.push(b',');
        push_value(h.frictional_heating, row);
    }
    if optional.heat.obstacle_heating {
        row.push(b',');
        push_value(h.obstacle_heating, row);
    }
    for ((g, s), tangential) in groups
        .iter()
        .zip(&r.contact.groups)
        .zip(optional.tangential)
    {
        row.push(b',');
        if g.range.len() == 1 {
            push_value(s.min_gap, row);
        } else {
            write!(row, "{},", s.contact_nodes).expect("writing to a vector");
            for x in s.extent {
                // No contact: empty cells.
                if !x.is_nan() {
                    push_time(x, row);
                }
                row.push(b',');
            }
            push_value(s.min_gap, row);
        }
        row.push(b',');
        push_value(s.reaction, row);
        if tangential {
            row.push(b',');
            push_value(s.tangential_reaction, row);
        }
    }
    writeln!(row, ",{}", r.iterations).expect("writing to a vector");
}
