//! The `viscobar` command line.

/// `println!` and `print!` that end the process quietly when standard output is closed
/// (`viscobar scenes | head`: a reader that stops early is not a failure, and the runs' files
/// are already whole); any other failure to write is an error ([`stdout_failed`]).
macro_rules! println {
    ($($t:tt)*) => {{
        use std::io::Write as _;
        if let Err(e) = writeln!(std::io::stdout(), $($t)*) {
            stdout_failed(e)
        }
    }};
}
macro_rules! print {
    ($($t:tt)*) => {{
        use std::io::Write as _;
        if let Err(e) = write!(std::io::stdout(), $($t)*) {
            stdout_failed(e)
        }
    }};
}

/// Exit 0 on a closed pipe, else exit 1 naming the failure.
fn stdout_failed(e: std::io::Error) -> ! {
    if e.kind() == std::io::ErrorKind::BrokenPipe {
        std::process::exit(0);
    }
    eprintln!("error: writing to standard output: {e}");
    std::process::exit(1)
}

use clap::{Parser, Subcommand};
use std::io::IsTerminal;
use std::path::PathBuf;
use viscobar::scene;
use viscobar::{SceneError, SolverMethod};

#[derive(Parser)]
#[command(
    name = "viscobar",
    version,
    about = "Viscoelastic bar with unilateral constraints"
)]
struct Cli {
    #[command(subcommand)]
    command: Command,
}

#[derive(Subcommand)]
enum Command {
    /// Run a scene, bar or plane (built-in name or TOML file), and write summary.json,
    /// history.csv and displacement.csv (with `[output] format = "npy"`: displacement.npy).
    Run {
        /// A built-in scene (a name from `viscobar scenes`) or the path of a TOML scene file.
        scene: String,
        /// Output folder [default: out/<scene>].
        #[arg(long)]
        out: Option<PathBuf>,
        /// Step solver (overrides [solver] method).
        #[arg(long)]
        solver: Option<String>,
        /// Override a scene key, e.g. --set time.step=0.001 (repeatable).
        #[arg(long = "set", value_name = "KEY=VALUE")]
        set: Vec<String>,
        /// Also draw the run's figures into the output folder: for a plane scene the deformed
        /// mesh coloured by the von Mises stress at 6 times (deformed.png, deformed.svg), with
        /// Signorini edges the contact pressure over (s, t) (contact-pressure.png, .svg), with
        /// friction the stick/slip/open state and the forces (friction-state.png, .svg); for a
        /// bar scene u(x, t) beside the contact reactions (<scene>.png, <scene>.svg), with
        /// [heat] also θ(x, t). A figure that cannot be drawn after the run exits 1.
        #[arg(long)]
        figure: bool,
        /// Write a run that breaks its certificate (an energy-identity residual over its bound
        /// at some step) instead of exiting 1 without output; a warning on stderr names the
        /// step, and summary.json says `"certified": false`.
        #[arg(long)]
        uncertified: bool,
    },
    /// Run the talk's scenes and draw their figures (PNG and SVG): one per scene (colour map of
    /// u(x, t) and contact history) and one per talk figure (l = 0 beside forced).
    Figures {
        /// Output folder.
        #[arg(long, default_value = viscobar::study::figures::DEFAULT_OUT)]
        out: PathBuf,
        /// Step solver (overrides [solver] method of every scene).
        #[arg(long)]
        solver: Option<String>,
    },
    /// Run `impact` with each mass variant (consistent, redistributed, lumped) and draw
    /// mass-variants-impact.png/.svg: energy and contact reaction, one variant per row.
    Mass {
        /// Output folder.
        #[arg(long, default_value = viscobar::study::mass_figure::DEFAULT_OUT)]
        out: PathBuf,
        /// Override a key of the impact scene, e.g. --set bar.viscosity=0.1 (repeatable).
        #[arg(long = "set", value_name = "KEY=VALUE")]
        set: Vec<String>,
    },
    /// Refinement study of the step solvers (convergence.csv, work-precision.png/.svg), or
    /// with --viscosity-sweep the alpha -> 0 study of the impact scene.
    Converge {
        /// A built-in scene (a name from `viscobar scenes`) or the path of a TOML scene file.
        scene: String,
        /// Comma-separated solvers: exact, osqp (once per --osqp-eps), penalty (once per
        /// --penalty-epsilon).
        #[arg(long, default_value = "exact,osqp,penalty")]
        solvers: String,
        /// OSQP tolerances (eps_abs = eps_rel), comma-separated.
        #[arg(long, default_value = "1e-4,1e-7,1e-10", value_name = "LIST")]
        osqp_eps: String,
        /// Penalty parameters epsilon, comma-separated.
        #[arg(long, default_value = "1e-3,1e-5,1e-7", value_name = "LIST")]
        penalty_epsilon: String,
        /// Refinement level of the exact reference run (the scene's mesh is level 0; finer
        /// than the finest level) [default: the closed form of a built-in scene that has one,
        /// else 2 levels above the finest, 4x finer in space and time]. Given, the reference is
        /// a run even where a closed form exists.
        #[arg(long, value_name = "LEVEL")]
        reference_level: Option<u32>,
        /// Timing repeats per run, taken one run at a time after the parallel error pass; the
        /// median is kept (0: the times of the parallel pass).
        #[arg(long, default_value_t = viscobar::study::converge::DEFAULT_REPEATS)]
        repeats: usize,
        /// Override a scene key, e.g. --set time.end=2 (repeatable).
        #[arg(long = "set", value_name = "KEY=VALUE")]
        set: Vec<String>,
        /// Levels of refinement (elements doubled per level from the scene's mesh).
        #[arg(long, default_value_t = viscobar::study::converge::DEFAULT_LEVELS)]
        levels: u32,
        /// dt/dx at every level [default: the scene's].
        #[arg(long)]
        ratio: Option<f64>,
        /// Comma-separated mass matrices (consistent, redistributed, lumped): one study each,
        /// in `<out>/mass-<variant>/` when more than one [default: the scene's `bar.mass`].
        #[arg(long, value_name = "LIST")]
        mass: Option<String>,
        /// Output folder [default: out/converge-<scene>].
        #[arg(long)]
        out: Option<PathBuf>,
        /// The alpha -> 0 sweep against the elastic closed form (impact only).
        #[arg(long)]
        viscosity_sweep: bool,
    },
    /// Run a scene with several step solvers side by side and print, as a Markdown table, how
    /// far each is from the first one listed over every step (displacements and reactions).
    Compare {
        /// A built-in scene (a name from `viscobar scenes`) or the path of a TOML scene file.
        scene: String,
        /// Comma-separated step solvers (exact, osqp, penalty); the first is the reference.
        /// Each uses the scene's [solver] settings that belong to it.
        #[arg(long, default_value = "exact,osqp,penalty")]
        solvers: String,
        /// Override a scene key, e.g. --set time.step=0.001 (repeatable).
        #[arg(long = "set", value_name = "KEY=VALUE")]
        set: Vec<String>,
        /// Output folder of comparison.md, the table also printed [default:
        /// out/compare-<scene>].
        #[arg(long)]
        out: Option<PathBuf>,
    },
    /// List the built-in scenes.
    Scenes,
    /// Print a built-in scene as TOML.
    Show {
        /// A built-in scene's name (as listed by `viscobar scenes`).
        name: String,
    },
}

