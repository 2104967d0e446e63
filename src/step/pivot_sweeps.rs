//! The loops of block principal pivoting ([`super::block_pivot`]): the whole-bar solve's two
//! chains and its pass over the interior margins, the sweeps of the incremental re-solves over
//! ranges of rows, and the scans and maxima they use.

use crate::linalg::norms::max_abs;
use crate::linalg::tridiag::SymTridiag;

/// The forward chain `t_j = b_j − l_{j−1} t_{j−1}` over rows with free neighbours (`l` holds
/// `l_{j−1}` for each row, `t` is the value before the first), with the running maxima of
/// `|b|` and `|lo|`; returns the last `t` and the maxima.
#[inline(never)]
pub(crate) fn forward_chain(
    rhs: &[f64],
    lo: &[f64],
    l: &[f64],
    ts: &mut [f64],
    mut t: f64,
    mut b_max: f64,
    mut lo_max: f64,
) -> (f64, f64, f64) {
    for (((tj, &b), &lo), &l) in ts.iter_mut().zip(rhs).zip(lo).zip(l) {
        b_max = max_of(b_max, b.abs());
        lo_max = max_of(lo_max, lo.abs());
        t = b - l * t;
        *tj = t;
    }
    (t, b_max, lo_max)
}

/// The backward chain `z_j = t_j / d_j − l_j z_{j+1}` downwards over the rows of `t`, from
/// `z`'s last entry (one more than `t`), which is given.
#[inline(never)]
pub(crate) fn backward_chain(t: &[f64], inv_d: &[f64], l: &[f64], z: &mut [f64]) {
    let k = t.len();
    let mut z_next = z[k];
    for (((zj, &t), &inv_d), &l) in z[..k].iter_mut().zip(t).zip(inv_d).zip(l).rev() {
        z_next = t * inv_d - l * z_next;
        *zj = z_next;
    }
}

/// The margins of the interior nodes `1..n − 1` (all constrained), as `margin_at` (the
/// interior branch of [`row_product`]), negative ones appended to `negative`. A loop of its
/// own: as a closure called per node it was not inlined.
#[inline(never)]
pub(crate) fn margins_interior(
    active: &[bool],
    lo: &[f64],
    rhs: &[f64],
    c: &SymTridiag,
    z: &[f64],
    margin: &mut [f64],
    negative: &mut Vec<usize>,
) {
    let n = z.len();
    // Node i's neighbourhood: `z` and `e` around it, its other inputs and its margin.
    let inner = 1..n - 1;
    let (s, e) = (&c.row_sums()[inner.clone()], c.off[..n - 1].windows(2));
    let (active, lo, rhs) = (
        &active[inner.clone()],
        &lo[inner.clone()],
        &rhs[inner.clone()],
    );
    let rows = z
        .windows(3)
        .zip(e)
        .zip(s)
        .zip(active.iter().zip(lo).zip(rhs));
    for ((i, margin), (((z, e), &s), ((&active, &lo), &rhs))) in
        inner.clone().zip(&mut margin[inner]).zip(rows)
    {
        let zi = z[1];
        let m = if active {
            s * zi + e[0] * (z[0] - zi) + e[1] * (z[2] - zi) - rhs
        } else {
            zi - lo
        };
        *margin = m;
        if m < 0.0 {
            negative.push(i);
        }
    }
}

/// `(C z)_i`, with the bits of [`SymTridiag::mul_into`] (difference form).
#[inline(always)]
pub(crate) fn row_product(c: &SymTridiag, i: usize, z: &[f64]) -> f64 {
    let n = z.len();
    let (s, e) = (c.row_sums(), &c.off);
    if n == 1 {
        c.diag[0] * z[0]
    } else if i == 0 {
        s[0] * z[0] + e[0] * (z[1] - z[0])
    } else if i + 1 == n {
        s[i] * z[i] + e[i - 1] * (z[i - 1] - z[i])
    } else {
        s[i] * z[i] + e[i - 1] * (z[i - 1] - z[i]) + e[i] * (z[i + 1] - z[i])
    }
}

