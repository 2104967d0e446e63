//! The `viscobar` command line: outputs of `run`, listing and showing scenes (bad input is in
//! `bad_input.rs`).

mod common;
use common::viscobar;

use std::process::Command;
use viscobar_certificate::tolerances::osqp_agreement_bound;

fn tmpdir(name: &str) -> std::path::PathBuf {
    common::fresh_dir("cli", name)
}

#[test]
fn run_writes_summary_history_and_displacement() {
    let out = tmpdir("run");
    let o = viscobar(&[
        "run",
        "impact",
        "--out",
        out.to_str().unwrap(),
        "--set",
        "time.end=0.5",
    ]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let summary: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(out.join("summary.json")).unwrap()).unwrap();
    for key in [
        "scene",
        "solver",
        "nodes",
        "dt",
        "steps",
        "wall_time_s",
        "ns_per_unknown_step",
        "energy_initial",
        "energy_final",
        "max_energy_rise",
        "max_identity_residual",
        "max_complementarity",
        "max_violation",
        "contact_intervals",
        "solver_iterations",
    ] {
        assert!(summary.get(key).is_some(), "summary.json lacks {key}");
    }
    assert_eq!(summary["steps"], 50);
    let history = std::fs::read_to_string(out.join("history.csv")).unwrap();
    let mut lines = history.lines();
    assert_eq!(
        lines.next().unwrap(),
        "step,t,energy,work,viscous_dissipation,contact_dissipation,identity_residual,gap_left,reaction_left,iterations"
    );
    assert_eq!(lines.count(), 50, "one row per step");
    let disp = std::fs::read_to_string(out.join("displacement.csv")).unwrap();
    assert_eq!(disp.lines().next().unwrap(), "t,x,u,v");
    // Kept steps: t = 0, every 5th step and the last; 101 nodes each.
    assert_eq!(disp.lines().count() - 1, 101 * (1 + 10));
    assert!(
        !out.read_dir()
            .unwrap()
            .any(|e| e.unwrap().file_name().to_string_lossy().starts_with('.'))
    );
}

/// `viscobar scenes`: one entry per built-in scene, its name in a column as wide as the longest
/// name, then the first sentence of its description whole (continuation lines indented to the
/// description column).
#[test]
fn scenes_lists_every_builtin_with_a_whole_first_sentence() {
    let o = viscobar(&["scenes"]);
    assert!(o.status.success());
    let text = String::from_utf8_lossy(&o.stdout);
    // Bar scenes, the bar's with a temperature, then plane scenes.
    let mut names = viscobar::scene::builtin_names();
    names.extend(viscobar::scene::thermal_builtin_names());
    names.extend(
        viscobar::scene::plane::PLANE_BUILTIN
            .iter()
            .map(|(n, _)| *n),
    );
    let longest = names.iter().map(|n| n.len()).max().unwrap();
    let indent = |line: &str| line.len() - line.trim_start().len();
    // Entries: a line starting with a name, then its indented continuation lines; every
    // description line starts in the same column, right of the longest name.
    let mut entries: Vec<(String, String)> = Vec::new();
    let mut columns = Vec::new();
    for line in text.lines() {
        if line.starts_with(' ') {
            let (_, description) = entries.last_mut().expect("a name line comes first");
            columns.push(indent(line));
            description.push(' ');
            description.push_str(line.trim());
        } else {
            let (name, rest) = line.split_once(' ').expect("name and description");
            columns.push(name.len() + 1 + indent(rest));
            entries.push((name.to_string(), rest.trim().to_string()));
        }
    }
    assert!(
        columns.iter().all(|c| *c == columns[0] && *c > longest),
        "descriptions not in one column right of the longest name:\n{text}"
    );
    let listed: Vec<&str> = entries.iter().map(|(n, _)| n.as_str()).collect();
    assert_eq!(listed, names);
    for (name, description) in &entries {
        assert!(
            description.ends_with('.') || description.ends_with(')'),
            "{name}: description cut mid-sentence: {description:?}"
        );
        let full = match viscobar::scene::load_any(name, &[]).unwrap().1 {
            viscobar::scene::AnyScene::Bar(s) => s.description,
            viscobar::scene::AnyScene::Plane(s) => s.description,
        }
        .unwrap();
        let full = full.split_whitespace().collect::<Vec<_>>().join(" ");
        assert!(
            full.starts_with(description.as_str()),
            "{name}: not the description's opening: {description:?}"
        );
    }
}

