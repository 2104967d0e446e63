//! `[output] format = "npy"` (cargo feature `npy`): `displacement.npy` is a structured array
//! `t, x, u, v` of `<f8` holding the same rows as `displacement.csv`, `u` and `v` the
//! simulation's own bits; its header is the one `numpy.load` parses; summary.json names it.
#![cfg(feature = "npy")]

mod common;
use std::path::{Path, PathBuf};
use viscobar::Simulation;
use viscobar::internals::output::npy::ProfileRow;
use viscobar::internals::output::text::output_time;
use viscobar::output::run_to_dir;

fn fresh_dir(tag: &str) -> PathBuf {
    common::fresh_dir("npy", tag)
}

/// The rows of `dir/displacement.npy` through npyz's reader, after checking its header.
fn read_npy(dir: &Path, rows: u64) -> Vec<ProfileRow<4>> {
    let bytes = std::fs::read(dir.join("displacement.npy")).unwrap();
    let npy = npyz::NpyFile::new(&bytes[..]).unwrap();
    assert_eq!(npy.shape(), &[rows], "shape");
    assert_eq!(npy.order(), npyz::Order::C);
    // The dtype spelled out here, not taken from the library.
    let f8 = npyz::DType::Plain("<f8".parse().unwrap());
    let expected = npyz::DType::Record(
        ["t", "x", "u", "v"]
            .iter()
            .map(|n| npyz::Field {
                name: n.to_string(),
                dtype: f8.clone(),
            })
            .collect(),
    );
    assert_eq!(npy.dtype(), expected, "dtype");
    npy.into_vec::<ProfileRow<4>>().unwrap()
}

#[test]
fn displacement_npy_holds_the_simulation_bits_and_the_csv_rows() {
    // Values of every size (a kink, contact, a displacement crossing zero), thinned in steps
    // and, in the second case, in nodes.
    for (extra, tag) in [(None, "all"), (Some("output.nodes=7"), "nodes")] {
        let mut set = vec!["output.every=7"];
        set.extend(extra);
        let csv_scene = common::builtin("impact", &set);
        set.push("output.format=npy");
        let scene = common::builtin("impact", &set);
        let sampling = scene.output_sampling();

        let dir = fresh_dir(tag);
        run_to_dir("impact", &scene, &dir, false).unwrap();
        let rows = read_npy(&dir, sampling.rows);
        let summary: serde_json::Value =
            serde_json::from_str(&std::fs::read_to_string(dir.join("summary.json")).unwrap())
                .unwrap();
        assert_eq!(summary["output"]["file"], "displacement.npy");
        assert_eq!(summary["output"]["format"], "npy");
        assert_eq!(summary["output"]["rows"], sampling.rows);
        assert!(!dir.join("displacement.csv").exists());
        std::fs::remove_dir_all(&dir).unwrap();

        // The simulation, stepped here: `u`, `v` bit for bit, `t` and `x` rounded as in the CSV.
        let mut sim = Simulation::new(&scene).unwrap();
        let nodes = sim.discretisation().nodes;
        let written: Vec<usize> = (0..nodes)
            .filter(|&i| sampling.writes_node(i, nodes))
            .collect();
        assert_eq!(written.len() as u64, sampling.nodes_written);
        let (mut u, mut v) = (vec![0.0; nodes], vec![0.0; nodes]);
        let mut next = rows.iter();
        let mut check = |t: f64, u: &[f64], v: &[f64], sim: &Simulation| {
            for &i in &written {
                let r = next.next().expect("a row a written node");
                let [rt, rx, ru, rv] = r.0;
                assert_eq!(rt.to_bits(), output_time(t).to_bits(), "t at {t}");
                let x = output_time(sim.discretisation().x(i));
                assert_eq!(rx.to_bits(), x.to_bits(), "x of node {i}");
                assert_eq!(ru.to_bits(), u[i].to_bits(), "u at t = {t}, node {i}");
                assert_eq!(rv.to_bits(), v[i].to_bits(), "v at t = {t}, node {i}");
            }
        };
        sim.body().initial_state_into(&mut u, &mut v);
        check(0.0, &u, &v, &sim);
        let steps = scene.steps();
        for n in 1..=steps {
            if n > 1 {
                sim.step().unwrap();
            }
            if n.is_multiple_of(7) || n == steps {
                sim.displacement_into(&mut u);
                sim.velocity_into(&mut v);
                check(sim.time(), &u, &v, &sim);
            }
        }
        assert!(next.next().is_none(), "no rows beyond the kept steps");

        // The same scene written as CSV: the same rows, value for value.
        let dir = fresh_dir(&format!("{tag}-csv"));
        run_to_dir("impact", &csv_scene, &dir, false).unwrap();
        let text = std::fs::read_to_string(dir.join("displacement.csv")).unwrap();
        std::fs::remove_dir_all(&dir).unwrap();
        let mut count = 0;
        for (line, r) in text.lines().skip(1).zip(&rows) {
            let f: Vec<f64> = line.split(',').map(|c| c.parse().unwrap()).collect();
            let bits = |a: &[f64]| a.iter().map(|x| x.to_bits()).collect::<Vec<_>>();
            assert_eq!(bits(&f), bits(&r.0), "{line}");
            count += 1;
        }
        assert_eq!(count as u64, sampling.rows, "{tag}: CSV rows");
    }
}

