//! Coulomb friction on each of the plane body's four edges. A frictional block thrown sideways
//! onto a floor (friction on the bottom edge), turned by a half turn (onto the top edge) and by
//! a quarter turn either way (onto the left and the right edge), geometry, gap, load and initial
//! velocity carried along (`viscobar_certificate::plane::symmetry::Case::image`), is the same
//! continuous problem on the image grid: each turned run must be the image of the bottom run
//! (displacements, normal and tangential reactions, friction dissipation, step by step) up to
//! the round-off of another elimination order, and must differ from the same turned scene
//! without friction, so that an edge whose friction is silently dropped fails. No reference
//! value: the bottom run is the reference, and it slips and sticks (checked).

use std::collections::HashMap;
use viscobar::plane::PlaneSimulation;
use viscobar::scene::plane::{EDGE_NAMES, PlaneScene};
use viscobar_certificate::plane::symmetry::{
    BOTTOM, Case, Edge, HALF_TURN, Run, Symmetry, TURN_ACW, TURN_CW, deviation,
};

/// Coulomb's coefficient of the frictional edge.
const MU: Option<f64> = Some(0.3);
/// Displacements, normal and tangential reactions and friction dissipation of a turned run
/// against the image of the bottom run, relative to each quantity's largest value over the
/// run: the round-off of another elimination order on the image grid (the frictionless
/// symmetry tests allow 1e-13 for reactions) carried through 100 frictional steps; ten times
/// that. The deviations are printed by `cargo test --release --test plane_friction_edges --
/// --nocapture`.
const TURNED_TOL: f64 = 1e-12;
/// Least deviation of a frictional run from the same scene without friction, relative to the
/// largest displacement: friction takes the block's sideways speed of 0.5, so the runs part
/// at order 1 (printed as above); a dropped friction gives 0.
const FRICTION_EFFECT_MIN: f64 = 1e-2;

/// The identity, to compare two runs of one scene with [`deviation`].
const IDENTITY: Symmetry = Symmetry {
    name: "identity",
    q: [[1, 0], [0, 1]],
};

/// A viscous 2 × 1 block (16 × 8 cells), turned by 0.02 rad, thrown sideways at 0.5 onto a
/// floor 0.02 … 0.05 below it (the gap grows along the edge) under gravity and a shear load.
fn thrown_block() -> Case {
    let s = |t: &str| t.to_string();
    Case {
        size: [2.0, 1.0],
        cells: [16, 8],
        y_grading: 1.0,
        viscosity: 0.05,
        displacement: [s("-0.02*{y}"), s("0.02*{x}")],
        velocity: [s("0.5"), s("-0.5")],
        load: [s("0.2*{y}"), s("-1")],
        signorini: vec![(BOTTOM, s("0.02 + 0.015*{s}"))],
        step: 0.01,
        end: 1.0,
        method: "exact",
    }
}

/// The scene's TOML text with friction `mu` on every Signorini edge (none when `mu` is `None`).
fn toml(case: &Case, mu: Option<f64>) -> String {
    let text = case.toml();
    let Some(mu) = mu else { return text };
    let lines = text.lines().map(|l| {
        if l.contains("condition = \"signorini\"") {
            let head = l.strip_suffix(" }").expect("an inline edge table");
            format!("{head}, friction = {mu:?} }}")
        } else {
            l.to_string()
        }
    });
    lines.map(|l| l + "\n").collect()
}

/// A frictional run: the frames of [`Run`] and, per step, the tangential reactions by (edge,
/// node) and `D_f`; with the counts of frictional nodes in contact that slipped and stuck.
struct FrictionRun {
    run: Run,
    tangential: Vec<HashMap<(String, usize), f64>>,
    dissipation: Vec<f64>,
    slips: usize,
    sticks: usize,
}

fn run(case: &Case, mu: Option<f64>) -> FrictionRun {
    let text = toml(case, mu);
    let scene = PlaneScene::from_toml(&text, &[]).unwrap_or_else(|e| panic!("{e}\n{text}"));
    let mut sim = PlaneSimulation::new(&scene).unwrap_or_else(|e| panic!("{e}\n{text}"));
    let friction = sim.contact().friction().clone();
    let key = |sim: &PlaneSimulation, k: usize| {
        let n = &sim.body().normals()[k];
        (EDGE_NAMES[n.edge].to_string(), n.node)
    };
    let frame = |sim: &PlaneSimulation| {
        let r = (0..sim.reactions().len()).map(|k| (key(sim, k), sim.reactions()[k]));
        (sim.displacement_dofs(), r.collect())
    };
    let mut out = FrictionRun {
        run: Run {
            frames: vec![frame(&sim)],
        },
        tangential: vec![HashMap::new()],
        dissipation: vec![0.0],
        slips: 0,
        sticks: 0,
    };
    for _ in 1..scene.steps() {
        let record = sim.step().unwrap_or_else(|e| panic!("{e}\n{text}"));
        out.run.frames.push(frame(&sim));
        let rt = sim.tangential_reactions().iter().enumerate();
        let rt = rt.map(|(j, &r)| (key(&sim, friction.normals[j]), r));
        out.tangential.push(rt.collect());
        out.dissipation.push(record.friction_dissipation);
        out.slips += record.slip_nodes;
        out.sticks += record.stick_nodes;
    }
    out
}

