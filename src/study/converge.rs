//! `viscobar converge`: refinement studies of every step solver against a reference (the
//! scene's closed form, or a finer run of the exact solver) and the data of the work-precision
//! diagram (drawn by `study::work_precision`). The `α → 0` sweep is `study::viscosity_sweep`.
//!
//! Runs are independent and go to rayon's pool; each worker builds its own [`Simulation`]
//! (OSQP's workspace is not `Send`), and results are sorted before anything is written, so the
//! files do not depend on the scheduling. Wall times do: they are the only non-deterministic
//! column.

use crate::bar::closed_form::{self, ClosedForm};
use crate::scene::{Scene, SolverMethod, SolverSpec};
use crate::study::accuracy::observed_order;
use crate::time::RunError;
use crate::time::run::write_atomically;
use crate::time::simulation::Simulation;
use crate::time::summary::Tracker;
use rayon::prelude::*;
use std::fmt::Write as _;
use std::path::{Path, PathBuf};
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
    fn label(&self) -> String {
        match self {
            SolverSetting::Exact => "exact".into(),
            _ => format!("{} {}", self.solver(), self.setting()),
        }
    }
    /// `scene` with its `[solver]` table replaced by this setting.
    pub fn apply(&self, scene: &Scene) -> Scene {
        let mut s = scene.clone();
        s.solver = match *self {
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

/// The settings of a comma-separated solver list (`exact,osqp,penalty`), in that order.
pub fn parse_solvers(list: &str) -> Result<Vec<SolverSetting>, ConvergeError> {
    let mut out = Vec::new();
    for name in list.split(',').map(str::trim) {
        match name {
            "exact" => out.push(SolverSetting::Exact),
            "osqp" => out.extend(OSQP_EPS.iter().map(|e| SolverSetting::Osqp(*e))),
            "penalty" => out.extend(PENALTY_EPSILON.iter().map(|e| SolverSetting::Penalty(*e))),
            _ => {
                return Err(ConvergeError::BadInput(format!(
                    "--solvers: unknown solver `{name}` (known: exact, osqp, penalty)"
                )));
            }
        }
    }
    out.dedup();
    Ok(out)
}

/// `base` with `base.elements · 2^level` elements and `dt = ratio · dx`.
pub fn refined(base: &Scene, level: u32, ratio: f64) -> Scene {
    let mut s = base.refined(level);
    s.time.step = ratio * s.dx();
    s
}

/// What the runs are measured against.
pub enum Reference {
    /// The closed form of the built-in scene `name`.
    ClosedForm { name: String },
    /// A run of the exact solver at `elements` elements, sampled at `times` on the nodes of the
    /// finest level of the study.
    Run(Arc<SampledReference>),
}

impl Reference {
    pub fn describe(&self) -> String {
        match self {
            Reference::ClosedForm { name } => format!("closed form ({name})"),
            Reference::Run(r) => format!("exact solver, {} elements", r.elements),
        }
    }
}

/// A reference run kept at a few times on a coarser node set.
pub struct SampledReference {
    pub elements: usize,
    /// The step indices (of the coarsest level) at which `values` are kept.
    pub coarse_steps: Vec<usize>,
    /// Steps of the coarsest level.
    pub coarse_dt: f64,
    /// Nodes of the finest level.
    pub nodes: usize,
    pub values: Vec<Vec<f64>>,
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
    pub wall_time_s: f64,
}

/// Trapezoidal weights on a uniform mesh.
pub(crate) fn l2_norm(e: &[f64], dx: f64) -> f64 {
    let n = e.len();
    let mut s = 0.0;
    for (i, v) in e.iter().enumerate() {
        let w = if i == 0 || i + 1 == n { 0.5 } else { 1.0 };
        s += w * v * v;
    }
    (s * dx).sqrt()
}

fn h1_seminorm(e: &[f64], dx: f64) -> f64 {
    (e.windows(2).map(|w| (w[1] - w[0]).powi(2)).sum::<f64>() / dx).sqrt()
}

/// Runs `scene` (already set to its solver and level), measuring against `reference`. Only
/// the steps are timed.
fn measure(
    scene_name: &str,
    scene: &Scene,
    setting: SolverSetting,
    level: u32,
    finest: u32,
    reference: &Reference,
) -> Result<Row, RunError> {
    let closed: Option<Box<dyn ClosedForm>> = match reference {
        Reference::ClosedForm { name } => closed_form::for_scene(name, scene),
        Reference::Run(_) => None,
    };
    // Compared only where the closed form states its energy.
    let energy = closed.as_deref().filter(|c| c.energy(0.0).is_some());
    let mut sim = Simulation::new(scene)?;
    let mut tracker = Tracker::new(&sim, scene.load.density.is_none());
    let nodes = sim.discretisation().nodes;
    let xs: Vec<f64> = (0..nodes).map(|i| sim.discretisation().x(i)).collect();
    let (dx, dt) = (scene.dx(), scene.time.step);
    let mut u = vec![0.0; nodes];
    let mut e = vec![0.0; nodes];
    let (mut l2, mut h1, mut en) = (0.0f64, 0.0f64, 0.0f64);
    let mut sample = 0usize;
    let mut observe = |sim: &Simulation, step: usize, u: &mut Vec<f64>, e: &mut Vec<f64>| {
        let have = match (&closed, reference) {
            (Some(c), _) => {
                sim.displacement_into(u);
                let t = sim.time();
                for i in 0..nodes {
                    e[i] = u[i] - c.displacement(xs[i], t);
                }
                true
            }
            (None, Reference::Run(r)) => {
                // Steps of this level per coarse step, and finest-level nodes per node here.
                let per = 1usize << level;
                let stride = 1usize << (finest - level);
                if sample < r.coarse_steps.len() && step == r.coarse_steps[sample] * per {
                    sim.displacement_into(u);
                    let v = &r.values[sample];
                    for i in 0..nodes {
                        e[i] = u[i] - v[i * stride];
                    }
                    sample += 1;
                    true
                } else {
                    false
                }
            }
            (None, Reference::ClosedForm { .. }) => false,
        };
        if have {
            l2 = l2.max(l2_norm(e, dx));
            h1 = h1.max(h1_seminorm(e, dx));
        }
    };
    observe(&sim, 0, &mut u, &mut e);
    let mut wall = 0.0;
    for n in 1..scene.steps() {
        let start = Instant::now();
        let r = sim.step()?;
        wall += start.elapsed().as_secs_f64();
        tracker.observe(&r);
        // E^{n+1/2} lives at t_{n+1} − Δt/2.
        if let Some(exact) = energy.and_then(|c| c.energy(r.time - 0.5 * dt)) {
            en = en.max((r.energy - exact).abs());
        }
        observe(&sim, n, &mut u, &mut e);
    }
    let contact_time_error = match closed
        .as_ref()
        .and_then(|c| c.contact_intervals(sim.time()))
    {
        Some(exact) => {
            let summary = tracker.finish(scene_name, &sim, wall);
            let discrete = summary
                .contact_intervals
                .get("left")
                .map_or(&[][..], |v| &v[..]);
            contact_time_error(&exact, discrete)
        }
        _ => None,
    };
    Ok(Row {
        setting,
        level,
        elements: scene.mesh.elements as usize,
        dx,
        dt,
        steps: scene.steps(),
        l2_error: l2,
        h1_error: h1,
        energy_error: energy.map(|_| en),
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

/// The exact solver at `levels − 1 + REFERENCE_EXTRA_LEVELS`, kept at (at most
/// [`REFERENCE_MAX_SAMPLES`]) steps of the coarsest level, on the finest level's nodes.
fn reference_run(base: &Scene, levels: u32, ratio: f64) -> Result<SampledReference, RunError> {
    let finest = levels - 1;
    let scene = SolverSetting::Exact.apply(&refined(base, finest + REFERENCE_EXTRA_LEVELS, ratio));
    let coarse = refined(base, 0, ratio);
    let coarse_steps_total = coarse.steps();
    let every = coarse_steps_total.div_ceil(REFERENCE_MAX_SAMPLES).max(1);
    let coarse_steps: Vec<usize> = (0..coarse_steps_total).step_by(every).collect();
    let per = 1usize << (finest + REFERENCE_EXTRA_LEVELS);
    let stride = 1usize << REFERENCE_EXTRA_LEVELS;
    let mut sim = Simulation::new(&scene)?;
    let all = sim.discretisation().nodes;
    let mut u = vec![0.0; all];
    let mut values = Vec::with_capacity(coarse_steps.len());
    let mut next = 0usize;
    let mut n = 0usize;
    loop {
        if next < coarse_steps.len() && n == coarse_steps[next] * per {
            sim.displacement_into(&mut u);
            values.push(u.iter().step_by(stride).copied().collect::<Vec<f64>>());
            next += 1;
        }
        if next == coarse_steps.len() || n + 1 >= scene.steps() {
            break;
        }
        sim.step()?;
        n += 1;
    }
    let kept = values.len();
    Ok(SampledReference {
        elements: scene.mesh.elements as usize,
        coarse_steps: coarse_steps[..kept].to_vec(),
        coarse_dt: coarse.time.step,
        nodes: (all - 1) / stride + 1,
        values,
    })
}

/// The outcome of a study.
#[derive(Debug)]
pub struct Study {
    pub scene: String,
    pub reference: String,
    pub rows: Vec<Row>,
}

/// Runs every setting at every level in parallel. `ratio`: `dt/dx` (default: the scene's).
pub fn study(
    scene_name: &str,
    base: &Scene,
    settings: &[SolverSetting],
    levels: u32,
    ratio: Option<f64>,
) -> Result<Study, ConvergeError> {
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
    let ratio = ratio.unwrap_or(base.time.step / base.dx());
    if !(ratio.is_finite() && ratio > 0.0) {
        return Err(ConvergeError::BadInput(format!(
            "--ratio {ratio}: dt/dx must be positive and finite"
        )));
    }
    let reference = if closed_form::for_scene(scene_name, base).is_some() {
        Reference::ClosedForm {
            name: scene_name.to_string(),
        }
    } else {
        Reference::Run(Arc::new(reference_run(base, levels, ratio)?))
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
            let scene = setting.apply(&refined(base, level, ratio));
            measure(scene_name, &scene, setting, level, levels - 1, &reference).map(|r| (i, r))
        })
        .collect::<Result<Vec<_>, RunError>>()?;
    rows.sort_by_key(|(i, _)| *i);
    Ok(Study {
        scene: scene_name.to_string(),
        reference: reference.describe(),
        rows: rows.into_iter().map(|(_, r)| r).collect(),
    })
}

/// The settings in the order they first appear.
fn settings_of(rows: &[Row]) -> Vec<SolverSetting> {
    let mut out: Vec<SolverSetting> = Vec::new();
    for r in rows {
        if !out.contains(&r.setting) {
            out.push(r.setting);
        }
    }
    out
}

/// A column of [`Study::table`]: its header and the cell of a row.
pub type Column = (&'static str, fn(&Row) -> String);

impl Study {
    /// Observed orders (L2, H1) per setting: least-squares slopes of log error against log dx.
    pub fn orders(&self) -> Vec<(SolverSetting, f64, f64)> {
        settings_of(&self.rows)
            .into_iter()
            .map(|s| {
                let rs: Vec<&Row> = self.rows.iter().filter(|r| r.setting == s).collect();
                let h: Vec<f64> = rs.iter().map(|r| r.dx).collect();
                let l2: Vec<f64> = rs.iter().map(|r| r.l2_error).collect();
                let h1: Vec<f64> = rs.iter().map(|r| r.h1_error).collect();
                (s, observed_order(&h, &l2), observed_order(&h, &h1))
            })
            .collect()
    }

    pub fn csv(&self) -> String {
        let mut out = String::from(
            "solver,setting,elements,dt,steps,l2_error,h1_error,energy_error,contact_time_error,wall_time_s,reference\n",
        );
        let opt = |v: Option<f64>| v.map_or(String::new(), |v| format!("{v:e}"));
        for r in &self.rows {
            let _ = writeln!(
                out,
                "{},{},{},{:e},{},{:e},{:e},{},{},{:.6},{}",
                r.setting.solver(),
                r.setting.setting(),
                r.elements,
                r.dt,
                r.steps,
                r.l2_error,
                r.h1_error,
                opt(r.energy_error),
                opt(r.contact_time_error),
                r.wall_time_s,
                self.reference
            );
        }
        out
    }

    /// The Markdown table of the runs, one row each: the `lead` columns, the four errors
    /// (`-` where one does not apply), then the `trail` columns. `viscobar converge` and
    /// VERIFICATION.md (section "Falling bar") both render through it.
    pub fn table(&self, lead: &[Column], trail: &[Column]) -> String {
        fn opt(v: Option<f64>) -> String {
            v.map_or("-".to_string(), |v| format!("{v:.3e}"))
        }
        let errors: [Column; 4] = [
            ("L2 error", |r| format!("{:.3e}", r.l2_error)),
            ("H1 error", |r| format!("{:.3e}", r.h1_error)),
            ("energy error", |r| opt(r.energy_error)),
            ("contact time error", |r| opt(r.contact_time_error)),
        ];
        let columns: Vec<&Column> = lead.iter().chain(&errors).chain(trail).collect();
        let mut md = String::from("|");
        for (header, _) in &columns {
            let _ = write!(md, " {header} |");
        }
        let _ = writeln!(md, "\n|{}", "---|".repeat(columns.len()));
        for r in &self.rows {
            md.push('|');
            for (_, cell) in &columns {
                let _ = write!(md, " {} |", cell(r));
            }
            md.push('\n');
        }
        md
    }

    pub fn markdown(&self) -> String {
        let mut md = format!("Scene `{}`, reference: {}\n\n", self.scene, self.reference);
        md.push_str(&self.table(
            &[
                ("solver", |r| r.setting.solver().to_string()),
                ("setting", |r| r.setting.setting()),
                ("elements", |r| r.elements.to_string()),
                ("dt", |r| format!("{:.3e}", r.dt)),
            ],
            &[("wall time (s)", |r| format!("{:.2e}", r.wall_time_s))],
        ));
        md.push_str("\n| solver | setting | observed order (L2) | observed order (H1) |\n|---|---|---|---|\n");
        for (s, p2, p1) in self.orders() {
            let _ = writeln!(
                md,
                "| {} | {} | {p2:.3} | {p1:.3} |",
                s.solver(),
                s.setting()
            );
        }
        md
    }

    /// Writes `convergence.csv`, and with the `plots` feature `work-precision.png` and
    /// `work-precision.svg`, into `out`.
    pub fn write(&self, out: &Path) -> Result<Vec<PathBuf>, ConvergeError> {
        std::fs::create_dir_all(out).map_err(|source| ConvergeError::Write {
            path: out.to_path_buf(),
            source,
        })?;
        let csv = out.join("convergence.csv");
        write_atomically(&csv, self.csv().as_bytes()).map_err(|source| ConvergeError::Write {
            path: csv.clone(),
            source,
        })?;
        #[cfg_attr(not(feature = "plots"), expect(unused_mut))]
        let mut files = vec![csv];
        #[cfg(feature = "plots")]
        for ext in ["png", "svg"] {
            use crate::study::figure_writer::FigureError;
            let path = out.join(format!("work-precision.{ext}"));
            crate::study::work_precision::write_work_precision(&path, &self.title(), &self.lines())
                .map_err(|e| match e {
                    FigureError::Write { path, source } => ConvergeError::Write { path, source },
                    e => ConvergeError::Draw {
                        path: path.clone(),
                        message: match e {
                            FigureError::Draw { message, .. } => message,
                            e => e.to_string(),
                        },
                    },
                })?;
            files.push(path);
        }
        Ok(files)
    }

    /// Title of the work-precision diagram.
    pub fn title(&self) -> String {
        format!(
            "{}: L2 error against wall time (reference: {})",
            self.scene, self.reference
        )
    }

    /// The lines of the work-precision diagram: `(label, [(wall time, L2 error)])` per setting.
    pub fn lines(&self) -> Vec<(String, Vec<(f64, f64)>)> {
        settings_of(&self.rows)
            .into_iter()
            .map(|s| {
                let pts = self
                    .rows
                    .iter()
                    .filter(|r| r.setting == s)
                    .map(|r| (r.wall_time_s.max(1e-6), r.l2_error.max(1e-300)))
                    .collect();
                (s.label(), pts)
            })
            .collect()
    }
}
