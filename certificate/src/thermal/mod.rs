//! The thermal bar's certificate: the heat equation's Fourier mode (`γ = 0`) under refinement,
//! the exact total-energy identity on every thermal scene, the steady state with contact, the
//! coupled thermoelastic modes (the cubic's roots against the run's, extracted by Prony's
//! method) and a manufactured solution with contact; Rannacher's start (`smoothing`). Closed
//! forms and derivations: `docs/thermal.md`. Fast enough for `cargo test`.

pub mod boundary;
pub mod smoothing;

use nalgebra::{Complex, Matrix3, Vector3};
use std::fmt::Write;
use viscobar::output::run_thermal_in_memory;
use viscobar::scene::{self, Scene};
use viscobar::scheme::{Body, RunError};
use viscobar::study::accuracy::observed_order;
use viscobar::thermal::ThermalSimulation;

/// A thermal bar scene from its parts (TOML text; `heat` the `[heat]` table's body).
pub fn scene_text(bar: &str, ends: (&str, &str), initial: (&str, &str), heat: &str) -> String {
    format!(
        "[bar]\n{bar}\n[left]\n{}\n[right]\n{}\n[initial]\ndisplacement = \"{}\"\nvelocity = \"{}\"\n\
         [heat]\n{heat}\n[mesh]\nelements = 8\n[time]\nstep = 0.1\nend = 1.0\n",
        ends.0, ends.1, initial.0, initial.1
    )
}

/// `text` with `mesh.elements`, `time.step`, `time.end` set.
pub fn sized(text: &str, elements: u64, step: f64, end: f64) -> Result<Scene, RunError> {
    let sets = [
        format!("mesh.elements={elements}"),
        format!("time.step={step}"),
        format!("time.end={end}"),
    ];
    Ok(Scene::from_toml(text, &sets)?)
}

/// `θ` at every node of a thermal run's state (`θ^{n−1/2}`).
pub fn temperatures(sim: &ThermalSimulation) -> Vec<f64> {
    let body = sim.body();
    (0..body.nodes())
        .map(|i| body.temperature(sim.displacement(), i).unwrap_or(0.0))
        .collect()
}

/// Rows of a refinement study and its observed order.
pub type Study<R> = (Vec<R>, f64);
/// Rows of a refinement study and the observed orders of its two fields.
pub type Study2<R> = (Vec<R>, f64, f64);

/// The Fourier mode's data: `κ`, wave number `k = 2π` (L = 1), end time.
pub const FOURIER: (f64, f64, f64) = (0.1, 2.0 * std::f64::consts::PI, 0.25);
/// The refinement levels of the Fourier study (`J`, `Δt = 0.4/J`).
pub const FOURIER_ELEMENTS: [u64; 4] = [16, 32, 64, 128];

/// The heat equation's Fourier mode `θ = exp(−κk²t) cos(kx)` on a free bar with insulated ends
/// and `γ = 0`: the max nodal error of `θ^{N−1/2}` at `t_N − Δt/2` per level, and the observed
/// order (least squares over the levels).
pub fn fourier_study() -> Result<Study<(u64, f64, f64)>, RunError> {
    let (kappa, k, end) = FOURIER;
    let text = scene_text(
        "length = 1.0\nviscosity = 0.0",
        ("condition = \"free\"", "condition = \"free\""),
        ("0", "0"),
        &format!(
            "coupling = 0.0\ndiffusivity = {kappa}\ntemperature = \"cos(2*pi*x)\"\n\
             left = {{ condition = \"insulated\" }}\nright = {{ condition = \"insulated\" }}"
        ),
    );
    let mut rows = Vec::new();
    for elements in FOURIER_ELEMENTS {
        let dt = 0.4 / elements as f64;
        let scene = sized(&text, elements, dt, end)?;
        let (_, _, sim) = run_thermal_in_memory("fourier", &scene)?;
        let t = sim.time() - 0.5 * dt;
        let decay = (-kappa * k * k * t).exp();
        let dx = 1.0 / elements as f64;
        let err = (temperatures(&sim).iter().enumerate())
            .map(|(i, th)| (th - decay * (k * i as f64 * dx).cos()).abs())
            .fold(0.0, f64::max);
        rows.push((elements, dt, err));
    }
    let h: Vec<f64> = rows.iter().map(|r| r.1).collect();
    let e: Vec<f64> = rows.iter().map(|r| r.2).collect();
    Ok((rows.clone(), observed_order(&h, &e)))
}

