//! Mirror and turn symmetry of the plane body with Signorini edges (`tests/plane_symmetry.rs`).
//! A scene reflected (x → W − x, y → H − y) or turned by ±90° or 180° (edges, gaps, initial data
//! and load carried along) is the same continuous problem, and its Q1 grid is the image of the
//! original grid, so its run must be the image of the original run, node by node and step by
//! step, up to the round-off of a different elimination order. Here: the cases ([`Case`]), the
//! symmetries and their maps of scenes and runs ([`Symmetry`], [`Case::image`], [`deviation`]),
//! the check that contact reaches both end nodes of every Signorini edge ([`end_contact`]), and
//! the checks of each test ([`suites`]), whose worst deviations the tolerance registry measures
//! ([`worst_deviation`]) and the tests assert on.

use std::collections::HashMap;
use std::rc::Rc;
use viscobar::scheme::RunError;

// ---- runs ------------------------------------------------------------------------------------

/// One run: per step `n = 1..=N`, `u^n` at every full degree of freedom `2 node + c` (node
/// `i + j (nx + 1)`) and the reaction of every contact normal keyed by (edge name, node).
#[derive(Clone, Debug)]
pub struct Run {
    pub frames: Vec<Frame>,
}

/// `u^n` and the reactions by (edge name, node).
pub type Frame = (Vec<f64>, HashMap<(String, usize), f64>);

/// A run of a scene that failed: the error and the scene's TOML text.
#[derive(Debug)]
pub struct CaseError {
    pub error: RunError,
    pub toml: String,
}

impl std::fmt::Display for CaseError {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(f, "{}\n{}", self.error, self.toml)
    }
}

impl std::error::Error for CaseError {}

impl From<CaseError> for RunError {
    fn from(e: CaseError) -> Self {
        e.error
    }
}

/// Runs the plane scene `toml` with the library (a scene without Signorini edges is refused).
pub fn run(toml: &str) -> Result<Run, CaseError> {
    use viscobar::plane::PlaneSimulation;
    use viscobar::scene::SceneError;
    use viscobar::scene::plane::{EDGE_NAMES, PlaneScene};
    let failed = |error: RunError| CaseError {
        error,
        toml: toml.to_string(),
    };
    let scene = PlaneScene::from_toml(toml, &[]).map_err(|e| failed(e.into()))?;
    let mut sim = PlaneSimulation::new(&scene).map_err(failed)?;
    if sim.contact().is_empty() {
        return Err(failed(RunError::Scene(SceneError::Invalid {
            field: "edges".into(),
            value: "no Signorini edge".into(),
            allowed: "a symmetry case has Signorini edges".into(),
        })));
    }
    let frame = |sim: &PlaneSimulation| {
        let r = sim.body().normals().iter().zip(sim.reactions());
        let r = r.map(|(n, &r)| ((EDGE_NAMES[n.edge].to_string(), n.node), r));
        (sim.displacement_dofs(), r.collect())
    };
    let mut frames = vec![frame(&sim)];
    for _ in 1..scene.steps() {
        sim.step().map_err(failed)?;
        frames.push(frame(&sim));
    }
    Ok(Run { frames })
}

/// The runs of cases, each scene run once.
#[derive(Debug, Default)]
pub struct Runs {
    by_scene: HashMap<String, Rc<Run>>,
}

impl Runs {
    /// The run of `case` (run now if not yet run).
    pub fn of(&mut self, case: &Case) -> Result<Rc<Run>, CaseError> {
        let toml = case.toml();
        if let Some(r) = self.by_scene.get(&toml) {
            return Ok(Rc::clone(r));
        }
        let r = Rc::new(run(&toml)?);
        self.by_scene.insert(toml, Rc::clone(&r));
        Ok(r)
    }
}

// ---- scenes and their images -----------------------------------------------------------------

/// An edge: the axis of its outward normal (0: x, 1: y), and whether it lies at x = W or y = H.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Edge {
    pub axis: usize,
    pub far: bool,
}

pub const BOTTOM: Edge = Edge {
    axis: 1,
    far: false,
};
pub const TOP: Edge = Edge { axis: 1, far: true };
pub const LEFT: Edge = Edge {
    axis: 0,
    far: false,
};
pub const RIGHT: Edge = Edge { axis: 0, far: true };

impl Edge {
    pub fn name(self) -> &'static str {
        match (self.axis, self.far) {
            (0, false) => "left",
            (0, true) => "right",
            (1, false) => "bottom",
            _ => "top",
        }
    }
}

