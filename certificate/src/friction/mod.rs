//! The plane friction certificate (VERIFICATION.md, "Plane friction"): `μ = 0` against the
//! frictionless runs bit for bit, the energy identity with `D_f`, `D_f >= 0`, the momentum
//! balance along the tangent and the audit at every step of the built-in friction scenes, the
//! exact solver against OSQP's Tresca fixed point, the rigid-limit closed forms
//! ([`crate::friction::rigid`]) and the frictional drop's convergence against a finer exact run.
//! The tests (`tests/plane_coulomb_friction.rs`) assert on the same computations.

pub mod period_two;
pub mod rigid;

use crate::friction::rigid::{RigidRow, closed_form_self_test, rigid_table};
use crate::plane::contact::{Method, plane_error, plane_scene};
use std::fmt::Write;
use viscobar::plane::PlaneSimulation;
use viscobar::scene::plane::{EdgeCondition, PLANE_BUILTIN, PlaneScene};
use viscobar::scheme::Body;
use viscobar::study::converge::ConvergeError;

/// The built-in friction scenes.
pub const FRICTION_SCENES: [&str; 3] = [
    "plane-friction-tilted-drop",
    "plane-friction-slope",
    "plane-friction-launch",
];

/// `scene` with the friction key of every Signorini edge set to `friction` (`None`: absent;
/// without friction an edge's obstacle does not slide and its temperature has no frictional
/// heating).
pub fn with_friction(scene: &PlaneScene, friction: Option<f64>) -> PlaneScene {
    let mut s = scene.clone();
    let frictionless = !friction.is_some_and(|mu| mu > 0.0);
    let mut heat_edges = s.heat.as_mut().map(|h| {
        [
            &mut h.left.frictional_heating,
            &mut h.right.frictional_heating,
            &mut h.bottom.frictional_heating,
            &mut h.top.frictional_heating,
        ]
    });
    for (k, e) in [
        &mut s.edges.left,
        &mut s.edges.right,
        &mut s.edges.bottom,
        &mut s.edges.top,
    ]
    .into_iter()
    .enumerate()
    {
        if e.condition == EdgeCondition::Signorini {
            e.friction = friction.map(|mu| mu.to_string());
            // A sliding obstacle and frictional heating belong to a frictional edge.
            if frictionless {
                e.velocity = None;
                if let Some(heating) = heat_edges.as_mut() {
                    *heating[k] = None;
                }
            }
        }
    }
    s
}

/// One scene run without the friction key and with `friction = 0` on every Signorini edge.
#[derive(Clone, Debug)]
pub struct BitwiseCase {
    pub name: String,
    pub steps: usize,
    /// Every step's displacement, reactions and record the same bits.
    pub identical: bool,
}

/// [`BitwiseCase`] for every built-in plane scene with a Signorini edge.
pub fn mu_zero_cases() -> Result<Vec<BitwiseCase>, ConvergeError> {
    let mut out = Vec::new();
    for (name, _) in PLANE_BUILTIN {
        let scene = plane_scene(name, &[])?;
        if scene.edges.gaps()?.iter().all(Option::is_none) {
            continue;
        }
        let mut a = PlaneSimulation::new(&with_friction(&scene, None)).map_err(plane_error)?;
        let mut b = PlaneSimulation::new(&with_friction(&scene, Some(0.0))).map_err(plane_error)?;
        let bits = |v: &[f64]| v.iter().map(|x| x.to_bits()).collect::<Vec<u64>>();
        let same = |a: &PlaneSimulation, b: &PlaneSimulation| {
            bits(a.displacement()) == bits(b.displacement())
                && bits(a.reactions()) == bits(b.reactions())
                && b.tangential_reactions().is_empty()
        };
        let mut identical =
            same(&a, &b) && format!("{:?}", a.first_record()) == format!("{:?}", b.first_record());
        for _ in 1..scene.steps() {
            let (ra, rb) = (
                a.step().map_err(plane_error)?,
                b.step().map_err(plane_error)?,
            );
            identical &= same(&a, &b) && format!("{ra:?}") == format!("{rb:?}");
        }
        out.push(BitwiseCase {
            name: name.to_string(),
            steps: scene.steps(),
            identical,
        });
    }
    Ok(out)
}

