//! `viscobar converge --viscosity-sweep`: the `α → 0` sweep of the impact scene. Each run at
//! viscosity `α` is measured against the elastic closed form and against the discrete elastic
//! run on the same mesh (no discretisation error in that difference), with its relative energy
//! loss; the fitted exponents of `distance ~ α^p` go to VERIFICATION.md (section "The limit
//! α → 0").
//!
//! Apart from the refinement study (`study::converge`): it shares its solver settings, errors
//! and L2 norm, not its reference runs or its diagram. Runs go to rayon's pool in parallel.

use crate::bar::Simulation;
use crate::bar::closed_form::{self, ClosedForm, Impact};
use crate::output::files::write_atomically;
use crate::scene::Scene;
use crate::scheme::RunError;
use crate::study::accuracy::observed_order;
use crate::study::converge::{ConvergeError, SolverSetting};
use crate::study::refine::l2_norm;
use rayon::prelude::*;
use std::fmt::Write as _;
use std::path::{Path, PathBuf};

fn impact_of(scene: &Scene) -> Option<Impact> {
    let v =
        crate::scene::expr::Expression::parse("initial.velocity", &scene.initial.velocity, false)
            .ok()?
            .eval(0.0, 0.0)
            .ok()?;
    Some(Impact {
        length: scene.bar.length,
        gap: scene.left.constant_gap()?,
        speed: -v,
    })
}

/// Viscosities of the `α → 0` sweep: half-decades from 1e-1 down to 1e-6.
pub const SWEEP_ALPHAS: [f64; 11] = [
    1e-1,
    3.162_277_660_168_38e-2,
    1e-2,
    3.162_277_660_168_379_5e-3,
    1e-3,
    3.162_277_660_168_379_5e-4,
    1e-4,
    3.162_277_660_168_379_5e-5,
    1e-5,
    3.162_277_660_168_379_5e-6,
    1e-6,
];
/// Meshes of the sweep (dt = dx): a fixed fine mesh and one refined twice.
pub const SWEEP_ELEMENTS: [u64; 2] = [1600, 6400];

/// One row of `viscosity-sweep.csv`.
#[derive(Clone, Debug)]
pub struct SweepRow {
    pub alpha: f64,
    pub elements: u64,
    pub dt: f64,
    /// `max_n ‖u_h^α(t_n) − u^0(·, t_n)‖_{L2}`, `u^0` the elastic closed form.
    pub l2_to_closed_form: f64,
    /// `max_n ‖u_h^α(t_n) − u_h^0(t_n)‖_{L2}`: the same mesh and dt, α = 0 (no discretisation
    /// error in the difference).
    pub l2_to_discrete_elastic: f64,
    /// `(E^{1/2} − E^{N−1/2}) / E^{1/2}`.
    pub energy_loss: f64,
}

/// The outcome of the sweep.
#[derive(Debug)]
pub struct Sweep {
    pub scene: String,
    pub rows: Vec<SweepRow>,
}

/// Runs `scene` (the impact scene, any α) with `α` in `alphas` at each mesh of `elements`
/// (dt = dx), in parallel, beside the α = 0 run on the same mesh.
pub fn viscosity_sweep(
    scene_name: &str,
    base: &Scene,
    alphas: &[f64],
    elements: &[u64],
) -> Result<Sweep, ConvergeError> {
    let mut elastic = SolverSetting::Exact.apply(base);
    elastic.bar.viscosity = 0.0;
    if scene_name != "impact" || closed_form::for_scene(scene_name, &elastic).is_none() {
        return Err(ConvergeError::BadInput(format!(
            "--viscosity-sweep: needs the `impact` scene (its elastic closed form); got `{scene_name}`"
        )));
    }
    let tasks: Vec<(u64, f64)> = elements
        .iter()
        .flat_map(|j| alphas.iter().map(move |a| (*j, *a)))
        .collect();
    let rows = tasks
        .par_iter()
        .map(|&(j, alpha)| sweep_one(&elastic, j, alpha))
        .collect::<Result<Vec<_>, RunError>>()?;
    Ok(Sweep {
        scene: scene_name.to_string(),
        rows,
    })
}