/// A plane scene on `(0, size[0]) × (0, size[1])`, Lamé λ = μ = 1: the expressions are
/// templates in `{x}`, `{y}` (and `t` in the load), each Signorini edge's gap in `{s}`.
#[derive(Clone, Debug)]
pub struct Case {
    pub size: [f64; 2],
    pub cells: [usize; 2],
    pub y_grading: f64,
    pub viscosity: f64,
    pub displacement: [String; 2],
    pub velocity: [String; 2],
    pub load: [String; 2],
    pub signorini: Vec<(Edge, String)>,
    pub step: f64,
    pub end: f64,
    pub method: &'static str,
}

/// An isometry `p ↦ Q p + t` of the rectangle onto its image rectangle `(0, W') × (0, H')`:
/// `Q` a signed permutation, `t` the shift putting the image at the origin.
#[derive(Clone, Copy, Debug)]
pub struct Symmetry {
    pub name: &'static str,
    pub q: [[i32; 2]; 2],
}

/// `x → W − x`: left ↔ right, the bottom and top onto themselves, `s → W − s`.
pub const REFLECT_X: Symmetry = Symmetry {
    name: "x -> W - x",
    q: [[-1, 0], [0, 1]],
};
/// `y → H − y`: bottom ↔ top, `s` kept along them.
pub const REFLECT_Y: Symmetry = Symmetry {
    name: "y -> H - y",
    q: [[1, 0], [0, -1]],
};
/// A quarter turn clockwise, `(x, y) → (y, W − x)`: bottom → left (`s → W − s`), top → right.
pub const TURN_CW: Symmetry = Symmetry {
    name: "quarter turn clockwise",
    q: [[0, 1], [-1, 0]],
};
/// A quarter turn anticlockwise, `(x, y) → (H − y, x)`: bottom → right, top → left.
pub const TURN_ACW: Symmetry = Symmetry {
    name: "quarter turn anticlockwise",
    q: [[0, -1], [1, 0]],
};
/// A half turn, `(x, y) → (W − x, H − y)`: bottom ↔ top, left ↔ right, `s → L − s`.
pub const HALF_TURN: Symmetry = Symmetry {
    name: "half turn",
    q: [[-1, 0], [0, -1]],
};

impl Symmetry {
    /// The axis `i` onto which axis `j` goes and the sign `Q_ij`.
    pub fn image(self, j: usize) -> (usize, i32) {
        (0..2)
            .find_map(|i| (self.q[i][j] != 0).then_some((i, self.q[i][j])))
            .expect("a signed permutation")
    }

    /// The image `(i', j')` of the grid node `(i, j)` of a grid of `cells`.
    pub fn node(self, p: [usize; 2], cells: [usize; 2]) -> [usize; 2] {
        let mut out = [0; 2];
        for j in 0..2 {
            let (i, q) = self.image(j);
            out[i] = if q > 0 { p[j] } else { cells[j] - p[j] };
        }
        out
    }

    /// `Q v`.
    pub fn vector(self, v: [f64; 2]) -> [f64; 2] {
        let mut out = [0.0; 2];
        for (j, vj) in v.into_iter().enumerate() {
            let (i, q) = self.image(j);
            out[i] = f64::from(q) * vj;
        }
        out
    }
}

/// `template` with `{x}`, `{y}` replaced by `subs[0]`, `subs[1]` (simultaneously).
fn substitute(template: &str, subs: &[String; 2]) -> String {
    let (mut out, mut rest) = (String::new(), template);
    while let Some(k) = rest.find('{') {
        out += &rest[..k];
        out += match &rest[k..k + 3] {
            "{x}" => &subs[0],
            "{y}" => &subs[1],
            other => panic!("unknown placeholder {other} in {template}"),
        };
        rest = &rest[k + 3..];
    }
    out + rest
}

impl Case {
    /// The scene's TOML text.
    pub fn toml(&self) -> String {
        let fill = |t: &str| {
            t.replace("{x}", "x")
                .replace("{y}", "y")
                .replace("{s}", "s")
        };
        let pair = |v: &[String; 2]| format!("[\"{}\", \"{}\"]", fill(&v[0]), fill(&v[1]));
        let mut edges = String::new();
        for (e, gap) in &self.signorini {
            let gap = fill(gap);
            edges += &format!(
                "{} = {{ condition = \"signorini\", gap = \"{gap}\" }}\n",
                e.name()
            );
        }
        format!(
            "[plane]\nwidth = {:?}\nheight = {:?}\nlambda = 1.0\nmu = 1.0\nviscosity = {:?}\n\n\
             [edges]\n{edges}\n[initial]\ndisplacement = {}\nvelocity = {}\n\n\
             [load]\ndensity = {}\n\n[mesh]\nnx = {}\nny = {}\ny_grading = {:?}\n\n\
             [time]\nstep = {:?}\nend = {:?}\n\n[solver]\nmethod = \"{}\"\n",
            self.size[0],
            self.size[1],
            self.viscosity,
            pair(&self.displacement),
            pair(&self.velocity),
            pair(&self.load),
            self.cells[0],
            self.cells[1],
            self.y_grading,
            self.step,
            self.end,
            self.method
        )
    }