/// The positional arguments a newcomer meets first are described in `--help`.
#[test]
fn help_describes_the_scene_arguments() {
    for (command, argument) in [
        ("run", "<SCENE>"),
        ("converge", "<SCENE>"),
        ("compare", "<SCENE>"),
        ("show", "<NAME>"),
    ] {
        let o = viscobar(&[command, "--help"]);
        assert!(o.status.success());
        let help = String::from_utf8_lossy(&o.stdout);
        let line = help
            .lines()
            .find(|l| l.trim_start().starts_with(argument))
            .unwrap_or_else(|| panic!("`{command} --help` lists no {argument}: {help}"));
        assert!(
            line.contains("viscobar scenes"),
            "`{command} --help` does not describe {argument}: {help}"
        );
    }
    let run = String::from_utf8_lossy(&viscobar(&["run", "--help"]).stdout).into_owned();
    assert!(run.contains("TOML scene file"), "{run}");
}

#[test]
fn scenes_and_show_list_the_builtins() {
    let o = viscobar(&["scenes"]);
    assert!(o.status.success());
    let text = String::from_utf8_lossy(&o.stdout);
    for name in viscobar::scene::builtin_names() {
        assert!(text.contains(name), "`scenes` lacks {name}");
        let shown = viscobar(&["show", name]);
        assert!(shown.status.success());
        let toml = String::from_utf8_lossy(&shown.stdout);
        viscobar::Scene::from_toml(&toml, &[]).expect("`show` prints a valid scene");
    }
}

/// Summary fields that measure the machine, not the numerics: the only content allowed to
/// differ between two runs.
const TIMING_FIELDS: [&str; 3] = ["wall_time_s", "ns_per_unknown_step", "time_shares"];

#[test]
fn two_runs_give_byte_identical_outputs() {
    let (a, b) = (tmpdir("det-a"), tmpdir("det-b"));
    for d in [&a, &b] {
        let o = viscobar(&[
            "run",
            "both-ends-forced",
            "--out",
            d.to_str().unwrap(),
            "--set",
            "time.end=3",
        ]);
        assert!(o.status.success());
    }
    for file in ["history.csv", "displacement.csv"] {
        assert!(
            std::fs::read(a.join(file)).unwrap() == std::fs::read(b.join(file)).unwrap(),
            "{file} differs"
        );
    }
    let strip = |d: &std::path::Path| {
        let mut v: serde_json::Value =
            serde_json::from_str(&std::fs::read_to_string(d.join("summary.json")).unwrap())
                .unwrap();
        for f in TIMING_FIELDS {
            v.as_object_mut()
                .unwrap()
                .remove(f)
                .expect("timing field present");
        }
        v
    };
    assert_eq!(strip(&a), strip(&b));
}

/// The crates only the command line, its progress bar and the figures need: optional, so that
/// a library user depending on viscobar with `default-features = false` builds none of them.
const OPTIONAL_CRATES: [&str; 5] = ["clap", "indicatif", "plotters", "plotters-svg", "dejavu"];

/// The normal dependencies of the library, as `cargo tree` lists them, with `extra` flags.
fn dependency_names(extra: &[&str]) -> Vec<String> {
    let cargo = std::env::var("CARGO").unwrap_or_else(|_| "cargo".into());
    let manifest = concat!(env!("CARGO_MANIFEST_DIR"), "/Cargo.toml");
    let o = Command::new(cargo)
        .args([
            "tree",
            "--offline",
            "--manifest-path",
            manifest,
            "-p",
            "viscobar",
        ])
        .args(["-e", "normal", "--prefix", "none"])
        .args(extra)
        .output()
        .expect("cargo runs");
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    String::from_utf8_lossy(&o.stdout)
        .lines()
        .filter_map(|l| l.split_whitespace().next().map(str::to_string))
        .collect()
}

