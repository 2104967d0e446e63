//! ParaView output (`[output] format = "vtu"`): `solution.pvd` and one `vtu/step-N.vtu` per kept
//! step, read back through vtkio (and Python's meshio when it is installed) and checked against
//! the run's own bits: points, quads, displacement, velocity, stress, reactions and gaps;
//! sampled and bounded as the other outputs, written whole or not at all. With friction: the
//! obstacle's full force (its normal part the reaction, its tangential part the tangential
//! reactions, summing to `history.csv`'s totals, inside Coulomb's cone) and the nodes' states
//! (agreeing with the records' stick and slip counts). With `[heat]`: `theta`, the run's
//! temperature.

use std::path::{Path, PathBuf};
use viscobar::internals::plane::stress::von_mises;
use viscobar::output::run_plane_to_dir;
use viscobar::plane::PlaneSimulation;
use viscobar::scene::plane::{PlaneScene, plane_builtin_text};
use viscobar::scheme::Body;
use vtkio::model::{Attribute, DataSet, IOBuffer, Vtk};

fn scene(overrides: &[&str]) -> PlaneScene {
    let mut all = vec![
        "output.format=\"vtu\"".to_string(),
        "output.every=40".into(),
    ];
    all.extend(overrides.iter().map(|s| s.to_string()));
    PlaneScene::from_toml(plane_builtin_text("plane-tilted-drop").unwrap(), &all).unwrap()
}

fn fresh(name: &str) -> PathBuf {
    let d = std::env::temp_dir().join(format!("viscobar-vtu-{}-{name}", std::process::id()));
    let _ = std::fs::remove_dir_all(&d);
    d
}

/// A file's points, quads and point data, read through vtkio.
struct Read {
    points: Vec<f64>,
    connectivity: Vec<u64>,
    arrays: Vec<(String, Vec<f64>)>,
}

impl Read {
    fn array(&self, name: &str) -> &[f64] {
        &self.arrays.iter().find(|(n, _)| n == name).expect(name).1
    }
}

fn f64s(b: &IOBuffer) -> Vec<f64> {
    match b {
        IOBuffer::F64(v) => v.clone(),
        other => panic!("not Float64: {other:?}"),
    }
}

fn read(path: &Path) -> Read {
    let vtk = Vtk::import(path).unwrap();
    let DataSet::UnstructuredGrid { pieces, .. } = vtk.data else {
        panic!("an unstructured grid");
    };
    let piece = pieces[0].load_piece_data(None).unwrap();
    let connectivity = match piece.cells.cell_verts {
        vtkio::model::VertexNumbers::XML { connectivity, .. } => connectivity,
        other => panic!("{other:?}"),
    };
    let arrays = (piece.data.point.iter())
        .map(|a| match a {
            Attribute::DataArray(d) => (d.name.clone(), f64s(&d.data)),
            other => panic!("{other:?}"),
        })
        .collect();
    Read {
        points: f64s(&piece.points),
        connectivity,
        arrays,
    }
}

fn bits(a: &[f64]) -> Vec<u64> {
    a.iter().map(|v| v.to_bits()).collect()
}

