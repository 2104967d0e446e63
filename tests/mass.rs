//! The mass variants of `[bar] mass` end to end: the refused combinations through
//! the binary, `--set bar.mass=…` against the library's `run_with_mass`, the massless nodes of
//! the discretisation, and the bands of VERIFICATION.md's claims ("Mass variants") on the study
//! itself. The matrices are tested in `tests/matrices.rs`, the solvers with every variant in
//! the generic checker of `tests/solvers.rs`.

mod common;
use common::viscobar;

use viscobar::bar::Discretisation;
use viscobar::scene::MassVariant;
use viscobar::study::mass_variants::run_with_mass;
use viscobar_certificate::bar::mass_study::{MassRow, group_order, groups, mass_study};

/// The refused combinations exit 2 with a message naming both keys, and write nothing.
#[test]
fn refused_combinations_name_both_keys_and_exit_2() {
    let out = std::env::temp_dir().join(format!("viscobar-mass-refused-{}", std::process::id()));
    let cases: [(&str, &[&str], [&str; 2]); 3] = [
        (
            "impact",
            &["bar.mass=lumped", "bar.matrices=talk-printed"],
            ["bar.mass", "bar.matrices"],
        ),
        (
            "distributed",
            &["bar.mass=redistributed"],
            ["bar.mass", "obstacle.gap"],
        ),
        (
            "both-ends",
            &["bar.mass=redistributed", "mesh.elements=5"],
            ["bar.mass", "mesh.elements"],
        ),
    ];
    for (scene, sets, keys) in cases {
        let mut args = vec!["run", scene, "--out", out.to_str().unwrap()];
        for s in sets {
            args.extend(["--set", s]);
        }
        let o = viscobar(&args);
        let err = String::from_utf8_lossy(&o.stderr);
        assert_eq!(o.status.code(), Some(2), "{scene} {sets:?}: {err}");
        for key in keys {
            assert!(
                err.contains(key),
                "{scene} {sets:?}: `{key}` not named: {err}"
            );
        }
        assert!(!err.contains("panicked"), "{err}");
        assert!(!out.exists(), "{scene} {sets:?}: output written");
    }
    // Lumped goes with an obstacle; consistent with the talk's matrices.
    common::builtin("distributed", &["bar.mass=lumped"]);
    common::builtin(
        "impact",
        &["bar.matrices=talk-printed", "bar.mass=consistent"],
    );
}

/// The number of the top-level field `key` of a JSON text, parsed exactly by `str::parse`
/// (serde_json's default parser may land one ulp off the shortest round-trip text it wrote).
fn exact_number(json: &str, key: &str) -> f64 {
    let field = format!("\n  \"{key}\": ");
    let start = json
        .find(&field)
        .unwrap_or_else(|| panic!("no field {key}"))
        + field.len();
    let end = start + json[start..].find([',', '\n']).unwrap();
    json[start..end].parse().unwrap()
}

/// `viscobar run SCENE --set bar.mass=V` is the library's `run_with_mass(…, V)`: the same final
/// energy and contact episodes, bit for bit.
#[test]
fn set_bar_mass_on_the_command_line_is_run_with_mass() {
    let base = std::env::temp_dir().join(format!("viscobar-mass-set-{}", std::process::id()));
    let scene = common::builtin("impact", &[]);
    let mut finals = Vec::new();
    for mass in MassVariant::ALL {
        let out = base.join(mass.name());
        let set = format!("bar.mass={}", mass.name());
        let o = viscobar(&[
            "run",
            "impact",
            "--out",
            out.to_str().unwrap(),
            "--set",
            &set,
        ]);
        assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
        let text = std::fs::read_to_string(out.join("summary.json")).unwrap();
        let json: serde_json::Value = serde_json::from_str(&text).unwrap();
        let (_, summary, _) = run_with_mass("impact", &scene, mass).unwrap();
        let cli = exact_number(&text, "energy_final");
        assert_eq!(cli.to_bits(), summary.energy_final.to_bits(), "{mass:?}");
        assert_eq!(
            json["contact_intervals"]["left"].as_array().unwrap().len(),
            summary.contact_intervals["left"].len()
        );
        finals.push(cli);
    }
    // The variant is not ignored: three different runs.
    assert!(finals[0] != finals[1] && finals[1] != finals[2] && finals[0] != finals[2]);
    let _ = std::fs::remove_dir_all(&base);
}

