//! `verify` (`cargo run --release -p viscobar-certificate -- verify`): recomputes the measured
//! figures of VERIFICATION.md and prints them as Markdown tables, each between
//! `<!-- generated:ID -->` and `<!-- end:ID -->` markers, so the document is regenerated
//! (`verify --update VERIFICATION.md`), never hand-edited.
//! Every figure here is deterministic (no timings), so a test checks the document is current.

use crate::bar::roundoff::rigid_mode_drift;
use crate::bar::{stiff, stiff_runs};
use crate::solvers::agreement;
use std::fmt::Write;
use std::sync::OnceLock;
use viscobar::bar::closed_form;
use viscobar::bar::matrices::{MatrixVariant, mass, stiffness};
use viscobar::internals::linalg::norms::max_abs;
use viscobar::output::run_in_memory;
use viscobar::scene;
use viscobar::scheme::RunError;
use viscobar::study::accuracy::{error_against, observed_order};
use viscobar::study::converge::ConvergeError;

/// One generated block of VERIFICATION.md.
#[derive(Clone, Debug, PartialEq)]
pub struct Section {
    pub id: &'static str,
    pub markdown: String,
}

/// Levels of the convergence tables (dx and dt halved together from the scene's own mesh).
pub const CONVERGENCE_LEVELS: u32 = 5;
/// Size of the rigid-mode round-off study (the independent figure was taken at J = 8192).
pub const RIGID_ELEMENTS: u64 = 8193;
pub const RIGID_STEPS: usize = 26_000;

/// One independent computation of the document: its sections (none for a measurement that
/// sections assemble later).
type Job<'a> = Box<dyn FnOnce() -> Result<Vec<Section>, ConvergeError> + Send + 'a>;

/// Wraps one section's computation as a [`Job`].
fn job<'a>(
    id: &'static str,
    markdown: impl FnOnce() -> Result<String, ConvergeError> + Send + 'a,
) -> Job<'a> {
    Box::new(move || {
        Ok(vec![Section {
            id,
            markdown: markdown()?,
        }])
    })
}

/// Stores the value of a measurement job for the sections assembled after it.
fn keep<'a, T: Send + Sync>(
    cell: &'a OnceLock<T>,
    value: impl FnOnce() -> Result<T, ConvergeError> + Send + 'a,
) -> Job<'a> {
    Box::new(move || {
        let _ = cell.set(value()?);
        Ok(Vec::new())
    })
}

/// All sections (in the order of their jobs; each replaces its own block). The computations
/// are independent and deterministic, so they run on the machine's cores side by side and give
/// the same document in any order; the round-off, stiff and tolerance tables are assembled
/// afterwards from the measurements they share (the stiff case matrix, the rigid-mode run,
/// the registry's measurements).
/// Errors are those of the runs and of the α-sweep (both carry their exit code).
pub fn sections() -> Result<Vec<Section>, ConvergeError> {
    let stiff = OnceLock::new();
    let drift = OnceLock::new();
    let registry: [OnceLock<Vec<crate::tolerances::Measured>>; 5] = Default::default();
    let backward = OnceLock::new();
    let jobs: Vec<Job> = vec![
        // The longest first.
        job("plane-friction", crate::friction::markdown),
        job("plane-friction-period-two", || {
            let rows = crate::friction::period_two::table()?;
            Ok(crate::friction::period_two::markdown(&rows))
        }),
        job("plane", crate::plane::markdown),
        keep(&stiff, || Ok(stiff_runs::run_all(stiff::Size::Full))),
        keep(&registry[0], || Ok(crate::tolerances::measured()?)),
        keep(&registry[1], || Ok(crate::tolerances::plane_measured()?)),
        keep(&registry[2], || Ok(crate::tolerances::friction_measured()?)),
        keep(&registry[3], || Ok(crate::tolerances::thermal_measured()?)),
        keep(&registry[4], || {
            Ok(crate::tolerances::plane_heat_measured()?)
        }),
        job("solver-agreement", || Ok(agreement::markdown()?)),
        job("plane-contact", crate::plane::contact::markdown),
        Box::new(|| Ok(vec![convergence_section()?, falling_bar_section()?])),
        keep(&drift, || Ok(rigid_drift()?)),
        job("viscous-contact", || {
            let study = crate::bar::viscous_contact::study(CONVERGENCE_LEVELS)?;
            Ok(crate::bar::viscous_contact::markdown(&study))
        }),
        Box::new(|| Ok(vec![viscosity_section()?])),
        Box::new(|| Ok(vec![mass_variants_section()?])),
        keep(&backward, || Ok(backward_ulps())),
        Box::new(|| Ok(vec![matrices_section(), solve_section(), scenes_section()?])),
        job("locking", || Ok(crate::plane::locking::markdown()?)),
        job("moving", || Ok(crate::plane::moving::markdown()?)),
        job("thermal", || Ok(crate::thermal::markdown()?)),
        job("plane-heat", || Ok(crate::plane_heat::markdown()?)),
    ];
    let mut out = run_jobs(jobs)?;
    let (stiff, drift) = (stiff.get().expect("kept"), *drift.get().expect("kept"));
    let measured = registry
        .into_iter()
        .flat_map(|m| m.into_inner().expect("kept"))
        .collect();
    out.push(roundoff_section(drift));
    out.push(stiff_section(stiff));
    out.push(Section {
        id: "tolerances",
        markdown: crate::tolerances::registry_markdown_of(
            measured,
            stiff,
            drift.0,
            *backward.get().expect("kept"),
        ),
    });
    Ok(out)
}