/// The checks of one frictional run, worst over its steps (the start-up step excepted where
/// it has no friction).
#[derive(Clone, Debug, Default)]
pub struct FrictionCheck {
    pub name: String,
    pub steps: usize,
    /// Steps with a sticking and with a slipping node, and the most of each at one step.
    pub steps_sticking: usize,
    pub steps_slipping: usize,
    pub max_stick: usize,
    pub max_slip: usize,
    pub max_identity: f64,
    /// `min D_f / E^{n+1/2}` (negative only by round-off) and `Σ D_f`.
    pub min_dissipation_ratio: f64,
    pub total_dissipation: f64,
    /// The momentum balance along the tangent `x`: `|1_xᵀ(M(u^{n+1} − 2u^n + u^{n−1})/Δt² − F^n
    /// − Eᵀr)|` over the magnitudes its round-off is relative to: `1_xᵀ` of `M(|z| + |w|)/Δt²`,
    /// `|F^n|`, `|Eᵀr|` and `|K| |v|` for the stiffness terms, whose sum vanishes (`K 1_x = 0`).
    pub momentum: f64,
    /// The audit's worst ratio to its tolerance over all its checks, and its cone and slip law.
    pub audit_worst_ratio: f64,
    pub cone: f64,
    pub slip_law: f64,
    /// Lemke's bases tried per step (mean, max).
    pub mean_iterations: f64,
    pub max_iterations: u32,
}

/// The sum of the `x` entries of `v` (unknowns `free[i]` even) and of their magnitudes.
fn x_sums(free: &[usize], v: &[f64]) -> (f64, f64) {
    free.iter()
        .zip(v)
        .filter(|(d, _)| *d % 2 == 0)
        .fold((0.0, 0.0), |(s, a), (_, x)| (s + x, a + x.abs()))
}