#[test]
fn the_header_is_numpys_format_1_0_text() {
    let scene = common::builtin("impact", &["output.every=50", "output.format=npy"]);
    let rows = scene.output_sampling().rows;
    let dir = fresh_dir("header");
    run_to_dir("impact", &scene, &dir, false).unwrap();
    let bytes = std::fs::read(dir.join("displacement.npy")).unwrap();
    std::fs::remove_dir_all(&dir).unwrap();
    // NPY format 1.0: magic, version, little-endian u16 header length, a Python dict literal
    // padded with spaces to a 64-byte boundary and ended by a newline, then the rows.
    assert_eq!(&bytes[..8], b"\x93NUMPY\x01\x00");
    let len = usize::from(u16::from_le_bytes([bytes[8], bytes[9]]));
    assert_eq!((10 + len) % 64, 0, "data aligned");
    let header = std::str::from_utf8(&bytes[10..10 + len]).unwrap();
    // npyz writes trailing commas (`[..., ]`, `(N, )`); numpy reads the dict with
    // `ast.literal_eval`, to which they are the same literal.
    let dict = format!(
        "{{'descr': [('t', '<f8'), ('x', '<f8'), ('u', '<f8'), ('v', '<f8'), ], \
         'fortran_order': False, 'shape': ({rows}, ), }}"
    );
    assert_eq!(header.trim_end(), dict);
    assert!(header.ends_with('\n'));
    assert_eq!(
        bytes.len() as u64,
        10 + len as u64 + 32 * rows,
        "32 bytes a row"
    );
}

#[test]
fn a_run_in_one_format_removes_the_other_formats_stale_profiles() {
    let dir = fresh_dir("switch");
    let csv = common::builtin("impact", &["output.every=50"]);
    let npy = common::builtin("impact", &["output.every=50", "output.format=npy"]);
    run_to_dir("impact", &csv, &dir, false).unwrap();
    assert!(dir.join("displacement.csv").exists());
    run_to_dir("impact", &npy, &dir, false).unwrap();
    assert!(dir.join("displacement.npy").exists());
    assert!(!dir.join("displacement.csv").exists(), "stale CSV removed");
    run_to_dir("impact", &csv, &dir, false).unwrap();
    assert!(!dir.join("displacement.npy").exists(), "stale npy removed");
    std::fs::remove_dir_all(&dir).unwrap();
}

/// `scene` (a plane scene's TOML) run with `extra` settings to CSV and to NPY: every NPY row
/// the bits of the CSV row, under the header `header` of `N` columns, sampled in both
/// directions by `output.nodes`.
fn plane_npy_matches_csv<const N: usize>(scene: &str, extra: &[&str], header: &str)
where
    viscobar::internals::output::npy::ProfileRow<N>: npyz::Deserialize,
{
    let plane = |format: &[&str]| {
        let mut set = vec!["output.every=5", "output.nodes=60"];
        set.extend(extra);
        set.extend(format);
        let set: Vec<String> = set.iter().map(|s| s.to_string()).collect();
        viscobar::PlaneScene::from_toml(scene, &set).unwrap()
    };
    let (csv_scene, npy_scene) = (plane(&[]), plane(&["output.format=npy"]));
    let sampling = npy_scene.output_sampling();
    let (a, b) = (
        fresh_dir(&format!("plane-csv-{N}")),
        fresh_dir(&format!("plane-npy-{N}")),
    );
    viscobar::output::run_plane_to_dir("plane", &csv_scene, &a, false).unwrap();
    viscobar::output::run_plane_to_dir("plane", &npy_scene, &b, false).unwrap();
    let bytes = std::fs::read(b.join("displacement.npy")).unwrap();
    let npy = npyz::NpyFile::new(&bytes[..]).unwrap();
    assert_eq!(npy.shape(), &[sampling.rows]);
    let rows = npy.into_vec::<ProfileRow<N>>().unwrap();
    let text = std::fs::read_to_string(a.join("displacement.csv")).unwrap();
    let mut lines = text.lines();
    assert_eq!(lines.next(), Some(header));
    let mut count = 0;
    for (line, r) in lines.zip(&rows) {
        let f: Vec<u64> = line
            .split(',')
            .map(|c| c.parse::<f64>().unwrap().to_bits())
            .collect();
        assert_eq!(f, r.0.map(f64::to_bits).to_vec(), "{line}");
        count += 1;
    }
    assert_eq!(count, rows.len());
    assert_eq!(count as u64, sampling.rows);
    assert!(sampling.nodes_written <= 60 && sampling.node_stride > 1);
    for d in [a, b] {
        std::fs::remove_dir_all(&d).unwrap();
    }
}

/// The plane body writes the same format: `t, x, y, ux, uy, vx, vy`, every value the bits of
/// the CSV of the same run.
#[test]
fn a_plane_run_writes_the_same_rows_as_its_csv() {
    let text = viscobar::scene::plane::plane_builtin_text("plane-tilted-drop").unwrap();
    plane_npy_matches_csv::<7>(text, &["time.end=0.1"], "t,x,y,ux,uy,vx,vy");
}

/// With `[heat]` a column `theta` follows, in both formats, to the same bits.
#[test]
fn a_plane_run_with_a_temperature_writes_theta_as_its_csv() {
    let text = viscobar::scene::plane::plane_builtin_text("plane-brake").unwrap();
    plane_npy_matches_csv::<8>(text, &["time.end=0.2"], "t,x,y,ux,uy,vx,vy,theta");
}