/// The massless unknowns are the Signorini end nodes, only with a redistributed mass, and their
/// rows of `M` are zero.
#[test]
fn the_massless_nodes_are_the_signorini_ends_of_a_redistributed_mass() {
    for (scene, ends) in [
        ("impact", "left"),
        ("clamped-impact", "left"),
        ("both-ends", "both"),
        ("modal", "none"),
    ] {
        for mass in MassVariant::ALL {
            let s = common::builtin(scene, &[&format!("bar.mass={}", mass.name())]);
            let d = Discretisation::new(&s).unwrap();
            let n = d.unknowns();
            let expected = match (mass, ends) {
                (MassVariant::Redistributed, "left") => vec![0],
                (MassVariant::Redistributed, "both") => vec![0, n - 1],
                _ => vec![],
            };
            assert_eq!(d.massless, expected, "{scene} {mass:?}");
            for &k in &d.massless {
                assert_eq!(d.mass.diag[k], 0.0);
                assert_eq!(d.mass.row_sums()[k], 0.0);
            }
        }
    }
}

// ---- the bands of VERIFICATION.md's claims -------------------------------------------------

/// At α = 0 the contact term loses energy at the one step where contact begins,
/// `½ r (u^{n−1} + a)` with `0 <= u^{n−1} + a < v Δt`: first order in Δx for every variant
/// (measured 1.00 on both scenes); ±0.03 is a tenth of the way to order 0.7 (the L2 order).
const DISSIPATION_ORDER_BAND: (f64, f64) = (0.97, 1.03);
/// Redistributed over consistent contact dissipation at α = 0, finest level: measured 0.535 on
/// both scenes (the ratio is the same at every level: both are `c Δx`); the band keeps it
/// clearly below 1 ("reduced, not removed") and fails if the end node keeps its mass (ratio 1;
/// the loss is set by the massless node: dropping the moment correction leaves it in the band,
/// and [`REDISTRIBUTED_TV_RATIO_MIN`] then fails).
const REDISTRIBUTED_LOSS_RATIO_BAND: (f64, f64) = (0.50, 0.57);
/// Lumped over consistent, the same: measured 1.134 ("lumping loses more").
const LUMPED_LOSS_RATIO_BAND: (f64, f64) = (1.10, 1.17);
/// Redistributed over consistent total variation of the reaction at α = 0: measured 1.43
/// (impact) and 1.31 (falling-bar); the claim is "larger", with a margin.
const REDISTRIBUTED_TV_RATIO_MIN: f64 = 1.2;
/// Redistributed over consistent L2 error at α = 0: measured within 0.3 % ("the same
/// accuracy"); 5 % either way.
const REDISTRIBUTED_L2_RATIO_BAND: (f64, f64) = (0.95, 1.05);
/// Lumped over consistent L2 error, every scene and α: measured 1.14 … 1.52 ("less
/// accurate").
const LUMPED_L2_RATIO_MIN: f64 = 1.1;
// Defined beside their measurement in the tolerance registry (`viscobar-certificate verify
// --tolerances`).
use viscobar_certificate::tolerances::{DROP_TOL, START_TOL, drop_worst, start_up_motion};

fn finest<'a>(rows: &'a [MassRow], scene: &str, alpha: f64, mass: MassVariant) -> &'a MassRow {
    groups(rows)
        .find(|g| g[0].scene == scene && g[0].alpha == alpha && g[0].mass == mass)
        .and_then(|g| g.last())
        .expect("group in the study")
}

#[test]
fn the_mass_study_shows_the_claimed_bands() {
    let rows = mass_study().unwrap();
    for g in groups(&rows) {
        let at = format!("{} α = {} {:?}", g[0].scene, g[0].alpha, g[0].mass);
        if g[0].alpha == 0.0 {
            let order = group_order(g, |r| r.contact_dissipation).unwrap();
            assert!(
                (DISSIPATION_ORDER_BAND.0..=DISSIPATION_ORDER_BAND.1).contains(&order),
                "{at}: contact dissipation order {order}"
            );
        }
    }
    // Energy drop against the contact term on impact at α = 0: the registry's measurement.
    let drop = drop_worst(&rows);
    assert!(drop <= DROP_TOL, "drop − dissipation {drop:e}");
    let ratio = |scene, alpha, mass, f: fn(&MassRow) -> f64| {
        f(finest(&rows, scene, alpha, mass))
            / f(finest(&rows, scene, alpha, MassVariant::Consistent))
    };
    for scene in ["impact", "falling-bar"] {
        let loss = |m| ratio(scene, 0.0, m, |r: &MassRow| r.contact_dissipation);
        let (red, lump) = (loss(MassVariant::Redistributed), loss(MassVariant::Lumped));
        assert!(
            (REDISTRIBUTED_LOSS_RATIO_BAND.0..=REDISTRIBUTED_LOSS_RATIO_BAND.1).contains(&red),
            "{scene}: redistributed/consistent loss {red}"
        );
        assert!(
            (LUMPED_LOSS_RATIO_BAND.0..=LUMPED_LOSS_RATIO_BAND.1).contains(&lump),
            "{scene}: lumped/consistent loss {lump}"
        );
        let tv = ratio(scene, 0.0, MassVariant::Redistributed, |r| {
            r.reaction_variation
        });
        assert!(tv >= REDISTRIBUTED_TV_RATIO_MIN, "{scene}: TV ratio {tv}");
        let l2 = ratio(scene, 0.0, MassVariant::Redistributed, |r| r.l2_error);
        assert!(
            (REDISTRIBUTED_L2_RATIO_BAND.0..=REDISTRIBUTED_L2_RATIO_BAND.1).contains(&l2),
            "{scene}: redistributed/consistent L2 {l2}"
        );
        for alpha in [0.0, 0.1] {
            let l2 = ratio(scene, alpha, MassVariant::Lumped, |r| r.l2_error);
            assert!(
                l2 >= LUMPED_L2_RATIO_MIN,
                "{scene} α = {alpha}: lumped/consistent L2 {l2}"
            );
        }
    }
}