/// Runs `scene` (its `[solver]` method) with the checks of [`FrictionCheck`] at every step.
pub fn friction_check(name: &str, scene: &PlaneScene) -> Result<FrictionCheck, ConvergeError> {
    let mut sim = PlaneSimulation::new(scene).map_err(plane_error)?;
    let free = sim.discretisation().free.clone();
    let n = free.len();
    let (dt, alpha) = (scene.time.step, scene.plane.viscosity);
    let constraints = sim.contact().constraints();
    let friction = sim.contact().friction().clone();
    let mut c = FrictionCheck {
        name: name.to_string(),
        steps: scene.steps(),
        min_dissipation_ratio: f64::INFINITY,
        // Friction acts from the start-up step: its D_f opens the sum.
        total_dissipation: sim.first_record().friction_dissipation,
        ..Default::default()
    };
    let (mut acc, mut mass_abs) = (vec![0.0; n], vec![0.0; n]);
    let mut iterations = 0u64;
    for _ in 1..scene.steps() {
        let step = sim.step_index();
        let force = sim.load_vector(step).map_err(plane_error)?;
        let (u_old, w_old) = (sim.displacement().to_vec(), sim.state().w.to_vec());
        let r = sim.step().map_err(plane_error)?;
        let (u, z) = (sim.displacement(), sim.state().w);
        iterations += u64::from(r.iterations);
        c.max_iterations = c.max_iterations.max(r.iterations);
        c.max_identity = c.max_identity.max(r.identity_residual);
        if r.energy > 0.0 {
            let ratio = r.friction_dissipation / r.energy;
            c.min_dissipation_ratio = c.min_dissipation_ratio.min(ratio);
        }
        c.total_dissipation += r.friction_dissipation;
        c.steps_sticking += usize::from(r.stick_nodes > 0);
        c.steps_slipping += usize::from(r.slip_nodes > 0);
        c.max_stick = c.max_stick.max(r.stick_nodes);
        c.max_slip = c.max_slip.max(r.slip_nodes);
        // M (z − w)/Δt², the reactions' Eᵀr, and K (u^{n+1} + u^{n−1})/2 + αK(z + w)/(2Δt).
        let dz: Vec<f64> = z.iter().zip(&w_old).map(|(a, b)| a - b).collect();
        sim.body().mass_mul(&dz, &mut acc);
        acc.iter_mut().for_each(|a| *a /= dt * dt);
        let mut et_r = vec![0.0; n];
        for (k, rk) in sim.reactions().iter().enumerate() {
            et_r[constraints.unknowns[k]] += constraints.directions[k] * rk;
        }
        for (j, rt) in sim.tangential_reactions().iter().enumerate() {
            et_r[friction.tangents[j]] += rt;
        }
        let mean: Vec<f64> = (0..n).map(|i| 0.5 * (u[i] + u_old[i] - w_old[i])).collect();
        let rate: Vec<f64> = (0..n)
            .map(|i| alpha / (2.0 * dt) * (z[i] + w_old[i]))
            .collect();
        let abs_zw: Vec<f64> = z
            .iter()
            .zip(&w_old)
            .map(|(a, b)| a.abs() + b.abs())
            .collect();
        sim.body().mass_mul(&abs_zw, &mut mass_abs);
        let d = sim.discretisation();
        let k_abs: Vec<f64> = (0..n)
            .map(|r| {
                (d.pattern.row_ptr[r]..d.pattern.row_ptr[r + 1])
                    .map(|k| {
                        let c = d.pattern.cols[k];
                        d.stiffness[k].abs() * (mean[c].abs() + rate[c].abs())
                    })
                    .sum()
            })
            .collect();
        let (sa, _) = x_sums(&free, &acc);
        let (sf, mf) = x_sums(&free, &force);
        let (se, me) = x_sums(&free, &et_r);
        let (_, ma) = x_sums(&free, &mass_abs);
        let (_, mk) = x_sums(&free, &k_abs);
        let scale = ma / (dt * dt) + mf + me + mk;
        if scale > 0.0 {
            c.momentum = c.momentum.max((sa - sf - se).abs() / scale);
        }
    }
    c.mean_iterations = iterations as f64 / (scene.steps().max(2) - 1) as f64;
    if let Some(report) = sim.solver_report() {
        let a = report.audit;
        c.cone = a.friction_cone.unwrap_or_default().max_over_tolerance;
        c.slip_law = a.slip_law.unwrap_or_default().max_over_tolerance;
        c.audit_worst_ratio = [
            a.primal_violation.unwrap_or_default().max_over_tolerance,
            a.negative_reaction.max_over_tolerance,
            a.complementarity.unwrap_or_default().max_over_tolerance,
            a.stationarity.max_over_tolerance,
            a.stationarity_displacement.max_over_tolerance,
            c.cone,
            c.slip_law,
        ]
        .into_iter()
        .fold(0.0, f64::max);
    }
    Ok(c)
}

/// [`friction_check`] of every built-in friction scene (exact solver).
pub fn scene_checks() -> Result<Vec<FrictionCheck>, ConvergeError> {
    FRICTION_SCENES
        .iter()
        .map(|name| friction_check(name, &plane_scene(name, &[])?))
        .collect()
}

/// The exact frictional solver against OSQP's Tresca fixed point over a whole run.
#[derive(Clone, Debug, Default)]
pub struct FrictionAgreement {
    pub name: String,
    pub steps: usize,
    /// `max |u − u_exact|` over `max |u_exact|`; the same for the normal and the tangential
    /// reactions (over the largest normal reaction).
    pub displacement: f64,
    pub normal: f64,
    pub tangential: f64,
    /// Tresca problems per step (mean, max) and OSQP's audit, worst ratio to its tolerance.
    pub mean_iterations: f64,
    pub max_iterations: u32,
    pub audit_worst_ratio: f64,
}

