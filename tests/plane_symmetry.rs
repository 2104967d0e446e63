//! Mirror and turn symmetry of the plane body with Signorini edges. A scene reflected
//! (x → W − x, y → H − y) or turned by ±90° or 180° (edges, gaps, initial data and load carried
//! along) is the same continuous problem, and its Q1 grid is the image of the original grid, so
//! its run must be the image of the original run, node by node and step by step, up to the
//! round-off of a different elimination order. The gaps vary along their edges and contact
//! reaches both end nodes of every Signorini edge (checked), so the tests guard, with no
//! reference value: the outward normal and the unknown of each edge (contact on the bottom,
//! top, left and right edges), the edge coordinate `s` at every node of an edge, its end nodes
//! included, and the corner normals of two Signorini edges; for the exact method (α > 0 and
//! α = 0), the penalty and OSQP.

use std::collections::HashMap;

// ---- the library calls (the only ones this file makes) --------------------------------------

/// One run: per step `n = 1..=N`, `u^n` at every full degree of freedom `2 node + c` (node
/// `i + j (nx + 1)`) and the reaction of every contact normal keyed by (edge name, node).
struct Run {
    frames: Vec<Frame>,
}

/// `u^n` and the reactions by (edge name, node).
type Frame = (Vec<f64>, HashMap<(String, usize), f64>);

/// Runs the plane scene `toml` with the library.
fn run(toml: &str) -> Run {
    use viscobar::plane::PlaneSimulation;
    use viscobar::scene::plane::{EDGE_NAMES, PlaneScene};
    let scene = PlaneScene::from_toml(toml, &[]).unwrap_or_else(|e| panic!("{e}\n{toml}"));
    let mut sim = PlaneSimulation::new(&scene).unwrap_or_else(|e| panic!("{e}\n{toml}"));
    let frame = |sim: &PlaneSimulation| {
        assert!(!sim.contact().is_empty(), "the scene has Signorini edges");
        let r = sim.body().normals().iter().zip(sim.reactions());
        let r = r.map(|(n, &r)| ((EDGE_NAMES[n.edge].to_string(), n.node), r));
        (sim.displacement_dofs(), r.collect())
    };
    let mut frames = vec![frame(&sim)];
    for _ in 1..scene.steps() {
        sim.step().unwrap_or_else(|e| panic!("{e}\n{toml}"));
        frames.push(frame(&sim));
    }
    Run { frames }
}

// ---- scenes and their images ------------------------------------------------------------------

/// An edge: the axis of its outward normal (0: x, 1: y), and whether it lies at x = W or y = H.
#[derive(Clone, Copy, Debug, PartialEq)]
struct Edge {
    axis: usize,
    far: bool,
}

const BOTTOM: Edge = Edge {
    axis: 1,
    far: false,
};
const TOP: Edge = Edge { axis: 1, far: true };
const LEFT: Edge = Edge {
    axis: 0,
    far: false,
};

impl Edge {
    fn name(self) -> &'static str {
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
struct Case {
    size: [f64; 2],
    cells: [usize; 2],
    y_grading: f64,
    viscosity: f64,
    displacement: [String; 2],
    velocity: [String; 2],
    load: [String; 2],
    signorini: Vec<(Edge, String)>,
    step: f64,
    end: f64,
    method: &'static str,
}

/// An isometry `p ↦ Q p + t` of the rectangle onto its image rectangle `(0, W') × (0, H')`:
/// `Q` a signed permutation, `t` the shift putting the image at the origin.
#[derive(Clone, Copy, Debug)]
struct Symmetry {
    name: &'static str,
    q: [[i32; 2]; 2],
}

/// `x → W − x`: left ↔ right, the bottom and top onto themselves, `s → W − s`.
const REFLECT_X: Symmetry = Symmetry {
    name: "x -> W - x",
    q: [[-1, 0], [0, 1]],
};
/// `y → H − y`: bottom ↔ top, `s` kept along them.
const REFLECT_Y: Symmetry = Symmetry {
    name: "y -> H - y",
    q: [[1, 0], [0, -1]],
};
/// A quarter turn clockwise, `(x, y) → (y, W − x)`: bottom → left (`s → W − s`), top → right.
const TURN_CW: Symmetry = Symmetry {
    name: "quarter turn clockwise",
    q: [[0, 1], [-1, 0]],
};
/// A quarter turn anticlockwise, `(x, y) → (H − y, x)`: bottom → right, top → left.
const TURN_ACW: Symmetry = Symmetry {
    name: "quarter turn anticlockwise",
    q: [[0, -1], [1, 0]],
};
/// A half turn, `(x, y) → (W − x, H − y)`: bottom ↔ top, left ↔ right, `s → L − s`.
const HALF_TURN: Symmetry = Symmetry {
    name: "half turn",
    q: [[-1, 0], [0, -1]],
};

impl Symmetry {
    /// The axis `i` onto which axis `j` goes and the sign `Q_ij`.
    fn image(self, j: usize) -> (usize, i32) {
        (0..2)
            .find_map(|i| (self.q[i][j] != 0).then_some((i, self.q[i][j])))
            .expect("a signed permutation")
    }