#[test]
fn without_default_features_the_library_needs_no_cli_or_plotting_crate() {
    let full = dependency_names(&[]);
    let bare = dependency_names(&["--no-default-features"]);
    for name in OPTIONAL_CRATES {
        assert!(full.iter().any(|n| n == name), "{name} is not a dependency");
        assert!(!bare.iter().any(|n| n == name), "{name} is not optional");
    }
    assert!(bare.iter().any(|n| n == "nalgebra"), "{bare:?}");
}

/// Exit code, stdout and stderr of `viscobar args`.
fn outcome(args: &[&str]) -> (i32, String, String) {
    let o = viscobar(args);
    (
        o.status.code().expect("exited"),
        String::from_utf8_lossy(&o.stdout).into_owned(),
        String::from_utf8_lossy(&o.stderr).into_owned(),
    )
}

/// A step that does not divide `time.end` is refused (it used to run on to the nearest multiple
/// of the step, e.g. to t = 10 for an end of 6), with the valid ends and steps nearest to it.
#[test]
fn a_step_that_does_not_divide_the_end_is_refused_with_the_nearest_valid_values() {
    let out = tmpdir("grid");
    let dir = out.to_str().unwrap();
    let run = |set: &[&str]| {
        let mut args = vec!["run", "impact", "--out", dir];
        for s in set {
            args.extend(["--set", s]);
        }
        outcome(&args)
    };
    // Longer than the whole run: one valid end above, one valid step below.
    let (code, _, err) = run(&["time.step=10", "time.end=6"]);
    assert_eq!(code, 2, "{err}");
    for part in [
        "`time.step` = 10",
        "`time.end` = 6",
        "time.end = 10 (1 step)",
        "time.step = 6 (1 step)",
    ] {
        assert!(err.contains(part), "lacks {part:?}: {err}");
    }
    assert!(!out.exists(), "a refused run creates nothing");
    // 299.6 steps: the ends of 299 and 300 steps, the steps giving 300 and 299 of them.
    let (code, _, err) = run(&["time.end=2.996"]);
    assert_eq!(code, 2, "{err}");
    for part in [
        "time.end = 2.99 (299 steps) or time.end = 3 (300 steps)",
        "time.step = 0.00998666666667 (300 steps) or time.step = 0.0100200668896 (299 steps)",
    ] {
        assert!(err.contains(part), "lacks {part:?}: {err}");
    }
    // Each suggestion is accepted.
    for set in [
        ["time.end=2.99", "time.step=0.01"],
        ["time.end=2.996", "time.step=0.00998666666667"],
    ] {
        let (code, _, err) = run(&set);
        assert_eq!(code, 0, "{set:?}: {err}");
    }
    // Round-off is not a mismatch: 0.3 / 0.1 = 2.9999999999999996 in binary, three steps.
    let (code, _, err) = run(&["time.step=0.1", "time.end=0.3"]);
    assert_eq!(code, 0, "{err}");
    let summary: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(out.join("summary.json")).unwrap()).unwrap();
    assert_eq!(summary["steps"], 3);
}

/// The suggested expression of a message `... field = "TEXT"` (the last quoted text).
fn suggested(err: &str, field: &str) -> String {
    let start = err
        .rfind(&format!("{field} = \""))
        .unwrap_or_else(|| panic!("no suggestion for {field}: {err}"))
        + field.len()
        + 4;
    let end = start + err[start..].find('"').expect("closing quote");
    err[start..end].to_string()
}