    /// The image scene under `sym`: fields `v'(p') = Q v(p)`, each Signorini edge onto its
    /// image edge with `g'(s') = g(s)` at the image point.
    pub fn image(&self, sym: Symmetry) -> Case {
        const VAR: [&str; 2] = ["{x}", "{y}"];
        assert!(
            self.y_grading == 1.0 || sym.q[1][1] == 1,
            "the grading is along y: keep y to compare grids"
        );
        let (mut size, mut cells) = ([0.0; 2], [0; 2]);
        let mut subs = [String::new(), String::new()];
        for (j, sub) in subs.iter_mut().enumerate() {
            let (i, q) = sym.image(j);
            (size[i], cells[i]) = (self.size[j], self.cells[j]);
            // The old coordinate j in terms of the new ones.
            *sub = if q > 0 {
                VAR[i].to_string()
            } else {
                format!("({:?} - {})", self.size[j], VAR[i])
            };
        }
        let field = |v: &[String; 2]| {
            let mut out = [String::new(), String::new()];
            for (j, vj) in v.iter().enumerate() {
                let (i, q) = sym.image(j);
                let e = substitute(vj, &subs);
                out[i] = if q > 0 { e } else { format!("-({e})") };
            }
            out
        };
        let signorini = self.signorini.iter().map(|(e, gap)| {
            let (a, qa) = sym.image(e.axis);
            let along = 1 - e.axis;
            let gap = if sym.image(along).1 > 0 {
                gap.clone()
            } else {
                gap.replace("{s}", &format!("({:?} - {{s}})", self.size[along]))
            };
            let edge = Edge {
                axis: a,
                far: e.far != (qa < 0),
            };
            (edge, gap)
        });
        Case {
            size,
            cells,
            displacement: field(&self.displacement),
            velocity: field(&self.velocity),
            load: field(&self.load),
            signorini: signorini.collect(),
            ..self.clone()
        }
    }

    /// The node number of grid node `p`.
    pub fn node(&self, p: [usize; 2]) -> usize {
        p[0] + p[1] * (self.cells[0] + 1)
    }
}

// ---- comparison ------------------------------------------------------------------------------

/// The worst deviation of run `b` (of `case.image(sym)`) from the image of run `a` (of `case`)
/// over every step and node: displacements relative to the run's largest, reactions relative to
/// the largest reaction.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Deviation {
    pub u: f64,
    pub r: f64,
}

/// [`Deviation`] of run `b` of `case.image(sym)` from the image of run `a` of `case` (panics if
/// `b` has other steps or normals than the image of `a`: not the run of the image scene).
pub fn deviation(case: &Case, a: &Run, sym: Symmetry, b: &Run) -> Deviation {
    let image = case.image(sym);
    let edge: HashMap<&str, &str> = case
        .signorini
        .iter()
        .zip(&image.signorini)
        .map(|((e, _), (f, _))| (e.name(), f.name()))
        .collect();
    let [nx, ny] = case.cells;
    assert_eq!(a.frames.len(), b.frames.len(), "steps");
    let (mut du, mut u_max, mut dr, mut r_max) = (0.0f64, 0.0f64, 0.0f64, 0.0f64);
    for ((ua, ra), (ub, rb)) in a.frames.iter().zip(&b.frames) {
        assert_eq!(ra.len(), rb.len(), "contact normals");
        for j in 0..=ny {
            for i in 0..=nx {
                let (na, nb) = (case.node([i, j]), image.node(sym.node([i, j], case.cells)));
                let v = sym.vector([ua[2 * na], ua[2 * na + 1]]);
                for c in 0..2 {
                    du = du.max((ub[2 * nb + c] - v[c]).abs());
                    u_max = u_max.max(v[c].abs());
                }
            }
        }
        for ((e, node), r) in ra {
            let p = [node % (nx + 1), node / (nx + 1)];
            let key = (
                edge[e.as_str()].to_string(),
                image.node(sym.node(p, case.cells)),
            );
            let r_image = rb.get(&key).unwrap_or_else(|| panic!("no normal {key:?}"));
            dr = dr.max((r_image - r).abs());
            r_max = r_max.max(r.abs());
        }
    }
    Deviation {
        u: du / u_max,
        r: dr / r_max,
    }
}