    /// The image `(i', j')` of the grid node `(i, j)` of a grid of `cells`.
    fn node(self, p: [usize; 2], cells: [usize; 2]) -> [usize; 2] {
        let mut out = [0; 2];
        for j in 0..2 {
            let (i, q) = self.image(j);
            out[i] = if q > 0 { p[j] } else { cells[j] - p[j] };
        }
        out
    }

    /// `Q v`.
    fn vector(self, v: [f64; 2]) -> [f64; 2] {
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
    fn toml(&self) -> String {
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
    fn image(&self, sym: Symmetry) -> Case {
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
    fn node(&self, p: [usize; 2]) -> usize {
        p[0] + p[1] * (self.cells[0] + 1)
    }
}

// ---- tolerances ----------------------------------------------------------------------------

// The deviations measured are printed by `cargo test --release --test plane_symmetry --
// --nocapture`.

/// Image run vs image of the run, displacements over the largest: round-off of another
/// elimination order (AMD on the image mesh), measured 1.3e-15 … 4.3e-15 over these cases,
/// so 2.3x the worst.
const SYMMETRY_DISPLACEMENT_TOL: f64 = 1e-14;
/// The same for the reactions over the largest: solved from nearly closed gaps (cancelling)
/// times `S⁻¹ ~ M/Δt²`, an order above u; measured 2.4e-15 … 3.4e-14 over these cases, so 2.9x
/// the worst.
const SYMMETRY_REACTION_TOL: f64 = 1e-13;
/// Least share of the run's largest reaction that each end node of a Signorini edge must carry
/// at some step: real contact, far above round-off (these cases: 0.095 at the least).
const END_REACTION_SHARE: f64 = 0.01;

// ---- comparison -------------------------------------------------------------------------------

/// The worst deviation of run `b` (of `case.image(sym)`) from the image of run `a` (of `case`)
/// over every step and node: displacements relative to the run's largest, reactions relative to
/// the largest reaction.
#[derive(Debug)]
struct Deviation {
    u: f64,
    r: f64,
}

fn deviation(case: &Case, a: &Run, sym: Symmetry, b: &Run) -> Deviation {
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

/// Checks that contact occurs at both end nodes of every Signorini edge of `case` at some step,
/// with a reaction of at least [`END_REACTION_SHARE`] of the run's largest, and that the contact
/// set changes at least twice (lands, and changes again): the comparison then runs the gap at
/// the ends and the contact solver's choices.
fn assert_contact_reaches_the_ends(case: &Case, run: &Run) {
    let reactions = run.frames.iter().flat_map(|(_, r)| r.values());
    let largest = reactions.fold(0.0, |a: f64, &b| a.max(b));
    let mut least_share = f64::INFINITY;
    for (e, _) in &case.signorini {
        let along = 1 - e.axis;
        for end in [0, case.cells[along]] {
            let mut p = [0; 2];
            p[e.axis] = if e.far { case.cells[e.axis] } else { 0 };
            p[along] = end;
            let key = (e.name().to_string(), case.node(p));
            let most = run.frames.iter().map(|(_, r)| r[&key]).fold(0.0, f64::max);
            least_share = least_share.min(most / largest);
            assert!(
                most >= END_REACTION_SHARE * largest,
                "{}: no contact at its end node {p:?} (largest reaction there {most:e}, in the \
                 run {largest:e})",
                e.name()
            );
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
    let changes = active.windows(2).filter(|w| w[0] != w[1]).count();
    eprintln!(
        "end nodes' reaction share at least {least_share:.3}, contact set changes {changes} times"
    );
    assert!(changes >= 2, "the contact set changes {changes} times");
}

/// Runs `case.image(sym)`, checks it against the image of `a` (the run of `case`) and returns
/// it.
fn check(case: &Case, a: &Run, sym: Symmetry) -> Run {
    let image = case.image(sym);
    let b = run(&image.toml());
    let d = deviation(case, a, sym, &b);
    let edges: Vec<_> = case.signorini.iter().map(|(e, _)| e.name()).collect();
    let what = format!(
        "{} ({edges:?}, {}) under {}",
        case.method, case.viscosity, sym.name
    );
    eprintln!("{what}: {d:?}");
    assert!(
        d.u <= SYMMETRY_DISPLACEMENT_TOL,
        "{what}: displacements deviate by {:e} of the largest, beyond {SYMMETRY_DISPLACEMENT_TOL:e}",
        d.u
    );
    assert!(
        d.r <= SYMMETRY_REACTION_TOL,
        "{what}: reactions deviate by {:e} of the largest, beyond {SYMMETRY_REACTION_TOL:e}",
        d.r
    );
    b
}

// ---- the cases -------------------------------------------------------------------------------

/// A viscous 2 × 1 block (16 × 8 cells), turned by 0.01 rad, falling with a sideways drift under
/// gravity and a shear load onto a floor whose gap rises from 0.02 to 0.08 along the bottom.
fn falling_block(method: &'static str) -> Case {
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
fn block_between_walls() -> Case {
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
fn block_in_a_corner() -> Case {
    let s = |t: &str| t.to_string();
    Case {
        viscosity: 0.02,
        velocity: [s("-0.2"), s("-0.1*{x}")],
        load: [s("-0.8"), s("-1")],
        signorini: vec![(BOTTOM, s("0.02 + 0.03*{s}")), (LEFT, s("0.01 + 0.02*{s}"))],
        ..block_between_walls()
    }
}

#[test]
fn a_viscous_block_falling_on_a_sloped_floor_runs_the_same_mirrored_and_turned() {
    let base = falling_block("exact");
    let a = run(&base.toml());
    assert_contact_reaches_the_ends(&base, &a);
    for sym in [REFLECT_X, TURN_CW, TURN_ACW] {
        check(&base, &a, sym);
    }
    // Contact on the top, and that run reflected.
    let on_top = check(&base, &a, REFLECT_Y);
    check(&base.image(REFLECT_Y), &on_top, REFLECT_X);
}

#[test]
fn an_undamped_block_between_two_walls_runs_the_same_mirrored_and_turned() {
    let base = block_between_walls();
    let a = run(&base.toml());
    assert_contact_reaches_the_ends(&base, &a);
    for sym in [REFLECT_X, HALF_TURN, TURN_ACW] {
        check(&base, &a, sym);
    }
}

#[test]
fn a_block_pushed_into_a_corner_runs_the_same_mirrored_and_turned() {
    let base = block_in_a_corner();
    let a = run(&base.toml());
    assert_contact_reaches_the_ends(&base, &a);
    for sym in [REFLECT_X, HALF_TURN, TURN_CW] {
        check(&base, &a, sym);
    }
}

#[test]
fn penalty_and_osqp_runs_are_mirrored_too() {
    for method in ["penalty", "osqp"] {
        let base = falling_block(method);
        let a = run(&base.toml());
        assert_contact_reaches_the_ends(&base, &a);
        check(&base, &a, REFLECT_X);
    }
}