fn main() {
    let cli = Cli::parse();
    let code = match cli.command {
        Command::Scenes => {
            print!("{}", scene_list());
            0
        }
        Command::Show { name } => {
            match scene::builtin_text(&name).or_else(|| scene::plane::plane_builtin_text(&name)) {
                Some(text) => {
                    print!("{text}");
                    0
                }
                None => {
                    eprintln!(
                        "error: unknown scene `{name}` (built-in scenes: {})",
                        all_builtin_names().join(", ")
                    );
                    2
                }
            }
        }
        Command::Converge {
            scene,
            solvers,
            osqp_eps,
            penalty_epsilon,
            reference_level,
            repeats,
            set,
            levels,
            ratio,
            out,
            viscosity_sweep,
            mass,
        } => match converge(
            &scene,
            [&solvers, &osqp_eps, &penalty_epsilon],
            mass.as_deref(),
            &set,
            viscobar::study::converge::StudyOptions {
                levels,
                ratio,
                reference_level,
                repeats,
            },
            out,
            viscosity_sweep,
        ) {
            Ok(()) => 0,
            Err(e) => {
                eprintln!("error: {e}");
                e.exit_code()
            }
        },
        Command::Compare {
            scene,
            solvers,
            set,
            out,
        } => match compare(&scene, &solvers, &set, out) {
            Ok(()) => 0,
            Err(e) => {
                eprintln!("error: {e}");
                e.exit_code()
            }
        },
        Command::Run {
            scene: name,
            out,
            solver,
            mut set,
            figure,
            uncertified,
        } => {
            if let Some(s) = solver {
                set.push(format!("solver.method=\"{s}\""));
            }
            let certify = if uncertified {
                viscobar::output::Certify::Record
            } else {
                viscobar::output::Certify::Strict
            };
            match run_any(&name, out, &set, figure, certify) {
                Ok(()) => 0,
                Err(code) => code,
            }
        }
        Command::Mass { out, set } => {
            match viscobar::study::mass_figure::write_mass_figure(&out, &set) {
                Ok(files) => {
                    for f in &files {
                        println!("wrote {}", f.display());
                    }
                    0
                }
                Err(e) => {
                    eprintln!("error: {e}");
                    e.exit_code()
                }
            }
        }
        Command::Figures { out, solver } => {
            let set: Vec<String> = solver
                .iter()
                .map(|s| format!("solver.method=\"{s}\""))
                .collect();
            match viscobar::study::figures::write_talk_figures(&out, &set) {
                Ok(files) => {
                    for f in &files {
                        println!("wrote {}", f.display());
                    }
                    0
                }
                Err(e) => {
                    eprintln!("error: {e}");
                    e.exit_code()
                }
            }
        }
    };
    std::process::exit(code);
}

