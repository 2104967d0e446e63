//! Which algorithm solves a step for each `[solver] method`: one table, [`ALGORITHMS`], keyed
//! by the shape of the step problem ([`Shape`], named by the body), that every body's
//! construction reads through [`algorithm_for`]; README's "Step solvers" section prints it
//! ([`markdown_table`], checked by a test).

use serde::{Deserialize, Serialize};

/// Which step solver a scene asks for: `[solver] method`.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum SolverMethod {
    /// The step problem solved exactly to round-off, by the algorithm [`ALGORITHMS`] gives.
    #[default]
    Exact,
    /// OSQP (ADMM, Stellato et al. 2020), every answer audited against the KKT conditions.
    Osqp,
    /// The talk's penalised problem (PP): normal compliance `(u + a)⁻/ε` instead of contact.
    Penalty,
}

impl SolverMethod {
    /// Every method, in the order of [`ALGORITHMS`]' columns.
    pub const ALL: [SolverMethod; 3] = [
        SolverMethod::Exact,
        SolverMethod::Osqp,
        SolverMethod::Penalty,
    ];

    pub fn name(self) -> &'static str {
        match self {
            SolverMethod::Exact => "exact",
            SolverMethod::Osqp => "osqp",
            SolverMethod::Penalty => "penalty",
        }
    }
}

/// The shape of a step problem, as far as the choice of its algorithm depends on it.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Shape {
    /// The bar with bounds at its Signorini ends only (at most two).
    BarEnds,
    /// The bar under an obstacle: a bound at every node.
    BarObstacle,
    /// The thermo-viscoelastic bar: bounds at its ends, the heat coupled or not.
    ThermalEnds,
    /// The plane body's contact normals, at most [`PENALTY_CONDENSED_MAX_NORMALS`].
    PlaneNormals,
    /// More contact normals than [`PENALTY_CONDENSED_MAX_NORMALS`].
    ManyPlaneNormals,
    /// The plane body with Coulomb friction at some of its normals.
    PlaneFriction,
}

impl Shape {
    /// How README's table names the shape.
    pub fn describe(self) -> String {
        let normals = PENALTY_CONDENSED_MAX_NORMALS;
        match self {
            Shape::BarEnds => "bar, Signorini ends".into(),
            Shape::BarObstacle => "bar, obstacle under every node".into(),
            Shape::ThermalEnds => "thermal bar, Signorini ends".into(),
            Shape::PlaneNormals => format!("plane, Signorini edges, up to {normals} normals"),
            Shape::ManyPlaneNormals => format!("plane, Signorini edges, over {normals} normals"),
            Shape::PlaneFriction => "plane, Coulomb friction".into(),
        }
    }
}

/// The algorithms behind [`crate::step::StepSolver`], each the solver type of its name in this
/// layer ([`Algorithm::CondensedPenalty`]: [`crate::step::CondensedLcp`] with `ε > 0`).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Algorithm {
    EndEnumeration,
    BlockPivoting,
    EndPenalty,
    CondensedLcp,
    CondensedPenalty,
    SemismoothPenalty,
    CondensedLemke,
    Osqp,
    OsqpTresca,
}

/// The penalty law is solved on the condensed `S + εI` (as the exact step) up to this many
/// normals (256 MiB of dense arrays), and beyond by the sparse Newton iteration
/// ([`crate::step::SemismoothPenalty`]), which needs no dense matrix: a fixed switch, so that
/// a scene gives the same bits on every machine.
pub const PENALTY_CONDENSED_MAX_NORMALS: u64 = 4096;

/// For each shape, the algorithm of each method in the order of [`SolverMethod::ALL`]
/// (exact, osqp, penalty); `None`: the method is refused for that shape.
pub const ALGORITHMS: [(Shape, [Option<Algorithm>; 3]); 6] = {
    use Algorithm::*;
    [
        (
            Shape::BarEnds,
            [Some(EndEnumeration), Some(Osqp), Some(EndPenalty)],
        ),
        (Shape::BarObstacle, [Some(BlockPivoting), Some(Osqp), None]),
        (Shape::ThermalEnds, [Some(EndEnumeration), None, None]),
        (
            Shape::PlaneNormals,
            [Some(CondensedLcp), Some(Osqp), Some(CondensedPenalty)],
        ),
        (
            Shape::ManyPlaneNormals,
            [Some(CondensedLcp), Some(Osqp), Some(SemismoothPenalty)],
        ),
        (
            Shape::PlaneFriction,
            [Some(CondensedLemke), Some(OsqpTresca), None],
        ),
    ]
};

/// The algorithm [`ALGORITHMS`] gives `method` on `shape`; `None` where it refuses it.
pub fn algorithm_for(method: SolverMethod, shape: Shape) -> Option<Algorithm> {
    let column = SolverMethod::ALL.iter().position(|&m| m == method)?;
    ALGORITHMS
        .iter()
        .find(|(s, _)| *s == shape)
        .and_then(|(_, row)| row[column])
}

/// [`ALGORITHMS`] as the Markdown table that README's "Step solvers" section holds.
pub fn markdown_table() -> String {
    let mut out = String::from("| step problem |");
    for method in SolverMethod::ALL {
        out += &format!(" `{}` |", method.name());
    }
    out += "\n|---|";
    out += &"---|".repeat(SolverMethod::ALL.len());
    out += "\n";
    for (shape, row) in ALGORITHMS {
        out += &format!("| {} |", shape.describe());
        for cell in row {
            match cell {
                Some(a) => out += &format!(" `{a:?}` |"),
                None => out += " refused |",
            }
        }
        out += "\n";
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Every shape has exactly one row, and `exact` an algorithm on each.
    #[test]
    fn every_shape_has_one_row_with_an_exact_algorithm() {
        for (shape, row) in ALGORITHMS {
            let rows = ALGORITHMS.iter().filter(|(s, _)| *s == shape).count();
            assert_eq!(rows, 1, "{shape:?}");
            assert!(row[0].is_some(), "{shape:?} has no exact algorithm");
            assert_eq!(algorithm_for(SolverMethod::Exact, shape), row[0]);
        }
    }

    /// README's "Step solvers" section holds the table as the code has it.
    #[test]
    fn readme_holds_the_table() {
        let readme =
            std::fs::read_to_string(concat!(env!("CARGO_MANIFEST_DIR"), "/README.md")).unwrap();
        let table = markdown_table();
        assert!(
            readme.contains(&table),
            "README.md's \"Step solvers\" table differs from step::algorithm::ALGORITHMS; it \
             should read:\n{table}"
        );
    }
}
