//! The `viscobar` command line.

use clap::{Parser, Subcommand};
use std::io::IsTerminal;
use std::path::PathBuf;
use viscobar::scene;

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
    /// Run a scene (built-in name or TOML file) and write summary.json, history.csv and
    /// displacement.csv.
    Run {
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
    },
    /// List the built-in scenes.
    Scenes,
    /// Print a built-in scene as TOML.
    Show { name: String },
}

fn main() {
    let cli = Cli::parse();
    let code = match cli.command {
        Command::Scenes => {
            for (name, text) in scene::BUILTIN {
                let first = scene::Scene::from_toml(text, &[])
                    .ok()
                    .and_then(|s| s.description)
                    .and_then(|d| d.lines().find(|l| !l.trim().is_empty()).map(str::to_string))
                    .unwrap_or_default();
                println!("{name:16} {first}");
            }
            0
        }
        Command::Show { name } => match scene::builtin_text(&name) {
            Some(text) => {
                print!("{text}");
                0
            }
            None => {
                eprintln!(
                    "error: unknown scene `{name}` (built-in scenes: {})",
                    scene::builtin_names().join(", ")
                );
                2
            }
        },
        Command::Run {
            scene: name,
            out,
            solver,
            mut set,
        } => {
            if let Some(s) = solver {
                set.push(format!("solver.method=\"{s}\""));
            }
            match run(&name, out, &set) {
                Ok(()) => 0,
                Err(e) => {
                    eprintln!("error: {e}");
                    e.exit_code()
                }
            }
        }
    };
    std::process::exit(code);
}

fn run(name: &str, out: Option<PathBuf>, set: &[String]) -> Result<(), viscobar::RunError> {
    let (scene_name, scene) = scene::load(name, set)?;
    let out = out.unwrap_or_else(|| PathBuf::from("out").join(&scene_name));
    let summary =
        viscobar::run::run_to_dir(&scene_name, &scene, &out, std::io::stderr().is_terminal())?;
    println!(
        "{}: {} steps of {} nodes with `{}` in {:.3} s ({:.1} ns per node-step); \
         max identity residual {:.1e}; results in {}",
        summary.scene,
        summary.steps,
        summary.nodes,
        summary.solver,
        summary.wall_time_s,
        summary.ns_per_node_step,
        summary.max_identity_residual,
        out.display()
    );
    if let Some(n) = summary.inaccurate_steps.filter(|n| *n > 0) {
        eprintln!(
            "warning: {n} steps accepted although OSQP reported `solved inaccurate` \
             (solver.accept_inaccurate = true); see inaccurate_steps and audit in summary.json"
        );
    }
    Ok(())
}