/// Runs `jobs` on up to `available_parallelism` threads, each taking the next job in turn;
/// the first error (in job order) is returned.
fn run_jobs(jobs: Vec<Job<'_>>) -> Result<Vec<Section>, ConvergeError> {
    let count = jobs.len();
    let queue = std::sync::Mutex::new(jobs.into_iter().enumerate().collect::<Vec<_>>());
    let results = std::sync::Mutex::new(Vec::with_capacity(count));
    let threads = std::thread::available_parallelism()
        .map_or(1, |n| n.get())
        .min(count);
    std::thread::scope(|scope| {
        for _ in 0..threads {
            scope.spawn(|| {
                loop {
                    // Take from the front: the list starts with the longest jobs.
                    let next = {
                        let mut q = queue.lock().expect("no job panics while holding the queue");
                        if q.is_empty() {
                            None
                        } else {
                            Some(q.remove(0))
                        }
                    };
                    let Some((index, job)) = next else { break };
                    let result = job();
                    results
                        .lock()
                        .expect("no job panics while holding the results")
                        .push((index, result));
                }
            });
        }
    });
    let mut results = results.into_inner().expect("the threads have ended");
    results.sort_by_key(|(index, _)| *index);
    let mut out = Vec::new();
    for (_, r) in results {
        out.extend(r?);
    }
    Ok(out)
}

fn matrices_section() -> Section {
    let mut md = String::from(
        "| variant | nodes | 1ᵀM1 / L | max abs(R·1) · Δx | M symmetric | R symmetric |\n|---|---|---|---|---|---|\n",
    );
    for variant in [MatrixVariant::Consistent, MatrixVariant::TalkPrinted] {
        for nodes in [11usize, 101, 1001] {
            let dx = 1.0 / (nodes - 1) as f64;
            let m = mass(variant, nodes, dx);
            let r = stiffness(variant, nodes, dx);
            let total: f64 = m.mul(&vec![1.0; nodes]).iter().sum();
            let r1 = max_abs(&r.mul(&vec![1.0; nodes]));
            let sym = |a: &viscobar::internals::linalg::tridiag::SymTridiag| {
                let d = a.to_dense();
                d == d.transpose()
            };
            let _ = writeln!(
                md,
                "| {} | {nodes} | {:.6} | {} | {} | {} |",
                variant_name(variant),
                total,
                r1 * dx,
                sym(&m),
                sym(&r)
            );
        }
    }
    Section {
        id: "matrices",
        markdown: md,
    }
}

