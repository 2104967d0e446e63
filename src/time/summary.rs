//! What a run reports: the [`Summary`] of `summary.json` accumulated step by step by the
//! [`Tracker`] (energies, identity residual, complementarity, contact episodes, iterations,
//! time shares), and the rounding of times in every output file.

use crate::time::clock::PhaseTimes;
use crate::time::simulation::{CONTACT_GAP_TOL, Simulation, StepRecord};
use serde::Serialize;

/// Times in the outputs: `t = n·Δt` rounded to [`TIME_DIGITS`] significant digits, so that
/// `3.0300000000000002` reads `3.03`; the exact value stays `step · dt`.
pub const TIME_DIGITS: usize = 12;

/// `t` rounded to [`TIME_DIGITS`] significant digits (see there): the double nearest to the
/// decimal `t` rounds to, as parsing its 12-digit text would give.
pub fn output_time(t: f64) -> f64 {
    if let Some((digits, k)) = rounded_digits(t) {
        return digits as f64 / POWERS_OF_TEN[k as usize];
    }
    if t == 0.0 || !t.is_finite() {
        return t;
    }
    format!("{:.*e}", TIME_DIGITS - 1, t)
        .parse()
        .expect("a formatted float parses")
}

/// `10^k` for `k = 0..=22`, each exact (the values `10f64.powi(k)` gives).
const POWERS_OF_TEN: [f64; 23] = [
    1e0, 1e1, 1e2, 1e3, 1e4, 1e5, 1e6, 1e7, 1e8, 1e9, 1e10, 1e11, 1e12, 1e13, 1e14, 1e15, 1e16,
    1e17, 1e18, 1e19, 1e20, 1e21, 1e22,
];

/// The fast path of [`output_time`]: `t ≈ digits / 10^k` with `digits = round(t·10^k)` and
/// `k` such that `digits` has [`TIME_DIGITS`] digits, when `10^k` is exact (`0 <= k <= 22`)
/// and `|digits| < 10^15`. Then `digits / 10^k` is one correctly rounded division, the parse
/// of the 12-digit text. `None` for 0, non-finite `t` and outside that range.
fn rounded_digits(t: f64) -> Option<(i64, u32)> {
    if t == 0.0 || !t.is_finite() {
        return None;
    }
    let k = TIME_DIGITS as i32 - 1 - floor_log10(t.abs());
    if !(0..=22).contains(&k) {
        return None;
    }
    let digits = round_half_away(t * POWERS_OF_TEN[k as usize]);
    (digits.abs() < 1e15).then_some((digits as i64, k as u32))
}

/// `y.round()` (half away from zero) for finite `y`, inline rather than a libm call: `y` minus
/// its truncation is exact, and `|y| >= 2^52` is a whole number (up to `2^63`, where the
/// truncation saturates; callers refuse such `y` anyway). A `y` in `(−0.5, 0)` gives `+0`
/// where `round` gives `−0`; the caller converts to an integer, which drops that sign.
fn round_half_away(y: f64) -> f64 {
    let whole = y as i64 as f64;
    let frac = y - whole;
    if frac >= 0.5 {
        whole + 1.0
    } else if frac <= -0.5 {
        whole - 1.0
    } else {
        whole
    }
}

/// Relative distance from a power of ten beyond which `floor(log10 a)` is found by comparisons:
/// `log10` (glibc: within a few ulps, ~1e-15 here) is then at least 4e-10 from an integer, so
/// its floor is the same.
const POWER_OF_TEN_MARGIN: f64 = 1e-9;