/// The thermal scenes of the identity check: the built-ins and variants that exercise every
/// term (source, fixed temperatures varying in time, exchange at both ends, a load, `γ = 0`).
pub fn identity_scenes() -> Result<Vec<(String, Scene)>, RunError> {
    let mut v = Vec::new();
    for name in scene::thermal_builtin_names() {
        let (_, s) = scene::load(name, &[])?;
        v.push((name.to_string(), s));
    }
    let both = scene_text(
        "length = 1.0\nviscosity = 0.0",
        (
            "condition = \"signorini\"\ngap = 0.02",
            "condition = \"signorini\"\ngap = 0.03",
        ),
        ("0", "sin(pi*x) - 0.3"),
        "coupling = 0.3\ndiffusivity = 0.02\ntemperature = \"x*(1 - x)\"\n\
         source = \"sin(3*x)*cos(t)\"\n\
         left = { condition = \"exchange\", coefficient = 3.0, obstacle = \"1\" }\n\
         right = { condition = \"exchange\", coefficient = 0.5, obstacle = \"t - 1\" }",
    );
    v.push(("both-exchange".into(), sized(&both, 64, 0.01, 3.0)?));
    let fixed = scene_text(
        "length = 2.0\nviscosity = 0.1",
        (
            "condition = \"clamped\"",
            "condition = \"signorini\"\ngap = 0.01",
        ),
        ("0", "0"),
        "coupling = 0.5\ndiffusivity = 0.3\ntemperature = \"0\"\nsource = \"x*t\"\n\
         left = { condition = \"temperature\", value = \"sin(5*t)\" }\n\
         right = { condition = \"exchange\", coefficient = 2.0, obstacle = \"-1\" }",
    );
    let mut fixed = sized(&fixed, 50, 0.02, 4.0)?;
    fixed.load.density = Some("cos(t)*(x - 1)".into());
    v.push(("fixed-temperature-load".into(), fixed));
    let (_, mut uncoupled) = scene::load("thermal-impact", &[])?;
    uncoupled.heat.as_mut().expect("a thermal scene").coupling = 0.0;
    v.push(("thermal-impact-uncoupled".into(), uncoupled));
    Ok(v)
}

/// The worst relative residual of the total-energy identity over every step of every scene of
/// [`identity_scenes`], and the number of steps in contact (the check covers contact).
pub fn identity_worst() -> Result<(f64, usize), RunError> {
    let (mut worst, mut contact) = (0.0f64, 0);
    for (name, scene) in identity_scenes()? {
        let (records, _, _) = run_thermal_in_memory(&name, &scene)?;
        for r in &records {
            worst = worst.max(r.identity_residual);
            contact += usize::from(r.contact.contact_nodes > 0);
        }
    }
    Ok((worst, contact))
}

/// The steady state's data: gap `a0`, coupling `γ`, L = 1; heated at the clamped end x = L.
pub const STEADY: (f64, f64) = (0.05, 0.1);

/// The closing temperature `a0/(γL)`: a uniform temperature above it closes the gap.
pub fn closing_temperature() -> f64 {
    STEADY.0 / STEADY.1
}

/// The closed-form steady state at end temperature `theta`: `(u(0), reaction)`, free
/// `u = γθ(x − L)` below the closing temperature, `u = a0 (x − L)/L` and the reaction
/// `γθ − a0/L` above.
pub fn steady_closed_form(theta: f64) -> (f64, f64) {
    let (a0, gamma) = STEADY;
    if gamma * theta <= a0 {
        (-gamma * theta, 0.0)
    } else {
        (-a0, gamma * theta - a0)
    }
}

/// Runs the steady-state scene to `t = 40` at end temperature `theta`: the largest deviation
/// from the closed form (of `θ`, `u` at every node and the reaction) at the end.
pub fn steady_deviation(theta: f64) -> Result<f64, RunError> {
    let (a0, gamma) = STEADY;
    let text = scene_text(
        "length = 1.0\nviscosity = 0.5",
        (
            &format!("condition = \"signorini\"\ngap = {a0}"),
            "condition = \"clamped\"",
        ),
        ("0", "0"),
        &format!(
            "coupling = {gamma}\ndiffusivity = 1.0\ntemperature = \"0\"\n\
             left = {{ condition = \"insulated\" }}\n\
             right = {{ condition = \"temperature\", value = \"{theta}\" }}"
        ),
    );
    let scene = sized(&text, 40, 0.025, 40.0)?;
    let (records, _, sim) = run_thermal_in_memory("steady", &scene)?;
    let (u0, reaction) = steady_closed_form(theta);
    let last = records.last().expect("steps");
    let mut dev = (last.contact.groups[0].reaction - reaction).abs();
    let dofs = sim.displacement_dofs();
    for (i, (u, th)) in dofs.iter().zip(temperatures(&sim)).enumerate() {
        let x = i as f64 / 40.0;
        dev = dev.max((u - u0 * (1.0 - x)).abs()).max((th - theta).abs());
    }
    Ok(dev)
}

