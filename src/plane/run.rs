//! Running a plane scene end to end: the step loop and the output files, as for the bar
//! (`summary.json`, `history.csv`, `displacement.csv` in long format `t,x,y,ux,uy,vx,vy`),
//! written into a temporary folder and moved into place only when the run succeeds.

use crate::plane::error::PlaneError;
use crate::plane::simulation::{PlaneRecord, PlaneSimulation};
use crate::scene::plane::PlaneScene;
use crate::step::report::AuditReport;
use crate::time::run::{RUN_FILES, write_whole};
use crate::time::summary::{TimeShares, output_time};
use serde::Serialize;
use std::io::Write;
use std::path::{Path, PathBuf};
use std::time::Instant;

/// The name of the plane's linear solver in `summary.json`.
pub const SOLVER_NAME: &str = "sparse-cholesky";

/// `summary.json` of a plane run: the bar's fields where they apply.
#[derive(Clone, Debug, Serialize)]
pub struct PlaneSummary {
    pub scene: String,
    /// [`SOLVER_NAME`]: one solve with the factor of `C` per step.
    pub solver: String,
    /// The step problems' method, `[solver] method`: `exact`, `osqp` or `penalty` (named
    /// even without Signorini edges, as the bar's `solver`).
    pub method: String,
    /// `(nx + 1)(ny + 1)`.
    pub nodes: usize,
    /// Cells, `nx · ny`.
    pub elements: usize,
    /// Degrees of freedom not clamped.
    pub unknowns: usize,
    /// Stored values of the factor of `C` (supernodal, AMD ordering).
    pub factor_values: usize,
    pub dt: f64,
    pub steps: usize,
    pub final_time: f64,
    pub wall_time_s: f64,
    /// `wall_time_s` / (steps × unknowns), nanoseconds.
    pub ns_per_unknown_step: f64,
    /// Shares of the stepping time per phase, estimated on a sample of the steps, as the
    /// bar's: `rhs` (load and right-hand side), `solver` (the solve with the factor of `C` or
    /// the contact solver, and `u += z`), `diagnostics` (contact figures, energy balance),
    /// `stepping` (the sampled phases' share of the wall time).
    pub time_shares: TimeShares,
    /// `E^{1/2}`, `E^{N−1/2}`.
    pub energy_initial: f64,
    pub energy_final: f64,
    /// Largest `E^{n+1/2} − E^{n−1/2}` over `E^{1/2}`; `null` with a load.
    pub max_energy_rise: Option<f64>,
    pub max_identity_residual: f64,
    /// With Signorini edges only: the contact figures over all steps.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub contact: Option<ContactSummary>,
    /// OSQP only: the worst audit residuals, each with its ratio to its tolerance.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub audit: Option<AuditReport>,
    /// OSQP only: steps accepted as "solved inaccurate" (`solver.accept_inaccurate`).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub inaccurate_steps: Option<u64>,
}

/// The contact figures of a plane run with Signorini edges.
#[derive(Clone, Debug, Default, Serialize)]
pub struct ContactSummary {
    /// `m`, the contact normals.
    pub normals: usize,
    /// Largest number of normals in contact (`r > 0`) at one step.
    pub max_active: usize,
    /// Steps with some normal in contact.
    pub contact_steps: usize,
    /// `Σ_n D^n`, the energy the contact took.
    pub dissipation: f64,
    /// Largest `max(0, −gap)` and `|r · gap|`, each over its step's gap scale
    /// (`max(|g|, |u·n|)`): round-off.
    pub max_penetration: f64,
    pub max_complementarity: f64,
    /// `mean` and `max` of the iterations per step: active sets tried (exact, penalty) or
    /// ADMM iterations (OSQP).
    pub iterations_mean: f64,
    pub iterations_max: u32,
}

/// Collects the summary's figures over the records.
struct Tracker {
    energy_initial: f64,
    last_energy: f64,
    max_rise: f64,
    max_residual: f64,
    forced: bool,
    contact: Option<ContactSummary>,
    iterations: u64,
    records: u64,
}

impl Tracker {
    fn new(first: &PlaneRecord, forced: bool) -> Self {
        Self {
            energy_initial: first.energy,
            last_energy: first.energy,
            max_rise: f64::NEG_INFINITY,
            max_residual: 0.0,
            forced,
            contact: None,
            iterations: 0,
            records: 0,
        }
    }