/// `viscobar mass` writes the figure as PNG and SVG; a bad override exits 2 and writes nothing.
#[test]
fn the_mass_command_writes_the_figure() {
    let out = std::env::temp_dir().join(format!("viscobar-mass-figure-{}", std::process::id()));
    let o = viscobar(&[
        "mass",
        "--out",
        out.to_str().unwrap(),
        "--set",
        "time.end=1",
    ]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let png = std::fs::read(out.join("mass-variants-impact.png")).unwrap();
    assert!(png.starts_with(b"\x89PNG"), "not a PNG");
    let svg = std::fs::read_to_string(out.join("mass-variants-impact.svg")).unwrap();
    for variant in MassVariant::ALL {
        assert!(
            svg.contains(variant.name()),
            "{} not in the SVG",
            variant.name()
        );
    }
    let _ = std::fs::remove_dir_all(&out);
    let o = viscobar(&[
        "mass",
        "--out",
        out.to_str().unwrap(),
        "--set",
        "bar.mass=heavy",
    ]);
    assert_eq!(o.status.code(), Some(2));
    assert!(!out.exists());
}

/// The README shows `docs/figures/mass-variants-impact.png`, which `viscobar mass --out
/// docs/figures` writes (the name; the pixels are not pinned, as for the talk's figures).
#[test]
fn the_committed_mass_figure_is_the_one_the_command_writes() {
    let name = format!("{}.png", viscobar::study::mass_figure::STEM);
    let docs = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("docs/figures");
    assert!(docs.join(&name).is_file(), "docs/figures/{name} missing");
    let readme =
        std::fs::read_to_string(concat!(env!("CARGO_MANIFEST_DIR"), "/README.md")).unwrap();
    assert!(readme.contains(&format!("(docs/figures/{name})")));
    assert!(readme.contains("cargo run --release -- mass --out docs/figures"));
}

/// Start-up with a massless node: its Taylor term is 0, so away from contact `u^1 = u^0 + Δt u_1`
/// there (the projection of an inactive start-up is `z = C⁻¹C w = w` up to the solve's
/// round-off), while the massive nodes accelerate. `one-end` starts at rest in the shape
/// `0.3 cos 2x`, its left end 0.4 above the obstacle.
#[test]
fn the_start_up_leaves_the_massless_node_without_acceleration() {
    // The first step of the left end and of the bar: the registry's measurement.
    for (mass, moved, scale) in start_up_motion().unwrap() {
        assert!(scale > 0.0, "{mass:?}: the bar does not move at the start");
        if mass == MassVariant::Redistributed {
            assert!(
                moved <= START_TOL * scale,
                "{mass:?}: massless node moved {moved:e}"
            );
        } else {
            assert!(
                moved > START_TOL * scale * 1e6,
                "{mass:?}: end node at rest ({moved:e})"
            );
        }
    }
}

/// The list a `converge --mass` option will take (not wired yet): every variant by name, errors
/// naming the option and the bad item.
#[test]
fn mass_lists_parse_and_bad_items_are_named() {
    use viscobar::study::mass_variants::parse_mass_list;
    assert_eq!(
        parse_mass_list("consistent, redistributed,lumped").unwrap(),
        MassVariant::ALL.to_vec()
    );
    assert_eq!(
        parse_mass_list("lumped").unwrap(),
        vec![MassVariant::Lumped]
    );
    for bad in ["heavy", "lumped,", "", "Lumped"] {
        let err = parse_mass_list(bad).unwrap_err().to_string();
        assert!(
            err.contains("--mass") && err.contains("redistributed"),
            "{bad}: {err}"
        );
    }
}