/// Width of the `scenes` listing: the width of the source text and of the help texts.
const LIST_WIDTH: usize = 100;
/// Spaces between the name column and the descriptions of the `scenes` listing.
const LIST_GAP: usize = 2;

/// The `scenes` listing: each built-in name, in a column as wide as the longest, beside the
/// first sentence of its description, wrapped onto indented continuation lines.
fn scene_list() -> String {
    let all = || {
        (scene::BUILTIN.iter())
            .chain(scene::THERMAL_BUILTIN)
            .chain(scene::plane::PLANE_BUILTIN)
    };
    let width = all()
        .map(|(name, _)| name.chars().count())
        .max()
        .unwrap_or(0);
    let indent = width + LIST_GAP;
    let mut list = String::new();
    for (name, text) in all() {
        let description = match scene::plane::any_from_toml(text, &[]) {
            Ok(scene::AnyScene::Bar(s)) => s.description,
            Ok(scene::AnyScene::Plane(s)) => s.description,
            Err(_) => None,
        };
        let sentence = description.map(|d| first_sentence(&d)).unwrap_or_default();
        let mut line = format!("{name:width$}");
        let mut empty = true;
        for word in sentence.split_whitespace() {
            if !empty && line.chars().count() + 1 + word.chars().count() > LIST_WIDTH {
                list.push_str(line.trim_end());
                list.push('\n');
                line = " ".repeat(indent);
                empty = true;
            }
            if empty {
                line = format!("{line:indent$}");
            } else {
                line.push(' ');
            }
            line.push_str(word);
            empty = false;
        }
        list.push_str(line.trim_end());
        list.push('\n');
    }
    list
}

/// The first sentence of `text`, its lines joined: up to the first `.` outside parentheses
/// that ends the text or comes before white space (so `0.5` and `f(x). ` inside brackets do
/// not end it). The whole text when it has no such full stop.
fn first_sentence(text: &str) -> String {
    let words: Vec<&str> = text.split_whitespace().collect();
    let joined = words.join(" ");
    let mut depth = 0i32;
    let mut chars = joined.char_indices().peekable();
    while let Some((i, c)) = chars.next() {
        match c {
            '(' | '[' => depth += 1,
            ')' | ']' => depth -= 1,
            '.' if depth <= 0 && chars.peek().is_none_or(|(_, n)| n.is_whitespace()) => {
                return joined[..=i].to_string();
            }
            _ => {}
        }
    }
    joined
}

/// The names of the built-in scenes, bar and plane.
fn all_builtin_names() -> Vec<&'static str> {
    let mut names = scene::builtin_names();
    names.extend(scene::thermal_builtin_names());
    names.extend(scene::plane::PLANE_BUILTIN.iter().map(|(n, _)| *n));
    names
}