/// The tangent `+e_x` of the bottom and top edges, `+e_y` of the left and right ones.
fn tangent(edge: Edge) -> [f64; 2] {
    if edge.axis == 1 {
        [1.0, 0.0]
    } else {
        [0.0, 1.0]
    }
}

/// The worst deviation, relative to the largest value, of `b`'s tangential reactions and
/// friction dissipation from the image under `sym` of `a`'s (`case` the scene of `a`).
fn friction_deviation(case: &Case, a: &FrictionRun, sym: Symmetry, b: &FrictionRun) -> [f64; 2] {
    let image = case.image(sym);
    let edge: HashMap<&str, (&str, f64)> = (case.signorini.iter().zip(&image.signorini))
        .map(|((e, _), (f, _))| {
            let t = sym.vector(tangent(*e));
            let sign = t[0] * tangent(*f)[0] + t[1] * tangent(*f)[1];
            (e.name(), (f.name(), sign))
        })
        .collect();
    let nx = case.cells[0];
    let (mut dt, mut t_max) = (0.0f64, 0.0f64);
    for (ta, tb) in a.tangential.iter().zip(&b.tangential) {
        assert_eq!(ta.len(), tb.len(), "frictional nodes of {}", sym.name);
        for ((e, node), r) in ta {
            let (f, sign) = edge[e.as_str()];
            let p = [node % (nx + 1), node / (nx + 1)];
            let key = (f.to_string(), image.node(sym.node(p, case.cells)));
            let r_image = tb
                .get(&key)
                .unwrap_or_else(|| panic!("no frictional node {key:?}"));
            dt = dt.max((r_image - sign * r).abs());
            t_max = t_max.max(r.abs());
        }
    }
    let d_max = a.dissipation.iter().fold(0.0f64, |m, d| m.max(d.abs()));
    let dd =
        (a.dissipation.iter().zip(&b.dissipation)).fold(0.0f64, |m, (x, y)| m.max((x - y).abs()));
    [dt / t_max, dd / d_max]
}

#[test]
fn friction_turned_onto_every_edge_reproduces_the_bottom_run_and_is_not_dropped() {
    let base = thrown_block();
    let bottom = run(&base, MU);
    // The bottom run is frictional: its nodes slip and stick, and friction dissipates.
    let total: f64 = bottom.dissipation.iter().sum();
    eprintln!(
        "bottom: {} slipping and {} sticking node-steps, D_f total {total:e}",
        bottom.slips, bottom.sticks
    );
    assert!(bottom.slips > 0 && bottom.sticks > 0 && total > 0.0);
    let turns = [(HALF_TURN, "top"), (TURN_CW, "left"), (TURN_ACW, "right")];
    for (sym, onto) in turns {
        let image = base.image(sym);
        assert_eq!(image.signorini[0].0.name(), onto, "{}", sym.name);
        let turned = run(&image, MU);
        let d = deviation(&base, &bottom.run, sym, &turned.run);
        eprintln!("{onto} ({}): u {:e}, r_N {:e}", sym.name, d.u, d.r);
        let check = |what: &str, v: f64| {
            assert!(
                v <= TURNED_TOL,
                "friction on the {onto} edge: {what} deviates from the bottom run's image by \
                 {v:e} of its largest, beyond {TURNED_TOL:e}"
            );
        };
        check("u", d.u);
        check("r_N", d.r);
        let [dt, dd] = friction_deviation(&base, &bottom, sym, &turned);
        eprintln!("{onto}: r_T {dt:e}, D_f {dd:e}");
        check("r_T", dt);
        check("D_f", dd);
        // The same turned scene without friction runs otherwise.
        let frictionless = run(&image, None);
        let apart = deviation(&image, &turned.run, IDENTITY, &frictionless.run).u;
        eprintln!("{onto}: frictional against frictionless {apart:e}");
        assert!(
            apart >= FRICTION_EFFECT_MIN,
            "friction on the {onto} edge changes the run by only {apart:e} of its largest \
             displacement: dropped?"
        );
    }
}