/// One symmetry check: what was compared (method, Signorini edges, viscosity, symmetry) and
/// the deviation found.
#[derive(Clone, Debug, PartialEq)]
pub struct Checked {
    pub what: String,
    pub deviation: Deviation,
}

/// Runs `case` and `case.image(sym)` (each once in `runs`) and compares the image run with the
/// image of the run of `case`.
pub fn check(runs: &mut Runs, case: &Case, sym: Symmetry) -> Result<Checked, CaseError> {
    let a = runs.of(case)?;
    let b = runs.of(&case.image(sym))?;
    let edges: Vec<_> = case.signorini.iter().map(|(e, _)| e.name()).collect();
    Ok(Checked {
        what: format!(
            "{} ({edges:?}, {}) under {}",
            case.method, case.viscosity, sym.name
        ),
        deviation: deviation(case, &a, sym, &b),
    })
}

// ---- contact at the ends of the edges -------------------------------------------------------

/// An end node of a Signorini edge and the largest reaction it carries over the run (0 if it
/// carries no normal).
#[derive(Clone, Debug, PartialEq)]
pub struct EndNode {
    pub edge: &'static str,
    pub node: [usize; 2],
    pub most: f64,
}

/// What [`end_contact`] found in a run.
#[derive(Clone, Debug, PartialEq)]
pub struct EndContact {
    /// The largest reaction of the run.
    pub largest: f64,
    /// Both end nodes of every Signorini edge.
    pub ends: Vec<EndNode>,
    /// How many times the contact set (the normals with `r > 0`) changes from a step to the next.
    pub contact_set_changes: usize,
}

impl EndContact {
    /// The least share of the run's largest reaction that an end node carries at its most.
    pub fn least_share(&self) -> f64 {
        let shares = self.ends.iter().map(|e| e.most / self.largest);
        shares.fold(f64::INFINITY, f64::min)
    }
}

/// The contact at both end nodes of every Signorini edge of `case` in its `run`, and how often
/// the contact set changes: the comparison runs the gap at the ends and the contact solver's
/// choices when each end carries real contact and the set changes at least twice (lands, and
/// changes again).
pub fn end_contact(case: &Case, run: &Run) -> EndContact {
    let reactions = run.frames.iter().flat_map(|(_, r)| r.values());
    let largest = reactions.fold(0.0, |a: f64, &b| a.max(b));
    let mut ends = Vec::new();
    for (e, _) in &case.signorini {
        let along = 1 - e.axis;
        for end in [0, case.cells[along]] {
            let mut p = [0; 2];
            p[e.axis] = if e.far { case.cells[e.axis] } else { 0 };
            p[along] = end;
            let key = (e.name().to_string(), case.node(p));
            let most = run
                .frames
                .iter()
                .map(|(_, r)| r.get(&key).copied().unwrap_or(0.0))
                .fold(0.0, f64::max);
            ends.push(EndNode {
                edge: e.name(),
                node: p,
                most,
            });
        }
    }
    let active: Vec<Vec<&(String, usize)>> = run
        .frames
        .iter()
        .map(|(_, r)| {
            let mut s: Vec<_> = r
                .iter()
                .filter(|(_, r)| **r > 0.0)
                .map(|(k, _)| k)
                .collect();
            s.sort();
            s
        })
        .collect();
    EndContact {
        largest,
        ends,
        contact_set_changes: active.windows(2).filter(|w| w[0] != w[1]).count(),
    }
}

// ---- the cases -------------------------------------------------------------------------------

/// A viscous 2 × 1 block (16 × 8 cells), turned by 0.01 rad, falling with a sideways drift under
/// gravity and a shear load onto a floor whose gap rises from 0.02 to 0.08 along the bottom.
pub fn falling_block(method: &'static str) -> Case {
    let s = |t: &str| t.to_string();
    Case {
        size: [2.0, 1.0],
        cells: [16, 8],
        y_grading: 1.0,
        viscosity: 0.05,
        displacement: [s("-0.01*{y}"), s("0.01*{x}")],
        velocity: [s("0.1"), s("-0.5")],
        load: [s("0.3*{y}"), s("-1")],
        signorini: vec![(BOTTOM, s("0.02 + 0.03*{s}"))],
        step: 0.01,
        end: 2.0,
        method,
    }
}