/// `viscobar run` of a bar or plane scene; the exit code on failure.
fn run_any(
    name: &str,
    out: Option<PathBuf>,
    set: &[String],
    figure: bool,
    certify: viscobar::output::Certify,
) -> Result<(), i32> {
    let fail = |e: viscobar::RunError| {
        let hint = if matches!(e, viscobar::RunError::Uncertified(_)) {
            " (nothing written; `--uncertified` writes such a run anyway)"
        } else {
            ""
        };
        eprintln!("error: {e}{hint}");
        e.exit_code()
    };
    let (scene_name, any) = scene::load_any(name, set).map_err(|e| {
        eprintln!("error: {e}");
        2
    })?;
    let options = viscobar::output::RunOptions {
        progress: std::io::stderr().is_terminal(),
        certify,
    };
    match any {
        scene::AnyScene::Bar(bar) => {
            let out = out.unwrap_or_else(|| PathBuf::from("out").join(&scene_name));
            let summary = viscobar::output::run_to_dir_with(&scene_name, &bar, &out, options)
                .map_err(fail)?;
            report(&summary, &out);
            if figure {
                let files = viscobar::study::figures::write_scene_figure(&scene_name, &bar, &out)
                    .map_err(|e| {
                    eprintln!("error: {e}");
                    FIGURE_FAILED
                })?;
                for f in &files {
                    println!("wrote {}", f.display());
                }
            }
            Ok(())
        }
        scene::AnyScene::Plane(plane) => {
            let out = out.unwrap_or_else(|| PathBuf::from("out").join(&scene_name));
            let summary =
                viscobar::output::run_plane_to_dir_with(&scene_name, &plane, &out, options)
                    .map_err(fail)?;
            report(&summary, &out);
            if figure {
                plane_figure(&scene_name, &plane, &out)?;
            }
            Ok(())
        }
    }
}

/// Exit code of `run --figure` when the figure fails after the run has written its files: the
/// input was accepted by the run, so whatever stops the figure is a failed run.
const FIGURE_FAILED: i32 = 1;

/// Draws the deformed-mesh figure of a plane scene into `out` (the scene is run again in
/// memory, keeping six snapshots).
fn plane_figure(name: &str, scene: &scene::PlaneScene, out: &std::path::Path) -> Result<(), i32> {
    match viscobar::study::plane_figure::write(name, scene, out) {
        Ok(files) => {
            for f in &files {
                println!("wrote {}", f.display());
            }
            Ok(())
        }
        Err(e) => {
            eprintln!("error: {e}");
            Err(FIGURE_FAILED)
        }
    }
}

/// The closing lines of `run`, either body: what ran, how fast, the identity residual, one
/// line of contact episodes per group of constraints, and a warning for inaccurate OSQP steps.
fn report(summary: &viscobar::Summary, out: &std::path::Path) {
    println!(
        "{}: {} steps of {} unknowns ({} nodes) with `{}` in {:.3} s ({:.1} ns per \
         unknown-step); max identity residual {:.1e} (bound {:.1e}); results in {}",
        summary.scene,
        summary.steps,
        summary.unknowns,
        summary.nodes,
        summary.solver,
        summary.wall_time_s,
        summary.ns_per_unknown_step,
        summary.max_identity_residual,
        summary.max_identity_bound,
        out.display()
    );
    for (group, episodes) in &summary.contact_episodes {
        println!("  {group}: {}", episode_line(episodes));
    }
    if let Some(d) = summary.friction_dissipation {
        println!("  friction dissipation {d:.3e}");
    }
    if let Some(f) = &summary.certificate.first_failure {
        eprintln!(
            "warning: the run is not certified: {f}; written because of --uncertified \
             (summary.json: \"certified\": false)"
        );
    }
    if let Some(n) = summary.inaccurate_steps.filter(|n| *n > 0) {
        eprintln!(
            "warning: {n} steps accepted although OSQP reported `solved inaccurate` \
             (solver.accept_inaccurate = true); see inaccurate_steps and audit in summary.json"
        );
    }
}