fn sweep_one(elastic: &Scene, elements: u64, alpha: f64) -> Result<SweepRow, RunError> {
    let mut e0 = elastic.clone();
    e0.mesh.elements = elements;
    e0.time.step = e0.dx();
    let mut va = e0.clone();
    va.bar.viscosity = alpha;
    let exact = impact_of(&e0).expect("checked by viscosity_sweep");
    let mut s0 = Simulation::new(&e0)?;
    let mut sa = Simulation::new(&va)?;
    let nodes = s0.discretisation().nodes;
    let dx = e0.dx();
    let xs: Vec<f64> = (0..nodes).map(|i| s0.discretisation().x(i)).collect();
    let (mut u0, mut ua, mut d) = (vec![0.0; nodes], vec![0.0; nodes], vec![0.0; nodes]);
    let (mut to_closed, mut to_discrete) = (0.0f64, 0.0f64);
    let mut e_first = None;
    let mut e_last = 0.0;
    for n in 0..e0.steps() {
        if n > 0 {
            s0.step()?;
            let r = sa.step()?;
            e_first.get_or_insert(r.energy);
            e_last = r.energy;
        }
        s0.displacement_into(&mut u0);
        sa.displacement_into(&mut ua);
        let t = sa.time();
        for i in 0..nodes {
            d[i] = ua[i] - exact.displacement(xs[i], t);
        }
        to_closed = to_closed.max(l2_norm(&d, dx));
        for i in 0..nodes {
            d[i] = ua[i] - u0[i];
        }
        to_discrete = to_discrete.max(l2_norm(&d, dx));
    }
    let e_first = e_first.unwrap_or(sa.first_record().energy);
    Ok(SweepRow {
        alpha,
        elements,
        dt: e0.time.step,
        l2_to_closed_form: to_closed,
        l2_to_discrete_elastic: to_discrete,
        energy_loss: (e_first - e_last) / e_first,
    })
}

impl Sweep {
    /// Fitted exponents `p` of `distance ~ α^p` per mesh: (elements, p to the closed form, p to
    /// the discrete elastic run, p of the energy loss).
    pub fn exponents(&self) -> Vec<(u64, f64, f64, f64)> {
        let mut meshes: Vec<u64> = self.rows.iter().map(|r| r.elements).collect();
        meshes.dedup();
        meshes
            .into_iter()
            .map(|j| {
                let rs: Vec<&SweepRow> = self.rows.iter().filter(|r| r.elements == j).collect();
                let a: Vec<f64> = rs.iter().map(|r| r.alpha).collect();
                let f = |g: fn(&SweepRow) -> f64| {
                    observed_order(&a, &rs.iter().map(|r| g(r)).collect::<Vec<f64>>())
                };
                (
                    j,
                    f(|r| r.l2_to_closed_form),
                    f(|r| r.l2_to_discrete_elastic),
                    f(|r| r.energy_loss),
                )
            })
            .collect()
    }

    pub fn csv(&self) -> String {
        let mut out = String::from(
            "alpha,elements,dt,l2_to_closed_form,l2_to_discrete_elastic,energy_loss\n",
        );
        for r in &self.rows {
            let _ = writeln!(
                out,
                "{:e},{},{:e},{:e},{:e},{:e}",
                r.alpha,
                r.elements,
                r.dt,
                r.l2_to_closed_form,
                r.l2_to_discrete_elastic,
                r.energy_loss
            );
        }
        out
    }

    /// Deterministic (no timings): the table and the fitted exponents.
    pub fn markdown(&self) -> String {
        let mut md = String::from(
            "| alpha | elements | L2 distance to elastic closed form | L2 distance to discrete elastic run | relative energy loss |\n|---|---|---|---|---|\n",
        );
        for r in &self.rows {
            let _ = writeln!(
                md,
                "| {:.2e} | {} | {:.3e} | {:.3e} | {:.3e} |",
                r.alpha, r.elements, r.l2_to_closed_form, r.l2_to_discrete_elastic, r.energy_loss
            );
        }
        md.push_str("\n| elements | p (closed form) | p (discrete elastic) | p (energy loss) |\n|---|---|---|---|\n");
        for (j, a, b, c) in self.exponents() {
            let _ = writeln!(md, "| {j} | {a:.3} | {b:.3} | {c:.3} |");
        }
        md
    }

    pub fn write(&self, out: &Path) -> Result<Vec<PathBuf>, ConvergeError> {
        std::fs::create_dir_all(out).map_err(|source| ConvergeError::Write {
            path: out.to_path_buf(),
            source,
        })?;
        let csv = out.join("viscosity-sweep.csv");
        write_atomically(&csv, self.csv().as_bytes()).map_err(|source| ConvergeError::Write {
            path: csv.clone(),
            source,
        })?;
        Ok(vec![csv])
    }
}
