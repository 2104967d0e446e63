//! Running a scene of either body end to end: the step loop and the output files
//! (`summary.json`, `history.csv`, the profile file), written whole or not at all through the
//! same code for both bodies.

use crate::bar::Simulation;
use crate::output::files::write_whole;
use crate::output::history;
use crate::output::summary::{Summary, Tracker};
use crate::output::vtk::{Kept, KeptSteps};
use crate::plane::PlaneSimulation;
use crate::scene::plane::PlaneScene;
use crate::scene::{OutputFormat, OutputSampling, OutputSpec, Scene};
use crate::scheme::{Body, RunError, Scheme, StepRecord, Unstarted};
use crate::thermal::ThermalSimulation;
use std::io::Write;
use std::path::{Path, PathBuf};
use std::time::Instant;

/// What a run does with a step that breaks its certificate ([`crate::scheme::certify`]).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum Certify {
    /// End the run at that step with [`RunError::Uncertified`]; a run to a folder writes
    /// nothing.
    #[default]
    Strict,
    /// Finish the run; its summary says `certified: false` and names the first failure.
    Record,
}

/// The records of a run so far, checked against its certificate as `certify` asks.
pub(crate) fn observe(
    tracker: &mut Tracker,
    r: &StepRecord,
    certify: Certify,
) -> Result<(), RunError> {
    match tracker.observe(r) {
        Some(failure) if certify == Certify::Strict => Err(RunError::Uncertified(failure)),
        _ => Ok(()),
    }
}

/// Steps `sim` to step `steps`, keeping every record (the start-up step first); returns them
/// with the summary and the finished simulation. A step that breaks the run's certificate
/// ends it ([`Certify::Strict`]).
pub fn run_scheme_in_memory<B: Body>(
    name: &str,
    sim: Scheme<B>,
    steps: usize,
) -> Result<(Vec<StepRecord>, Summary, Scheme<B>), RunError> {
    run_scheme_in_memory_with(name, sim, steps, Certify::Strict)
}

/// [`run_scheme_in_memory`], with a certificate failure handled as `certify` says.
pub fn run_scheme_in_memory_with<B: Body>(
    name: &str,
    mut sim: Scheme<B>,
    steps: usize,
    certify: Certify,
) -> Result<(Vec<StepRecord>, Summary, Scheme<B>), RunError> {
    let start = Instant::now();
    let mut tracker = Tracker::new(&sim, !sim.is_forced());
    let mut records = vec![sim.first_record()];
    for _ in 1..steps {
        let r = sim.step()?;
        observe(&mut tracker, &r, certify)?;
        records.push(r);
    }
    let summary = tracker.finish(name, &sim, start.elapsed().as_secs_f64());
    Ok((records, summary, sim))
}

/// Runs a bar scene in memory (for tests and studies; [`run_to_dir`] streams instead).
///
/// A scene built in code (or parsed with [`crate::Scene::from_toml`], or a built-in from
/// [`crate::scene::load`]), run, its contact intervals and energy history read. The bar
/// below moves at `v0 = 1` towards an obstacle `a0 = 0.1` under its left end (the `impact`
/// scene): contact starts at `t1 = a0 / v0` and lasts `2L`.
///
/// ```
/// use viscobar::scene::{Bar, Condition, EndSpec, Initial, Mesh, Time};
/// use viscobar::{Scene, run_in_memory};
///
/// let scene = Scene {
///     description: None,
///     bar: Bar { length: 1.0, viscosity: 0.0, matrices: Default::default(), mass: Default::default() },
///     left: EndSpec::new(Condition::Signorini, Some(0.1)),
///     right: EndSpec::new(Condition::Free, None),
///     initial: Initial { displacement: "0".into(), velocity: "-1".into() },
///     load: Default::default(),
///     obstacle: None,
///     heat: None,
///     mesh: Mesh { elements: 100 },
///     time: Time { step: 0.01, end: 3.0 },
///     solver: Default::default(),
///     output: Default::default(),
/// };
/// let (records, summary, _simulation) = run_in_memory("impact", &scene)?;
///
/// // One contact episode at the left end: [t1, t1 + 2L] = [0.1, 2.1] up to a few steps (the
/// // contact-time error of P1 elements, VERIFICATION.md).
/// let left = &summary.contact_intervals["left"];
/// let within = |t: f64, exact: f64| (t - exact).abs() <= 3.0 * scene.time.step;
/// assert_eq!(left.len(), 1);
/// assert!(within(left[0][0], 0.1) && within(left[0][1], 2.1), "{left:?}");
///
/// // The energy history: without viscosity or load, only contact can change the energy.
/// let energy: Vec<f64> = records.iter().map(|r| r.energy).collect();
/// assert_eq!(energy.len(), summary.steps);
/// assert!(energy.last().unwrap() <= &energy[0]);
/// # Ok::<(), viscobar::RunError>(())
/// ```
///
/// A scene built in code is validated like a scene file: [`crate::Simulation::new`] returns the
/// same [`crate::SceneError`] (inside [`RunError::Scene`]) that the command line prints. A
/// scene with `[heat]` runs with its temperature, as [`run_to_dir`] runs it.
pub fn run_in_memory(
    name: &str,
    scene: &Scene,
) -> Result<(Vec<StepRecord>, Summary, BarSimulation), RunError> {
    if scene.heat.is_some() {
        let (records, summary, sim) = run_thermal_in_memory(name, scene)?;
        return Ok((records, summary, BarSimulation::Thermal(Box::new(sim))));
    }
    let (records, summary, sim) =
        run_scheme_in_memory(name, Simulation::new(scene)?, scene.steps())?;
    Ok((records, summary, BarSimulation::Mechanical(Box::new(sim))))
}