/// `a.log10().floor()` for `a > 0`, the same value, found by comparing `a` with the powers of ten
/// in `[1e-11, 1e12)` (the range of `rounded_digits`' fast path; ~10x cheaper than `log10`);
/// `log10` itself near a power of ten and outside that range.
fn floor_log10(a: f64) -> i32 {
    if (1e-11..1e12).contains(&a) {
        // With `a` in `[2^b, 2^(b+1))` the answer is `floor(b·log10 2)` or one more
        // (`1233 / 4096` is `log10 2` closely enough for these `b`); one comparison decides.
        // The powers below 1 are not exact, but within an ulp: far inside the margin.
        let b = ((a.to_bits() >> 52) as i32) - 1023;
        let mut e = (b * 1233) >> 12;
        let power = |e: i32| NEAR_POWERS_OF_TEN[(e - NEAR_POWERS_FROM) as usize];
        if a >= power(e + 1) {
            e += 1;
        }
        let lo = power(e);
        if lo * (1.0 + POWER_OF_TEN_MARGIN) <= a && a <= lo * 10.0 * (1.0 - POWER_OF_TEN_MARGIN) {
            return e;
        }
    }
    a.log10().floor() as i32
}

/// The exponent of [`NEAR_POWERS_OF_TEN`]' first entry.
const NEAR_POWERS_FROM: i32 = -12;

/// The doubles nearest `10^e` for `e = -12..=12` (those from 1 up exact).
const NEAR_POWERS_OF_TEN: [f64; 25] = [
    1e-12, 1e-11, 1e-10, 1e-9, 1e-8, 1e-7, 1e-6, 1e-5, 1e-4, 1e-3, 1e-2, 1e-1, 1e0, 1e1, 1e2, 1e3,
    1e4, 1e5, 1e6, 1e7, 1e8, 1e9, 1e10, 1e11, 1e12,
];

/// Appends the text of `output_time(t)` as `Display` writes it (`output_time(t).to_string()`,
/// the same bytes), through Żmij rather than `core::fmt`. Both give the shortest digits that
/// read back to the value (here unique: a rounded time is the double nearest a decimal of at
/// most 15 digits, and any other such decimal on its grid is far beyond an ulp away); they
/// differ only in layout. In Żmij's fixed-point range (`1e-5 <= |t| < 1e16`) the layouts agree
/// but for Żmij's `.0` on whole numbers, which is dropped; elsewhere `Display` writes the text.
///
/// On `rounded_digits`' fast path the text is written from the integer digits directly:
/// the shortest digits of `digits / 10^k` are those digits without their trailing zeros (the
/// argument above), which `Display` lays out without an exponent.
pub fn push_output_time(t: f64, out: &mut Vec<u8>) {
    let mut text = [0; TIME_TEXT_BYTES];
    if let Some(len) = output_time_text(t, &mut text) {
        out.extend_from_slice(&text[..len]);
        return;
    }
    if let Some((digits, k)) = rounded_digits(t) {
        push_decimal(digits, k, out);
        return;
    }
    let t = output_time(t);
    if t.is_finite() {
        let mut buffer = zmij::Buffer::new();
        let text = buffer.format_finite(t).as_bytes();
        if !text.contains(&b'e') {
            out.extend_from_slice(text.strip_suffix(b".0").unwrap_or(text));
            return;
        }
    }
    out.extend_from_slice(t.to_string().as_bytes());
}

/// Room for [`output_time_text`]'s text: a sign, 16 digits and a point, and the 16-byte copies
/// that write them.
pub const TIME_TEXT_BYTES: usize = 40;

/// The bytes of [`push_output_time`] written into `out`, and their length, when `t` is on
/// `rounded_digits`' fast path with at most 15 decimals (`|t| >= 1e-4` or so): the common case,
/// done without a `Vec` and with whole-word copies. `None` otherwise (`out` then holds
/// garbage). Bytes of `out` past the length are garbage too.
pub fn output_time_text(t: f64, out: &mut [u8; TIME_TEXT_BYTES]) -> Option<usize> {
    let (digits, k) = rounded_digits(t)?;
    let (mut m, mut k) = (digits.unsigned_abs(), k as usize);
    while k > 0 && m.is_multiple_of(10) {
        m /= 10;
        k -= 1;
    }
    if k > 15 {
        return None;
    }
    // `m < 10^15`: its 16 digits, zero-padded, then room for the 16-byte copy of the decimals.
    let mut padded = [b'0'; 32];
    padded[..8].copy_from_slice(&eight_digits((m / 100_000_000) as u32));
    padded[8..16].copy_from_slice(&eight_digits((m % 100_000_000) as u32));
    // Integer digits: those of `m / 10^k`, at least one (a `0`).
    let int = m / POWERS_OF_TEN_U64[k];
    let int_len = int.checked_ilog10().map_or(1, |l| l as usize + 1);
    let sign = usize::from(digits < 0);
    out[0] = b'-';
    let first = 16 - k - int_len;
    out[sign..sign + 16].copy_from_slice(&padded[first..first + 16]);
    let point = sign + int_len;
    if k == 0 {
        return Some(point);
    }
    out[point] = b'.';
    out[point + 1..point + 17].copy_from_slice(&padded[16 - k..32 - k]);
    Some(point + 1 + k)
}

