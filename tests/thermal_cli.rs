//! The thermal bar through the command line: its files (history's thermal columns, the
//! profile's `theta`, the figure's θ panel) and its bad input, refused with exit 2 naming the
//! key, nothing written; a figure that fails after the run exits 1.

mod common;
use common::{assert_each_refused, fresh_dir, png_size, viscobar};

#[test]
fn a_thermal_run_writes_the_thermal_columns() {
    let out = fresh_dir("thermal", "columns");
    let o = viscobar(&[
        "run",
        "thermal-impact",
        "--out",
        out.to_str().unwrap(),
        "--set",
        "time.end=0.5",
    ]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let history = std::fs::read_to_string(out.join("history.csv")).unwrap();
    let header = history.lines().next().unwrap();
    assert!(header.starts_with(
        "step,t,energy,work,viscous_dissipation,contact_dissipation,identity_residual,\
         thermal_energy,thermal_dissipation,exchange,heat_supply,smoothing_dissipation,gap_left,\
         reaction_left"
    ));
    let columns = header.split(',').count();
    assert!(
        history
            .lines()
            .skip(1)
            .all(|l| l.split(',').count() == columns)
    );
    let profile = std::fs::read_to_string(out.join("displacement.csv")).unwrap();
    assert_eq!(profile.lines().next(), Some("t,x,u,v,theta"));
    assert!(profile.lines().skip(1).all(|l| l.split(',').count() == 5));
    std::fs::remove_dir_all(&out).unwrap();
}

/// `run SCENE --figure` of a scene with `[heat]` draws the bar's figure with the θ panel: the
/// wider size, the panel's title and colour bar label, and a second colour map (each map is one
/// embedded image; the bar without a temperature has one).
#[test]
fn a_thermal_run_draws_its_figure_with_theta() {
    let out = fresh_dir("thermal", "figure");
    let o = viscobar(&[
        "run",
        "thermal-impact",
        "--figure",
        "--out",
        out.to_str().unwrap(),
        "--set",
        "time.end=0.5",
    ]);
    let stdout = String::from_utf8_lossy(&o.stdout);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    for ext in ["png", "svg"] {
        let f = out.join(format!("thermal-impact.{ext}"));
        assert!(
            std::fs::metadata(&f).unwrap().len() > 1000,
            "{}",
            f.display()
        );
        assert!(
            stdout.contains(&format!("thermal-impact.{ext}")),
            "{stdout}"
        );
    }
    let png = std::fs::read(out.join("thermal-impact.png")).unwrap();
    assert_eq!(png_size(&png), viscobar::study::figures::THERMAL_SCENE_SIZE);
    let svg = std::fs::read_to_string(out.join("thermal-impact.svg")).unwrap();
    let texts: Vec<&str> = svg
        .split("<text")
        .map(|t| t.split('<').next().unwrap())
        .collect();
    let has = |label: &str| {
        texts
            .iter()
            .any(|t| t.split('>').nth(1).map(str::trim) == Some(label))
    };
    assert!(has("temperature θ(x, t)") && has("θ"), "no θ panel");
    assert!(has("displacement u(x, t)") && has("u"));
    assert_eq!(
        svg.matches("data:image/png;base64,").count(),
        2,
        "two colour maps"
    );
    assert!(out.join("history.csv").exists());
    std::fs::remove_dir_all(&out).unwrap();
}

/// A figure that cannot be written after the run has written its files is a failed run: exit
/// 1, the error names the file, and the run's own files stay.
#[test]
fn a_figure_that_fails_after_the_run_exits_1() {
    let out = fresh_dir("thermal", "figure-fails");
    // A folder (not empty) where the SVG goes: the rename into place fails.
    std::fs::create_dir_all(out.join("thermal-impact.svg/inside")).unwrap();
    let o = viscobar(&[
        "run",
        "thermal-impact",
        "--figure",
        "--out",
        out.to_str().unwrap(),
        "--set",
        "time.end=0.1",
    ]);
    let stderr = String::from_utf8_lossy(&o.stderr);
    assert_eq!(o.status.code(), Some(1), "{stderr}");
    assert!(stderr.contains("thermal-impact.svg"), "{stderr}");
    assert!(out.join("history.csv").exists() && out.join("summary.json").exists());
    std::fs::remove_dir_all(&out).unwrap();
}

#[test]
fn bad_thermal_input_exits_2_naming_the_key_and_writes_nothing() {
    let out = fresh_dir("thermal", "bad");
    let cases: &[(&str, &[&str], &str)] = &[
        (
            "zero diffusivity",
            &["heat.diffusivity=0"],
            "heat.diffusivity",
        ),
        (
            "negative diffusivity",
            &["heat.diffusivity=-1"],
            "heat.diffusivity",
        ),
        (
            "nan diffusivity",
            &["heat.diffusivity=nan"],
            "heat.diffusivity",
        ),
        (
            "negative coupling",
            &["heat.coupling=-0.1"],
            "heat.coupling",
        ),
        ("infinite coupling", &["heat.coupling=inf"], "heat.coupling"),
        (
            "negative exchange",
            &["heat.left.coefficient=-1"],
            "heat.left.coefficient",
        ),
        (
            "nan exchange",
            &["heat.left.coefficient=nan"],
            "heat.left.coefficient",
        ),
        (
            "exchange at a free end",
            &["heat.right.condition=exchange", "heat.right.coefficient=1"],
            "heat.right.condition",
        ),
        (
            "value at an exchange end",
            &["heat.left.value=1"],
            "heat.left.value",
        ),
        (
            "non-finite temperature",
            &["heat.temperature=\"1/0\""],
            "heat.temperature",
        ),
        (
            "source non-finite mid-run",
            &["heat.source=\"sqrt(0.1 - t)\""],
            "heat.source",
        ),
        (
            "non-finite obstacle",
            &["heat.left.obstacle=\"1/0\""],
            "heat.left.obstacle",
        ),
        // An end is a point: a temperature in x would be read at one node only.
        (
            "obstacle temperature in x",
            &["heat.left.obstacle=\"x\""],
            "heat.left.obstacle",
        ),
        (
            "diffusivity too stiff to certify",
            &["heat.diffusivity=1e12"],
            "heat.diffusivity",
        ),
        ("unknown key", &["heat.conductivity=1"], "conductivity"),
        ("osqp", &["solver.method=osqp"], "solver.method"),
        ("penalty", &["solver.method=penalty"], "solver.method"),
        (
            "obstacle under every node",
            &["obstacle.gap=0.1"],
            "obstacle.gap",
        ),
    ];
    assert_each_refused("thermal-impact", cases, &out);
    let fixed: &[(&str, &[&str], &str)] = &[
        (
            "non-finite end temperature",
            &["heat.right.value=\"1/t\""],
            "heat.right.value",
        ),
        (
            "end temperature in x",
            &["heat.right.value=\"x\""],
            "heat.right.value",
        ),
        (
            "temperature without value",
            &["heat.right.value=\"\""],
            "heat.right.value",
        ),
        (
            "no unknown temperature",
            &[
                "mesh.elements=1",
                "heat.left.condition=temperature",
                "heat.left.value=0.5",
            ],
            "mesh.elements",
        ),
    ];
    assert_each_refused("heated-expansion", fixed, &out);
    let clamped: &[(&str, &[&str], &str)] = &[(
        "exchange at a clamped end",
        &[
            "right.condition=clamped",
            "heat.right.condition=exchange",
            "heat.right.coefficient=1",
        ],
        "heat.right.condition",
    )];
    assert_each_refused("thermal-impact", clamped, &out);
    // A thermal end on a bar without [heat].
    let no_heat: &[(&str, &[&str], &str)] = &[
        (
            "thermal end without [heat]",
            &["heat.left.condition=insulated"],
            "heat.coupling",
        ),
        (
            "thermal key in [left]",
            &["left.coefficient=2"],
            "left.coefficient",
        ),
        (
            "thermal condition in [left]",
            &["left.condition=exchange"],
            "left.condition",
        ),
    ];
    assert_each_refused("impact", no_heat, &out);
}

/// The smallest meshes run: one element with one fixed temperature (one unknown
/// temperature), with the coupling and without.
#[test]
fn one_element_thermal_bars_run() {
    for coupling in ["0.1", "0"] {
        let out = fresh_dir("thermal", &format!("one-element-{coupling}"));
        let o = viscobar(&[
            "run",
            "heated-expansion",
            "--out",
            out.to_str().unwrap(),
            "--set",
            "mesh.elements=1",
            "--set",
            &format!("heat.coupling={coupling}"),
            "--set",
            "time.end=0.5",
        ]);
        let stderr = String::from_utf8_lossy(&o.stderr);
        assert_eq!(o.status.code(), Some(0), "{stderr}");
        assert!(out.join("history.csv").exists());
        std::fs::remove_dir_all(&out).unwrap();
    }
}

/// The commands that take bar scenes without a temperature refuse a thermal one (exit 2).
#[test]
fn commands_without_a_temperature_refuse_a_thermal_scene() {
    let o = viscobar(&[
        "converge",
        "heated-expansion",
        "--levels",
        "2",
        "--solvers",
        "exact",
    ]);
    assert_eq!(
        o.status.code(),
        Some(2),
        "{}",
        String::from_utf8_lossy(&o.stderr)
    );
    assert!(String::from_utf8_lossy(&o.stderr).contains("heat"));
}
