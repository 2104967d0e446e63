//! What a run reports in `summary.json`, for either body: the [`Summary`] accumulated step
//! by step by the [`Tracker`] (energies, identity residual, complementarity, contact episodes
//! per group of constraints, iterations, time shares).

use crate::output::text::output_time;
use crate::scheme::clock::PhaseTimes;
use crate::scheme::{Body, Certificate, CertificateFailure, Scheme, StepRecord};
use serde::Serialize;
use std::collections::BTreeMap;

fn serialize_time<S: serde::Serializer>(t: &f64, s: S) -> Result<S::Ok, S::Error> {
    s.serialize_f64(output_time(*t))
}

fn serialize_intervals<S: serde::Serializer>(
    m: &BTreeMap<String, Vec<[f64; 2]>>,
    s: S,
) -> Result<S::Ok, S::Error> {
    let rounded: BTreeMap<&String, Vec<[f64; 2]>> = m
        .iter()
        .map(|(k, v)| (k, v.iter().map(|i| i.map(output_time)).collect()))
        .collect();
    serde::Serialize::serialize(&rounded, s)
}

/// One contact episode of a group of constraints (an end, an edge, the whole obstacle): the
/// steps from the first with some constraint of the group in contact
/// ([`crate::scheme::in_contact`]) to the last.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct ContactEpisode {
    /// `t` of the first step in contact.
    #[serde(serialize_with = "serialize_time")]
    pub start: f64,
    /// `t` of the last step in contact (the end of the run when `open_at_end`).
    #[serde(serialize_with = "serialize_time")]
    pub end: f64,
    /// Still in contact at the end of the run.
    pub open_at_end: bool,
    /// `max Σ_k r_k^{n+1}` over the episode (force; summed over the group's constraints).
    pub peak_reaction: f64,
    /// `Σ Δt Σ_k r_k^{n+1}` over the episode: the momentum the obstacle gives the body
    /// (exactly, in the scheme, when no end or edge is clamped).
    pub impulse: f64,
    /// The group's share of the identity's contact term `D`, summed over the episode
    /// (energy); `null` when a step of the episode was not measured.
    pub contact_dissipation: Option<f64>,
    /// `E^{n−1/2}` before the first step in contact; `null` when contact starts at the
    /// start-up step or that energy was not measured.
    pub energy_before: Option<f64>,
    /// `E^{n+1/2}` after the last step in contact; `null` when not measured.
    pub energy_after: Option<f64>,
}

/// Summary statistics of a run, as written to `summary.json`.
#[derive(Clone, Debug, Serialize)]
pub struct Summary {
    pub scene: String,
    /// `bar` or `plane`.
    pub body: String,
    /// The step solver: `exact`, `osqp` or `penalty`.
    pub solver: String,
    /// Mesh nodes (clamped ones included), elements (cells), unknowns.
    pub nodes: usize,
    pub elements: usize,
    pub unknowns: usize,
    pub dt: f64,
    pub steps: usize,
    #[serde(serialize_with = "serialize_time")]
    pub final_time: f64,
    pub wall_time_s: f64,
    /// `wall_time_s` / (steps × unknowns), nanoseconds.
    pub ns_per_unknown_step: f64,
    /// Shares of the stepping time per phase, estimated on a sample of the steps.
    pub time_shares: TimeShares,
    /// `E^{1/2}`.
    pub energy_initial: f64,
    /// `E^{N−1/2}` (the last measured one).
    pub energy_final: f64,
    /// Largest one-step increase `E^{n+1/2} − E^{n−1/2}` divided by `E^{1/2}`; only for scenes
    /// without load (where the scheme cannot gain energy), `null` otherwise.
    pub max_energy_rise: Option<f64>,
    pub max_identity_residual: f64,
    /// The largest bound a measured step's `identity_residual` was held to (it follows the
    /// step's conditioning, [`crate::scheme::certify`]).
    pub max_identity_bound: f64,
    /// The run's certificate: `certified` (every measured step's identity residual within its
    /// bound), `measured_steps`, and on failure `first_failure` (step, time, check, value,
    /// bound); [`crate::scheme::certify`].
    #[serde(flatten)]
    pub certificate: Certificate,
    /// Largest `|gap · reaction|` over steps and constraints.
    pub max_complementarity: f64,
    /// Largest penetration `max(0, −gap)`.
    pub max_violation: f64,
    /// Most negative reaction (0 when none is negative).
    pub min_reaction: f64,
    /// `[start, end]` time intervals of contact per group (the episodes' start and end).
    #[serde(serialize_with = "serialize_intervals")]
    pub contact_intervals: BTreeMap<String, Vec<[f64; 2]>>,
    /// The contact episodes per group: each Signorini end or edge, and for the bar's obstacle
    /// one list for the whole contact set (an episode lasts while any node is in contact).
    pub contact_episodes: BTreeMap<String, Vec<ContactEpisode>>,
    /// With friction: the friction dissipation `Σ D_f` over the measured steps (energy).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub friction_dissipation: Option<f64>,
    pub solver_iterations: Iterations,
    /// What the profile file holds (written runs only): its name and format, kept steps, node
    /// stride, rows.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub output: Option<crate::scene::OutputSampling>,
    /// Worst optimality residuals of the solver's answers, for solvers that audit them
    /// (`osqp`, the bar's `penalty`; see `viscobar::step::audit`).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub audit: Option<crate::step::AuditReport>,
    /// Steps where OSQP's "solved inaccurate" was accepted (`accept_inaccurate`; osqp only).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub inaccurate_steps: Option<u64>,
}