    fn with_contact(mut self, sim: &PlaneSimulation) -> Self {
        if let Some(c) = sim.contact() {
            self.contact = Some(ContactSummary {
                normals: c.len(),
                ..Default::default()
            });
            self.observe_contact(&sim.first_record());
        }
        self
    }

    fn observe_contact(&mut self, r: &PlaneRecord) {
        if let Some(s) = &mut self.contact {
            let c = &r.contact;
            s.max_active = s.max_active.max(c.active);
            s.contact_steps += usize::from(c.active > 0);
            s.dissipation += c.dissipation;
            if c.gap_scale > 0.0 {
                s.max_penetration = s.max_penetration.max(c.penetration / c.gap_scale);
                s.max_complementarity = s.max_complementarity.max(c.complementarity / c.gap_scale);
            }
            s.iterations_max = s.iterations_max.max(c.iterations);
            self.iterations += u64::from(c.iterations);
            self.records += 1;
        }
    }

    fn observe(&mut self, r: &PlaneRecord) {
        self.observe_contact(r);
        self.max_rise = self.max_rise.max(r.energy - self.last_energy);
        self.max_residual = self.max_residual.max(r.identity_residual);
        self.last_energy = r.energy;
    }

    fn finish(self, name: &str, sim: &PlaneSimulation, wall: f64) -> PlaneSummary {
        let d = sim.discretisation();
        let steps = sim.step_index();
        let rise = if self.max_rise.is_finite() {
            self.max_rise / self.energy_initial
        } else {
            0.0
        };
        PlaneSummary {
            scene: name.to_string(),
            solver: SOLVER_NAME.into(),
            method: sim.method().name().into(),
            nodes: d.grid.nodes(),
            elements: d.grid.cells(),
            unknowns: d.unknowns(),
            factor_values: sim.factor_len(),
            dt: d.dt,
            steps,
            final_time: output_time(sim.time()),
            wall_time_s: wall,
            ns_per_unknown_step: wall * 1e9 / (steps as f64 * d.unknowns() as f64),
            time_shares: TimeShares::from_phases(sim.phase_times(), steps, wall),
            energy_initial: self.energy_initial,
            energy_final: self.last_energy,
            max_energy_rise: (!self.forced).then_some(rise),
            max_identity_residual: self.max_residual,
            contact: self.contact.map(|mut c| {
                c.iterations_mean = self.iterations as f64 / self.records.max(1) as f64;
                c
            }),
            audit: sim.osqp_report().map(|(a, _)| a.clone()),
            inaccurate_steps: sim.osqp_report().map(|(_, n)| n),
        }
    }
}

/// Whether a scene has a load (which can feed energy in).
fn forced(scene: &PlaneScene) -> bool {
    scene.load.density.as_ref().is_some_and(|v| {
        v.0.iter()
            .any(|c| c.trim().parse::<f64>().ok().is_none_or(|x| x != 0.0))
    })
}

/// Runs a plane scene in memory: every record (the start-up step first), the summary and the
/// final simulation.
pub fn run_plane_in_memory(
    name: &str,
    scene: &PlaneScene,
) -> Result<(Vec<PlaneRecord>, PlaneSummary, PlaneSimulation), PlaneError> {
    let start = Instant::now();
    let mut sim = PlaneSimulation::new(scene)?;
    let mut tracker = Tracker::new(&sim.first_record(), forced(scene)).with_contact(&sim);
    let mut records = vec![sim.first_record()];
    for _ in 1..scene.steps() {
        let r = sim.step()?;
        tracker.observe(&r);
        records.push(r);
    }
    let summary = tracker.finish(name, &sim, start.elapsed().as_secs_f64());
    Ok((records, summary, sim))
}

/// Runs a plane scene and writes `summary.json`, `history.csv` and `displacement.csv` into
/// `out`, whole or not at all (the bar's [`crate::time::run::run_to_dir`] discipline: the scene
/// is set up before anything is created; folders created for `out` are removed on failure).
pub fn run_plane_to_dir(
    name: &str,
    scene: &PlaneScene,
    out: &Path,
) -> Result<PlaneSummary, PlaneError> {
    let start = Instant::now();
    let sim = PlaneSimulation::new(scene)?;
    write_whole(
        out,
        &RUN_FILES,
        |path, source| PlaneError::Write { path, source },
        |tmp| write_run(name, scene, sim, start, tmp),
    )
}