/// The modes' data: `α`, `κ`, `γ`, `k = π` (L = 1, clamped ends, insulated).
pub const MODES: (f64, f64, f64, f64) = (0.05, 0.1, 0.5, std::f64::consts::PI);
/// The refinement levels of the mode study (`J`, `Δt = 0.5/J`).
pub const MODE_ELEMENTS: [u64; 4] = [8, 16, 32, 64];

/// The roots of `(s² + αk²s + k²)(s + κk²) + γ²k²s = 0`: the real one, then the one with
/// positive imaginary part.
pub fn cubic_roots() -> (f64, Complex<f64>) {
    let (a, kappa, g, k) = MODES;
    let k2 = k * k;
    let c2 = a * k2 + kappa * k2;
    let c1 = k2 + a * kappa * k2 * k2 + g * g * k2;
    let c0 = kappa * k2 * k2;
    let roots = polish(companion_roots([c0, c1, c2]), [c0, c1, c2]);
    let real = roots
        .iter()
        .min_by(|p, q| p.im.abs().total_cmp(&q.im.abs()))
        .unwrap();
    let complex = roots.iter().max_by(|p, q| p.im.total_cmp(&q.im)).unwrap();
    (real.re, *complex)
}

/// The roots of the monic `λ³ + c2 λ² + c1 λ + c0`.
fn companion_roots([c0, c1, c2]: [f64; 3]) -> Vec<Complex<f64>> {
    let m = Matrix3::new(0.0, 0.0, -c0, 1.0, 0.0, -c1, 0.0, 1.0, -c2);
    m.complex_eigenvalues().iter().copied().collect()
}

/// Two Newton steps on each root (the companion matrix's eigenvalues to full precision).
fn polish(roots: Vec<Complex<f64>>, [c0, c1, c2]: [f64; 3]) -> Vec<Complex<f64>> {
    roots
        .into_iter()
        .map(|mut z| {
            for _ in 0..3 {
                let p = ((z + c2) * z + c1) * z + c0;
                let dp = (z * 3.0 + c2 * 2.0) * z + c1;
                z -= p / dp;
            }
            z
        })
        .collect()
}

/// The run started on the real part of the mode of root `s`, its displacement at `x = L/2`
/// sampled every `stride` steps from step `start`: six samples.
fn mode_samples(
    s: Complex<f64>,
    elements: u64,
    stride: usize,
) -> Result<(f64, Vec<f64>), RunError> {
    let (alpha, kappa, gamma, k) = MODES;
    let b = -(s * gamma * k) / (s + kappa * k * k);
    let text = scene_text(
        &format!("length = 1.0\nviscosity = {alpha}"),
        ("condition = \"clamped\"", "condition = \"clamped\""),
        ("sin(pi*x)", &format!("{}*sin(pi*x)", s.re)),
        &format!(
            "coupling = {gamma}\ndiffusivity = {kappa}\ntemperature = \"{}*cos(pi*x)\"\n\
             left = {{ condition = \"insulated\" }}\nright = {{ condition = \"insulated\" }}",
            b.re
        ),
    );
    let dt = 0.5 / elements as f64;
    let steps = 6 * stride + 2;
    let scene = sized(&text, elements, dt, steps as f64 * dt)?;
    let mut sim = ThermalSimulation::new(&scene)?;
    let mid = elements as usize / 2 - 1; // unknown of node J/2 (node 0 clamped)
    let mut samples = Vec::new();
    while samples.len() < 6 {
        let n = sim.step_index();
        if n >= 2 && (n - 2).is_multiple_of(stride) {
            samples.push(sim.displacement()[mid]);
        }
        sim.step()?;
    }
    Ok((dt, samples))
}

/// Prony: the roots `λ` of the recurrence `a_{i+3} = c2 a_{i+2} + c1 a_{i+1} + c0 a_i` that six
/// samples satisfy, as rates `ln(λ)/(stride Δt)`.
fn prony(samples: &[f64], step: f64) -> Vec<Complex<f64>> {
    let a = samples;
    let m = Matrix3::new(a[2], a[1], a[0], a[3], a[2], a[1], a[4], a[3], a[2]);
    let rhs = Vector3::new(a[3], a[4], a[5]);
    let c = m.lu().solve(&rhs).expect("three independent modes");
    companion_roots([-c[2], -c[1], -c[0]])
        .into_iter()
        .map(|l| l.ln() / step)
        .collect()
}