/// Where the time of the steps goes, as fractions of the timed phases of the sampled steps
/// (one in `crate::scheme::clock::TIMING_SAMPLE_EVERY`): `rhs` (load and right-hand side),
/// `solver` (the step solver and `u += z`), `diagnostics` (energy identity and contact state);
/// the three add up to 1. `stepping` is the step loop's share of the wall time, measured from
/// the first step after the start-up to the last (with the rows it writes); the rest is set-up,
/// start-up and closing the outputs. It is at most 1.
#[derive(Clone, Copy, Debug, Default, Serialize)]
pub struct TimeShares {
    pub solver: f64,
    pub rhs: f64,
    pub diagnostics: f64,
    pub stepping: f64,
    pub sampled_steps: u64,
}

impl TimeShares {
    /// The shares of `p`, sampled on the steps `1 → 2 … n − 1 → n` of a run, whose step loop
    /// took `stepping_s` of its `wall_time_s` (0 when the run's wall time is not known).
    pub fn from_phases(p: PhaseTimes, stepping_s: f64, wall_time_s: f64) -> Self {
        let total = p.total_ns() as f64;
        let share = |x: u64| if total > 0.0 { x as f64 / total } else { 0.0 };
        Self {
            solver: share(p.solve_ns),
            rhs: share(p.rhs_ns),
            diagnostics: share(p.diagnostics_ns),
            // Both intervals measured, the loop's inside the run's: the `min` only absorbs the
            // nanoseconds between the two clock reads.
            stepping: if wall_time_s > 0.0 {
                (stepping_s / wall_time_s).min(1.0)
            } else {
                0.0
            },
            sampled_steps: p.sampled_steps,
        }
    }
}

#[derive(Clone, Copy, Debug, Default, Serialize)]
pub struct Iterations {
    pub mean: f64,
    pub max: u32,
}

/// Accumulates the summary from the step records, in step order.
#[derive(Clone, Debug)]
pub struct Tracker {
    /// The groups' names, in the order of the records' group states.
    groups: Vec<&'static str>,
    unforced: bool,
    energy_initial: f64,
    energy_prev: f64,
    energy_final: f64,
    max_rise: f64,
    max_residual: f64,
    max_bound: f64,
    max_comp: f64,
    max_violation: f64,
    min_reaction: f64,
    episodes: Vec<Vec<ContactEpisode>>,
    in_contact: Vec<bool>,
    dt: f64,
    /// `E` of the last record, when it was measured.
    last_energy: Option<f64>,
    iterations_sum: u64,
    iterations_max: u32,
    records: usize,
    /// `Σ D_f` so far, with friction.
    friction: Option<f64>,
    certificate: Certificate,
    /// When the step loop began (the tracker is made after the start-up step).
    started: std::time::Instant,
}

impl Tracker {
    /// A tracker of `sim` from its start-up record; `unforced` for a scene without load.
    pub fn new<B: Body>(sim: &Scheme<B>, unforced: bool) -> Self {
        let groups: Vec<&'static str> = sim.contact().groups().iter().map(|g| g.name).collect();
        let k = groups.len();
        let first = sim.first_record();
        let mut t = Self {
            groups,
            unforced,
            energy_initial: first.energy,
            energy_prev: first.energy,
            energy_final: first.energy,
            max_rise: f64::NEG_INFINITY,
            max_residual: 0.0,
            max_bound: 0.0,
            max_comp: 0.0,
            max_violation: 0.0,
            min_reaction: 0.0,
            episodes: vec![Vec::new(); k],
            in_contact: vec![false; k],
            dt: sim.body().dt(),
            last_energy: None,
            iterations_sum: 0,
            iterations_max: 0,
            records: 0,
            // The start-up's D_f (friction acts from the first step) opens the sum.
            friction: (!sim.contact().friction().is_empty()).then_some(first.friction_dissipation),
            certificate: Certificate::new(),
            started: std::time::Instant::now(),
        };
        t.certify(&first);
        t.observe_contact(&first);
        t.last_energy = Some(first.energy);
        t
    }

