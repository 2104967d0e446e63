//! Rannacher's start for the heat step: implicit Euler steps (L-stable: they damp the stiff
//! modes that Crank–Nicolson's factor, near −1 for `κΔt λ ≫ 1`, lets ring) where the heat's
//! data jump — at `t = 0` (a fixed end's value against the initial temperature, an exchange in
//! contact from the start) the start-up's half step and the [`SMOOTHING_STEPS`] steps after it;
//! later [`SMOOTHING_STEPS`] steps from a step in which a fixed end's data jump
//! ([`jumps_within`]) or an exchange end's contact changes — and Crank–Nicolson steps
//! elsewhere. A fixed number of steps with an `O(Δt²)` local error each keeps the second order
//! (Rannacher 1984, Numer. Math. 43). Derivation and the identity's term: `docs/thermal.md`.

use crate::scheme::RunError;
use crate::thermal::solver::ImplicitFlag;
use std::sync::atomic::Ordering;

/// Implicit Euler steps taken from a step where the data jump (and after the start-up's half
/// step): two, Rannacher's count, which the maximum-principle tests measure as enough
/// (`tests/thermal_smoothing.rs`).
pub const SMOOTHING_STEPS: usize = 2;

/// The relative disagreement between the initial temperature at a fixed end and the end's
/// value at `t = 0` that makes a sudden end temperature: well above the few ulps of evaluating
/// two expressions of one value, far below any intended step (whose ringing is proportional).
pub const START_MISMATCH: f64 = 1e-12;

/// Whether the initial temperature at a fixed end disagrees with the end's value at `t = 0`
/// by more than [`START_MISMATCH`] (relative to the larger of them and 1): a sudden end
/// temperature.
pub fn starts_with_a_jump(initial: f64, end: f64) -> bool {
    (initial - end).abs() > START_MISMATCH * initial.abs().max(end.abs()).max(1.0)
}

/// Halvings of a step that [`jumps_within`] follows: a smooth `θ_end` gives each level's
/// larger half about half of the level's change, so it fails [`JUMP_SHARE`] within one or two
/// levels (a parabola's extremum fails it at the next); a jump keeps all of it at every level.
pub const JUMP_LEVELS: usize = 4;

/// The share of a level's change (the sum of its halves' absolute changes) its larger half
/// must carry at every level for a jump: a jump `J` beside a slope `s` over the half's length
/// `ℓ` carries `(J + sℓ/2)/(J + sℓ)`, at least 0.9 when `J >= 4 sℓ`; a smooth change, ½.
pub const JUMP_SHARE: f64 = 0.9;

/// Whether `f` jumps within `[a, b]` (`fa`, `fb` its values there): its change does not shrink
/// with the interval. Bisects [`JUMP_LEVELS`] times into the half with the larger change,
/// which must carry at least [`JUMP_SHARE`] of the level's change each time. A change of
/// exactly 0 over the step (constant data) is no jump and costs no evaluation.
pub fn jumps_within(
    f: impl Fn(f64) -> Result<f64, RunError>,
    (a, b): (f64, f64),
    (fa, fb): (f64, f64),
) -> Result<bool, RunError> {
    if fa == fb {
        return Ok(false);
    }
    let (mut a, mut b, mut fa, mut fb) = (a, b, fa, fb);
    for _ in 0..JUMP_LEVELS {
        let m = 0.5 * (a + b);
        let fm = f(m)?;
        let (left, right) = ((fm - fa).abs(), (fb - fm).abs());
        let total = left + right;
        if total == 0.0 || left.max(right) < JUMP_SHARE * total {
            return Ok(false);
        }
        if left >= right {
            (b, fb) = (m, fm);
        } else {
            (a, fa) = (m, fm);
        }
    }
    Ok(true)
}

/// Whether an initial temperature `f` jumps between consecutive points of a line of nodes
/// (`points`): [`jumps_within`] on each interval, its change not shrinking under bisection. A
/// value that is not finite inside an interval counts as a jump.
pub fn profile_jumps(f: impl Fn(f64) -> f64, points: &[f64]) -> bool {
    points.windows(2).any(|w| {
        let (a, b) = (w[0], w[1]);
        jumps_within(|x| Ok(f(x)), (a, b), (f(a), f(b))).unwrap_or(true)
    })
}

/// Which heat steps are implicit Euler ones; shares its answer with the step solver.
#[derive(Clone, Debug, Default)]
pub struct Smoothing {
    /// Steps `n < until` are implicit.
    until: usize,
    flag: ImplicitFlag,
}

impl Smoothing {
    /// The flag the step solver reads.
    pub fn flag(&self) -> ImplicitFlag {
        self.flag.clone()
    }

    /// Whether step `n` (the start-up at `n = 0`) is implicit, `jump` telling whether its
    /// data jump; sets the shared flag.
    pub fn schedule(&mut self, n: usize, jump: bool) -> bool {
        if jump {
            // The start-up is a half step: the next SMOOTHING_STEPS full steps follow it.
            let steps = SMOOTHING_STEPS + usize::from(n == 0);
            self.until = self.until.max(n + steps);
        }
        let implicit = n < self.until;
        self.flag.store(implicit, Ordering::Relaxed);
        implicit
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn ok(f: impl Fn(f64) -> f64) -> impl Fn(f64) -> Result<f64, RunError> {
        move |t| Ok(f(t))
    }

    /// Steps (inside, at either end of the interval) are jumps; constants, lines, parabolas
    /// with their extremum anywhere, `sin` and the smooth start `min(1, t/0.2)` are not.
    #[test]
    fn jumps_are_told_from_smooth_changes() {
        let (a, b) = (0.3, 0.35);
        let step = |at: f64| move |t: f64| f64::from(u8::from(t >= at));
        for at in [0.31, 0.325, 0.3499, 0.35] {
            let f = step(at);
            assert!(jumps_within(ok(f), (a, b), (f(a), f(b))).unwrap(), "{at}");
        }
        let smooth: [Box<dyn Fn(f64) -> f64>; 6] = [
            Box::new(|_| 1.0),
            Box::new(|t| 2.0 * t - 1.0),
            Box::new(|t| (t - 0.31) * (t - 0.31)),
            Box::new(|t| (t - 0.3) * (t - 0.3)),
            Box::new(|t| (40.0 * t).sin()),
            Box::new(|t| (t / 0.32).min(1.0)),
        ];
        for (i, f) in smooth.iter().enumerate() {
            assert!(!jumps_within(ok(f), (a, b), (f(a), f(b))).unwrap(), "{i}");
        }
    }

    /// A jump at the start: the start-up and the next [`SMOOTHING_STEPS`] steps are implicit;
    /// a jump later: its step and the next ones, [`SMOOTHING_STEPS`] in all; smooth data: none.
    #[test]
    fn the_schedule_covers_each_jump() {
        for start in [false, true] {
            let mut s = Smoothing::default();
            let flag = s.flag();
            let taken: Vec<bool> = (0..10)
                .map(|n| s.schedule(n, n == 6 || (n == 0 && start)))
                .collect();
            let mut expected = vec![false; 10];
            let first = (0..=SMOOTHING_STEPS).filter(|_| start);
            for n in first.chain(6..6 + SMOOTHING_STEPS) {
                expected[n] = true;
            }
            assert_eq!(taken, expected, "start {start}");
            assert!(!flag.load(Ordering::Relaxed));
        }
        let mut s = Smoothing::default();
        assert!((0..10).all(|n| !s.schedule(n, false)));
    }
}
