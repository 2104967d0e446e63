//! `viscobar figures`: the sampled data the figures are drawn from are the run's own mesh values,
//! the command writes every talk figure as PNG and SVG, byte-for-byte reproducibly, and refuses
//! bad input without writing anything.

mod common;
use common::{png_size, viscobar};

use std::path::{Path, PathBuf};
use viscobar::Simulation;
use viscobar::internals::output::text::output_time;
use viscobar::internals::study::sampled_run::{self, Sampling};
use viscobar::study::figures::{self, TALK_FIGURES};

fn tmpdir(name: &str) -> PathBuf {
    common::fresh_dir("figures", name)
}

/// Strides that do not divide the mesh, so the last node and the last step are added.
#[test]
fn sampled_run_holds_the_runs_mesh_values_and_peak_reactions() {
    let scene = common::builtin("both-ends", &["time.end=2.0"]); // contact from t = 1.055
    let sampling = Sampling {
        x_stride: 7,
        t_stride: 30,
    };
    let run = sampled_run::sample_run("both-ends", &scene, sampling).unwrap();
    let nodes: Vec<usize> = (0..=399).step_by(7).chain([400]).collect();
    let steps: Vec<usize> = (0..=390).step_by(30).chain([400]).collect();
    assert_eq!(run.nodes, nodes);
    assert_eq!(run.steps_sampled, steps);
    assert_eq!(run.energy.len(), steps.len());
    assert_eq!(
        run.contact.times.len(),
        steps.len() - 1,
        "one bin per interval"
    );

    let mut sim = Simulation::new(&scene).unwrap();
    assert_eq!(
        run.u_row(0),
        &nodes
            .iter()
            .map(|&i| sim.initial_state().0[i])
            .collect::<Vec<_>>()[..]
    );
    let mut records = vec![sim.first_record()];
    while records.len() < scene.steps() {
        records.push(sim.step().unwrap());
        let n = records.len();
        if let Some(k) = steps.iter().position(|&s| s == n) {
            let u = sim.displacement();
            let expected: Vec<f64> = nodes.iter().map(|&i| u[i]).collect();
            assert_eq!(run.u_row(k), &expected[..], "u after step {n}");
            assert_eq!(
                run.energy[k],
                Some(records[n - 1].energy),
                "energy at step {n}"
            );
        }
    }
    assert_eq!(run.energy[0], None);
    let mut peak = 0.0f64;
    for (b, w) in steps.windows(2).enumerate() {
        let bin = &records[w[0]..w[1]]; // steps w[0]+1 ..= w[1]
        assert_eq!(run.contact.times[b], bin.last().unwrap().time);
        for j in 0..2 {
            let r = bin
                .iter()
                .map(|r| r.contact.groups[j].reaction)
                .fold(f64::MIN, f64::max);
            let g = bin
                .iter()
                .map(|r| r.contact.groups[j].min_gap)
                .fold(f64::MAX, f64::min);
            assert_eq!(
                run.contact.reaction[2 * b + j],
                r,
                "peak reaction, bin {b}, end {j}"
            );
            assert_eq!(run.contact.gap[2 * b + j], g, "least gap, bin {b}, end {j}");
            peak = peak.max(r);
        }
    }
    assert!(
        peak > 0.0,
        "the window must contain contact, or the test checks nothing"
    );
    let (_, summary, _) = viscobar::output::run_in_memory("both-ends", &scene).unwrap();
    assert_eq!(run.summary.contact_intervals, summary.contact_intervals);
}