/// The step matrices of the backward-error study of the solve: `(α, Δt/Δx)` from
/// mass-dominated to the stiffest corner of the stiff case matrix.
pub const SOLVE_STUDY_CASES: [(f64, f64); 6] = [
    (0.0, 0.01),
    (0.0, 1.0),
    (0.1, 1.0),
    (10.0, 1.0),
    (1.0, 10.0),
    (1e6, 1e4),
];

/// One solve of the backward-error study.
#[derive(Clone, Copy, Debug)]
pub struct SolveCase {
    pub alpha: f64,
    pub dt_over_dx: f64,
    pub nodes: usize,
    /// Normwise backward error of the per-step solve `TwistedLdlt::solve_in_place`, in units
    /// of ε.
    pub backward_error: f64,
    /// Whether `solve_into` gave the same bits.
    pub into_same_bits: bool,
}

/// Solves `C x = b` on a bar of length 1 with `C = M/Δt² + (½ + α/(2Δt)) R` (consistent
/// matrices) for each case and node count, with a smooth `b`.
pub fn solve_study(nodes: &[usize]) -> Vec<SolveCase> {
    let mut out = Vec::new();
    for &n in nodes {
        for (alpha, ratio) in SOLVE_STUDY_CASES {
            let dx = 1.0 / (n - 1) as f64;
            let dt = ratio * dx;
            let (m, r) = (
                mass(MatrixVariant::Consistent, n, dx),
                stiffness(MatrixVariant::Consistent, n, dx),
            );
            let c = viscobar::internals::linalg::tridiag::SymTridiag::combine(
                1.0 / (dt * dt),
                &m,
                0.5 + alpha / (2.0 * dt),
                &r,
            );
            let b: Vec<f64> = (0..n).map(|i| (i as f64 * 0.37).sin() + 0.1).collect();
            let Ok(factor) =
                viscobar::internals::linalg::kernels::ldlt_fast::TwistedLdlt::factor(&c)
            else {
                continue;
            };
            let mut x = b.clone();
            factor.solve_in_place(&mut x);
            let mut y = vec![f64::NAN; n];
            factor.solve_into(&b, &mut y);
            out.push(SolveCase {
                alpha,
                dt_over_dx: ratio,
                nodes: n,
                backward_error: viscobar::internals::linalg::tridiag::backward_error(&c, &x, &b),
                into_same_bits: x.iter().zip(&y).all(|(p, q)| p.to_bits() == q.to_bits()),
            });
        }
    }
    out
}

/// Node counts of the study's table (even and odd: the reduction differs at the last node).
pub const SOLVE_STUDY_NODES: [usize; 4] = [1000, 1001, 100_000, 100_001];

fn solve_section() -> Section {
    let mut md = String::from(
        "| α | Δt/Δx | nodes | backward error / ε | `solve_into` same bits |\n|---|---|---|---|---|\n",
    );
    for case in solve_study(&SOLVE_STUDY_NODES) {
        let _ = writeln!(
            md,
            "| {:e} | {:e} | {} | {:.2} | {} |",
            case.alpha, case.dt_over_dx, case.nodes, case.backward_error, case.into_same_bits
        );
    }
    Section {
        id: "solve",
        markdown: md,
    }
}

fn variant_name(v: MatrixVariant) -> &'static str {
    match v {
        MatrixVariant::Consistent => "consistent",
        MatrixVariant::TalkPrinted => "talk-printed",
    }
}

fn scenes_section() -> Result<Section, RunError> {
    let mut md = String::from(
        "| scene | solver | nodes | steps | max identity residual | max energy rise / E^{1/2} | max abs(gap·reaction) | max penetration | min reaction | contact episodes |\n\
         |---|---|---|---|---|---|---|---|---|---|\n",
    );
    for name in scene::builtin_names() {
        let (_, scene) = scene::load(name, &[])?;
        let (_, s, _) = run_in_memory(name, &scene)?;
        let episodes: Vec<String> = s
            .contact_intervals
            .iter()
            .map(|(side, v)| format!("{side}: {}", v.len()))
            .collect();
        let _ = writeln!(
            md,
            "| {name} | {} | {} | {} | {:.1e} | {} | {:.1e} | {:.1e} | {:.1e} | {} |",
            s.solver,
            s.nodes,
            s.steps,
            s.max_identity_residual,
            s.max_energy_rise
                .map_or("(forced)".to_string(), |v| format!("{v:.1e}")),
            s.max_complementarity,
            s.max_violation,
            s.min_reaction,
            if episodes.is_empty() {
                "(no contact)".into()
            } else {
                episodes.join(", ")
            }
        );
    }
    Ok(Section {
        id: "scenes",
        markdown: md,
    })
}