/// Initial data that do not vanish at a clamped end are refused with the field, its value there
/// and an expression that does vanish (the data times a ramp written with the scene's length),
/// which runs.
#[test]
fn initial_data_not_vanishing_at_a_clamped_end_get_a_ramp_that_does() {
    let out = tmpdir("ramp");
    std::fs::create_dir_all(&out).unwrap();
    let file = out.join("clamped.toml");
    let scene = |left: &str, right: &str| {
        format!(
            "[bar]\nlength = 2.0\n[left]\ncondition = \"{left}\"\n[right]\ncondition = \"{right}\"\n\
             [initial]\nvelocity = \"-0.3\"\n[mesh]\nelements = 40\n[time]\nstep = 0.05\nend = 0.5\n"
        )
    };
    for (left, right, side, ramp) in [
        ("free", "clamped", "right", "(-0.3)*(2 - x)/2"),
        ("clamped", "free", "left", "(-0.3)*x/2"),
        ("clamped", "clamped", "left", "(-0.3)*4*x*(2 - x)/(2*2)"),
    ] {
        std::fs::write(&file, scene(left, right)).unwrap();
        let path = file.to_str().unwrap();
        let run_out = out.join("run");
        let run = |set: &[&str]| {
            let mut args = vec!["run", path, "--out", run_out.to_str().unwrap()];
            for s in set {
                args.extend(["--set", s]);
            }
            outcome(&args)
        };
        let (code, _, err) = run(&[]);
        assert_eq!(code, 2, "{err}");
        for part in [
            "`initial.velocity` = -0.3",
            &format!("must vanish at the clamped {side} end"),
        ] {
            assert!(err.contains(part), "lacks {part:?}: {err}");
        }
        let fix = suggested(&err, "initial.velocity");
        assert_eq!(fix, ramp, "{err}");
        let (code, _, err) = run(&[&format!("initial.velocity=\"{fix}\"")]);
        assert_eq!(code, 0, "the suggestion {fix} is refused: {err}");
    }
    // The built-in clamped scene, at its own length 1.
    let (code, _, err) = outcome(&[
        "run",
        "clamped-impact",
        "--set",
        "initial.velocity=\"-0.3\"",
    ]);
    assert_eq!(code, 2, "{err}");
    assert_eq!(
        suggested(&err, "initial.velocity"),
        "(-0.3)*(1 - x)/1",
        "{err}"
    );
}

/// The cells of the Markdown table row that starts with `| pair |`.
fn row<'a>(table: &'a str, pair: &str) -> Vec<&'a str> {
    table
        .lines()
        .find(|l| l.starts_with(&format!("| {pair} |")))
        .unwrap_or_else(|| panic!("no row {pair}: {table}"))
        .trim_matches('|')
        .split(" | ")
        .map(str::trim)
        .collect()
}

#[test]
fn compare_prints_the_agreement_of_each_solver_with_the_first() {
    let out = tmpdir("compare");
    let (code, table, err) = outcome(&[
        "compare",
        "impact",
        "--solvers",
        "exact,osqp,penalty",
        "--set",
        "time.end=0.5",
        "--out",
        out.to_str().unwrap(),
    ]);
    assert_eq!(code, 0, "{err}");
    // The table printed is the one written (`--out`), before the line naming the file.
    let written = std::fs::read_to_string(out.join("comparison.md")).unwrap();
    assert!(table.starts_with(&written), "{table}\n---\n{written}");
    let _ = std::fs::remove_dir_all(&out);
    let header = table
        .lines()
        .find(|l| l.starts_with("| solvers |"))
        .unwrap_or_else(|| panic!("no table: {table}"));
    for column in ["steps", "max \\|Δu\\|", "max \\|Δreaction\\| (per group)"] {
        assert!(header.contains(column), "lacks {column}: {header}");
    }
    let osqp = row(&table, "osqp vs exact");
    let penalty = row(&table, "penalty vs exact");
    assert_eq!(osqp.len(), header.matches(" | ").count() + 1, "{table}");
    for cells in [&osqp, &penalty] {
        assert_eq!(cells[1], "50", "{table}");
    }
    let number = |cells: &[&str], i: usize| -> f64 {
        cells[i]
            .parse()
            .unwrap_or_else(|_| panic!("cell {i} not a number: {cells:?}"))
    };
    // The printed OSQP row is the library's comparison (the same run in process), which is
    // within the registry's a-posteriori bound of the run (`osqp_agreement_bound`).
    use viscobar::scene::SolverMethod;
    use viscobar::study::compare::{compare, with_solver};
    let impact = viscobar::scene::load("impact", &["time.end=0.5".to_string()])
        .unwrap()
        .1;
    let (exact, osqp_scene) = (
        with_solver(&impact, SolverMethod::Exact),
        with_solver(&impact, SolverMethod::Osqp),
    );
    let cmp = compare("osqp", &exact, &osqp_scene).unwrap();
    let a = cmp.agreement;
    assert_eq!(osqp[2], format!("{:.3e}", a.max_difference), "{table}");
    assert_eq!(
        osqp[5],
        format!("{:.3e}", a.max_reaction_difference),
        "{table}"
    );
    let bound = osqp_agreement_bound(&cmp);
    assert!(
        a.max_difference <= bound,
        "{:e} > {bound:e}",
        a.max_difference
    );
    // Displacement and reaction differences: the penalty agrees only to O(ε).
    for i in [2, 5] {
        assert!(number(&penalty, i) > number(&osqp, i), "{table}");
    }
    // A scene file and --set, with the penalty on a distributed obstacle: a row, not a crash.
    let out = tmpdir("compare-distributed");
    let (code, table, err) = outcome(&[
        "compare",
        concat!(env!("CARGO_MANIFEST_DIR"), "/scenes/distributed.toml"),
        "--solvers",
        "exact,penalty,osqp",
        "--set",
        "time.end=0.1",
        "--out",
        out.to_str().unwrap(),
    ]);
    let _ = std::fs::remove_dir_all(&out);
    assert_eq!(code, 0, "{err}");
    assert!(
        row(&table, "penalty vs exact")[1].starts_with("does not apply"),
        "{table}"
    );
    row(&table, "osqp vs exact");
}