/// `10^k` for `k = 0..=15`.
const POWERS_OF_TEN_U64: [u64; 16] = {
    let mut p = [1u64; 16];
    let mut k = 1;
    while k < 16 {
        p[k] = p[k - 1] * 10;
        k += 1;
    }
    p
};

/// The 8 decimal digits of `x < 10^8`, zero-padded: two digits a 16-bit lane, then one a byte
/// (multiplications by reciprocals, exact in these ranges; see the test).
fn eight_digits(x: u32) -> [u8; 8] {
    let (hi, lo) = (u64::from(x / 10_000), u64::from(x % 10_000));
    let fours = hi | (lo << 32);
    let hundreds = ((fours * 10_486) >> 20) & 0x0000_007f_0000_007f;
    let twos = hundreds | ((fours - hundreds * 100) << 16);
    let tens = ((twos * 103) >> 10) & 0x000f_000f_000f_000f;
    let ones = tens | ((twos - tens * 10) << 8);
    (ones | 0x3030_3030_3030_3030).to_le_bytes()
}

/// `digits / 10^k` in plain decimal notation, trailing zeros dropped (`digits != 0`,
/// `|digits| < 10^15`, so at most 15 digits).
fn push_decimal(digits: i64, k: u32, out: &mut Vec<u8>) {
    let (mut m, mut k) = (digits.unsigned_abs(), k as usize);
    while k > 0 && m.is_multiple_of(10) {
        m /= 10;
        k -= 1;
    }
    let mut buf = [0u8; 20];
    let mut start = buf.len();
    loop {
        start -= 1;
        buf[start] = b'0' + (m % 10) as u8;
        m /= 10;
        if m == 0 {
            break;
        }
    }
    let text = &buf[start..];
    if digits < 0 {
        out.push(b'-');
    }
    if k == 0 {
        out.extend_from_slice(text);
    } else if text.len() > k {
        let (int, frac) = text.split_at(text.len() - k);
        out.extend_from_slice(int);
        out.push(b'.');
        out.extend_from_slice(frac);
    } else {
        out.extend_from_slice(b"0.");
        out.resize(out.len() + (k - text.len()), b'0');
        out.extend_from_slice(text);
    }
}

fn serialize_time<S: serde::Serializer>(t: &f64, s: S) -> Result<S::Ok, S::Error> {
    s.serialize_f64(output_time(*t))
}

fn serialize_intervals<S: serde::Serializer>(
    m: &std::collections::BTreeMap<String, Vec<[f64; 2]>>,
    s: S,
) -> Result<S::Ok, S::Error> {
    let rounded: std::collections::BTreeMap<&String, Vec<[f64; 2]>> = m
        .iter()
        .map(|(k, v)| (k, v.iter().map(|i| i.map(output_time)).collect()))
        .collect();
    serde::Serialize::serialize(&rounded, s)
}