/// The files of `scene` in `out` against a run of the same scene stepped here: every kept
/// step's arrays, bit for bit. Returns the number of nodes written per step.
fn check_against_the_run(scene: &PlaneScene, out: &Path) -> usize {
    let summary = run_plane_to_dir("drop", scene, out, false).unwrap();
    let sampling = summary.output.unwrap();
    let pvd = std::fs::read_to_string(out.join("solution.pvd")).unwrap();
    let mut sim = PlaneSimulation::new(scene).unwrap();
    let prepared = PlaneSimulation::prepare(scene).unwrap();
    let body = prepared.body();
    let stride = sampling.node_stride as usize;
    let nodes = viscobar::internals::output::profiles::written_nodes(body.lattice(), stride);
    assert_eq!(nodes.len() as u64, sampling.nodes_written);
    let mut files = 0;
    let steps = scene.steps();
    for n in 1..=steps {
        if n > 1 {
            sim.step().unwrap();
        }
        if !(n % 40 == 0 || n == steps) {
            continue;
        }
        let name = format!("vtu/step-{n:03}.vtu");
        assert!(
            pvd.contains(&format!(
                "timestep=\"{}\" group=\"\" part=\"0\" file=\"{name}\"",
                {
                    let mut t = Vec::new();
                    viscobar::internals::output::text::push_time(sim.time(), &mut t);
                    String::from_utf8(t).unwrap()
                }
            )),
            "{name} in {pvd}"
        );
        let r = read(&out.join(&name));
        files += 1;
        let body = sim.body();
        let state = sim.state();
        let v: Vec<f64> = state.w.iter().map(|w| w * state.scale).collect();
        let at = |f: &[f64], n: usize, c: usize| body.unknown_of(2 * n + c).map_or(0.0, |i| f[i]);
        let (mut u, mut vel, mut pts) = (Vec::new(), Vec::new(), Vec::new());
        for &node in &nodes {
            u.extend([at(state.u, node, 0), at(state.u, node, 1), 0.0]);
            vel.extend([at(&v, node, 0), at(&v, node, 1), 0.0]);
            let (x, y) = body.point(node);
            pts.extend([x, y.unwrap(), 0.0]);
        }
        assert_eq!(bits(&r.points), bits(&pts), "{name}: points");
        assert_eq!(
            bits(r.array("displacement")),
            bits(&u),
            "{name}: displacement"
        );
        assert_eq!(bits(r.array("velocity")), bits(&vel), "{name}: velocity");
        let stress = body.nodal_stress(state.u, &v).unwrap();
        let pick = |f: &dyn Fn(&[f64; 4]) -> f64| -> Vec<f64> {
            nodes.iter().map(|&n| f(&stress[n])).collect()
        };
        assert_eq!(bits(r.array("sigma_xx")), bits(&pick(&|s| s[0])), "{name}");
        assert_eq!(bits(r.array("sigma_yy")), bits(&pick(&|s| s[1])), "{name}");
        assert_eq!(bits(r.array("sigma_xy")), bits(&pick(&|s| s[2])), "{name}");
        assert_eq!(
            bits(r.array("von_mises")),
            bits(&pick(&|s| von_mises(*s))),
            "{name}"
        );
        // The bottom edge's constraints, in the order of its nodes (all written when the stride
        // is 1): reaction along +y (the obstacle pushes along −n = +y), the gap.
        let (reaction, gap) = (r.array("contact_reaction"), r.array("gap"));
        let mut gaps = vec![0.0; sim.contact().len()];
        sim.gaps_into(&mut gaps);
        for (w, &node) in nodes.iter().enumerate() {
            let k = body
                .unknown_of(2 * node + 1)
                .and_then(|i| (0..sim.contact().len()).find(|&k| sim.contact().unknown(k) == i));
            match k {
                Some(k) => {
                    let want = sim.reactions()[k] * sim.contact().direction(k);
                    assert_eq!(reaction[3 * w + 1].to_bits(), want.to_bits(), "{name}");
                    assert_eq!(gap[w].to_bits(), gaps[k].to_bits(), "{name}: gap at {node}");
                    assert_eq!(r.array("contact_constraints")[w], 1.0);
                }
                None => {
                    assert_eq!((reaction[3 * w + 1], gap[w]), (0.0, 0.0));
                    assert_eq!(r.array("contact_constraints")[w], 0.0);
                }
            }
            assert_eq!(reaction[3 * w], 0.0);
        }
        // Without friction the full force is the normal reaction and every state is 0.
        assert_eq!(bits(r.array("contact_force")), bits(reaction), "{name}");
        assert!(r.array("friction_state").iter().all(|&s| s == 0.0));
        // Quads: (cols − 1)(rows − 1) of them, every index a written node.
        assert!(r.connectivity.iter().all(|&i| (i as usize) < nodes.len()));
    }
    assert_eq!(
        files as u64 + 1,
        sampling.kept_steps,
        "the kept steps and t = 0"
    );
    assert!(pvd.contains("timestep=\"0\" group=\"\" part=\"0\" file=\"vtu/step-000.vtu\""));
    nodes.len()
}

