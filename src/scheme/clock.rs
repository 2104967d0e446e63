//! Where a step's time goes: the wall time of its phases (right-hand side, solve, diagnostics),
//! read on a sample of the steps so that timing costs below 1 % of a step.

use std::time::Instant;

/// The clock is read in one step out of this many (timer reads cost ~25 ns each, four a
/// step: sampling keeps that below 1 % of a 100-node step).
pub const TIMING_SAMPLE_EVERY: usize = 32;

/// Wall time per phase of [`Scheme::step`](crate::scheme::Scheme::step), summed over the sampled steps (one in
/// [`TIMING_SAMPLE_EVERY`], starting with the first): `rhs` (load vector and right-hand
/// side), `solve` (bounds, on a measured step after an unmeasured one the recomputation of
/// `E^{n−1/2}`, the step solver and `u += z`, which the exact end solver merges with its own
/// last pass), `diagnostics` (the energy balance pass, contact state, record). Shares of a
/// run are ratios of these sums.
#[derive(Clone, Copy, Debug, Default, PartialEq, serde::Serialize)]
pub struct PhaseTimes {
    pub sampled_steps: u64,
    pub rhs_ns: u64,
    pub solve_ns: u64,
    pub diagnostics_ns: u64,
}

impl PhaseTimes {
    /// Whether step `n → n + 1` is timed (and counts it).
    pub(crate) fn samples(&mut self, n: usize) -> bool {
        let sampled = n % TIMING_SAMPLE_EVERY == 1;
        self.sampled_steps += u64::from(sampled);
        sampled
    }

    /// The sum of the three phases.
    pub fn total_ns(&self) -> u64 {
        self.rhs_ns + self.solve_ns + self.diagnostics_ns
    }
}

/// The time of the last lap, when this step is sampled.
pub(crate) struct PhaseClock(Option<Instant>);

impl PhaseClock {
    pub(crate) fn start(sampled: bool) -> Self {
        Self(sampled.then(Instant::now))
    }

    /// Adds the time since the last lap to `into`.
    pub(crate) fn lap(self, into: &mut u64) -> Self {
        let Some(then) = self.0 else { return self };
        let now = Instant::now();
        *into += u64::try_from((now - then).as_nanos()).unwrap_or(u64::MAX);
        Self(Some(now))
    }
}