/// One contact episode: the steps from the first with the end (or any obstacle node) in
/// contact to the last, contact meaning a gap at most [`CONTACT_GAP_TOL`].
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
    /// `max r^{n+1}` over the episode (force; at an end its reaction, for the obstacle the sum
    /// over its nodes).
    pub peak_reaction: f64,
    /// `Σ Δt r^{n+1}` over the episode: the momentum the obstacle gives the bar (exactly, in
    /// the scheme: `R` has zero row sums when no end is clamped).
    pub impulse: f64,
    /// `Σ −½ r^{n+1}·(u^{n+1} − u^{n−1})` over the episode, the contact term of the energy
    /// identity (energy); `null` when a step of the episode was not measured.
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
    pub solver: String,
    pub nodes: usize,
    pub elements: usize,
    pub dt: f64,
    pub steps: usize,
    #[serde(serialize_with = "serialize_time")]
    pub final_time: f64,
    pub wall_time_s: f64,
    pub ns_per_node_step: f64,
    /// Shares of the stepping time per phase, estimated on a sample of the steps.
    pub time_shares: TimeShares,
    /// `E^{1/2}`.
    pub energy_initial: f64,
    /// `E^{N−1/2}`.
    pub energy_final: f64,
    /// Largest one-step increase `E^{n+1/2} − E^{n−1/2}` divided by `E^{1/2}`; only for scenes
    /// without load (where the scheme cannot gain energy), `null` otherwise.
    pub max_energy_rise: Option<f64>,
    pub max_identity_residual: f64,
    /// Largest `|gap · reaction|` over steps and constrained nodes.
    pub max_complementarity: f64,
    /// Largest penetration `max(0, −gap)`.
    pub max_violation: f64,
    /// Most negative reaction (0 when none is negative).
    pub min_reaction: f64,
    /// `[start, end]` time intervals of contact per constrained end (the episodes' start and
    /// end).
    #[serde(serialize_with = "serialize_intervals")]
    pub contact_intervals: std::collections::BTreeMap<String, Vec<[f64; 2]>>,
    /// The contact episodes per Signorini end, and for a distributed obstacle one list for the
    /// whole contact set (`obstacle`: an episode lasts while any node is in contact).
    pub contact_episodes: std::collections::BTreeMap<String, Vec<ContactEpisode>>,
    pub solver_iterations: Iterations,
    /// What the profile file holds (written runs only): its name and format, kept steps, node
    /// stride, rows.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub output: Option<crate::scene::OutputSampling>,
    /// Worst optimality residuals of the solver's answers, for solvers that audit them
    /// (`osqp`, `penalty`; see `viscobar::step::audit`).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub audit: Option<crate::step::AuditReport>,
    /// Steps where OSQP's "solved inaccurate" was accepted (`accept_inaccurate`; osqp only).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub inaccurate_steps: Option<u64>,
}

/// Where the time of the steps goes, as fractions of the timed phases of the sampled steps
/// (one in [`crate::time::clock::TIMING_SAMPLE_EVERY`], see [`crate::time::clock::PhaseTimes`]):
/// `rhs` (load and right-hand side), `solver` (the step solver, including its copy of the
/// right-hand side, and `u += z`), `diagnostics` (energy balance and contact state).
/// `stepping` is the sampled phases' share of the wall time (the rest is set-up, start-up and
/// writing the outputs), extrapolated from the sample.
#[derive(Clone, Copy, Debug, Default, Serialize)]
pub struct TimeShares {
    pub solver: f64,
    pub rhs: f64,
    pub diagnostics: f64,
    pub stepping: f64,
    pub sampled_steps: u64,
}

impl TimeShares {
    fn new(sim: &Simulation, wall_time_s: f64) -> Self {
        Self::from_phases(sim.phase_times(), sim.step_index(), wall_time_s)
    }

