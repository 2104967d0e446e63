//! The snapshot tests' rows: a sampled step, its time and the test's own columns, and the
//! rounding of each quantity to significant digits of its largest magnitude over the run.

use serde::Serialize;

/// One sampled step of a snapshot: its number `step`, its time `t`, then the test's columns
/// `C` (serialised as fields of the row, in their order).
#[derive(Serialize)]
pub struct Row<C> {
    pub step: usize,
    pub t: f64,
    #[serde(flatten)]
    pub columns: C,
}

/// Whether step `n` of `steps` is sampled for `points` rows: the start-up step `n = 1` and
/// `N/(points − 1), …, N`.
pub fn sampled(n: usize, steps: usize, points: usize) -> bool {
    n == 1 || (n * (points - 1)).is_multiple_of(steps)
}

/// Rounds every row's `t` to `digits` significant digits of 1 ([`super::round_to_digits`]).
pub fn round_times<C>(rows: &mut [Row<C>], digits: i32) {
    for r in rows {
        r.t = super::round_to_digits(r.t, 1.0, digits);
    }
}

/// Rounds one quantity over the run: the values `values` yields of each row's columns, each
/// to `digits` significant digits of their largest magnitude over all rows
/// ([`super::round_to_digits`]).
pub fn round_quantity<C>(
    rows: &mut [Row<C>],
    digits: i32,
    values: impl for<'a> Fn(&'a mut C) -> Vec<&'a mut f64>,
) {
    let mut scale = 0.0;
    for r in rows.iter_mut() {
        scale = values(&mut r.columns)
            .into_iter()
            .fold(scale, |m, v| f64::max(m, v.abs()));
    }
    for r in rows.iter_mut() {
        for v in values(&mut r.columns) {
            *v = super::round_to_digits(*v, scale, digits);
        }
    }
}