/// [`FrictionAgreement`] of `scene`.
pub fn osqp_agreement(name: &str, scene: &PlaneScene) -> Result<FrictionAgreement, ConvergeError> {
    let mut e = Method::Exact.simulation(scene)?;
    let mut o = Method::Osqp.simulation(scene)?;
    let (mut du, mut u_max, mut dn, mut dt, mut r_max) = (0.0f64, 0.0f64, 0.0f64, 0.0f64, 0.0f64);
    let mut a = FrictionAgreement {
        name: name.to_string(),
        steps: scene.steps(),
        ..Default::default()
    };
    let mut iterations = 0u64;
    for n in 0..scene.steps() {
        if n > 0 {
            e.step().map_err(plane_error)?;
            let r = o.step().map_err(plane_error)?;
            iterations += u64::from(r.iterations);
            a.max_iterations = a.max_iterations.max(r.iterations);
        }
        for (x, y) in e.displacement().iter().zip(o.displacement()) {
            du = du.max((x - y).abs());
            u_max = u_max.max(x.abs());
        }
        for (x, y) in e.reactions().iter().zip(o.reactions()) {
            dn = dn.max((x - y).abs());
            r_max = r_max.max(x.abs());
        }
        for (x, y) in (e.tangential_reactions().iter()).zip(o.tangential_reactions()) {
            dt = dt.max((x - y).abs());
        }
    }
    let relative = |d: f64, s: f64| if s > 0.0 { d / s } else { d };
    a.displacement = relative(du, u_max);
    a.normal = relative(dn, r_max);
    a.tangential = relative(dt, r_max);
    a.mean_iterations = iterations as f64 / (scene.steps().max(2) - 1) as f64;
    if let Some(report) = o.solver_report() {
        let r = report.audit;
        a.audit_worst_ratio = [
            r.primal_violation.unwrap_or_default().max_over_tolerance,
            r.negative_reaction.max_over_tolerance,
            r.complementarity.unwrap_or_default().max_over_tolerance,
            r.stationarity.max_over_tolerance,
            r.stationarity_displacement.max_over_tolerance,
            r.friction_cone.unwrap_or_default().max_over_tolerance,
            r.slip_law.unwrap_or_default().max_over_tolerance,
        ]
        .into_iter()
        .fold(0.0, f64::max);
    }
    Ok(a)
}

/// [`osqp_agreement`] on every built-in friction scene.
pub fn osqp_agreements() -> Result<Vec<FrictionAgreement>, ConvergeError> {
    FRICTION_SCENES
        .iter()
        .map(|name| osqp_agreement(name, &plane_scene(name, &[])?))
        .collect()
}

/// The frictional drop's convergence study (as the frictionless drop's,
/// [`crate::plane::contact`]): its end time; the test's levels and reference (within seconds)
/// and the document's (the reference one level finer, about 25 s).
pub const CONVERGENCE_END: f64 = 0.6;
pub const CONVERGENCE_LEVELS: [u32; 2] = [0, 1];
pub const CONVERGENCE_REFERENCE: u32 = 2;
pub const FULL_CONVERGENCE_LEVELS: [u32; 3] = [0, 1, 2];
pub const FULL_CONVERGENCE_REFERENCE: u32 = 3;

/// The frictional tilted drop at `levels` against its exact run at `reference`.
fn drop_convergence(
    levels: &[u32],
    reference: u32,
) -> Result<Vec<crate::plane::contact::ContactLevel>, ConvergeError> {
    let scene = plane_scene(
        "plane-friction-tilted-drop",
        &[format!("time.end={CONVERGENCE_END}")],
    )?;
    crate::plane::contact::convergence(&scene, levels, reference)
}

/// The test's study: [`CONVERGENCE_LEVELS`] against [`CONVERGENCE_REFERENCE`].
pub fn convergence() -> Result<Vec<crate::plane::contact::ContactLevel>, ConvergeError> {
    drop_convergence(&CONVERGENCE_LEVELS, CONVERGENCE_REFERENCE)
}

/// The document's study: [`FULL_CONVERGENCE_LEVELS`] against [`FULL_CONVERGENCE_REFERENCE`].
pub fn full_convergence() -> Result<Vec<crate::plane::contact::ContactLevel>, ConvergeError> {
    drop_convergence(&FULL_CONVERGENCE_LEVELS, FULL_CONVERGENCE_REFERENCE)
}