#[test]
fn the_files_read_back_to_the_runs_bits() {
    let out = fresh("bits");
    let nodes = check_against_the_run(&scene(&[]), &out);
    assert_eq!(nodes, 17 * 9, "every node of 16 × 8 cells");
    let r = read(&out.join("vtu/step-240.vtu"));
    assert_eq!(r.connectivity.len(), 4 * 16 * 8);
    let _ = std::fs::remove_dir_all(&out);
}

/// `[output] max_rows` bounds the files as it bounds displacement.csv: a strided sub-lattice of
/// nodes, the edges kept, joined into coarser quads.
#[test]
fn the_files_are_sampled_and_bounded_as_the_profiles() {
    let out = fresh("bounded");
    let s = scene(&["output.max_rows=300"]);
    let nodes = check_against_the_run(&s, &out);
    let sampling = s.output_sampling();
    assert!(
        sampling.node_stride > 1 && sampling.rows <= 300,
        "{sampling:?}"
    );
    assert_eq!(nodes as u64, sampling.nodes_written);
    let _ = std::fs::remove_dir_all(&out);
}

/// A run that fails leaves an earlier run's files untouched; a successful one replaces the
/// whole `vtu/` folder (no stale step of an earlier, longer run survives) and a later csv run
/// removes the ParaView files.
#[test]
fn the_files_are_written_whole_or_not_at_all() {
    let out = fresh("whole");
    run_plane_to_dir("drop", &scene(&["output.every=20"]), &out, false).unwrap();
    assert!(out.join("vtu/step-020.vtu").exists());
    let before = std::fs::read(out.join("vtu/step-240.vtu")).unwrap();
    let failing = scene(&["edges.bottom.gap=\"0.05 + sqrt(0.5 - t)\""]);
    assert!(run_plane_to_dir("drop", &failing, &out, false).is_err());
    assert_eq!(std::fs::read(out.join("vtu/step-240.vtu")).unwrap(), before);
    run_plane_to_dir("drop", &scene(&[]), &out, false).unwrap();
    assert!(!out.join("vtu/step-020.vtu").exists(), "a stale step file");
    assert!(out.join("vtu/step-040.vtu").exists());
    let csv = scene(&["output.format=\"csv\""]);
    run_plane_to_dir("drop", &csv, &out, false).unwrap();
    assert!(!out.join("vtu").exists() && !out.join("solution.pvd").exists());
    assert!(out.join("displacement.csv").exists());
    let _ = std::fs::remove_dir_all(&out);
}

/// A bar scene refuses "vtu", naming `output.format`.
#[test]
fn a_bar_scene_refuses_vtu() {
    let e = viscobar::Scene::from_toml(
        viscobar::scene::builtin_text("impact").unwrap(),
        &["output.format=\"vtu\"".into()],
    )
    .unwrap_err()
    .to_string();
    assert!(
        e.contains("output.format") && e.contains("plane body"),
        "{e}"
    );
}

/// Python's meshio reads the last file to the same bits (every array printed with `repr`,
/// which round-trips). Skipped, with a message, where meshio is not installed.
#[test]
fn meshio_reads_the_files_to_the_same_bits() {
    let probe = std::process::Command::new("python3")
        .args(["-c", "import meshio"])
        .output();
    if !probe.is_ok_and(|o| o.status.success()) {
        eprintln!(
            "skipped: Python's meshio is not installed (pip install meshio to run this check)"
        );
        return;
    }
    let out = fresh("meshio");
    run_plane_to_dir("drop", &scene(&[]), &out, false).unwrap();
    let file = out.join("vtu/step-240.vtu");
    let script = "import sys, meshio\n\
                  m = meshio.read(sys.argv[1])\n\
                  print('points', ' '.join(repr(float(v)) for v in m.points.ravel()))\n\
                  print('quads', ' '.join(str(int(v)) for v in m.cells_dict['quad'].ravel()))\n\
                  for k in sorted(m.point_data):\n    \
                      print(k, ' '.join(repr(float(v)) for v in m.point_data[k].ravel()))\n";
    let o = std::process::Command::new("python3")
        .args(["-c", script, file.to_str().unwrap()])
        .output()
        .unwrap();
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let text = String::from_utf8(o.stdout).unwrap();
    let r = read(&file);
    let mut seen = 0;
    for line in text.lines() {
        let (name, values) = line.split_once(' ').unwrap();
        let parsed: Vec<f64> = values.split(' ').map(|v| v.parse().unwrap()).collect();
        let want: Vec<f64> = match name {
            "points" => r.points.clone(),
            "quads" => r.connectivity.iter().map(|&i| i as f64).collect(),
            other => r.array(other).to_vec(),
        };
        assert_eq!(bits(&parsed), bits(&want), "{name}");
        seen += 1;
    }
    assert_eq!(seen, 2 + 11, "points, quads and the eleven arrays");
    let _ = std::fs::remove_dir_all(&out);
}

