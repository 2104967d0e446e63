//! `viscobar converge`: refinement studies of every step solver against a reference (the
//! scene's closed form, or a finer run of the exact solver) and the data of the work-precision
//! diagram (drawn by `study::work_precision`). The `α → 0` sweep is `study::viscosity_sweep`.
//!
//! Bar and plane scenes alike ([`StudyScene`]). The error runs are independent and go to
//! rayon's pool (both cores); each worker builds its own simulation (OSQP's workspace is not
//! `Send`), and results are sorted before anything
//! is written, so the files do not depend on the scheduling. The wall times come from a second,
//! serial pass that runs each setting and level alone `repeats` times and keeps the median
//! ([`study_with`]): no timed run shares the cores with another run of the study. They are the
//! only non-deterministic columns.

use crate::bar::closed_form::ClosedForm;
use crate::output::Tracker;
use crate::scene::{SolverMethod, SolverSpec};
use crate::scheme::{Body, RunError, Scheme};
use crate::study::accuracy::observed_order;
use crate::study::refine::StudyScene;
use rayon::prelude::*;
use std::collections::BTreeMap;
use std::path::PathBuf;
use std::sync::Arc;
use std::time::Instant;

/// OSQP tolerances (`eps_abs = eps_rel`) of the work-precision study.
pub const OSQP_EPS: [f64; 3] = [1e-4, 1e-7, 1e-10];
/// Penalty parameters ε of the work-precision study.
pub const PENALTY_EPSILON: [f64; 3] = [1e-3, 1e-5, 1e-7];
/// Levels of refinement unless `--levels` says otherwise.
pub const DEFAULT_LEVELS: u32 = 4;
/// How many levels finer than the finest level the exact reference run is.
pub const REFERENCE_EXTRA_LEVELS: u32 = 2;
/// Most reference time samples kept (memory: nodes of the finest level × this × 8 bytes).
pub const REFERENCE_MAX_SAMPLES: usize = 512;