/// One level of the mode study: `J`, the run's complex and real rates' errors against the
/// cubic's roots.
#[derive(Clone, Copy, Debug)]
pub struct ModeRow {
    pub elements: u64,
    pub complex_error: f64,
    pub real_error: f64,
}

/// The mode study over [`MODE_ELEMENTS`] and the observed orders (complex root, real root).
pub fn mode_study() -> Result<Study2<ModeRow>, RunError> {
    let (real, complex) = cubic_roots();
    let mut rows = Vec::new();
    for elements in MODE_ELEMENTS {
        let stride = elements as usize / 2; // stride Δt = 1/4
        let (dt, a) = mode_samples(complex, elements, stride)?;
        let rates = prony(&a, stride as f64 * dt);
        let c = rates
            .iter()
            .min_by(|p, q| (*p - complex).norm().total_cmp(&(*q - complex).norm()));
        let (dt, a) = mode_samples(Complex::new(real, 0.0), elements, stride)?;
        let rates = prony(&a, stride as f64 * dt);
        let r = rates
            .iter()
            .min_by(|p, q| (p.re - real).abs().total_cmp(&(q.re - real).abs()));
        rows.push(ModeRow {
            elements,
            complex_error: (c.expect("three rates") - complex).norm(),
            real_error: (r.expect("three rates") - real).norm(),
        });
    }
    let h: Vec<f64> = rows.iter().map(|r| 1.0 / r.elements as f64).collect();
    let ec: Vec<f64> = rows.iter().map(|r| r.complex_error).collect();
    let er: Vec<f64> = rows.iter().map(|r| r.real_error).collect();
    Ok((rows, observed_order(&h, &ec), observed_order(&h, &er)))
}

/// VERIFICATION.md's thermal section.
pub fn markdown() -> Result<String, RunError> {
    let mut md = String::new();
    let (rows, order) = fourier_study()?;
    md.push_str("Fourier mode of the heat equation (γ = 0, κ = 0.1, k = 2π, t = 0.25):\n\n");
    md.push_str("| J | Δt | max nodal error |\n|---|---|---|\n");
    for (j, dt, e) in &rows {
        let _ = writeln!(md, "| {j} | {dt:.6} | {e:.3e} |");
    }
    let _ = writeln!(md, "\nobserved order {order:.3}\n");
    let (worst, contact) = identity_worst()?;
    let _ = writeln!(
        md,
        "Total-energy identity over every step of {} thermal scenes ({contact} steps in \
         contact): worst relative residual {worst:.2e}\n",
        identity_scenes()?.len()
    );
    let tc = closing_temperature();
    md.push_str("Steady state with contact (a0 = 0.05, γ = 0.1, L = 1, t = 40):\n\n");
    md.push_str("| end temperature | closed-form u(0) | closed-form reaction | max deviation |\n|---|---|---|---|\n");
    for theta in [0.9 * tc, 2.0 * tc] {
        let (u0, r) = steady_closed_form(theta);
        let _ = writeln!(
            md,
            "| {theta} | {u0:.4} | {r:.4} | {:.2e} |",
            steady_deviation(theta)?
        );
    }
    let (real, complex) = cubic_roots();
    let (rows, pc, pr) = mode_study()?;
    let _ = writeln!(
        md,
        "\nThermoelastic modes (α = 0.05, κ = 0.1, γ = 0.5, k = π): the cubic's roots \
         {real:.6} and {:.6} ± {:.6}i\n",
        complex.re, complex.im
    );
    md.push_str("| J | complex root error | real root error |\n|---|---|---|\n");
    for r in &rows {
        let _ = writeln!(
            md,
            "| {} | {:.3e} | {:.3e} |",
            r.elements, r.complex_error, r.real_error
        );
    }
    let _ = writeln!(md, "\nobserved orders {pc:.3} (complex), {pr:.3} (real)\n");
    let (rows, pu, pt) = manufactured_study()?;
    md.push_str("Manufactured solution with contact (Δt = 1/J, t = 2.5):\n\n");
    md.push_str("| J | steps in contact | max error of u | max error of θ |\n|---|---|---|---|\n");
    for (j, eu, et, contact) in &rows {
        let _ = writeln!(md, "| {j} | {contact} | {eu:.3e} | {et:.3e} |");
    }
    let _ = writeln!(md, "\nobserved orders {pu:.3} (u), {pt:.3} (θ)");
    Ok(md)
}

