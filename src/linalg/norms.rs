//! ∞-norms of vectors, shared by the solvers, their audit and the studies.

/// `max_i |v_i|`, the ∞-norm (0 for no values).
pub fn max_abs<'a>(values: impl IntoIterator<Item = &'a f64>) -> f64 {
    values.into_iter().fold(0.0f64, |m, v| m.max(v.abs()))
}

/// `max_i |a_i − b_i|`, the ∞-norm distance (over the shorter of the two).
pub fn max_distance(a: &[f64], b: &[f64]) -> f64 {
    a.iter()
        .zip(b)
        .fold(0.0f64, |m, (x, y)| m.max((x - y).abs()))
}