/// A bar scene's simulation as [`run_in_memory`] leaves it: the bar alone, or the bar with its
/// temperature (a scene with `[heat]`).
pub enum BarSimulation {
    Mechanical(Box<Simulation>),
    Thermal(Box<ThermalSimulation>),
}

impl BarSimulation {
    /// The bar without a temperature; `None` for a scene with `[heat]`.
    pub fn mechanical(&self) -> Option<&Simulation> {
        match self {
            Self::Mechanical(sim) => Some(sim.as_ref()),
            Self::Thermal(_) => None,
        }
    }

    /// The bar with its temperature; `None` for a scene without `[heat]`.
    pub fn thermal(&self) -> Option<&ThermalSimulation> {
        match self {
            Self::Mechanical(_) => None,
            Self::Thermal(sim) => Some(sim.as_ref()),
        }
    }
}

/// Runs a bar scene with a temperature (`[heat]`) in memory: [`run_in_memory`]'s run, its
/// simulation typed.
pub fn run_thermal_in_memory(
    name: &str,
    scene: &Scene,
) -> Result<(Vec<StepRecord>, Summary, ThermalSimulation), RunError> {
    run_scheme_in_memory(name, ThermalSimulation::new(scene)?, scene.steps())
}

/// Runs a plane scene in memory.
pub fn run_plane_in_memory(
    name: &str,
    scene: &PlaneScene,
) -> Result<(Vec<StepRecord>, Summary, PlaneSimulation), RunError> {
    run_scheme_in_memory(name, PlaneSimulation::new(scene)?, scene.steps())
}

/// Runs a bar scene (with or without a temperature) and writes `summary.json`, `history.csv` and the profiles
/// (`displacement.csv`, or `displacement.npy` with `[output] format = "npy"`) into `out`. The
/// scene is set up (discretised, its initial data evaluated) before anything is created, so
/// a refused scene leaves no trace on disk; the files are moved into place only when the run
/// has succeeded, so a failed run leaves earlier results untouched. A successful run removes
/// the other format's profile file left by an earlier run in `out`. `progress` shows a
/// progress bar on stderr for long runs (with the `progress` feature).
pub fn run_to_dir(
    name: &str,
    scene: &Scene,
    out: &Path,
    progress: bool,
) -> Result<Summary, RunError> {
    run_to_dir_with(name, scene, out, RunOptions::strict(progress))
}

/// How a run to a folder reports itself.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct RunOptions {
    /// A progress bar on stderr for long runs (with the `progress` feature).
    pub progress: bool,
    /// What a step that breaks the run's certificate does.
    pub certify: Certify,
}

impl RunOptions {
    /// A run that ends at a step breaking its certificate.
    pub fn strict(progress: bool) -> Self {
        Self {
            progress,
            certify: Certify::Strict,
        }
    }
}