/// `|r_T| <= μ r_N` at a node, up to this relative to the step's largest `μ r_N`: the exact
/// frictional step solves Coulomb's law by Lemke's pivots, exact but for their rounding (its
/// audit holds the cone to a few ulps of the reactions).
const CONE_ROUNDING: f64 = 1e-12;

/// The frictional tilted drop written every step: at each step, each written node's
/// `contact_force` is its `contact_reaction` plus its tangential reaction (the run's bits); the
/// tangential parts along the floor sum to `history.csv`'s `tangential_reaction_bottom` and lie
/// in Coulomb's cone; `friction_state` is 1 (stick) or 2 (slip) at as many nodes as the
/// records' `stick_nodes` and `slip_nodes`, 0 elsewhere; and the run has steps of both.
#[test]
fn the_friction_force_and_state_read_back_to_the_run() {
    let out = fresh("friction");
    let overrides = ["output.format=\"vtu\"".to_string(), "output.every=1".into()];
    let text = plane_builtin_text("plane-friction-tilted-drop").unwrap();
    let scene = PlaneScene::from_toml(text, &overrides).unwrap();
    run_plane_to_dir("friction", &scene, &out, false).unwrap();
    let history = std::fs::read_to_string(out.join("history.csv")).unwrap();
    let mut lines = history.lines();
    let header: Vec<&str> = lines.next().unwrap().split(',').collect();
    let column = |c: &str| header.iter().position(|h| *h == c).expect(c);
    let (total_at, reaction_at) = (
        column("tangential_reaction_bottom"),
        column("reaction_bottom"),
    );
    assert_eq!(
        total_at,
        reaction_at + 1,
        "beside reaction_bottom: {header:?}"
    );
    let (stick_at, slip_at) = (column("stick_nodes"), column("slip_nodes"));
    let rows: Vec<Vec<&str>> = lines.map(|l| l.split(',').collect()).collect();

    let mut sim = PlaneSimulation::new(&scene).unwrap();
    let body = sim.body();
    let nodes = viscobar::internals::output::profiles::written_nodes(body.lattice(), 1);
    let written = |unknown: usize| {
        let dof = (0..2 * body.nodes())
            .find(|&d| body.unknown_of(d) == Some(unknown))
            .unwrap();
        (nodes.iter().position(|&n| n == dof / 2).unwrap(), dof % 2)
    };
    let friction = sim.contact().friction().clone();
    let tangent_at: Vec<(usize, usize)> = friction.tangents.iter().map(|&t| written(t)).collect();
    assert!(!friction.is_empty());
    let (mut stick_steps, mut slip_steps, mut worst) = (0, 0, 0.0f64);
    for n in 1..=scene.steps() {
        if n > 1 {
            sim.step().unwrap();
        }
        let name = format!("vtu/step-{n:03}.vtu");
        let r = read(&out.join(&name));
        let (force, reaction) = (r.array("contact_force"), r.array("contact_reaction"));
        let state = r.array("friction_state");
        let row = &rows[n - 1];
        let tangential = sim.tangential_reactions();
        let mut expected = reaction.to_vec();
        let (mut total, mut largest) = (0.0, 0.0f64);
        for (j, &(w, c)) in tangent_at.iter().enumerate() {
            expected[3 * w + c] += tangential[j];
            // The tangential part as the file has it, summed in the frictional nodes' order.
            let r_t = force[3 * w + c] - reaction[3 * w + c];
            total += r_t;
            let normal = sim.reactions()[friction.normals[j]];
            largest = largest.max(friction.coefficients[j] * normal);
        }
        assert_eq!(bits(force), bits(&expected), "{name}: contact_force");
        assert_eq!(
            row[total_at].parse::<f64>().unwrap().to_bits(),
            total.to_bits(),
            "{name}"
        );
        for (j, &(w, c)) in tangent_at.iter().enumerate() {
            let r_t = force[3 * w + c] - reaction[3 * w + c];
            let cone = friction.coefficients[j] * sim.reactions()[friction.normals[j]];
            worst = worst.max((r_t.abs() - cone) / largest);
            assert!(
                r_t.abs() <= cone + CONE_ROUNDING * largest,
                "{name}: node {j}: |r_T| = {} > mu r_N = {cone}",
                r_t.abs()
            );
        }
        let count = |v: f64| state.iter().filter(|&&s| s == v).count();
        let (stick, slip): (usize, usize) = (
            row[stick_at].parse().unwrap(),
            row[slip_at].parse().unwrap(),
        );
        assert_eq!((count(1.0), count(2.0)), (stick, slip), "{name}");
        assert_eq!(count(0.0) + stick + slip, nodes.len(), "{name}");
        stick_steps += usize::from(stick > 0);
        slip_steps += usize::from(slip > 0);
    }
    eprintln!("worst excess over Coulomb's cone: {worst:e} of the largest mu r_N");
    assert!(
        stick_steps > 0 && slip_steps > 0,
        "{stick_steps} {slip_steps}"
    );
    let _ = std::fs::remove_dir_all(&out);
}