    /// Takes the record of the next step; returns the run's first certificate failure when
    /// this step is it. With thinned diagnostics, the energy statistics cover the measured
    /// steps: a rise is then over the steps since the last measured one (the identity
    /// telescopes, so without load that rise is still ≤ 0 up to round-off).
    pub fn observe(&mut self, r: &StepRecord) -> Option<CertificateFailure> {
        let failure = self.certify(r);
        if r.measured {
            self.max_rise = self.max_rise.max(r.energy - self.energy_prev);
            self.energy_prev = r.energy;
            self.energy_final = r.energy;
            self.max_residual = self.max_residual.max(r.identity_residual);
            if let Some(total) = self.friction.as_mut() {
                *total += r.friction_dissipation;
            }
        }
        self.iterations_sum += u64::from(r.iterations);
        self.iterations_max = self.iterations_max.max(r.iterations);
        self.records += 1;
        self.observe_contact(r);
        self.last_energy = r.measured.then_some(r.energy);
        failure
    }

    /// The certificate's check of a measured record.
    fn certify(&mut self, r: &StepRecord) -> Option<CertificateFailure> {
        if !r.measured {
            return None;
        }
        self.max_bound = self.max_bound.max(r.identity_bound);
        (self.certificate)
            .observe(r.step, r.time, r.identity_residual, r.identity_bound)
            .cloned()
    }

    /// The run's certificate so far.
    pub fn certificate(&self) -> &Certificate {
        &self.certificate
    }

    fn observe_contact(&mut self, r: &StepRecord) {
        self.max_comp = self.max_comp.max(r.contact.max_complementarity);
        self.max_violation = self.max_violation.max(-r.contact.min_gap);
        self.min_reaction = self.min_reaction.min(r.contact.min_reaction);
        for (j, g) in r.contact.groups[..self.groups.len()].iter().enumerate() {
            let contact = g.contact_nodes > 0;
            let measured = r.measured.then_some(g.dissipation);
            let energy = r.measured.then_some(r.energy);
            if contact && !self.in_contact[j] {
                self.episodes[j].push(ContactEpisode {
                    start: r.time,
                    end: r.time,
                    open_at_end: false,
                    peak_reaction: g.reaction,
                    impulse: self.dt * g.reaction,
                    contact_dissipation: measured,
                    energy_before: if r.step > 1 { self.last_energy } else { None },
                    energy_after: energy,
                });
            } else if contact {
                let e = self.episodes[j].last_mut().expect("an open episode");
                e.end = r.time;
                e.peak_reaction = e.peak_reaction.max(g.reaction);
                e.impulse += self.dt * g.reaction;
                e.contact_dissipation = e.contact_dissipation.zip(measured).map(|(a, b)| a + b);
                e.energy_after = energy;
            }
            self.in_contact[j] = contact;
        }
    }

    /// The summary of `sim` after its last step; `wall_time_s` the run's wall time.
    pub fn finish<B: Body>(&self, scene_name: &str, sim: &Scheme<B>, wall_time_s: f64) -> Summary {
        let body = sim.body();
        let steps = sim.step_index();
        let report = sim.solver_report();
        let unknowns = body.unknowns();
        let names = || self.groups.iter().map(|g| g.to_string());
        Summary {
            scene: scene_name.to_string(),
            body: B::NAME.to_string(),
            solver: sim.solver_name().to_string(),
            nodes: body.nodes(),
            elements: body.elements(),
            unknowns,
            dt: body.dt(),
            steps,
            final_time: sim.time(),
            wall_time_s,
            ns_per_unknown_step: wall_time_s * 1e9 / (steps as f64 * unknowns.max(1) as f64),
            time_shares: TimeShares::from_phases(
                sim.phase_times(),
                self.started.elapsed().as_secs_f64(),
                wall_time_s,
            ),
            energy_initial: self.energy_initial,
            energy_final: self.energy_final,
            max_energy_rise: (self.unforced && self.records > 0)
                .then(|| self.max_rise / self.energy_initial.max(f64::MIN_POSITIVE)),
            max_identity_residual: self.max_residual,
            max_identity_bound: self.max_bound,
            certificate: self.certificate.clone(),
            max_complementarity: self.max_comp,
            max_violation: self.max_violation,
            min_reaction: self.min_reaction,
            contact_intervals: names()
                .zip(
                    self.episodes
                        .iter()
                        .map(|e| e.iter().map(|e| [e.start, e.end]).collect()),
                )
                .collect(),
            contact_episodes: names()
                .zip(
                    self.episodes
                        .iter()
                        .zip(&self.in_contact)
                        .map(|(e, &open)| {
                            let mut e = e.clone();
                            if let Some(last) = e.last_mut().filter(|_| open) {
                                last.open_at_end = true;
                            }
                            e
                        }),
                )
                .collect(),
            friction_dissipation: self.friction,
            solver_iterations: Iterations {
                mean: self.iterations_sum as f64 / self.records.max(1) as f64,
                max: self.iterations_max,
            },
            output: None,
            inaccurate_steps: report.as_ref().and_then(|r| r.inaccurate_steps),
            audit: report.map(|r| r.audit),
        }
    }
}