fn convergence_section() -> Result<Section, RunError> {
    let mut md = String::from(
        "| scene | elements | dt | L2 error (max over t) | max-norm error | observed order (L2, all levels) |\n|---|---|---|---|---|---|\n",
    );
    for name in [
        "modal",
        "forced-mode",
        "impact",
        "clamped-impact",
        "falling-bar",
    ] {
        let (_, base) = scene::load(name, &[])?;
        let exact = closed_form::for_scene(name, &base).expect("built-in closed form");
        let mut rows = Vec::new();
        for level in 0..CONVERGENCE_LEVELS {
            let s = base.refined(level);
            let e = error_against(&s, exact.as_ref())?;
            rows.push((s.mesh.elements, s.time.step, s.dx(), e));
        }
        let h: Vec<f64> = rows.iter().map(|r| r.2).collect();
        let e: Vec<f64> = rows.iter().map(|r| r.3.l2).collect();
        let order = observed_order(&h, &e);
        for (i, (el, dt, _, err)) in rows.iter().enumerate() {
            let _ = writeln!(
                md,
                "| {name} | {el} | {dt} | {:.3e} | {:.3e} | {} |",
                err.l2,
                err.max,
                if i == 0 {
                    format!("{order:.3}")
                } else {
                    String::new()
                }
            );
        }
    }
    Ok(Section {
        id: "convergence",
        markdown: md,
    })
}

/// The falling bar through `viscobar converge` (exact solver; the wall times are left out):
/// the errors in displacement, energy and contact times, and their observed orders.
fn falling_bar_section() -> Result<Section, viscobar::study::converge::ConvergeError> {
    use viscobar::study::converge::{SolverSetting, study};
    let (_, base) = scene::load("falling-bar", &[])?;
    let st = study(
        "falling-bar",
        &base,
        &[SolverSetting::Exact],
        CONVERGENCE_LEVELS,
        None,
    )?;
    let mut md = format!("Reference: {}.\n\n", st.reference);
    md.push_str(&st.table(
        &[
            ("elements", |r| r.elements.to_string()),
            ("dt", |r| r.dt.to_string()),
        ],
        &[],
    ));
    let h: Vec<f64> = st.rows.iter().map(|r| r.dx).collect();
    let order = |f: fn(&viscobar::study::converge::Row) -> Option<f64>| {
        let e: Option<Vec<f64>> = st.rows.iter().map(f).collect();
        e.map_or("-".to_string(), |e| {
            format!("{:.3}", observed_order(&h, &e))
        })
    };
    let _ = writeln!(
        md,
        "| observed order | | {} | {} | {} | {} |",
        order(|r| Some(r.l2_error)),
        order(|r| Some(r.h1_error)),
        order(|r| r.energy_error),
        order(|r| r.contact_time_error)
    );
    Ok(Section {
        id: "falling-bar",
        markdown: md,
    })
}

/// The rigid-mode drift `(increment form, talk form)` at [`RIGID_ELEMENTS`], [`RIGID_STEPS`]
/// (`tests/roundoff.rs` runs the same).
pub fn rigid_drift() -> Result<(f64, f64), RunError> {
    rigid_mode_drift(RIGID_ELEMENTS, RIGID_STEPS)
}

fn roundoff_section((ours, talk): (f64, f64)) -> Section {
    let md = format!(
        "| formulation | max_i abs(u_i − t) after {RIGID_STEPS} steps, J = {} |\n|---|---|\n\
         | increment z = u^(n+1) − u^n (viscobar) | {ours:.2e} |\n| talk form C u^(n+1) = F̃^n | {talk:.2e} |\n",
        RIGID_ELEMENTS - 1
    );
    Section {
        id: "roundoff",
        markdown: md,
    }
}