/// [`run_to_dir`] with `options`: with [`Certify::Record`] a run that breaks its certificate
/// is written whole, its summary saying so.
pub fn run_to_dir_with(
    name: &str,
    scene: &Scene,
    out: &Path,
    options: RunOptions,
) -> Result<Summary, RunError> {
    let start = Instant::now();
    // Again here: a scene's fields are public, so this one may not have been validated.
    scene.output.format.check_available()?;
    let run = Run {
        name,
        steps: scene.steps(),
        output: &scene.output,
        sampling: scene.output_sampling(),
        options,
    };
    if scene.heat.is_some() {
        return run.write(ThermalSimulation::prepare(scene)?, start, out);
    }
    run.write(Simulation::prepare(scene)?, start, out)
}

/// Runs a plane scene and writes its files into `out`, as [`run_to_dir`] does for the bar.
pub fn run_plane_to_dir(
    name: &str,
    scene: &PlaneScene,
    out: &Path,
    progress: bool,
) -> Result<Summary, RunError> {
    run_plane_to_dir_with(name, scene, out, RunOptions::strict(progress))
}

/// [`run_plane_to_dir`] with `options`, as [`run_to_dir_with`].
pub fn run_plane_to_dir_with(
    name: &str,
    scene: &PlaneScene,
    out: &Path,
    options: RunOptions,
) -> Result<Summary, RunError> {
    let start = Instant::now();
    scene.output.format.check_available()?;
    let prepared = PlaneSimulation::prepare(scene)?;
    let run = Run {
        name,
        steps: scene.steps(),
        output: &scene.output,
        sampling: scene.output_sampling(),
        options,
    };
    run.write(prepared, start, out)
}

/// A run to write: its name, length and output settings.
struct Run<'a> {
    name: &'a str,
    steps: usize,
    output: &'a OutputSpec,
    sampling: OutputSampling,
    options: RunOptions,
}

impl Run<'_> {
    fn write<B: Body>(
        &self,
        prepared: Unstarted<B>,
        start: Instant,
        out: &Path,
    ) -> Result<Summary, RunError> {
        let format = self.sampling.format;
        let mut files = vec!["history.csv", format.file(), "summary.json"];
        files.extend(format.folder());
        let io = |path: PathBuf, source| RunError::Write { path, source };
        let summary = write_whole(out, &files, io, |tmp| {
            self.write_files(prepared, start, tmp)
        })?;
        for other in [OutputFormat::Csv, OutputFormat::Npy, OutputFormat::Vtu] {
            if other != format {
                let _ = std::fs::remove_file(out.join(other.file()));
                if let Some(folder) = other.folder() {
                    let _ = std::fs::remove_dir_all(out.join(folder));
                }
            }
        }
        Ok(summary)
    }

    fn write_files<B: Body>(
        &self,
        prepared: Unstarted<B>,
        start: Instant,
        dir: &Path,
    ) -> Result<Summary, RunError> {
        let io = |path: &PathBuf| {
            let path = path.clone();
            move |source| RunError::Write { path, source }
        };
        let create = |path: &PathBuf| std::fs::File::create(path).map_err(io(path));
        let hist_path = dir.join("history.csv");
        let mut hist = std::io::BufWriter::with_capacity(1 << 16, create(&hist_path)?);
        let groups = prepared.contact().groups().to_vec();
        let optional = history::OptionalColumns::of(
            prepared.contact(),
            prepared.body().has_temperature(),
            prepared.body().heat_outputs(),
        );
        hist.write_all(history::header(&groups, optional).as_bytes())
            .map_err(io(&hist_path))?;
        // `t = 0` is written before the start-up step moves `u^0` on (no reactions yet).
        let (body, contact) = (prepared.body(), prepared.contact());
        let mut disp = KeptSteps::new(dir, body, contact, &self.sampling)?;
        let (rest, rest_tangential) = (
            vec![0.0; contact.len()],
            vec![0.0; contact.friction().len()],
        );
        let at_rest = Kept {
            body,
            contact,
            reactions: &rest,
            tangential: &rest_tangential,
            increments: None,
        };
        disp.write(0, 0.0, prepared.state(), at_rest)?;
        let mut sim = prepared.start()?;
        let mut tracker = Tracker::new(&sim, !sim.is_forced());
        let mut row = Vec::new();
        let mut write_row = |hist: &mut std::io::BufWriter<std::fs::File>, r: &StepRecord| {
            history::row(r, &groups, optional, &mut row);
            hist.write_all(&row)
        };
        write_row(&mut hist, &sim.first_record()).map_err(io(&hist_path))?;
        let (steps, every) = (self.steps, self.output.every as usize);
        let keep = |n: usize| n.is_multiple_of(every) || n == steps;
        let bar = Progress::new(self.options.progress, steps, sim.body().unknowns());
        if keep(1) {
            disp.write(1, sim.time(), sim.state(), Kept::of(&sim))?;
        }
        for _ in 1..steps {
            let r = sim.step()?;
            observe(&mut tracker, &r, self.options.certify)?;
            write_row(&mut hist, &r).map_err(io(&hist_path))?;
            if keep(r.step) {
                disp.write(r.step, sim.time(), sim.state(), Kept::of(&sim))?;
            }
            bar.step(r.step);
        }
        bar.finish();
        hist.flush().map_err(io(&hist_path))?;
        disp.finish()?;
        let mut summary = tracker.finish(self.name, &sim, start.elapsed().as_secs_f64());
        summary.output = Some(self.sampling);
        let json_path = dir.join("summary.json");
        let json = serde_json::to_string_pretty(&summary).expect("summary serialises");
        std::fs::write(&json_path, json + "\n").map_err(io(&json_path))?;
        Ok(summary)
    }
}