/// A bar with a temperature is sampled with its `θ`: at every sampled node and step, `u` and
/// `θ` are the values the run's profile file (`displacement.csv`, a separate writer) holds, bit
/// for bit, in the file's own rows; a bar without a temperature has none.
#[test]
fn sampled_run_of_a_thermal_bar_holds_the_profile_files_theta() {
    let scene = common::builtin("thermal-impact", &["time.end=0.5"]); // 100 steps, every 5
    let sampling = Sampling {
        x_stride: 7,
        t_stride: 10,
    };
    let run = sampled_run::sample_run("thermal-impact", &scene, sampling).unwrap();
    let out = tmpdir("thermal-profile");
    viscobar::run_to_dir("thermal-impact", &scene, &out, false).unwrap();
    let profile = std::fs::read_to_string(out.join("displacement.csv")).unwrap();
    let _ = std::fs::remove_dir_all(&out);
    let mut lines = profile.lines();
    assert_eq!(lines.next(), Some("t,x,u,v,theta"));
    let rows: Vec<Vec<f64>> = lines
        .map(|l| l.split(',').map(|c| c.parse().unwrap()).collect())
        .collect();
    // The file keeps every 5th step, each with all 201 nodes in order; times and coordinates
    // are written rounded (`output_time`), the values exactly.
    let (every, nodes) = (5, 201);
    assert_eq!(rows.len(), (100 / every + 1) * nodes);
    let theta = run.theta.as_ref().expect("a thermal run samples θ");
    assert_eq!(theta.len(), run.u.len());
    assert_eq!(run.steps_sampled.len(), 11);
    for (k, &n) in run.steps_sampled.iter().enumerate() {
        for (i, &node) in run.nodes.iter().enumerate() {
            let row = &rows[n / every * nodes + node];
            let (t, x) = (run.ts[k], run.xs[i]);
            assert_eq!((row[0], row[1]), (output_time(t), output_time(x)));
            assert_eq!(run.u_row(k)[i], row[2], "u at t = {t}, x = {x}");
            assert_eq!(
                run.theta_row(k).unwrap()[i],
                row[4],
                "θ at t = {t}, x = {x}"
            );
        }
    }
    // The exchange heats the end in contact: the panel has something to show.
    assert!(theta.iter().any(|&v| v > 0.0), "θ stays 0");
    let bar = common::builtin("both-ends", &["time.end=0.1"]);
    let bar = sampled_run::sample_run("both-ends", &bar, sampling).unwrap();
    assert!(bar.theta.is_none() && bar.theta_row(0).is_none());
}

#[test]
fn exact_sampling_exists_only_when_the_grid_is_made_of_mesh_points() {
    let scene = common::builtin("one-end", &[]); // 400 elements, 2400 steps
    assert_eq!(
        Sampling::exact(&scene, 9, 11),
        Some(Sampling {
            x_stride: 50,
            t_stride: 240
        })
    );
    assert_eq!(
        Sampling::exact(&scene, 8, 11),
        None,
        "7 does not divide 400"
    );
    assert_eq!(
        Sampling::exact(&scene, 9, 8),
        None,
        "7 does not divide 2400"
    );
    assert_eq!(
        Sampling::exact(&scene, 1, 11),
        None,
        "one point has no spacing"
    );
}

fn expected_files() -> Vec<(String, (u32, u32))> {
    let mut files = Vec::new();
    for scene in figures::talk_scenes() {
        for ext in ["png", "svg"] {
            files.push((format!("{scene}.{ext}"), figures::SCENE_SIZE));
        }
    }
    for (stem, _, _) in TALK_FIGURES {
        for ext in ["png", "svg"] {
            files.push((format!("{stem}.{ext}"), figures::PAIR_SIZE));
        }
    }
    for scene in figures::FRICTION_FIGURES {
        for ext in ["png", "svg"] {
            files.push((format!("{scene}.{ext}"), figures::FRICTION_FIGURE_SIZE));
        }
    }
    for scene in figures::HEAT_FIGURES {
        for ext in ["png", "svg"] {
            files.push((format!("{scene}.{ext}"), figures::HEAT_FIGURE_SIZE));
        }
    }
    files
}

fn listing(dir: &Path) -> Vec<String> {
    let mut v: Vec<String> = std::fs::read_dir(dir)
        .unwrap()
        .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
        .collect();
    v.sort();
    v
}