/// The whole output of `verify`.
pub fn render(sections: &[Section]) -> String {
    let mut out = String::new();
    for s in sections {
        let _ = write!(
            out,
            "<!-- generated:{} -->\n{}<!-- end:{} -->\n\n",
            s.id, s.markdown, s.id
        );
    }
    out
}

/// Replaces each generated block of `doc` by the section of the same id. Errors name a
/// missing marker.
pub fn update_document(doc: &str, sections: &[Section]) -> Result<String, String> {
    let mut out = doc.to_string();
    for s in sections {
        let open = format!("<!-- generated:{} -->\n", s.id);
        let close = format!("<!-- end:{} -->", s.id);
        let a = out
            .find(&open)
            .ok_or(format!("the document has no marker `{}`", open.trim()))?;
        let b = out[a..]
            .find(&close)
            .ok_or(format!("the document has no marker `{close}`"))?
            + a;
        out.replace_range(a + open.len()..b, &s.markdown);
    }
    Ok(out)
}

/// The α → 0 study in reduced size (the full one: `viscobar converge impact --viscosity-sweep`).
pub const SWEEP_ALPHAS: [f64; 4] = [1e-1, 1e-2, 1e-3, 1e-4];
pub const SWEEP_ELEMENTS: [u64; 2] = [800, 1600];

fn viscosity_section() -> Result<Section, viscobar::study::converge::ConvergeError> {
    let (_, base) = scene::load("impact", &[])?;
    let sweep = viscobar::study::viscosity_sweep::viscosity_sweep(
        "impact",
        &base,
        &SWEEP_ALPHAS,
        &SWEEP_ELEMENTS,
    )?;
    Ok(Section {
        id: "viscosity",
        markdown: sweep.markdown(),
    })
}

/// The stiff and extreme case matrix from its runs (full size: about 40 s on 2 cores; alone:
/// `verify --stiff`); `tests/stiff.rs` runs the reduced size.
pub fn stiff_section(results: &[crate::bar::stiff::CaseResult]) -> Section {
    Section {
        id: "stiff",
        markdown: crate::bar::stiff::markdown(results),
    }
}

/// The mass variants on `impact` and `falling-bar` (`study::mass_variants`; a few seconds).
fn mass_variants_section() -> Result<Section, viscobar::study::converge::ConvergeError> {
    use crate::bar::mass_study::{MassStudyError, mass_study};
    use viscobar::study::converge::ConvergeError;
    let rows = mass_study().map_err(|e| match e {
        MassStudyError::Run(r) => ConvergeError::Run(r),
        other => ConvergeError::BadInput(other.to_string()),
    })?;
    let mut markdown = crate::bar::mass_study::certificate_markdown()?;
    markdown.push('\n');
    markdown.push_str(&crate::bar::mass_study::markdown(&rows));
    Ok(Section {
        id: "mass-variants",
        markdown,
    })
}

/// The tolerance registry (`verify --tolerances`, [`crate::tolerances`]), with the stiff
/// matrix's checks read from `results` and the rigid-mode drift `increment_drift` of
/// [`rigid_drift`].
pub fn tolerances_section(
    results: &[crate::bar::stiff::CaseResult],
    increment_drift: f64,
) -> Result<Section, RunError> {
    Ok(Section {
        id: "tolerances",
        markdown: crate::tolerances::registry_markdown(results, increment_drift, backward_ulps())?,
    })
}

/// The worst backward error of the solve over [`backward_error_nodes`], in units of ε.
fn backward_ulps() -> f64 {
    solve_study(&backward_error_nodes())
        .iter()
        .map(|c| c.backward_error)
        .fold(0.0, f64::max)
}

/// The node counts of `tests/matrices.rs`'s backward-error check (`BACKWARD_ULPS`): every small
/// count and the solve study's.
pub fn backward_error_nodes() -> Vec<usize> {
    (2..=24).chain(SOLVE_STUDY_NODES).collect()
}