/// Runs the recurrence `step` upwards over the rows of the sorted, disjoint ranges `dirty`
/// (rows whose inputs changed), continuing past a range until `step` reports the carried value
/// unchanged; the recomputed rows go to `out` (sorted, disjoint), their count to `rows`.
#[inline]
pub(crate) fn sweep_up(
    n: usize,
    dirty: &[(usize, usize)],
    out: &mut Vec<(usize, usize)>,
    rows: &mut usize,
    mut step: impl FnMut(usize) -> bool,
) {
    out.clear();
    let mut next = 0;
    while next < dirty.len() {
        let (start, mut must) = dirty[next];
        let mut j = start;
        loop {
            while next < dirty.len() && dirty[next].0 <= j {
                must = must.max(dirty[next].1);
                next += 1;
            }
            let same = step(j);
            *rows += 1;
            if j + 1 == n || (same && j >= must) {
                break;
            }
            j += 1;
        }
        push_merged(out, (start, j));
    }
}

/// [`sweep_up`] downwards: the recurrence carries from row `j + 1` to row `j`.
#[inline]
pub(crate) fn sweep_down(
    n: usize,
    dirty: &[(usize, usize)],
    out: &mut Vec<(usize, usize)>,
    rows: &mut usize,
    mut step: impl FnMut(usize) -> bool,
) {
    debug_assert!(dirty.iter().all(|r| r.1 < n));
    out.clear();
    let mut next = dirty.len();
    while next > 0 {
        let (mut must, start) = dirty[next - 1];
        let mut j = start;
        loop {
            while next > 0 && dirty[next - 1].1 >= j {
                must = must.min(dirty[next - 1].0);
                next -= 1;
            }
            let same = step(j);
            *rows += 1;
            if j == 0 || (same && j <= must) {
                break;
            }
            j -= 1;
        }
        out.push((j, start));
    }
    out.reverse();
    // Adjacent ranges found downwards are merged after the reversal.
    let mut w = 0;
    for r in 0..out.len() {
        let cur = out[r];
        if w > 0 && cur.0 <= out[w - 1].1 + 1 {
            out[w - 1].1 = out[w - 1].1.max(cur.1);
        } else {
            out[w] = cur;
            w += 1;
        }
    }
    out.truncate(w);
}

/// Flags compared a word at a time by [`run_end`] and [`run_start`].
pub(crate) const SCAN: usize = 32;

/// The first index at or after `from` whose flag is not `flag` (`flags.len()` if none).
#[inline]
pub(crate) fn run_end(flags: &[bool], from: usize, flag: bool) -> usize {
    let mut i = from;
    while i + SCAN <= flags.len()
        && flags[i..i + SCAN]
            .iter()
            .fold(true, |a, &f| a & (f == flag))
    {
        i += SCAN;
    }
    flags[i..]
        .iter()
        .position(|&f| f != flag)
        .map_or(flags.len(), |k| i + k)
}

/// The least `s <= top` with every flag of `s..=top` equal to `flag` (that of `top`).
#[inline]
pub(crate) fn run_start(flags: &[bool], top: usize, flag: bool) -> usize {
    let mut s = top;
    while s >= SCAN
        && flags[s - SCAN..s]
            .iter()
            .fold(true, |a, &f| a & (f == flag))
    {
        s -= SCAN;
    }
    flags[..s]
        .iter()
        .rposition(|&f| f != flag)
        .map_or(0, |k| k + 1)
}

/// `m.max(x)` for a running maximum `m` that is not NaN (it starts at 0): the same value (a
/// NaN `x` is ignored either way) in one `maxsd`, without `f64::max`'s NaN blend on the
/// dependency chain.
#[inline(always)]
pub(crate) fn max_of(m: f64, x: f64) -> f64 {
    if x > m { x } else { m }
}

/// [`max_abs`] with four accumulators (the same value: a maximum does not depend on the order;
/// NaNs are ignored either way), off the single chain of dependent comparisons.
pub(crate) fn max_abs_4(v: &[f64]) -> f64 {
    let mut m = [0.0f64; 4];
    let chunks = v.chunks_exact(4);
    let rest = max_abs(chunks.remainder());
    for c in chunks {
        for k in 0..4 {
            m[k] = max_of(m[k], c[k].abs());
        }
    }
    max_of(max_of(max_of(m[0], m[1]), max_of(m[2], m[3])), rest)
}

/// Appends `r` to sorted ranges, merging it with the last one when they overlap or touch.
pub(crate) fn push_merged(out: &mut Vec<(usize, usize)>, r: (usize, usize)) {
    match out.last_mut() {
        Some(last) if r.0 <= last.1 + 1 => last.1 = last.1.max(r.1),
        _ => out.push(r),
    }
}
