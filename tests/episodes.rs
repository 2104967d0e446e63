//! Contact episodes in `summary.json`: start and end, impulse, peak reaction, the contact term
//! of the energy identity and the energies around each episode; and the rounding of times in
//! the outputs.

mod common;

use common::{IDENTITY_TOL, KINK_ORDER_BAND, builtin};
use viscobar::ContactEpisode;
use viscobar::bar::matrices::{MatrixVariant, mass};
use viscobar::internals::output::text::{TIME_DIGITS, output_time};
use viscobar::study::accuracy::observed_order;
use viscobar::{Summary, run_in_memory};

// Defined beside its measurement in the tolerance registry (`viscobar-certificate verify
// --tolerances`).
use viscobar_certificate::tolerances::{RELEASE_ELEMENTS, RELEASE_TOL, release_error};

fn episodes(summary: &Summary, side: &str) -> Vec<ContactEpisode> {
    summary.contact_episodes[side].clone()
}

/// Impact (ρ = 1, L = 1, v0 = 1, a0 = 0.1): one episode on [t1, t1 + 2L] = [0.1, 2.1] up to
/// the step, closed before the end; its impulse is the momentum change of the bar, exactly
/// (the scheme's momentum balance: `R` has zero row sums on a bar with no clamped end), and
/// tends to 2ρLv0 (the momentum reverses); its energy drop is its contact dissipation.
#[test]
fn impact_has_one_episode_whose_impulse_reverses_the_momentum() {
    let mut deficits = Vec::new();
    let mut hs = Vec::new();
    for elements in RELEASE_ELEMENTS {
        let dt = 1.0 / elements as f64;
        let scene = builtin(
            "impact",
            &[
                &format!("mesh.elements={elements}"),
                &format!("time.step={dt}"),
            ],
        );
        let (_, summary, sim) = run_in_memory("impact", &scene).unwrap();
        let sim = sim.mechanical().expect("impact has no [heat]");
        let e = episodes(&summary, "left");
        assert_eq!(e.len(), 1, "{e:?}");
        let e = &e[0];
        // Contact detected at the first step whose gap closes; released near t1 + 2L (the
        // contact-time error, VERIFICATION.md: 0.02, 0.015, 0.0075 at these meshes).
        assert!((e.start - 0.1).abs() <= dt * (1.0 + 1e-9), "{e:?}");
        assert!(release_error(e) <= RELEASE_TOL, "{e:?}");
        assert!(!e.open_at_end);
        assert_eq!([e.start, e.end], summary.contact_intervals["left"][0]);
        assert!(e.peak_reaction > 0.0);

        // Momentum after the run (the bar flies free) minus the initial −ρLv0.
        let disc = sim.discretisation();
        let mut v = vec![0.0; disc.nodes];
        sim.velocity_into(&mut v);
        let m = mass(MatrixVariant::Consistent, disc.nodes, disc.dx);
        let mut mv = vec![0.0; disc.nodes];
        m.mul_into(&v, &mut mv);
        let p_after: f64 = mv.iter().sum();
        let p_before = -1.0;
        // Summing `steps` terms of size ≤ 2 (the momentum) rounds by about steps·ε·2.
        let balance_tol = 4.0 * summary.steps as f64 * f64::EPSILON;
        assert!(
            (e.impulse - (p_after - p_before)).abs() <= balance_tol,
            "impulse {} vs momentum change {}",
            e.impulse,
            p_after - p_before
        );

        // α = 0, no load: the energy lost over the episode is its contact term, to the
        // identity's round-off summed over the episode's steps.
        let (before, after) = (e.energy_before.unwrap(), e.energy_after.unwrap());
        let contact = e.contact_dissipation.unwrap();
        let episode_steps = ((e.end - e.start) / dt).round() + 1.0;
        assert!(contact > 0.0);
        assert!(
            (before - after - contact).abs() <= episode_steps * IDENTITY_TOL * before,
            "{before} − {after} vs {contact}"
        );
        deficits.push(2.0 - e.impulse);
        hs.push(1.0 / elements as f64);
    }
    // The momentum deficit (the scheme's impact loss) vanishes at the kink rate.
    assert!(deficits.iter().all(|d| *d > 0.0), "{deficits:?}");
    let order = observed_order(&hs, &deficits);
    assert!(
        KINK_ORDER_BAND.0 <= order && order <= KINK_ORDER_BAND.1,
        "impulse deficit order {order} ({deficits:?})"
    );
}