/// A plane scene with `[heat]` written every step: each file's `theta` is the run's temperature
/// at every written node, bit for bit, and a scene without `[heat]` has no `theta`.
#[test]
fn theta_reads_back_to_the_run() {
    let out = fresh("theta");
    let text = format!(
        "{}\n[heat]\ncoupling = 0\ndiffusivity = 0.3\n",
        plane_builtin_text("plane-friction-launch").unwrap()
    );
    let overrides = [
        "output.format=\"vtu\"".to_string(),
        "output.every=1".into(),
        "time.end=0.2".into(),
    ];
    let scene = PlaneScene::from_toml(&text, &overrides).unwrap();
    run_plane_to_dir("theta", &scene, &out, false).unwrap();
    let mut sim = PlaneSimulation::new(&scene).unwrap();
    let nodes = viscobar::internals::output::profiles::written_nodes(sim.body().lattice(), 1);
    let mut heated = 0;
    for n in 1..=scene.steps() {
        if n > 1 {
            sim.step().unwrap();
        }
        let file = read(&out.join(format!("vtu/step-{n:02}.vtu")));
        let expected: Vec<f64> = (nodes.iter())
            .map(|&i| sim.body().temperature(sim.displacement(), i).unwrap())
            .collect();
        assert_eq!(bits(file.array("theta")), bits(&expected), "step {n}");
        heated += usize::from(expected.iter().any(|&t| t > 0.0));
    }
    assert!(heated > 0, "friction heats the body");
    let _ = std::fs::remove_dir_all(&out);
    let plain = fresh("no-theta");
    run_plane_to_dir("plain", &scene_of_launch(&overrides), &plain, false).unwrap();
    let file = read(&plain.join("vtu/step-01.vtu"));
    assert!(file.arrays.iter().all(|(n, _)| n != "theta"));
    let _ = std::fs::remove_dir_all(&plain);
}

fn scene_of_launch(overrides: &[String]) -> PlaneScene {
    PlaneScene::from_toml(
        plane_builtin_text("plane-friction-launch").unwrap(),
        overrides,
    )
    .unwrap()
}