/// Runs below this many unknown-steps finish in seconds: no progress bar.
#[cfg(feature = "progress")]
const PROGRESS_MIN_UNKNOWN_STEPS: f64 = 2e8;
/// The progress bar is moved every this many steps (cheap next to a step of a large run).
#[cfg(feature = "progress")]
const PROGRESS_EVERY_STEPS: usize = 1024;

/// A progress bar on stderr for long runs; nothing without the `progress` feature.
struct Progress {
    #[cfg(feature = "progress")]
    bar: Option<indicatif::ProgressBar>,
}

impl Progress {
    #[cfg_attr(not(feature = "progress"), expect(unused_variables))]
    fn new(show: bool, steps: usize, unknowns: usize) -> Self {
        #[cfg(feature = "progress")]
        let bar =
            (show && steps as f64 * unknowns as f64 > PROGRESS_MIN_UNKNOWN_STEPS).then(|| {
                let bar = indicatif::ProgressBar::new(steps as u64);
                bar.set_style(
                    indicatif::ProgressStyle::with_template(
                        "{bar:40} {pos}/{len} steps, eta {eta}",
                    )
                    .expect("static template"),
                );
                bar
            });
        Self {
            #[cfg(feature = "progress")]
            bar,
        }
    }

    #[cfg_attr(not(feature = "progress"), expect(unused_variables))]
    fn step(&self, step: usize) {
        #[cfg(feature = "progress")]
        if let Some(b) = &self.bar
            && step.is_multiple_of(PROGRESS_EVERY_STEPS)
        {
            b.set_position(step as u64);
        }
    }

    fn finish(self) {
        #[cfg(feature = "progress")]
        if let Some(b) = self.bar {
            b.finish_and_clear();
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A record over its bound ends a strict run with the failure named, and is recorded by a
    /// run that goes on; the summary then says `certified: false` with the first failure. (No
    /// valid scene breaks its certificate, so the record's residual is set here.)
    #[test]
    fn a_step_over_its_bound_ends_a_strict_run_and_marks_a_recording_one() {
        let (_, scene) = crate::scene::load("impact", &["time.end=0.05".into()]).unwrap();
        let mut sim = Simulation::new(&scene).unwrap();
        let mut tracker = Tracker::new(&sim, true);
        let mut r = sim.step().unwrap();
        assert!(observe(&mut tracker, &r, Certify::Strict).is_ok());
        r.identity_residual = 2.0 * r.identity_bound;
        match observe(&mut tracker.clone(), &r, Certify::Strict) {
            Err(RunError::Uncertified(f)) => {
                assert_eq!(
                    (f.step, f.value, f.bound),
                    (2, r.identity_residual, r.identity_bound)
                );
                let message = RunError::Uncertified(f).to_string();
                assert!(message.contains("step 2") && message.contains("energy identity"));
            }
            other => panic!("{other:?}"),
        }
        assert!(observe(&mut tracker, &r, Certify::Record).is_ok());
        let summary = tracker.finish("impact", &sim, 1.0);
        assert!(!summary.certificate.certified);
        assert_eq!(summary.certificate.measured_steps, 3);
        let json = serde_json::to_value(&summary).unwrap();
        assert_eq!(json["certified"], false);
        assert_eq!(json["first_failure"]["step"], 2);
        let failure = summary.certificate.first_failure.clone().unwrap();
        assert_eq!(RunError::Uncertified(failure).exit_code(), 1);
    }
}