/// Why `viscobar converge` failed.
#[derive(Debug, thiserror::Error)]
pub enum ConvergeError {
    #[error("{0}")]
    BadInput(String),
    #[error(transparent)]
    Run(#[from] RunError),
    #[error(transparent)]
    Scene(#[from] crate::scene::SceneError),
    #[error("cannot draw {path}: {message}")]
    Draw { path: PathBuf, message: String },
    #[error("cannot write {path}: {source}")]
    Write {
        path: PathBuf,
        source: std::io::Error,
    },
}

impl ConvergeError {
    /// 2 for bad input, 1 for a failure during a run or while writing.
    pub fn exit_code(&self) -> i32 {
        match self {
            ConvergeError::BadInput(_) | ConvergeError::Scene(_) => 2,
            ConvergeError::Run(e) => e.exit_code(),
            _ => 1,
        }
    }
}

/// One solver with one setting.
#[derive(Clone, Copy, Debug, PartialEq, PartialOrd)]
pub enum SolverSetting {
    Exact,
    /// `eps_abs = eps_rel`.
    Osqp(f64),
    /// ε of (PP).
    Penalty(f64),
}

impl SolverSetting {
    pub fn solver(&self) -> &'static str {
        match self {
            SolverSetting::Exact => "exact",
            SolverSetting::Osqp(_) => "osqp",
            SolverSetting::Penalty(_) => "penalty",
        }
    }
    /// `eps=1e-7`, `epsilon=1e-5` or `-`.
    pub fn setting(&self) -> String {
        match self {
            SolverSetting::Exact => "-".into(),
            SolverSetting::Osqp(e) => format!("eps={e:e}"),
            SolverSetting::Penalty(e) => format!("epsilon={e:e}"),
        }
    }
    /// `exact`, `osqp eps=1e-7`, `penalty epsilon=1e-5`.
    pub fn label(&self) -> String {
        match self {
            SolverSetting::Exact => "exact".into(),
            _ => format!("{} {}", self.solver(), self.setting()),
        }
    }
    /// `scene` with its `[solver]` table replaced by this setting.
    pub fn apply<S: StudyScene>(&self, scene: &S) -> S {
        let mut s = scene.clone();
        *s.solver_mut() = match *self {
            SolverSetting::Exact => SolverSpec::default(),
            SolverSetting::Osqp(e) => SolverSpec {
                method: SolverMethod::Osqp,
                eps_abs: Some(e),
                eps_rel: Some(e),
                ..SolverSpec::default()
            },
            SolverSetting::Penalty(e) => SolverSpec {
                method: SolverMethod::Penalty,
                epsilon: Some(e),
                ..SolverSpec::default()
            },
        };
        s
    }
}

/// The settings of a comma-separated solver list (`exact,osqp,penalty`), in that order, with
/// the default tolerances ([`OSQP_EPS`], [`PENALTY_EPSILON`]).
pub fn parse_solvers(list: &str) -> Result<Vec<SolverSetting>, ConvergeError> {
    parse_solvers_with(list, &OSQP_EPS, &PENALTY_EPSILON)
}

/// The settings of a comma-separated solver list: `osqp` once per tolerance of `osqp_eps`,
/// `penalty` once per ε of `penalty_epsilon`.
pub fn parse_solvers_with(
    list: &str,
    osqp_eps: &[f64],
    penalty_epsilon: &[f64],
) -> Result<Vec<SolverSetting>, ConvergeError> {
    let mut out = Vec::new();
    for name in list.split(',').map(str::trim) {
        match name {
            "exact" => out.push(SolverSetting::Exact),
            "osqp" => out.extend(osqp_eps.iter().map(|e| SolverSetting::Osqp(*e))),
            "penalty" => out.extend(penalty_epsilon.iter().map(|e| SolverSetting::Penalty(*e))),
            _ => {
                return Err(ConvergeError::BadInput(format!(
                    "--solvers: unknown solver `{name}` (known: exact, osqp, penalty)"
                )));
            }
        }
    }
    let mut unique: Vec<SolverSetting> = Vec::new();
    for s in out {
        if !unique.contains(&s) {
            unique.push(s);
        }
    }
    Ok(unique)
}

/// A comma-separated list of tolerances for the flag `flag` (`--osqp-eps 1e-4,1e-7`): each a
/// finite number > 0; at least one.
pub fn parse_tolerances(flag: &str, list: &str) -> Result<Vec<f64>, ConvergeError> {
    let mut out = Vec::new();
    for item in list.split(',').map(str::trim) {
        let v: f64 = item.parse().map_err(|_| {
            ConvergeError::BadInput(format!(
                "{flag} {list}: `{item}` is not a number (a comma-separated list, e.g. 1e-4,1e-7)"
            ))
        })?;
        if !(v.is_finite() && v > 0.0) {
            return Err(ConvergeError::BadInput(format!(
                "{flag} {list}: `{item}` must be a finite number > 0"
            )));
        }
        out.push(v);
    }
    Ok(out)
}

/// What the runs are measured against.
pub enum Reference {
    /// The closed form of the built-in scene `name`.
    ClosedForm { name: String },
    /// A run of the exact solver at a finer level, sampled at `times` on the nodes of the
    /// finest level of the study.
    Run(Arc<SampledReference>),
}

impl Reference {
    pub fn describe(&self) -> String {
        match self {
            Reference::ClosedForm { name } => format!("closed form ({name})"),
            Reference::Run(r) => format!(
                "exact solver, {} elements, dt = {:e} (level {})",
                r.elements, r.dt, r.level
            ),
        }
    }
}

/// A reference run of the exact solver, kept at a few times on a coarser node set, with its
/// energy at every one of its time steps and its contact intervals.
pub struct SampledReference {
    pub elements: usize,
    /// Its refinement level (the scene's mesh is level 0).
    pub level: u32,
    pub dt: f64,
    /// The time indices of the coarsest level (`t = c · Δt_0`, `c >= 1`) at which `values`
    /// are kept.
    pub coarse_times: Vec<usize>,
    /// The lattice of nodes of the finest level of the study, and the degrees of freedom per
    /// node: `values` holds every degree of freedom of that lattice.
    pub lattice: [usize; 2],
    pub components: usize,
    pub values: Vec<Vec<f64>>,
    /// `E(t_m)` at the reference's own time steps `t_m = m · dt`, as the mean of its
    /// `E^{m−1/2}` and `E^{m+1/2}` (`NaN` where a neighbour was not measured); index `m`.
    pub energy: Vec<f64>,
    /// Its contact intervals per Signorini end (and `obstacle` for the whole contact set), as in
    /// `summary.json`.
    pub contact: BTreeMap<String, Vec<[f64; 2]>>,
}

/// One row of `convergence.csv`.
#[derive(Clone, Debug)]
pub struct Row {
    pub setting: SolverSetting,
    pub level: u32,
    pub elements: usize,
    pub dx: f64,
    pub dt: f64,
    pub steps: usize,
    pub l2_error: f64,
    pub h1_error: f64,
    pub energy_error: Option<f64>,
    pub contact_time_error: Option<f64>,
    /// Wall time of the steps (set-up excluded), seconds: the median of the serial timing
    /// pass (or, with no repeats asked, the time measured during the parallel error pass).
    pub wall_time_s: f64,
}

/// The degrees of freedom of `lattice` (`components` a node) at the nodes of a `2^steps` times
/// coarser lattice, in its order: the nodes `(i·2^steps, j·2^steps)`.
fn coarse_dofs(lattice: [usize; 2], components: usize, steps: u32) -> Vec<usize> {
    let s = 1usize << steps;
    let axis = |n: usize| (n - 1) / s + 1;
    let mut out = Vec::new();
    for j in 0..axis(lattice[1]) {
        for i in 0..axis(lattice[0]) {
            let node = i * s + j * s * lattice[0];
            out.extend((0..components).map(|c| components * node + c));
        }
    }
    out
}

/// Runs `scene` (already set to its solver and level), measuring against `reference`. Only
/// the steps are timed. `finest`: the finest level of the study.
fn measure<S: StudyScene>(
    scene_name: &str,
    scene: &S,
    setting: SolverSetting,
    level: u32,
    finest: u32,
    reference: &Reference,
) -> Result<Row, RunError> {
    let closed: Option<Box<dyn ClosedForm>> = match reference {
        Reference::ClosedForm { name } => scene.closed_form(name),
        Reference::Run(_) => None,
    };
    let run = match reference {
        Reference::Run(r) => Some(r.as_ref()),
        Reference::ClosedForm { .. } => None,
    };
    // Compared only where the closed form states its energy, or against the reference run.
    let energy = closed.as_deref().filter(|c| c.energy(0.0).is_some());
    let compare_energy = energy.is_some() || run.is_some();
    let mut sim = scene.simulation()?;
    let mut tracker = Tracker::new(&sim, !sim.is_forced());
    let dofs = sim.dofs();
    let xs: Vec<f64> = (0..sim.body().nodes())
        .map(|i| sim.body().point(i).0)
        .collect();
    // This level's degrees of freedom in the reference's values (on the finest level).
    let at = run.map(|r| coarse_dofs(r.lattice, r.components, finest - level));
    let dt = scene.dt();
    let mut u = vec![0.0; dofs];
    let mut e = vec![0.0; dofs];
    let (mut l2, mut h1, mut en) = (0.0f64, 0.0f64, 0.0f64);
    let mut sample = 0usize;
    // `k`: the time index of the state `u^k` the simulation holds (`u^1` after the start-up).
    let mut observe = |sim: &Scheme<S::Body>, k: usize, u: &mut Vec<f64>, e: &mut Vec<f64>| {
        let have = match (&closed, run, &at) {
            (Some(c), _, _) => {
                sim.displacement_into(u);
                let t = sim.time();
                for i in 0..dofs {
                    e[i] = u[i] - c.displacement(xs[i], t);
                }
                true
            }
            (None, Some(r), Some(at))
                if sample < r.coarse_times.len() && k == r.coarse_times[sample] << level =>
            {
                // The same time t = c·Δt_0 at this level and in the reference; the reference's
                // values are on the finest level's nodes.
                sim.displacement_into(u);
                let v = &r.values[sample];
                for i in 0..dofs {
                    e[i] = u[i] - v[at[i]];
                }
                sample += 1;
                true
            }
            _ => false,
        };
        if have {
            let (el2, eh1) = scene.norms(e);
            l2 = l2.max(el2);
            h1 = h1.max(eh1);
        }
    };
    observe(&sim, 1, &mut u, &mut e);
    let mut wall = 0.0;
    for n in 1..scene.steps() {
        let start = Instant::now();
        let r = sim.step()?;
        wall += start.elapsed().as_secs_f64();
        tracker.observe(&r);
        // E^{n+1/2} lives at t_{n+1} − Δt/2.
        if r.measured {
            let exact = match (energy, run) {
                (Some(c), _) => c.energy(r.time - 0.5 * dt),
                // t_{n+1} − Δt/2 = (2n + 1)·2^(R − l − 1) reference steps.
                (None, Some(rf)) => {
                    let m = (2 * n + 1) << (rf.level - level - 1);
                    rf.energy.get(m).copied().filter(|v| v.is_finite())
                }
                (None, None) => None,
            };
            if let Some(exact) = exact {
                en = en.max((r.energy - exact).abs());
            }
        }
        observe(&sim, n + 1, &mut u, &mut e);
    }
    let summary = tracker.finish(scene_name, &sim, wall);
    let contact_time_error = match (&closed, run) {
        (Some(c), _) => c.contact_intervals(sim.time()).and_then(|exact| {
            let discrete = summary
                .contact_intervals
                .get("left")
                .map_or(&[][..], |v| &v[..]);
            contact_time_error(&exact, discrete)
        }),
        // Every group in which the reference touches; the worst.
        (None, Some(rf)) => rf
            .contact
            .iter()
            .filter_map(|(group, exact)| {
                let discrete = summary
                    .contact_intervals
                    .get(group)
                    .map_or(&[][..], |v| &v[..]);
                contact_time_error(exact, discrete)
            })
            .reduce(f64::max),
        (None, None) => None,
    };
    Ok(Row {
        setting,
        level,
        elements: scene.elements(),
        dx: scene.spacing(),
        dt,
        steps: scene.steps(),
        l2_error: l2,
        h1_error: h1,
        energy_error: compare_energy.then_some(en),
        contact_time_error,
        wall_time_s: wall,
    })
}

/// The error of the discrete contact intervals against the exact ones (`None` when the exact
/// solution has none): each discrete interval is counted with the exact interval nearest to
/// its midpoint, and each exact interval `[s, e]` scores `|first start − s| + |last end − e|` of
/// its discrete intervals (so the brief separations and re-contacts of the P1 mesh do not count
/// as episodes); the worst score is returned, infinite when an exact interval has none.
pub fn contact_time_error(exact: &[[f64; 2]], discrete: &[[f64; 2]]) -> Option<f64> {
    if exact.is_empty() {
        return None;
    }
    let distance = |iv: &[f64; 2], t: f64| (iv[0] - t).max(t - iv[1]).max(0.0);
    let mut span: Vec<Option<[f64; 2]>> = vec![None; exact.len()];
    for d in discrete {
        let mid = 0.5 * (d[0] + d[1]);
        let k = (0..exact.len())
            .min_by(|&a, &b| distance(&exact[a], mid).total_cmp(&distance(&exact[b], mid)))
            .expect("not empty");
        let s = span[k].get_or_insert(*d);
        s[0] = s[0].min(d[0]);
        s[1] = s[1].max(d[1]);
    }
    Some(exact.iter().zip(&span).fold(0.0f64, |worst, (e, d)| {
        worst.max(d.map_or(f64::INFINITY, |d| (d[0] - e[0]).abs() + (d[1] - e[1]).abs()))
    }))
}

/// The exact solver at level `level` (above the study's finest, `finest`), kept at (at most
/// [`REFERENCE_MAX_SAMPLES`]) times of the coarsest level on the finest level's nodes, with
/// its energy at every step and its contact intervals.
fn reference_run<S: StudyScene>(
    scene_name: &str,
    base: &S,
    finest: u32,
    level: u32,
    ratio: f64,
) -> Result<SampledReference, RunError> {
    let scene = SolverSetting::Exact.apply(&base.refined(level, ratio));
    let coarse_steps_total = base.refined(0, ratio).steps();
    let every = coarse_steps_total.div_ceil(REFERENCE_MAX_SAMPLES).max(1);
    let coarse_times: Vec<usize> = (every..=coarse_steps_total).step_by(every).collect();
    let mut sim = scene.simulation()?;
    let mut tracker = Tracker::new(&sim, !sim.is_forced());
    let keep_dofs = coarse_dofs(scene.lattice(), scene.components(), level - finest);
    let mut u = vec![0.0; sim.dofs()];
    let mut values = Vec::with_capacity(coarse_times.len());
    // E^{k−1/2} by step k (index 0 unused).
    let first = sim.first_record();
    let mut half = vec![f64::NAN; scene.steps() + 1];
    half[1] = if first.measured {
        first.energy
    } else {
        f64::NAN
    };
    let mut keep = |k: usize, sim: &Scheme<S::Body>, values: &mut Vec<Vec<f64>>| {
        if values.len() < coarse_times.len() && k == coarse_times[values.len()] << level {
            sim.displacement_into(&mut u);
            values.push(keep_dofs.iter().map(|&d| u[d]).collect::<Vec<f64>>());
        }
    };
    keep(1, &sim, &mut values);
    for n in 1..scene.steps() {
        let r = sim.step()?;
        tracker.observe(&r);
        if r.measured {
            half[n + 1] = r.energy;
        }
        keep(n + 1, &sim, &mut values);
    }
    let kept = values.len();
    let energy: Vec<f64> = (0..half.len())
        .map(|m| {
            if m >= 1 && m + 1 < half.len() {
                0.5 * (half[m] + half[m + 1])
            } else {
                f64::NAN
            }
        })
        .collect();
    let summary = tracker.finish(scene_name, &sim, 0.0);
    Ok(SampledReference {
        elements: scene.elements(),
        level,
        dt: scene.dt(),
        coarse_times: coarse_times[..kept].to_vec(),
        lattice: base.refined(finest, ratio).lattice(),
        components: scene.components(),
        values,
        energy,
        contact: summary
            .contact_intervals
            .into_iter()
            .filter(|(_, v)| !v.is_empty())
            .collect(),
    })
}

/// The outcome of a study.
#[derive(Debug)]
pub struct Study {
    pub scene: String,
    pub reference: String,
    /// The reference's own estimated L2 error (max over t): 0 for a closed form; for a run,
    /// Richardson's estimate `e_F / (2^(p·(R − F)) − 1)` from the exact solver's error `e_F` at
    /// the finest level `F` of the study, its observed L2 order `p` and the reference level
    /// `R` (`None` without the exact solver in the study or without a positive order).
    pub reference_error: Option<f64>,
    /// Timing repeats per run of the serial pass (0: timed in the parallel error pass).
    pub repeats: usize,
    pub rows: Vec<Row>,
}

/// Default timing repeats of `viscobar converge` (the median is kept).
pub const DEFAULT_REPEATS: usize = 3;
/// Most timing repeats accepted (each repeats the whole study's runs serially).
pub const MAX_REPEATS: usize = 15;
/// Finest reference level accepted: `2^16` times the scene's elements and steps.
pub const MAX_REFERENCE_LEVEL: u32 = 16;

/// How a study is run.
#[derive(Clone, Debug)]
pub struct StudyOptions {
    /// Levels of refinement (`dx` and `dt` halved per level from the scene's mesh).
    pub levels: u32,
    /// `dt/dx` at every level (default: the scene's).
    pub ratio: Option<f64>,
    /// The level of the exact reference run (the scene's mesh is level 0). `None`: the closed
    /// form when the scene has one, else `levels − 1 + REFERENCE_EXTRA_LEVELS`. Given, the
    /// reference is a run even for a scene with a closed form.
    pub reference_level: Option<u32>,
    /// Timing repeats per run in the serial pass, median kept; 0: no serial pass (wall times
    /// of the parallel error pass, disturbed by the runs beside them).
    pub repeats: usize,
}

impl StudyOptions {
    pub fn new(levels: u32, ratio: Option<f64>) -> Self {
        Self {
            levels,
            ratio,
            reference_level: None,
            repeats: 1,
        }
    }
}

/// Runs every setting at every level; one serial timing repeat
/// ([`study_with`] and [`StudyOptions`] for the other choices).
pub fn study<S: StudyScene>(
    scene_name: &str,
    base: &S,
    settings: &[SolverSetting],
    levels: u32,
    ratio: Option<f64>,
) -> Result<Study, ConvergeError> {
    study_with(
        scene_name,
        base,
        settings,
        &StudyOptions::new(levels, ratio),
    )
}

/// Wall time of the steps of one run of `scene` (set-up excluded), seconds.
pub fn time_steps<S: StudyScene>(scene: &S) -> Result<f64, RunError> {
    let mut sim = scene.simulation()?;
    let start = Instant::now();
    for _ in 1..scene.steps() {
        sim.step()?;
    }
    Ok(start.elapsed().as_secs_f64())
}

/// The median of `v` (the mean of the middle two for an even count); `v` not empty.
pub fn median(mut v: Vec<f64>) -> f64 {
    v.sort_by(f64::total_cmp);
    let n = v.len();
    if n % 2 == 1 {
        v[n / 2]
    } else {
        0.5 * (v[n / 2 - 1] + v[n / 2])
    }
}

/// Runs every setting at every level: the errors in parallel on rayon's pool (each run is
/// independent and deterministic), then, with `repeats > 0`, a serial pass that times each
/// run alone `repeats` times and keeps the median, so no run is timed while another shares
/// the machine's cores.
pub fn study_with<S: StudyScene>(
    scene_name: &str,
    base: &S,
    settings: &[SolverSetting],
    options: &StudyOptions,
) -> Result<Study, ConvergeError> {
    let levels = options.levels;
    if levels < 2 {
        return Err(ConvergeError::BadInput(format!(
            "--levels {levels}: at least 2 levels are needed for an observed order"
        )));
    }
    if levels > 12 {
        return Err(ConvergeError::BadInput(format!(
            "--levels {levels}: at most 12 (each level doubles the elements)"
        )));
    }
    if let Some(why) = base.not_nested() {
        return Err(ConvergeError::BadInput(why));
    }
    let ratio = options.ratio.unwrap_or(base.dt() / base.spacing());
    if !(ratio.is_finite() && ratio > 0.0) {
        return Err(ConvergeError::BadInput(format!(
            "--ratio {ratio}: dt/dx must be positive and finite"
        )));
    }
    if options.repeats > MAX_REPEATS {
        return Err(ConvergeError::BadInput(format!(
            "--repeats {}: at most {MAX_REPEATS} (each repeat times every run again)",
            options.repeats
        )));
    }
    let finest = levels - 1;
    if let Some(r) = options.reference_level
        && (r <= finest || r > MAX_REFERENCE_LEVEL)
    {
        return Err(ConvergeError::BadInput(format!(
            "--reference-level {r}: must be finer than the finest level of the study ({finest}, \
             with --levels {levels}) and at most {MAX_REFERENCE_LEVEL}"
        )));
    }
    let reference = match options.reference_level {
        None if base.closed_form(scene_name).is_some() => Reference::ClosedForm {
            name: scene_name.to_string(),
        },
        level => Reference::Run(Arc::new(reference_run(
            scene_name,
            base,
            finest,
            level.unwrap_or(finest + REFERENCE_EXTRA_LEVELS),
            ratio,
        )?)),
    };
    let tasks: Vec<(SolverSetting, u32)> = settings
        .iter()
        .flat_map(|s| (0..levels).map(move |l| (*s, l)))
        .collect();
    // Largest tasks first, so the pool is not left waiting on one long run at the end.
    let mut order: Vec<usize> = (0..tasks.len()).collect();
    order.sort_by_key(|&i| std::cmp::Reverse(tasks[i].1));
    let mut rows = order
        .par_iter()
        .map(|&i| {
            let (setting, level) = tasks[i];
            let scene = setting.apply(&base.refined(level, ratio));
            measure(scene_name, &scene, setting, level, finest, &reference).map(|r| (i, r))
        })
        .collect::<Result<Vec<_>, RunError>>()?;
    rows.sort_by_key(|(i, _)| *i);
    let mut rows: Vec<Row> = rows.into_iter().map(|(_, r)| r).collect();
    if options.repeats > 0 {
        for row in &mut rows {
            let scene = row.setting.apply(&base.refined(row.level, ratio));
            let times = (0..options.repeats)
                .map(|_| time_steps(&scene))
                .collect::<Result<Vec<f64>, RunError>>()?;
            row.wall_time_s = median(times);
        }
    }
    let reference_error = match &reference {
        Reference::ClosedForm { .. } => Some(0.0),
        Reference::Run(r) => {
            let exact: Vec<&Row> = rows
                .iter()
                .filter(|r| r.setting == SolverSetting::Exact)
                .collect();
            let h: Vec<f64> = exact.iter().map(|r| r.dx).collect();
            let e: Vec<f64> = exact.iter().map(|r| r.l2_error).collect();
            let p = if exact.len() >= 2 {
                observed_order(&h, &e)
            } else {
                f64::NAN
            };
            exact
                .last()
                .filter(|_| p.is_finite() && p > 0.0)
                .map(|f| f.l2_error / (2f64.powf(p * f64::from(r.level - f.level)) - 1.0))
        }
    };
    Ok(Study {
        scene: scene_name.to_string(),
        reference: reference.describe(),
        reference_error,
        repeats: options.repeats,
        rows,
    })
}