    /// The shares of `p`, measured on the steps `1 → 2 … n − 1 → n` of a run that reached
    /// `u^n` (`n = steps`; the start-up step is not timed) in `wall_time_s`.
    pub(crate) fn from_phases(p: PhaseTimes, steps: usize, wall_time_s: f64) -> Self {
        let total = p.total_ns() as f64;
        let share = |x: u64| if total > 0.0 { x as f64 / total } else { 0.0 };
        let steps = steps.saturating_sub(1) as f64;
        let per_step = total / p.sampled_steps.max(1) as f64;
        Self {
            solver: share(p.solve_ns),
            rhs: share(p.rhs_ns),
            diagnostics: share(p.diagnostics_ns),
            stepping: if wall_time_s > 0.0 {
                per_step * steps / (wall_time_s * 1e9)
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
    sides: Vec<String>,
    unforced: bool,
    energy_initial: f64,
    energy_prev: f64,
    energy_final: f64,
    max_rise: f64,
    max_residual: f64,
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
    /// The first `ends` entries of `sides` are Signorini ends; a last entry "obstacle" (the
    /// whole contact set) follows for a distributed obstacle.
    ends: usize,
}

impl Tracker {
    pub fn new(sim: &Simulation, unforced: bool) -> Self {
        let disc = sim.discretisation();
        let mut sides: Vec<String> = disc
            .constraints
            .iter()
            .filter_map(|c| c.side.map(|s| s.name().to_string()))
            .collect();
        let ends = sides.len();
        let obstacle = !disc.ends_only();
        if obstacle {
            sides.push("obstacle".to_string());
        }
        let k = sides.len();
        let first = sim.first_record();
        let mut t = Self {
            sides,
            ends,
            unforced,
            energy_initial: first.energy,
            energy_prev: first.energy,
            energy_final: first.energy,
            max_rise: f64::NEG_INFINITY,
            max_residual: 0.0,
            max_comp: 0.0,
            max_violation: 0.0,
            min_reaction: 0.0,
            episodes: vec![Vec::new(); k],
            in_contact: vec![false; k],
            dt: sim.discretisation().dt,
            last_energy: None,
            iterations_sum: 0,
            iterations_max: 0,
            records: 0,
        };
        t.observe_contact(&first);
        t.last_energy = Some(first.energy);
        t
    }

    /// Takes the record of the next step. With thinned diagnostics, the energy statistics
    /// cover the measured steps: a rise is then over the steps since the last measured one
    /// (the identity telescopes, so without load that rise is still ≤ 0 up to round-off).
    pub fn observe(&mut self, r: &StepRecord) {
        if r.measured {
            self.max_rise = self.max_rise.max(r.energy - self.energy_prev);
            self.energy_prev = r.energy;
            self.energy_final = r.energy;
            self.max_residual = self.max_residual.max(r.identity_residual);
        }
        self.iterations_sum += u64::from(r.iterations);
        self.iterations_max = self.iterations_max.max(r.iterations);
        self.records += 1;
        self.observe_contact(r);
        self.last_energy = r.measured.then_some(r.energy);
    }

    fn observe_contact(&mut self, r: &StepRecord) {
        self.max_comp = self.max_comp.max(r.max_complementarity);
        self.max_violation = self.max_violation.max(-r.min_gap);
        self.min_reaction = self.min_reaction.min(r.min_reaction);
        for j in 0..self.sides.len() {
            let contact = if j < self.ends {
                r.gap[j] <= CONTACT_GAP_TOL
            } else {
                r.contact_nodes > 0
            };
            let (reaction, dissipation) = if j < self.ends {
                (r.reaction[j], r.end_contact_dissipation[j])
            } else {
                (r.total_reaction, r.contact_dissipation)
            };
            let measured = r.measured.then_some(dissipation);
            let energy = r.measured.then_some(r.energy);
            if contact && !self.in_contact[j] {
                self.episodes[j].push(ContactEpisode {
                    start: r.time,
                    end: r.time,
                    open_at_end: false,
                    peak_reaction: reaction,
                    impulse: self.dt * reaction,
                    contact_dissipation: measured,
                    energy_before: if r.step > 1 { self.last_energy } else { None },
                    energy_after: energy,
                });
            } else if contact {
                let e = self.episodes[j].last_mut().expect("an open episode");
                e.end = r.time;
                e.peak_reaction = e.peak_reaction.max(reaction);
                e.impulse += self.dt * reaction;
                e.contact_dissipation = e.contact_dissipation.zip(measured).map(|(a, b)| a + b);
                e.energy_after = energy;
            }
            self.in_contact[j] = contact;
        }
    }

    pub fn finish(&self, scene_name: &str, sim: &Simulation, wall_time_s: f64) -> Summary {
        let disc = sim.discretisation();
        let steps = sim.step_index();
        let report = sim.solver_report();
        Summary {
            scene: scene_name.to_string(),
            solver: sim.solver_name().to_string(),
            nodes: disc.nodes,
            elements: disc.nodes - 1,
            dt: disc.dt,
            steps,
            final_time: sim.time(),
            wall_time_s,
            ns_per_node_step: wall_time_s * 1e9 / (steps as f64 * disc.nodes as f64),
            time_shares: TimeShares::new(sim, wall_time_s),
            energy_initial: self.energy_initial,
            energy_final: self.energy_final,
            max_energy_rise: (self.unforced && self.records > 0)
                .then(|| self.max_rise / self.energy_initial.max(f64::MIN_POSITIVE)),
            max_identity_residual: self.max_residual,
            max_complementarity: self.max_comp,
            max_violation: self.max_violation,
            min_reaction: self.min_reaction,
            contact_intervals: self
                .sides
                .iter()
                .cloned()
                .zip(
                    self.episodes
                        .iter()
                        .map(|e| e.iter().map(|e| [e.start, e.end]).collect()),
                )
                .collect(),
            contact_episodes: self
                .sides
                .iter()
                .cloned()
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

#[cfg(test)]
mod tests {
    use super::*;

    /// `floor_log10` is `log10().floor()`: at every power of ten from 1e-13 to 1e13 and 64 ulps
    /// either side, either side of the margin, on 10⁶ log-uniform values and on node grids.
    #[test]
    fn floor_log10_is_the_floor_of_log10() {
        let check = |a: f64| {
            assert_eq!(floor_log10(a), a.log10().floor() as i32, "{a:e}");
        };
        for m in -13..=13 {
            let p = 10f64.powi(m);
            for base in [
                p,
                p * (1.0 + POWER_OF_TEN_MARGIN),
                p * (1.0 - POWER_OF_TEN_MARGIN),
            ] {
                let (mut up, mut down) = (base, base);
                for _ in 0..64 {
                    check(up);
                    check(down);
                    (up, down) = (up.next_up(), down.next_down());
                }
            }
        }
        let mut state = 0x9e37_79b9_7f4a_7c15_u64;
        for _ in 0..1_000_000 {
            state = state
                .wrapping_mul(6_364_136_223_846_793_005)
                .wrapping_add(1_442_695_040_888_963_407);
            let u = (state >> 11) as f64 / (1u64 << 53) as f64;
            check(10f64.powf(-13.0 + 26.0 * u));
        }
        for (n, length) in [(16384, std::f64::consts::PI), (100_000, 1.0), (400, 2.6)] {
            let dx = length / n as f64;
            for i in 1..=n {
                check(i as f64 * dx);
            }
        }
    }

    /// `count` values `± m · 10^d` from an xorshift stream seeded with `seed`: `m` uniform in
    /// [0, 1), `d` in `decades`, the sign from the bit `sign_bit` of the state.
    fn random_values(
        seed: u64,
        count: usize,
        decades: std::ops::Range<i32>,
        sign_bit: u64,
    ) -> impl Iterator<Item = f64> {
        let span = (decades.end - decades.start) as u64;
        let mut state = seed;
        (0..count).map(move |_| {
            state ^= state << 13;
            state ^= state >> 7;
            state ^= state << 17;
            let mantissa = (state >> 11) as f64 / (1u64 << 53) as f64;
            let decade = (state % span) as i32 + decades.start;
            let sign = if state & sign_bit == 0 { 1.0 } else { -1.0 };
            sign * mantissa * 10f64.powi(decade)
        })
    }

    fn check(t: f64) {
        let mut out = Vec::new();
        push_output_time(t, &mut out);
        assert_eq!(
            String::from_utf8(out).unwrap(),
            output_time(t).to_string(),
            "t = {t:e} ({:#x})",
            t.to_bits()
        );
    }

    #[test]
    fn eight_digits_are_those_format_gives() {
        let check = |x: u32| {
            assert_eq!(eight_digits(x), *format!("{x:08}").as_bytes(), "{x}");
        };
        // The two 4-digit lanes are independent: every value in each.
        for a in 0..10_000 {
            check(a);
            check(a * 10_000);
            check(a * 10_000 + (9_999 - a));
        }
        for x in (0..100_000_000).step_by(9_973) {
            check(x);
        }
        check(99_999_999);
    }

    /// `output_time_text` writes what the general path (`push_decimal`) writes.
    #[test]
    fn text_fast_path_is_the_general_path() {
        let mut fast = 0;
        let mut check = |t: f64| {
            let mut text = [0; TIME_TEXT_BYTES];
            let Some(len) = output_time_text(t, &mut text) else {
                return;
            };
            fast += 1;
            let mut general = Vec::new();
            let (digits, k) = rounded_digits(t).expect("on the fast path");
            push_decimal(digits, k, &mut general);
            assert_eq!(&text[..len], &general[..], "t = {t:e}");
            let mut pushed = Vec::new();
            push_output_time(t, &mut pushed);
            assert_eq!(pushed, general, "t = {t:e}");
        };
        for m in -6..=16 {
            let p = 10f64.powi(m);
            for t in [
                p,
                p.next_up(),
                p.next_down(),
                p * 1.5,
                p * 9.999_999_999_995,
            ] {
                check(t);
                check(-t);
            }
        }
        for (n, length) in [
            (16384, std::f64::consts::PI),
            (100_000, 1.0),
            (777, 123.456),
        ] {
            let dx = length / n as f64;
            for i in 0..=n {
                check(i as f64 * dx);
            }
        }
        for i in 0..100_000 {
            check(f64::from(i) * 0.1);
            check(f64::from(i) * 0.000_123_456_7);
        }
        random_values(0x2545_f491_4f6c_dd1d, 500_000, -6..18, 2).for_each(check);
        assert!(fast > 600_000, "{fast} values on the fast path");
    }

    /// `floor_log10`'s first guess from the binary exponent is `floor(b·log10 2)` over its range.
    #[test]
    fn binary_exponent_guess_is_the_floor() {
        for b in -40..=40 {
            let exact = (f64::from(b) * std::f64::consts::LOG10_2).floor() as i32;
            assert_eq!((b * 1233) >> 12, exact, "b = {b}");
        }
    }

    #[test]
    fn round_half_away_is_round() {
        let mut state = 0x853c_49e6_748f_ea9b_u64;
        let check = |y: f64| assert_eq!(round_half_away(y), y.round(), "{y:e}");
        for y in [
            0.5,
            1.5,
            2.5,
            -0.5,
            -2.5,
            0.49999999999999994,
            4503599627370495.5,
            4503599627370497.0,
            1e15,
            -1e15 + 0.5,
            1e18,
        ] {
            check(y);
        }
        for _ in 0..1_000_000 {
            state = state
                .wrapping_mul(6_364_136_223_846_793_005)
                .wrapping_add(1);
            let y = ((state >> 11) as f64 / (1u64 << 53) as f64 - 0.5) * 2e15;
            check(y);
            check((y * 2.0).round() / 2.0);
        }
    }

    #[test]
    fn powers_of_ten_are_those_powi_gives() {
        for (k, p) in POWERS_OF_TEN.iter().enumerate() {
            assert_eq!(p.to_bits(), 10f64.powi(k as i32).to_bits());
        }
    }

    #[test]
    fn pushed_text_is_the_display_of_the_rounded_time() {
        for t in [
            0.0,
            -0.0,
            1.0,
            -1.0,
            0.1,
            1e-12,
            9.9999999999995,
            1e12,
            123456.0,
            3.03,
        ] {
            check(t);
        }
        for t in [f64::NAN, f64::INFINITY, f64::MIN_POSITIVE, 1e300, 5e-324] {
            check(t);
        }
        // Grid points as the runs write them, and random doubles over 30 decades.
        for (count, step) in [
            (20_000, std::f64::consts::PI / 16384.0),
            (5_000, 0.005),
            (5_000, 3.125e-5),
        ] {
            for i in 0..count {
                check(i as f64 * step);
            }
        }
        random_values(0x9e37_79b9_7f4a_7c15, 200_000, -15..16, 1).for_each(check);
    }
}