#[test]
fn compare_refuses_bad_input_with_2_and_a_failing_run_with_1() {
    for (args, names) in [
        (
            &["compare", "impact", "--solvers", "exact,cplex"][..],
            "cplex",
        ),
        (
            &["compare", "impact", "--solvers", "exact"][..],
            "--solvers",
        ),
        (&["compare", "no-such-scene"][..], "no-such-scene"),
        (
            &[
                "compare",
                "impact",
                "--set",
                "time.step=10",
                "--set",
                "time.end=6",
            ][..],
            "time.step",
        ),
        // The reference itself cannot handle an obstacle.
        (
            &["compare", "distributed", "--solvers", "penalty,exact"][..],
            "penalty",
        ),
    ] {
        let (code, _, err) = outcome(args);
        assert_eq!(code, 2, "{args:?}: {err}");
        assert!(err.contains(names), "{args:?}: {err}");
    }
    // OSQP allowed one iteration per step fails during the run.
    let (code, _, err) = outcome(&[
        "compare",
        "impact",
        "--solvers",
        "exact,osqp",
        "--set",
        "solver.method=\"osqp\"",
        "--set",
        "solver.max_iter=1",
    ]);
    assert_eq!(code, 1, "{err}");
    assert!(err.contains("osqp") && err.contains("step"), "{err}");
}

/// A strict RFC 4180 reader (the `csv` crate is not in the offline registry of this build, so
/// the test carries its own): records end at a line feed (the files are written with LF, not
/// CRLF, on every platform), fields are split at commas; a field is either unquoted, holding
/// no double quote, comma or line break, or wholly quoted, its quotes doubled, followed by a
/// comma or the end of the record. Anything else panics, naming where.
fn read_csv_strictly(text: &str) -> Vec<Vec<String>> {
    let mut records = Vec::new();
    let mut record = Vec::new();
    let mut field = String::new();
    let mut chars = text.chars().enumerate().peekable();
    let mut at_field_start = true;
    while let Some((i, c)) = chars.next() {
        match c {
            '"' if at_field_start => {
                loop {
                    match chars.next() {
                        Some((_, '"')) if matches!(chars.peek(), Some((_, '"'))) => {
                            chars.next();
                            field.push('"');
                        }
                        Some((_, '"')) => break,
                        Some((_, c)) => field.push(c),
                        None => panic!("unterminated quoted field starting at character {i}"),
                    }
                }
                match chars.peek() {
                    Some((_, ',' | '\n')) | None => {}
                    Some((j, c)) => panic!("{c:?} after a closing quote at character {j}"),
                }
                at_field_start = false;
            }
            '"' => panic!("a double quote inside an unquoted field at character {i}"),
            '\r' => panic!("a carriage return at character {i} (records end with LF)"),
            ',' => {
                record.push(std::mem::take(&mut field));
                at_field_start = true;
            }
            '\n' => {
                record.push(std::mem::take(&mut field));
                records.push(std::mem::take(&mut record));
                at_field_start = true;
            }
            c => {
                field.push(c);
                at_field_start = false;
            }
        }
    }
    assert!(
        record.is_empty() && field.is_empty(),
        "the last record does not end with a line feed"
    );
    records
}