/// `[solvers, osqp_eps, penalty_epsilon]`: the three lists of `converge`.
fn converge(
    name: &str,
    [solvers, osqp_eps, penalty_epsilon]: [&str; 3],
    mass: Option<&str>,
    set: &[String],
    options: viscobar::study::converge::StudyOptions,
    out: Option<PathBuf>,
    viscosity_sweep: bool,
) -> Result<(), viscobar::study::converge::ConvergeError> {
    use viscobar::study::{converge, viscosity_sweep as sweep};
    let settings = converge::parse_solvers_with(
        solvers,
        &converge::parse_tolerances("--osqp-eps", osqp_eps)?,
        &converge::parse_tolerances("--penalty-epsilon", penalty_epsilon)?,
    )?;
    let (scene_name, any) = scene::load_any(name, set)?;
    let out = out.unwrap_or_else(|| PathBuf::from("out").join(format!("converge-{scene_name}")));
    let scene = match any {
        scene::AnyScene::Bar(scene) => scene,
        scene::AnyScene::Plane(plane) => {
            let bar_only = if viscosity_sweep {
                Some("--viscosity-sweep")
            } else {
                mass.map(|_| "--mass")
            };
            if let Some(flag) = bar_only {
                return Err(converge::ConvergeError::BadInput(format!(
                    "{flag} studies a bar scene; `{scene_name}` is a plane scene"
                )));
            }
            let study = converge::study_with(&scene_name, plane.as_ref(), &settings, &options)?;
            print!("{}", study.markdown());
            for f in &study.write(&out)? {
                println!("wrote {}", f.display());
            }
            return Ok(());
        }
    };
    let files = if viscosity_sweep {
        let sweep = sweep::viscosity_sweep(
            &scene_name,
            &scene,
            &sweep::SWEEP_ALPHAS,
            &sweep::SWEEP_ELEMENTS,
        )?;
        print!("{}", sweep.markdown());
        sweep.write(&out)?
    } else if let Some(list) = mass {
        use viscobar::study::mass_variants::{parse_mass_list, with_mass};
        let variants = parse_mass_list(list)?;
        // Every variant validated (e.g. redistributed with an obstacle) before any is run.
        let scenes = variants
            .iter()
            .map(|&v| with_mass(&scene, v))
            .collect::<Result<Vec<_>, _>>()?;
        let mut files = Vec::new();
        for (variant, scene) in variants.iter().zip(&scenes) {
            let study = converge::study_with(&scene_name, scene, &settings, &options)?;
            let dir = if variants.len() > 1 {
                println!("## bar.mass = {}\n", variant.name());
                out.join(format!("mass-{}", variant.name()))
            } else {
                out.clone()
            };
            print!("{}", study.markdown());
            files.extend(study.write(&dir)?);
        }
        files
    } else {
        let study = converge::study_with(&scene_name, scene.as_ref(), &settings, &options)?;
        print!("{}", study.markdown());
        study.write(&out)?
    };
    for f in &files {
        println!("wrote {}", f.display());
    }
    Ok(())
}

/// The step solvers `compare` knows, by name.
const METHODS: [SolverMethod; 3] = [
    SolverMethod::Exact,
    SolverMethod::Osqp,
    SolverMethod::Penalty,
];

/// The `--solvers` list of `compare`: known names, no repeats, at least two.
fn parse_methods(list: &str) -> Result<Vec<SolverMethod>, SceneError> {
    let bad = |allowed: String| SceneError::Invalid {
        field: "--solvers".into(),
        value: list.to_string(),
        allowed,
    };
    let known = || METHODS.map(SolverMethod::name).join(", ");
    let mut methods = Vec::new();
    for name in list.split(',').map(str::trim) {
        let method = METHODS
            .into_iter()
            .find(|m| m.name() == name)
            .ok_or_else(|| bad(format!("unknown solver `{name}` (known: {})", known())))?;
        if methods.contains(&method) {
            return Err(bad(format!("`{name}` is listed twice")));
        }
        methods.push(method);
    }
    if methods.len() < 2 {
        return Err(bad(format!(
            "list at least two solvers, the reference first (known: {})",
            known()
        )));
    }
    Ok(methods)
}

/// `viscobar compare`: each solver after the first run side by side with the first, one row
/// of the Markdown table per pair, printed and written to `comparison.md` in `out`. A solver that cannot
/// handle the scene (the bar's penalty solver on an obstacle) gets a row saying why.
fn compare(
    name: &str,
    solvers: &str,
    set: &[String],
    out: Option<PathBuf>,
) -> Result<(), viscobar::RunError> {
    let methods = parse_methods(solvers)?;
    let (scene_name, table) = match scene::load_any(name, set)? {
        (n, scene::AnyScene::Bar(s)) => (n.clone(), compare_on(&n, s.as_ref(), &methods)?),
        (n, scene::AnyScene::Plane(s)) => (n.clone(), compare_on(&n, s.as_ref(), &methods)?),
    };
    let out = out.unwrap_or_else(|| PathBuf::from("out").join(format!("compare-{scene_name}")));
    let path = out.join("comparison.md");
    let written = std::fs::create_dir_all(&out).and_then(|()| {
        viscobar::internals::output::files::write_atomically(&path, table.as_bytes())
    });
    written.map_err(|source| viscobar::RunError::Write {
        path: path.clone(),
        source,
    })?;
    print!("{table}");
    println!("\nwrote {}", path.display());
    Ok(())
}