fn write_run(
    name: &str,
    scene: &PlaneScene,
    mut sim: PlaneSimulation,
    start: Instant,
    dir: &Path,
) -> Result<PlaneSummary, PlaneError> {
    let open = |file: &str| -> Result<(PathBuf, std::io::BufWriter<std::fs::File>), PlaneError> {
        let path = dir.join(file);
        let f = std::fs::File::create(&path).map_err(|source| PlaneError::Write {
            path: path.clone(),
            source,
        })?;
        Ok((path, std::io::BufWriter::with_capacity(1 << 20, f)))
    };
    let io = |path: &PathBuf| {
        let path = path.clone();
        move |source| PlaneError::Write { path, source }
    };
    let (hist_path, mut hist) = open("history.csv")?;
    let (disp_path, mut disp) = open("displacement.csv")?;
    let contact = sim.contact().is_some();
    writeln!(
        hist,
        "step,t,energy,work,viscous_dissipation,identity_residual{}",
        if contact { CONTACT_COLUMNS } else { "" }
    )
    .map_err(io(&hist_path))?;
    let first = sim.first_record();
    write_history_row(&mut hist, &first, contact).map_err(io(&hist_path))?;
    let mut tracker = Tracker::new(&first, forced(scene)).with_contact(&sim);

    let grid = sim.discretisation().grid.clone();
    // Coordinates rounded once per run, as the bar's x.
    let points: Vec<(f64, f64)> = (0..grid.nodes())
        .map(|k| {
            let (x, y) = grid.point(k);
            (output_time(x), output_time(y))
        })
        .collect();
    writeln!(disp, "t,x,y,ux,uy,vx,vy").map_err(io(&disp_path))?;
    let (u0, v0) = sim.initial_state();
    write_field(&mut disp, 0.0, &points, u0, v0).map_err(io(&disp_path))?;
    let mut u = vec![0.0; grid.dofs()];
    let mut v = vec![0.0; grid.dofs()];
    let steps = scene.steps();
    let every = scene.output.every as usize;
    let keep = |n: usize| n.is_multiple_of(every) || n == steps;
    if keep(1) {
        sim.displacement_into(&mut u);
        sim.velocity_into(&mut v);
        write_field(&mut disp, sim.time(), &points, &u, &v).map_err(io(&disp_path))?;
    }
    for _ in 1..steps {
        let r = sim.step()?;
        tracker.observe(&r);
        write_history_row(&mut hist, &r, contact).map_err(io(&hist_path))?;
        if keep(r.step) {
            sim.displacement_into(&mut u);
            sim.velocity_into(&mut v);
            write_field(&mut disp, sim.time(), &points, &u, &v).map_err(io(&disp_path))?;
        }
    }
    hist.flush().map_err(io(&hist_path))?;
    disp.flush().map_err(io(&disp_path))?;
    let summary = tracker.finish(name, &sim, start.elapsed().as_secs_f64());
    let json_path = dir.join("summary.json");
    let json = serde_json::to_string_pretty(&summary).expect("summary serialises");
    std::fs::write(&json_path, json + "\n").map_err(io(&json_path))?;
    Ok(summary)
}

/// The history's columns of a run with Signorini edges: the contact term `D` of the energy
/// identity, normals in contact, `Σ r`, the largest penetration, the LCP's active sets tried.
pub const CONTACT_COLUMNS: &str =
    ",contact_dissipation,contact_normals,total_reaction,max_penetration,iterations";

fn write_history_row(w: &mut impl Write, r: &PlaneRecord, contact: bool) -> std::io::Result<()> {
    write!(
        w,
        "{},{},{},{},{},{}",
        r.step,
        output_time(r.time),
        r.energy,
        r.work,
        r.viscous_dissipation,
        r.identity_residual
    )?;
    if contact {
        let c = &r.contact;
        write!(
            w,
            ",{},{},{},{},{}",
            c.dissipation, c.active, c.total_reaction, c.penetration, c.iterations
        )?;
    }
    writeln!(w)
}

/// One row a node: `t,x,y,ux,uy,vx,vy`.
fn write_field(
    w: &mut impl Write,
    t: f64,
    points: &[(f64, f64)],
    u: &[f64],
    v: &[f64],
) -> std::io::Result<()> {
    let t = output_time(t);
    for (k, (x, y)) in points.iter().enumerate() {
        writeln!(
            w,
            "{t},{x},{y},{},{},{},{}",
            u[2 * k],
            u[2 * k + 1],
            v[2 * k],
            v[2 * k + 1]
        )?;
    }
    Ok(())
}