#[test]
fn the_strict_csv_reader_refuses_what_rfc_4180_refuses() {
    assert_eq!(
        read_csv_strictly("a,\"b, \"\"c\"\"\",\n1,2,3\n"),
        [vec!["a", "b, \"c\"", ""], vec!["1", "2", "3"]]
    );
    for bad in ["a,b\"c\n", "\"a\"b,c\n", "\"a,b\n", "a,b", "a,b\r\n"] {
        assert!(
            std::panic::catch_unwind(|| read_csv_strictly(bad)).is_err(),
            "accepted {bad:?}"
        );
    }
}

/// `converge` as a researcher uses it on their own scene: a scene file (no closed form, so the
/// reference is an exact run), `--set`, the reference level, a list of OSQP tolerances; the CSV
/// reads back with one field per header (the reference cell holds commas), and the energy and
/// contact-time errors are measured against the reference run.
#[test]
fn converge_on_a_scene_file_writes_valid_csv_with_energy_and_contact_errors() {
    let out = tmpdir("converge-user");
    std::fs::create_dir_all(&out).unwrap();
    let file = out.join("my-impact.toml");
    std::fs::write(&file, viscobar::scene::builtin_text("impact").unwrap()).unwrap();
    let csv_dir = out.join("study");
    let (code, stdout, err) = outcome(&[
        "converge",
        file.to_str().unwrap(),
        "--set",
        "time.end=1",
        "--set",
        "mesh.elements=50",
        "--set",
        "time.step=0.02",
        "--solvers",
        "exact,osqp",
        "--osqp-eps",
        "1e-6,1e-9",
        "--levels",
        "2",
        "--reference-level",
        "3",
        "--repeats",
        "1",
        "--out",
        csv_dir.to_str().unwrap(),
    ]);
    assert_eq!(code, 0, "{err}");
    assert!(stdout.contains("level 3"), "{stdout}");
    let records =
        read_csv_strictly(&std::fs::read_to_string(csv_dir.join("convergence.csv")).unwrap());
    let header = &records[0];
    assert_eq!(
        header.len(),
        viscobar::internals::study::convergence_table::CSV_HEADER.len()
    );
    let column = |name: &str| header.iter().position(|h| h == name).unwrap();
    // exact, osqp 1e-6, osqp 1e-9 at 2 levels.
    assert_eq!(records.len(), 1 + 3 * 2, "{records:?}");
    let settings: Vec<&str> = records[1..]
        .iter()
        .map(|r| r[column("setting")].as_str())
        .collect();
    assert_eq!(
        settings,
        ["-", "-", "eps=1e-6", "eps=1e-6", "eps=1e-9", "eps=1e-9"]
    );
    for r in &records[1..] {
        assert_eq!(r.len(), header.len(), "{r:?}");
        // Level 3 of 50 elements, dt halved with dx: 400 elements.
        assert!(
            r[column("reference")].starts_with("exact solver, 400 elements"),
            "{r:?}"
        );
        assert_eq!(
            r[column("steps")],
            ["50", "100"][r[column("level")].parse::<usize>().unwrap()]
        );
        for name in [
            "l2_error",
            "energy_error",
            "contact_time_error",
            "wall_time_s",
            "time_relative_to_exact",
            "reference_l2_error_estimate",
        ] {
            let v: f64 = r[column(name)]
                .parse()
                .unwrap_or_else(|_| panic!("{name} is not a number: {r:?}"));
            assert!(v.is_finite() && v >= 0.0, "{name} = {v}: {r:?}");
        }
    }
}