/// The falling bar bounces twice in its default run; a run stopped during contact marks its
/// last episode open at the end.
#[test]
fn falling_bar_has_two_episodes_and_an_open_one_is_marked() {
    let scene = builtin("falling-bar", &[]);
    let (_, summary, _) = run_in_memory("falling-bar", &scene).unwrap();
    let e = episodes(&summary, "left");
    assert_eq!(e.len(), 2, "{e:?}");
    assert!(e.iter().all(|e| !e.open_at_end && e.impulse > 0.0));
    assert!(e[0].end < e[1].start);

    let stop = 0.5 * (e[0].start + e[0].end);
    let stop = (stop / scene.time.step).round() * scene.time.step;
    let cut = builtin("falling-bar", &[&format!("time.end={stop}")]);
    let (_, summary, _) = run_in_memory("falling-bar", &cut).unwrap();
    let open = episodes(&summary, "left");
    assert_eq!(open.len(), 1, "{open:?}");
    assert!(open[0].open_at_end);
    assert_eq!(open[0].end, summary.final_time);
}

/// A distributed obstacle has one list of episodes for its whole contact set, with the total
/// reaction of its nodes.
#[test]
fn distributed_obstacle_episodes_are_of_the_whole_set() {
    let scene = builtin("distributed", &[]);
    let (records, summary, _) = run_in_memory("distributed", &scene).unwrap();
    let e = episodes(&summary, "obstacle");
    assert!(!e.is_empty());
    let in_contact = records
        .iter()
        .filter(|r| r.contact.contact_nodes > 0)
        .count();
    let covered: f64 = e
        .iter()
        .map(|e| ((e.end - e.start) / scene.time.step).round() + 1.0)
        .sum();
    assert_eq!(covered as usize, in_contact);
    let peak = records
        .iter()
        .map(|r| r.contact.total_reaction)
        .fold(0.0, f64::max);
    assert_eq!(e.iter().map(|e| e.peak_reaction).fold(0.0, f64::max), peak);
}

/// The fast rounding of output times is the parse of the 12-digit text, for `n·Δt` over many
/// steps and steps, and for values outside the fast path's range.
#[test]
fn output_times_are_the_twelve_digit_decimals() {
    let text = |t: f64| -> f64 { format!("{:.*e}", TIME_DIGITS - 1, t).parse().unwrap() };
    for dt in [0.01, 0.005, 1.0 / 3.0, 1e-5, 0.03125, 0.00003125, 7.3e-3] {
        for n in 0..20_000u32 {
            let t = f64::from(n) * dt;
            assert_eq!(
                output_time(t).to_bits(),
                text(t).to_bits(),
                "n {n}, dt {dt}"
            );
        }
    }
    for t in [1e-30, 3.03e15 + 0.5, 1e300, -2.5e-7, 123456789012.345] {
        assert_eq!(output_time(t).to_bits(), text(t).to_bits(), "{t}");
    }
    assert_eq!(output_time(3.0300000000000002), 3.03);
}

/// The command line's closing lines name the same episodes as `summary.json`.
#[test]
fn run_prints_the_episodes_of_the_summary() {
    let out = std::env::temp_dir().join(format!("viscobar-episodes-{}", std::process::id()));
    let o = std::process::Command::new(env!("CARGO_BIN_EXE_viscobar"))
        .args(["run", "falling-bar", "--out"])
        .arg(&out)
        .output()
        .unwrap();
    assert!(o.status.success());
    let stdout = String::from_utf8_lossy(&o.stdout);
    let summary: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(out.join("summary.json")).unwrap()).unwrap();
    let episodes = summary["contact_episodes"]["left"].as_array().unwrap();
    let line = stdout
        .lines()
        .find(|l| l.trim_start().starts_with("left:"))
        .unwrap_or_else(|| panic!("no episode line in {stdout}"));
    assert!(
        line.contains(&format!("{} contact episodes", episodes.len())),
        "{line}"
    );
    for e in episodes {
        let time = |k: &str| e[k].as_f64().unwrap();
        let when = format!("[{}, {}]", time("start"), time("end"));
        assert!(line.contains(&when), "{when} not in {line}");
        assert!(line.contains(&format!("impulse {:.4}", e["impulse"].as_f64().unwrap())));
    }
    let _ = std::fs::remove_dir_all(&out);
}