#[test]
fn figures_command_writes_every_talk_figure_reproducibly() {
    let (a, b) = (tmpdir("a"), tmpdir("b"));
    for dir in [&a, &b] {
        let o = viscobar(&["figures", "--out", dir.to_str().unwrap()]);
        assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    }
    let expected = expected_files();
    let mut names: Vec<String> = expected.iter().map(|(n, _)| n.clone()).collect();
    names.sort();
    assert_eq!(
        listing(&a),
        names,
        "exactly the figures, no temporary files left"
    );
    for (name, size) in &expected {
        let bytes = std::fs::read(a.join(name)).unwrap();
        if name.ends_with(".png") {
            assert_eq!(png_size(&bytes), *size, "{name}");
            assert_eq!(
                bytes,
                std::fs::read(b.join(name)).unwrap(),
                "{name} differs between runs"
            );
            continue;
        }
        let svg = String::from_utf8(bytes).unwrap();
        assert!(svg.starts_with("<svg"), "{name}");
        assert!(
            svg.contains(&format!("width=\"{}\" height=\"{}\"", size.0, size.1)),
            "{name}: size"
        );
        if figures::FRICTION_FIGURES
            .iter()
            .any(|f| name.starts_with(f))
        {
            // The stick/slip state, the pressure and the traction over (s, t), as cells.
            for needle in [
                "state (white open, blue stick",
                "normal pressure",
                "traction",
            ] {
                assert!(svg.contains(needle), "{name}: lacks `{needle}`");
            }
            continue;
        }
        if figures::HEAT_FIGURES.iter().any(|f| name.starts_with(f)) {
            // The field at the end, the edge's state and θ over (s, t), one colour bar.
            for needle in [
                "temperature θ over the body",
                "bottom edge: state (white open, blue stick",
                "bottom edge: temperature θ",
                "temperature θ (dark: cold)",
            ] {
                assert!(svg.contains(needle), "{name}: lacks `{needle}`");
            }
            continue;
        }
        let maps = svg.matches("\"data:image/png;base64,").count();
        let panels = if name.starts_with("figure-") { 2 } else { 1 };
        // Distributed scenes draw their contact set over (x, t) as a second colour map.
        let distributed = name.starts_with("distributed") || name.starts_with("figure-3");
        let maps_per_panel = if distributed { 2 } else { 1 };
        assert_eq!(
            maps,
            panels * maps_per_panel,
            "{name}: one embedded image per colour map"
        );
        assert!(!svg.contains("\"data:png;"), "{name}: invalid MIME type");
        // Titles name the scene, alpha, J, dt and the solver (all talk scenes: alpha = 0.1,
        // 400 elements, dt = 0.005).
        for needle in ["α = 0.1", "J = 399", "Δt = 0.005", "solver: exact"] {
            assert!(svg.contains(needle), "{name}: title lacks `{needle}`");
        }
        for axis in [">\nx\n<", ">\nt\n<", ">\nu\n<"] {
            assert!(svg.contains(axis), "{name}: axis label {axis:?}");
        }
    }
    for scene in figures::talk_scenes() {
        let svg = std::fs::read_to_string(a.join(format!("{scene}.svg"))).unwrap();
        assert!(
            svg.contains(&format!("\n{scene}  (l = ")),
            "{scene}: title names the scene"
        );
    }
    for dir in [a, b] {
        let _ = std::fs::remove_dir_all(dir);
    }
}

#[test]
fn figures_command_refuses_bad_input_with_2_and_write_failures_with_1() {
    let out = tmpdir("bad");
    let o = viscobar(&[
        "figures",
        "--out",
        out.to_str().unwrap(),
        "--solver",
        "nope",
    ]);
    assert_eq!(o.status.code(), Some(2));
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(
        err.contains("nope") && err.contains("solver.method"),
        "{err}"
    );
    assert!(!out.exists(), "nothing written on bad input");

    let file = tmpdir("file");
    std::fs::write(&file, "not a folder").unwrap();
    let o = viscobar(&["figures", "--out", file.join("sub").to_str().unwrap()]);
    assert_eq!(o.status.code(), Some(1));
    assert!(String::from_utf8_lossy(&o.stderr).contains("cannot write"));
    let _ = std::fs::remove_file(file);
}

/// The README shows `docs/figures/*.png`, regenerated by `figures --out docs/figures` and, for
/// the work-precision diagrams, by `verify --timings --figures docs/figures`: the committed PNGs
/// are exactly the ones the two commands write (names; the pixels are not pinned).
#[test]
fn docs_figures_are_the_pngs_the_command_writes() {
    let docs = Path::new(env!("CARGO_MANIFEST_DIR")).join("docs/figures");
    // The mass variants' figure is `viscobar mass`'s (tests/mass.rs), not `figures`'.
    let mass_figure = format!("{}.png", viscobar::study::mass_figure::STEM);
    let committed: Vec<String> = listing(&docs)
        .into_iter()
        .filter(|n| n.ends_with(".png") && *n != mass_figure)
        .collect();
    let mut written: Vec<String> = expected_files()
        .into_iter()
        .map(|(n, _)| n)
        .filter(|n| n.ends_with(".png"))
        .collect();
    let diagrams: Vec<String> = viscobar_certificate::performance::timings::CASES
        .iter()
        .map(|c| format!("work-precision-{}.png", c.scene))
        .collect();
    written.extend(diagrams.iter().cloned());
    written.sort();
    assert_eq!(committed, written);
    let readme =
        std::fs::read_to_string(concat!(env!("CARGO_MANIFEST_DIR"), "/README.md")).unwrap();
    assert!(readme.contains("`cargo run --release -- figures --out docs/figures`"));
    let drawn = (figures::FRICTION_FIGURES.iter()).chain(figures::HEAT_FIGURES);
    for scene in figures::talk_scenes().chain(drawn.copied()) {
        let link = format!("(docs/figures/{scene}.png)");
        assert!(readme.contains(&link), "README does not show {scene}");
    }
    assert!(readme.contains(
        "cargo run --release -p viscobar-certificate -- verify --timings --update VERIFICATION.md \
         --figures docs/figures"
    ));
    for name in &diagrams {
        let link = format!("(docs/figures/{name})");
        assert!(readme.contains(&link), "README does not show {name}");
    }
}

