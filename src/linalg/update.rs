//! The update `z += Σ r_k a_k; u += z` of a step, returning `max_i |u_i|`, with an AVX path of
//! the same bits beside its portable reference (see [`super::dispatch`]).

use crate::linalg::dispatch;

/// `u += z`, returning the new `max_i |u_i|`: `add_columns_in_place` with no column.
pub fn add_in_place(u: &mut [f64], z: &[f64]) -> f64 {
    #[cfg(target_arch = "x86_64")]
    if dispatch::has_avx() {
        // SAFETY: the CPU supports AVX.
        return unsafe { update_avx::<0, false>(u, z.as_ptr().cast_mut(), z.len(), []) };
    }
    update::<0, false>(u, z.as_ptr().cast_mut(), z.len(), [])
}

/// `z = (z + r₁ a₁) + r₂ a₂` (the `K` terms given, each `a` as long as `z`), then `u += z`;
/// returns the new `max_i |u_i|` (four running maxima: the maximum is exact, so the order
/// does not change the bits). On a CPU with AVX it runs as AVX instructions ([`dispatch`]):
/// the same operations on each entry, so the same bits.
pub(crate) fn add_columns_in_place<const K: usize>(
    u: &mut [f64],
    z: &mut [f64],
    terms: [(f64, &[f64]); K],
) -> f64 {
    assert!(
        terms.iter().all(|(_, a)| a.len() == z.len()),
        "column length"
    );
    #[cfg(target_arch = "x86_64")]
    if dispatch::has_avx() {
        // SAFETY: the CPU supports AVX; `z` is exclusively borrowed for the call.
        return unsafe { update_avx::<K, true>(u, z.as_mut_ptr(), z.len(), terms) };
    }
    update::<K, true>(u, z.as_mut_ptr(), z.len(), terms)
}

/// The portable update (see [`add_columns_in_place`]). `z` is `len` doubles at `z_ptr`,
/// written only when `WRITE_Z` (so that [`add_in_place`] can pass a shared slice).
fn update<const K: usize, const WRITE_Z: bool>(
    u: &mut [f64],
    z_ptr: *mut f64,
    len: usize,
    terms: [(f64, &[f64]); K],
) -> f64 {
    max4(update_from::<K, WRITE_Z>(
        u, z_ptr, len, &terms, 0, [0.0; 4],
    ))
}

/// Entries `from..len` of [`update`], entry `i` into running maximum `i mod 4` of `m`.
#[inline(always)]
fn update_from<const K: usize, const WRITE_Z: bool>(
    u: &mut [f64],
    z_ptr: *mut f64,
    len: usize,
    terms: &[(f64, &[f64]); K],
    from: usize,
    mut m: [f64; 4],
) -> [f64; 4] {
    assert_eq!(u.len(), len, "state length");
    for i in from..len {
        // SAFETY: `i < len`, and the callers' `z` is `len` doubles, writable when `WRITE_Z`.
        let mut zi = unsafe { *z_ptr.add(i) };
        for (r, a) in terms {
            zi += r * a[i];
        }
        if WRITE_Z && K > 0 {
            // SAFETY: as above.
            unsafe { *z_ptr.add(i) = zi };
        }
        u[i] += zi;
        m[i % 4] = m[i % 4].max(u[i].abs());
    }
    m
}