/// The manufactured solution with contact (`docs/thermal.md`): `u = g(t) + h(t) sin(kx)/k`,
/// `θ = φ(t) cos(kx)`, `k = π/2`, L = 1, Signorini at x = 0 (gap 1/4, on the obstacle exactly
/// on `[1/2, 3/2]`, reaction `sin⁴(π(t − 1/2))`), free and at temperature 0 at x = 1,
/// insulated at x = 0; `α = 0.1`, `γ = 0.5`, `κ = 0.2`.
pub const MANUFACTURED: &str = r#"
[bar]
length = 1.0
viscosity = 0.1
[left]
condition = "signorini"
gap = 0.25
[right]
condition = "free"
[initial]
displacement = "-0.4/pi*sin(pi*x/2)"
velocity = "-2"
[load]
density = "48*(max(0, 0.5 - t)^2 + max(0, t - 1.5)^2) + (0.2*cos(t) - pi^2/4*if(t < 0.5, 0, if(t <= 1.5, sin(pi*(t - 0.5))^4, 0)))*2/pi*sin(pi*x/2)"
[heat]
coupling = 0.5
diffusivity = 0.2
temperature = "-0.4*cos(pi*x/2)"
source = "(2*(0.2*sin(t) + 0.02*cos(t) + if(t < 0.5, 0, if(t <= 1.5, 4*pi*sin(pi*(t - 0.5))^3*cos(pi*(t - 0.5)), 0))) + 0.05*pi^2*2*(-0.2*cos(t) + 0.02*sin(t) + if(t < 0.5, 0, if(t <= 1.5, sin(pi*(t - 0.5))^4, 0))) + 0.1*sin(t))*cos(pi*x/2)"
left = { condition = "insulated" }
right = { condition = "temperature", value = "0" }
[mesh]
elements = 8
[time]
step = 0.1
end = 2.5
"#;

/// The manufactured solution's `(u, θ)` at `(x, t)`.
pub fn manufactured_exact(x: f64, t: f64) -> (f64, f64) {
    let pi = std::f64::consts::PI;
    let s = if (0.5..=1.5).contains(&t) {
        (pi * (t - 0.5)).sin().powi(4)
    } else {
        0.0
    };
    let g = -0.25 + 4.0 * ((0.5 - t).max(0.0).powi(4) + (t - 1.5).max(0.0).powi(4));
    let h = -0.2 * t.cos();
    let phi = 2.0 * (-0.2 * t.cos() + 0.02 * t.sin() + s);
    let k = pi / 2.0;
    (g + h * (k * x).sin() / k, phi * (k * x).cos())
}

/// The manufactured study's levels (`J`, `Δt = 1/J`) to `t = 2.5`.
pub const MANUFACTURED_ELEMENTS: [u64; 4] = [16, 32, 64, 128];

/// Per level: `J`, the max nodal errors of `u^N` and of `θ^{N−1/2}`, the steps in contact; and
/// the observed orders of both.
pub fn manufactured_study() -> Result<Study2<(u64, f64, f64, usize)>, RunError> {
    manufactured_study_to(2.5)
}

/// [`manufactured_study`] to `t = end`.
pub fn manufactured_study_to(end: f64) -> Result<Study2<(u64, f64, f64, usize)>, RunError> {
    let mut rows = Vec::new();
    for elements in MANUFACTURED_ELEMENTS {
        let dt = 1.0 / elements as f64;
        let scene = sized(MANUFACTURED, elements, dt, end)?;
        let (records, _, sim) = run_thermal_in_memory("manufactured", &scene)?;
        let contact = records
            .iter()
            .filter(|r| r.contact.contact_nodes > 0)
            .count();
        let (t, dx) = (sim.time(), 1.0 / elements as f64);
        let (mut eu, mut et) = (0.0f64, 0.0f64);
        for (i, (u, th)) in sim
            .displacement_dofs()
            .iter()
            .zip(temperatures(&sim))
            .enumerate()
        {
            let x = i as f64 * dx;
            eu = eu.max((u - manufactured_exact(x, t).0).abs());
            et = et.max((th - manufactured_exact(x, t - 0.5 * dt).1).abs());
        }
        rows.push((elements, eu, et, contact));
    }
    let h: Vec<f64> = rows.iter().map(|r| 1.0 / r.0 as f64).collect();
    let eu: Vec<f64> = rows.iter().map(|r| r.1).collect();
    let et: Vec<f64> = rows.iter().map(|r| r.2).collect();
    Ok((rows, observed_order(&h, &eu), observed_order(&h, &et)))
}