/// plotters' `ttf` feature pulls font-kit and the system font libraries; the figures must not
/// need them (the font is embedded through `ab_glyph`).
#[test]
fn no_system_font_library_is_in_the_dependency_graph() {
    let lock = std::fs::read_to_string(concat!(env!("CARGO_MANIFEST_DIR"), "/Cargo.lock")).unwrap();
    assert!(
        lock.contains("name = \"ab_glyph\""),
        "text goes through ab_glyph"
    );
    for name in [
        "font-kit",
        "freetype",
        "freetype-sys",
        "yeslogic-fontconfig-sys",
        "servo-fontconfig",
    ] {
        assert!(
            !lock.contains(&format!("name = \"{name}\"")),
            "{name} is in Cargo.lock"
        );
    }
}

/// The work-precision diagram of `viscobar converge` (drawn in `study::work_precision`): PNG and
/// SVG, whole, byte-for-byte reproducible, with the title and one legend entry per line.
#[test]
fn work_precision_diagram_is_written_whole_and_reproducibly() {
    let lines = vec![
        (
            "exact".to_string(),
            vec![(1e-3, 1e-2), (4e-3, 2.5e-3), (1.6e-2, 6.25e-4)],
        ),
        (
            "osqp eps 1e-4".to_string(),
            vec![(2e-3, 1.1e-2), (9e-3, 3e-3), (4e-2, 1e-3)],
        ),
    ];
    let title = "modal: L2 error against wall time";
    let mut bytes = Vec::new();
    for run in ["a", "b"] {
        let dir = tmpdir(&format!("work-precision-{run}"));
        std::fs::create_dir_all(&dir).unwrap();
        let mut files = Vec::new();
        for ext in ["png", "svg"] {
            let path = dir.join(format!("work-precision.{ext}"));
            viscobar::study::work_precision::write_work_precision(&path, title, &lines).unwrap();
            files.push(std::fs::read(&path).unwrap());
        }
        let names: Vec<String> = std::fs::read_dir(&dir)
            .unwrap()
            .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
            .collect();
        assert_eq!(names.len(), 2, "no temporary file left: {names:?}");
        bytes.push(files);
    }
    assert_eq!(bytes[0], bytes[1], "reproducible");
    let [png, svg] = &bytes[0][..] else {
        unreachable!()
    };
    assert!(png.starts_with(b"\x89PNG\r\n\x1a\n"), "PNG signature");
    let svg = String::from_utf8_lossy(svg);
    for text in [
        title,
        "exact",
        "osqp eps 1e-4",
        "wall time of the steps (s)",
    ] {
        assert!(svg.contains(text), "SVG lacks {text:?}");
    }
}

/// `viscobar converge` writes the table and both diagrams.
#[test]
fn converge_writes_the_table_and_the_work_precision_diagrams() {
    let out = tmpdir("converge");
    let o = viscobar(&[
        "converge",
        "modal",
        "--solvers",
        "exact",
        "--levels",
        "2",
        "--out",
        out.to_str().unwrap(),
    ]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let mut names: Vec<String> = std::fs::read_dir(&out)
        .unwrap()
        .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
        .collect();
    names.sort();
    assert_eq!(
        names,
        [
            "convergence.csv",
            "work-precision.png",
            "work-precision.svg"
        ]
    );
    let svg = std::fs::read_to_string(out.join("work-precision.svg")).unwrap();
    assert!(svg.contains("modal: L2 error against wall time"), "{svg}");
}