fn sci(v: f64) -> String {
    format!("{v:.1e}")
}

/// The rigid-limit table's Markdown.
pub fn rigid_markdown(rows: &[RigidRow]) -> String {
    let mut md = String::from(
        "| κ = λ = μ_L | slope: mean acceleration | rel. error vs g(sin θ − μ cos θ) | stick (μ = 1): mean velocity, 2nd half / f_t T | launch: stop time from t = 0 | rel. error vs v0/(μg) | distance from t = 0 | rel. error vs v0²/(2μg) | max identity residual |\n|---|---|---|---|---|---|---|---|---|\n",
    );
    for r in rows {
        let _ = writeln!(
            md,
            "| {:e} | {:.6} | {} | {} | {:.6} | {} | {:.6} | {} | {} |",
            r.stiffness,
            r.slope_acceleration,
            sci(r.slope_error),
            sci(r.stick_velocity),
            r.stop_time,
            sci(r.stop_error),
            r.distance,
            sci(r.distance_error),
            sci(r.identity)
        );
    }
    md
}

/// The generated block of VERIFICATION.md's "Plane friction" section (id `plane-friction`).
pub fn markdown() -> Result<String, ConvergeError> {
    let mut md = String::from(
        "| scene (friction 0 on every Signorini edge) | steps | same bits as without the key |\n|---|---|---|\n",
    );
    for c in mu_zero_cases()? {
        let _ = writeln!(md, "| {} | {} | {} |", c.name, c.steps, c.identical);
    }
    md.push_str(
        "\n| scene | steps | steps with stick / slip | most stick / slip | max identity residual | min D_f / E | Σ D_f | momentum residual | audit: worst / tolerance (cone, slip law) | Lemke bases per step (mean, max) |\n|---|---|---|---|---|---|---|---|---|---|\n",
    );
    for c in scene_checks()? {
        let _ = writeln!(
            md,
            "| {} | {} | {} / {} | {} / {} | {} | {} | {:.4e} | {} | {} ({}, {}) | {:.2}, {} |",
            c.name,
            c.steps,
            c.steps_sticking,
            c.steps_slipping,
            c.max_stick,
            c.max_slip,
            sci(c.max_identity),
            sci(c.min_dissipation_ratio),
            c.total_dissipation,
            sci(c.momentum),
            sci(c.audit_worst_ratio),
            sci(c.cone),
            sci(c.slip_law),
            c.mean_iterations,
            c.max_iterations
        );
    }
    let [a, stick, stop, distance] = closed_form_self_test()?;
    let _ = writeln!(
        md,
        "\nClosed forms against the exact integration of the rigid block (largest relative \
         difference): slope acceleration {}, stick {}, stop time {}, distance {}.\n",
        sci(a),
        sci(stick),
        sci(stop),
        sci(distance)
    );
    md.push_str(&rigid_markdown(&rigid_table()?));
    md.push_str(
        "\n| scene | steps | max abs(u − u_exact) / max abs(u) | max abs(r_N − r_N,exact) / max r_N | max abs(r_T − r_T,exact) / max r_N | Tresca problems per step (mean, max) | OSQP audit: worst / tolerance |\n|---|---|---|---|---|---|---|\n",
    );
    for a in osqp_agreements()? {
        let _ = writeln!(
            md,
            "| {} | {} | {} | {} | {} | {:.2}, {} | {} |",
            a.name,
            a.steps,
            sci(a.displacement),
            sci(a.normal),
            sci(a.tangential),
            a.mean_iterations,
            a.max_iterations,
            sci(a.audit_worst_ratio)
        );
    }
    for (levels, reference) in [
        (convergence()?, CONVERGENCE_REFERENCE),
        (full_convergence()?, FULL_CONVERGENCE_REFERENCE),
    ] {
        md.push_str(&crate::plane::contact::convergence_markdown(
            &levels,
            reference,
            CONVERGENCE_END,
        ));
    }
    Ok(md)
}