#[test]
fn converge_refuses_bad_lists_and_levels_naming_the_flag() {
    for (args, flag) in [
        (&["--osqp-eps", "1e-4,0"][..], "--osqp-eps"),
        (&["--penalty-epsilon", "small"][..], "--penalty-epsilon"),
        (&["--reference-level", "1"][..], "--reference-level"),
        (&["--repeats", "1000"][..], "--repeats"),
        (&["--set", "time.step=10"][..], "time.step"),
    ] {
        let mut all = vec!["converge", "impact", "--levels", "2", "--out"];
        let out = tmpdir("converge-bad");
        all.push(out.to_str().unwrap());
        all.extend(args);
        let (code, _, err) = outcome(&all);
        assert_eq!(code, 2, "{args:?}: {err}");
        assert!(err.contains(flag), "{args:?}: {err}");
        assert!(!out.exists(), "{args:?}: a refused study writes nothing");
    }
}

/// `converge --mass`: one study per mass matrix, each in its own folder with its own
/// `convergence.csv`; an unknown variant, or one the scene refuses, exits 2 naming the key and
/// writes nothing.
#[test]
fn converge_mass_runs_one_study_per_variant() {
    let out = tmpdir("converge-mass");
    let o = viscobar(&[
        "converge",
        "impact",
        "--mass",
        "consistent,lumped",
        "--solvers",
        "exact",
        "--levels",
        "2",
        "--repeats",
        "0",
        "--out",
        out.to_str().unwrap(),
    ]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let mut l2 = Vec::new();
    for v in ["consistent", "lumped"] {
        let csv = std::fs::read_to_string(out.join(format!("mass-{v}/convergence.csv"))).unwrap();
        assert!(csv.lines().count() >= 3, "{v}: {csv}");
        l2.push(csv);
    }
    // Different mass matrices, different errors.
    assert_ne!(l2[0], l2[1]);
    for (args, key) in [
        (&["impact", "--mass", "heavy"][..], "--mass"),
        (
            &["distributed", "--mass", "consistent,redistributed"][..],
            "bar.mass",
        ),
    ] {
        let bad = tmpdir("converge-mass-bad");
        let mut a = vec!["converge"];
        a.extend_from_slice(args);
        a.extend_from_slice(&[
            "--solvers",
            "exact",
            "--levels",
            "2",
            "--out",
            bad.to_str().unwrap(),
        ]);
        let o = viscobar(&a);
        assert_eq!(o.status.code(), Some(2), "{args:?}");
        assert!(String::from_utf8_lossy(&o.stderr).contains(key), "{args:?}");
        assert!(!bad.exists(), "{args:?}: nothing written");
    }
}

/// A reader that closes standard output before the listing is written (`viscobar scenes |
/// head -0`) ends the command quietly: exit 0, no panic on the broken pipe.
#[test]
fn a_closed_standard_output_ends_the_command_quietly() {
    let mut child = Command::new(env!("CARGO_BIN_EXE_viscobar"))
        .arg("scenes")
        .stdout(std::process::Stdio::piped())
        .stderr(std::process::Stdio::piped())
        .spawn()
        .unwrap();
    drop(child.stdout.take());
    let o = child.wait_with_output().unwrap();
    let stderr = String::from_utf8_lossy(&o.stderr);
    assert!(!stderr.contains("panicked"), "{stderr}");
    assert_eq!(o.status.code(), Some(0), "{stderr}");
}

/// Any other failure to write standard output is an error: exit 1, named on stderr (a full
/// device, `/dev/full`).
#[cfg(target_os = "linux")]
#[test]
fn a_failed_write_to_standard_output_exits_1() {
    let full = std::fs::OpenOptions::new()
        .write(true)
        .open("/dev/full")
        .unwrap();
    let o = Command::new(env!("CARGO_BIN_EXE_viscobar"))
        .arg("scenes")
        .stdout(full)
        .output()
        .unwrap();
    let stderr = String::from_utf8_lossy(&o.stderr);
    assert_eq!(o.status.code(), Some(1), "{stderr}");
    assert!(
        stderr.contains("standard output") && !stderr.contains("panicked"),
        "{stderr}"
    );
}