/// Undamped 2 × 1 block between a floor (gap 0.02 … 0.08) and a ceiling (gap 0.03 … 0.01),
/// started with a vertical velocity growing along x, pushed down, then up, by a load turning
/// in time.
pub fn block_between_walls() -> Case {
    let s = |t: &str| t.to_string();
    Case {
        size: [2.0, 1.0],
        cells: [16, 8],
        y_grading: 1.0,
        viscosity: 0.0,
        displacement: [s("0"), s("0")],
        velocity: [s("0"), s("0.05*{x}")],
        load: [s("0.2"), s("-3*cos(3*t)")],
        signorini: vec![(BOTTOM, s("0.02 + 0.03*{s}")), (TOP, s("0.03 - 0.01*{s}"))],
        step: 0.01,
        end: 2.0,
        method: "exact",
    }
}

/// A viscous 2 × 1 block pushed into the corner of a floor (gap 0.02 … 0.08) and a left wall
/// (gap 0.01 … 0.03): the corner node carries two normals.
pub fn block_in_a_corner() -> Case {
    let s = |t: &str| t.to_string();
    Case {
        viscosity: 0.02,
        velocity: [s("-0.2"), s("-0.1*{x}")],
        load: [s("-0.8"), s("-1")],
        signorini: vec![(BOTTOM, s("0.02 + 0.03*{s}")), (LEFT, s("0.01 + 0.02*{s}"))],
        ..block_between_walls()
    }
}

// ---- the checks of the tests -----------------------------------------------------------------

/// The checks of one test: the run of `base` must reach the ends of its Signorini edges
/// ([`end_contact`]), and each `(case, symmetry)` compares the run of `case` (`base` or an
/// image of it) with the run of its image ([`check`]).
#[derive(Clone, Debug)]
pub struct Suite {
    pub base: Case,
    pub checks: Vec<(Case, Symmetry)>,
}

impl Suite {
    /// `base` checked under each of `symmetries`.
    pub fn new(base: Case, symmetries: &[Symmetry]) -> Suite {
        let checks = symmetries.iter().map(|&s| (base.clone(), s)).collect();
        Suite { base, checks }
    }
}

/// The exact falling block mirrored and turned; then contact on the top (the block's image
/// under `y → H − y`), and that run reflected.
pub fn falling_block_suite() -> Suite {
    let base = falling_block("exact");
    let on_top = base.image(REFLECT_Y);
    let mut suite = Suite::new(base, &[REFLECT_X, TURN_CW, TURN_ACW, REFLECT_Y]);
    suite.checks.push((on_top, REFLECT_X));
    suite
}

/// The undamped block between two walls, mirrored and turned.
pub fn between_walls_suite() -> Suite {
    Suite::new(block_between_walls(), &[REFLECT_X, HALF_TURN, TURN_ACW])
}

/// The block pushed into a corner, mirrored and turned.
pub fn corner_suite() -> Suite {
    Suite::new(block_in_a_corner(), &[REFLECT_X, HALF_TURN, TURN_CW])
}

/// The falling block with the penalty and with OSQP, mirrored.
pub fn solver_suites() -> Vec<Suite> {
    ["penalty", "osqp"]
        .into_iter()
        .map(|method| Suite::new(falling_block(method), &[REFLECT_X]))
        .collect()
}

/// Every suite of `tests/plane_symmetry.rs`.
pub fn suites() -> Vec<Suite> {
    let mut all = vec![falling_block_suite(), between_walls_suite(), corner_suite()];
    all.extend(solver_suites());
    all
}

/// The worst displacement and reaction deviations over every check of every suite (each
/// relative to its run's largest).
pub fn worst_deviation() -> Result<Deviation, CaseError> {
    let mut worst = Deviation::default();
    for suite in suites() {
        let mut runs = Runs::default();
        for (case, sym) in &suite.checks {
            let d = check(&mut runs, case, *sym)?.deviation;
            worst.u = worse(worst.u, d.u);
            worst.r = worse(worst.r, d.r);
        }
    }
    Ok(worst)
}

/// The larger of `a` and `b`, NaN winning (a NaN deviation fails the test's check).
fn worse(a: f64, b: f64) -> f64 {
    if a.is_nan() || b.is_nan() {
        f64::NAN
    } else {
        a.max(b)
    }
}