/// [`update`] in AVX instructions: blocks of four entries, then the rest one by one.
#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx")]
fn update_avx<const K: usize, const WRITE_Z: bool>(
    u: &mut [f64],
    z_ptr: *mut f64,
    len: usize,
    terms: [(f64, &[f64]); K],
) -> f64 {
    use std::arch::x86_64::{
        _mm256_add_pd, _mm256_andnot_pd, _mm256_loadu_pd, _mm256_max_pd, _mm256_mul_pd,
        _mm256_set1_pd, _mm256_setzero_pd, _mm256_storeu_pd,
    };
    assert_eq!(u.len(), len, "state length");
    let blocks = len / 4;
    let sign = _mm256_set1_pd(-0.0);
    let mut m = _mm256_setzero_pd();
    for b in 0..blocks {
        let i = 4 * b;
        // SAFETY: entries `i..i + 4` are inside `u`, `z` (`len` doubles) and every column.
        unsafe {
            let mut zi = _mm256_loadu_pd(z_ptr.add(i));
            for (r, a) in &terms {
                let ai = _mm256_loadu_pd(a[i..i + 4].as_ptr());
                zi = _mm256_add_pd(zi, _mm256_mul_pd(_mm256_set1_pd(*r), ai));
            }
            if WRITE_Z && K > 0 {
                _mm256_storeu_pd(z_ptr.add(i), zi);
            }
            let ui = _mm256_add_pd(_mm256_loadu_pd(u[i..i + 4].as_ptr()), zi);
            _mm256_storeu_pd(u[i..i + 4].as_mut_ptr(), ui);
            // max(|u|, m): `m` when |u| is NaN, as f64::max(m, |u|).
            m = _mm256_max_pd(_mm256_andnot_pd(sign, ui), m);
        }
    }
    let mut lanes = [0.0f64; 4];
    // SAFETY: `lanes` has room for four doubles.
    unsafe { _mm256_storeu_pd(lanes.as_mut_ptr(), m) };
    // The rest one by one.
    max4(update_from::<K, WRITE_Z>(
        u,
        z_ptr,
        len,
        &terms,
        4 * blocks,
        lanes,
    ))
}

/// The largest of four running maxima.
pub(crate) fn max4(m: [f64; 4]) -> f64 {
    m[0].max(m[1]).max(m[2].max(m[3]))
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The AVX and the portable updates give the same bits (`u`, `z` and the maximum), for
    /// zero, one and two columns and every tail length of the four-entry blocks; a NaN in `u`
    /// is skipped by the maximum on both paths, as `f64::max` does (mutation-checked: the
    /// AVX maximum with its operands swapped fails).
    #[cfg(target_arch = "x86_64")]
    #[test]
    fn updates_give_the_same_bits_with_and_without_avx() {
        if !dispatch::has_avx() {
            eprintln!("this CPU has no AVX: only the portable update runs, nothing to compare");
            return;
        }
        let bits = |x: &[f64]| x.iter().map(|v| v.to_bits()).collect::<Vec<_>>();
        for n in [0usize, 1, 2, 3, 4, 5, 6, 7, 8, 9, 101] {
            let v = |a: f64, offset: f64| {
                (0..n)
                    .map(|i| offset + (a * i as f64 + 0.3).sin())
                    .collect::<Vec<_>>()
            };
            let (mut u0, z0, a, b) = (v(0.7, 1e3), v(1.3, 0.0), v(2.1, 0.0), v(0.4, -1.0));
            // The largest entry, then a NaN in the same lane of the next block: a maximum that
            // took the NaN would lose the largest entry.
            if n > 6 {
                (u0[2], u0[6]) = (1e6, f64::NAN);
            }
            macro_rules! compare {
                ($k:literal, $write:literal, $terms:expr) => {{
                    let (mut u1, mut z1, mut u2, mut z2) =
                        (u0.clone(), z0.clone(), u0.clone(), z0.clone());
                    let m1 = update::<$k, $write>(&mut u1, z1.as_mut_ptr(), n, $terms);
                    // SAFETY: the CPU has AVX (checked above).
                    let m2 =
                        unsafe { update_avx::<$k, $write>(&mut u2, z2.as_mut_ptr(), n, $terms) };
                    assert_eq!(bits(&u1), bits(&u2), "u, n = {n}, {} columns", $k);
                    assert_eq!(bits(&z1), bits(&z2), "z, n = {n}, {} columns", $k);
                    assert_eq!(m1.to_bits(), m2.to_bits(), "max, n = {n}, {} columns", $k);
                    assert!(!m1.is_nan());
                }};
            }
            compare!(0, false, []);
            compare!(1, true, [(0.3, &a[..])]);
            compare!(2, true, [(0.3, &a[..]), (-7.0, &b[..])]);
        }
    }
}