/// [`compare`]'s table (Markdown) on a scene of either body.
fn compare_on<S: viscobar::study::StudyScene>(
    scene_name: &str,
    scene: &S,
    methods: &[SolverMethod],
) -> Result<String, viscobar::RunError> {
    use std::fmt::Write as _;
    use viscobar::study::compare::{compare, with_solver};
    let reference = with_solver(scene, methods[0]);
    // Refused here (exit 2) if the reference itself cannot handle the scene.
    let groups = reference.simulation()?.contact().groups().len();
    let dash = || "–".to_string();
    let mut table = String::new();
    writeln!(
        table,
        "{scene_name}: {} steps of dt = {}, {} elements; each solver against `{}`\n",
        scene.steps(),
        scene.dt(),
        scene.elements(),
        methods[0].name()
    )
    .expect("a String takes writes");
    writeln!(
        table,
        "| solvers | steps | max \\|Δu\\| | at step | max \\|Δu\\| / max \\|u\\| \
         | max \\|Δreaction\\| (per group) | max \\|Δreaction\\| / max \\|reaction\\| \
         | max violation | iterations mean / max | wall time (s) |"
    )
    .expect("a String takes writes");
    table.push_str("|---|---:|---:|---:|---:|---:|---:|---:|---:|---:|\n");
    for &method in &methods[1..] {
        let pair = format!("{} vs {}", method.name(), methods[0].name());
        let other = with_solver(scene, method);
        let c = match compare(method.name(), &reference, &other) {
            Ok(c) => c,
            Err(viscobar::RunError::Scene(SceneError::Invalid { field, allowed, .. }))
                if field == "solver.method" =>
            {
                let cells = " |".repeat(8);
                writeln!(table, "| {pair} | does not apply: {allowed} |{cells}")
                    .expect("a String takes writes");
                continue;
            }
            Err(e) => return Err(e),
        };
        let (a, s) = (c.agreement, &c.summary);
        let ratio = |d: f64, scale: f64| {
            if scale > 0.0 {
                format!("{:.2e}", d / scale)
            } else {
                dash()
            }
        };
        let (dr, dr_rel) = if groups > 0 {
            (
                format!("{:.3e}", a.max_reaction_difference),
                ratio(a.max_reaction_difference, a.max_reaction),
            )
        } else {
            (dash(), dash())
        };
        writeln!(
            table,
            "| {pair} | {} | {:.3e} | {} | {} | {dr} | {dr_rel} | {:.1e} | {:.1} / {} | {:.3} |",
            a.steps,
            a.max_difference,
            a.worst_step,
            ratio(a.max_difference, a.max_displacement),
            s.max_violation,
            s.solver_iterations.mean,
            s.solver_iterations.max,
            s.wall_time_s
        )
        .expect("a String takes writes");
    }
    Ok(table)
}

/// The contact episodes of one end (or of the obstacle) in one line: when, impulse and the
/// energy the contact term took (the same episodes as `summary.json` and the figures).
fn episode_line(episodes: &[viscobar::ContactEpisode]) -> String {
    use viscobar::internals::output::text::output_time;
    if episodes.is_empty() {
        return "no contact".into();
    }
    let each: Vec<String> = episodes
        .iter()
        .map(|e| {
            let end = if e.open_at_end {
                format!("{} (open at the end)", output_time(e.end))
            } else {
                output_time(e.end).to_string()
            };
            let lost = e
                .contact_dissipation
                .map_or_else(|| "not measured".into(), |d| format!("{d:.3e}"));
            format!(
                "[{}, {end}] impulse {:.4} peak reaction {:.4} contact dissipation {lost}",
                output_time(e.start),
                e.impulse,
                e.peak_reaction
            )
        })
        .collect();
    let n = episodes.len();
    format!(
        "{n} contact episode{}: {}",
        if n == 1 { "" } else { "s" },
        each.join("; ")
    )
}

#[cfg(test)]
mod tests {
    use super::first_sentence;

    #[test]
    fn first_sentence_stops_at_a_full_stop_outside_brackets_before_a_space() {
        assert_eq!(
            first_sentence("Gap a0 = 0.1\nbelow (see f. 2) the end. Then more."),
            "Gap a0 = 0.1 below (see f. 2) the end."
        );
        assert_eq!(first_sentence("Ends here."), "Ends here.");
        assert_eq!(first_sentence("  no full stop "), "no full stop");
    }
}
