//! The optimised twin of [`super::energy`] on a uniform mesh: the interior sums unweighted in
//! four lanes (scaled once by the two interior coefficients), the whole blocks of four rows as
//! AVX instructions when the CPU has it. Agrees with the plain
//! [`energy_sums`](super::energy::energy_sums) to round-off (another summation order).

use crate::linalg::dispatch;
use crate::linalg::tridiag::{SymTridiag, Uniform};
use crate::scheme::body::EnergySums;

/// [`energy_sums`](super::energy::energy_sums) on a uniform mesh, `(mi, ri)` the interior
/// coefficients of `M` and `R`; `LOAD = false` skips the work. The interior nodes' terms
/// `Σ z_i²`, `Σ (Δz_i)²`, … are summed unweighted and scaled once; the end nodes and the
/// element (0, 1) are added with their own coefficients.
#[inline(never)]
#[allow(clippy::too_many_arguments)]
pub fn energy_sums_uniform<const LOAD: bool>(
    mass: &SymTridiag,
    stiffness: &SymTridiag,
    (mi, ri): (Uniform, Uniform),
    u: &[f64],
    z: &[f64],
    w: &[f64],
    force: &[f64],
) -> EnergySums {
    let n = u.len();
    if n == 0 {
        return EnergySums::default();
    }
    let (z, w) = (&z[..n], &w[..n]);
    let force = if LOAD { &force[..n] } else { &[][..] };
    let d = |i: usize| z[i] + w[i];
    // Node and edge parts of zᵀMz, |u|²_R, |d|²_R, then F·d, over the interior nodes i with
    // their elements (i, i+1). R's interior rows sum to exactly 0: its node sums are then
    // not needed.
    let acc = if ri.s == 0.0 {
        uniform_sums::<LOAD, false>(u, z, w, force)
    } else {
        uniform_sums::<LOAD, true>(u, z, w, force)
    };
    let form = |k: Uniform, node: usize, edge: usize| k.s * acc[node] - k.e * acc[edge];
    let mut sums = EnergySums {
        kinetic: form(mi, 0, 1),
        potential: form(ri, 2, 3),
        viscous: form(ri, 4, 5),
        work: acc[6],
    };
    let (sm, sr) = (mass.row_sums(), stiffness.row_sums());
    for i in [0, n - 1].into_iter().take(n.min(2)) {
        let (zi, ui, di) = (z[i], u[i], d(i));
        sums.kinetic += sm[i] * zi * zi;
        sums.potential += sr[i] * ui * ui;
        sums.viscous += sr[i] * di * di;
        if LOAD {
            sums.work += force[i] * di;
        }
    }
    if n > 1 {
        let (em, er) = (mass.off[0], stiffness.off[0]);
        let (dz, du, dd) = (z[1] - z[0], u[1] - u[0], d(1) - d(0));
        sums.kinetic -= em * dz * dz;
        sums.potential -= er * du * du;
        sums.viscous -= er * dd * dd;
    }
    sums
}

/// Lanes of the energy sums: row `i` adds into lane `(i − 1) mod LANES`.
const LANES: usize = 4;

/// Running sums of [`uniform_sums`], lane by lane.
type Lanes = [[f64; LANES]; 7];

/// `Σ z_i²`, `Σ (Δz_i)²`, `Σ u_i²`, `Σ (Δu_i)²`, `Σ d_i²`, `Σ (Δd_i)²`, `Σ F_i d_i` over
/// `i = 1..n−1` with `d = z + w`, `Δx_i = x_{i+1} − x_i`, in [`LANES`] lanes added at the end in
/// a fixed order (shorter dependency chains); `S_R = false` leaves `Σ u_i²` and `Σ d_i²` 0.
/// The whole blocks of [`LANES`] rows run as AVX instructions when the CPU has them
/// ([`sums_blocks_avx`]: the compiler does not vectorise this loop, the overlapping loads of
/// rows `i` and `i + 1` defeat it), with the same bits as the portable [`sums_rows`].
fn uniform_sums<const LOAD: bool, const S_R: bool>(
    u: &[f64],
    z: &[f64],
    w: &[f64],
    force: &[f64],
) -> [f64; 7] {
    let (rows, zero) = (1..u.len().saturating_sub(1), [[0.0; LANES]; 7]);
    #[cfg(target_arch = "x86_64")]
    let acc = if dispatch::has_avx() {
        let blocks = rows.len() / LANES;
        // SAFETY: the CPU supports AVX.
        let acc = unsafe { sums_blocks_avx::<LOAD, S_R>(u, z, w, force, blocks) };
        sums_rows::<LOAD, S_R>((u, z, w, force), 1 + LANES * blocks..rows.end, acc)
    } else {
        sums_rows::<LOAD, S_R>((u, z, w, force), rows, zero)
    };
    #[cfg(not(target_arch = "x86_64"))]
    let acc = sums_rows::<LOAD, S_R>((u, z, w, force), rows, zero);
    acc.map(|[a, b, c, d]| (a + b) + (c + d))
}

/// Rows `rows` of [`uniform_sums`], portable, row `i` into lane `(i − 1) mod LANES` of `acc`.
fn sums_rows<const LOAD: bool, const S_R: bool>(
    (u, z, w, force): (&[f64], &[f64], &[f64], &[f64]),
    rows: std::ops::Range<usize>,
    mut acc: Lanes,
) -> Lanes {
    for i in rows {
        let lane = (i - 1) % LANES;
        let (zi, ui, di) = (z[i], u[i], z[i] + w[i]);
        let (dz, du, dd) = (z[i + 1] - zi, u[i + 1] - ui, (z[i + 1] + w[i + 1]) - di);
        acc[0][lane] += zi * zi;
        acc[1][lane] += dz * dz;
        if S_R {
            acc[2][lane] += ui * ui;
            acc[4][lane] += di * di;
        }
        acc[3][lane] += du * du;
        acc[5][lane] += dd * dd;
        if LOAD {
            acc[6][lane] += force[i] * di;
        }
    }
    acc
}

/// Rows `1..1 + LANES · blocks` of [`sums_rows`] in AVX instructions, from zero sums: each
/// lane's sums see the same operations in the same order, so the bits are the same.
#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx")]
fn sums_blocks_avx<const LOAD: bool, const S_R: bool>(
    u: &[f64],
    z: &[f64],
    w: &[f64],
    force: &[f64],
    blocks: usize,
) -> Lanes {
    use std::arch::x86_64::{
        __m256d, _mm256_add_pd, _mm256_loadu_pd, _mm256_mul_pd, _mm256_setzero_pd,
        _mm256_storeu_pd, _mm256_sub_pd,
    };
    let end = 1 + LANES * blocks;
    let (u, z, w) = (&u[..end + 1], &z[..end + 1], &w[..end + 1]);
    let force = if LOAD { &force[..end] } else { &[][..] };
    // Four entries from `i`, bounds-checked. Macros, not closures: a closure is not compiled
    // for AVX, and a vector it returns would go through memory.
    macro_rules! load {
        ($x:expr, $i:expr) => {{
            let four: &[f64; LANES] = $x[$i..$i + LANES].try_into().expect("four entries");
            // SAFETY: `four` is four readable doubles; unaligned loads are allowed.
            unsafe { _mm256_loadu_pd(four.as_ptr()) }
        }};
    }
    macro_rules! square_into {
        ($acc:expr, $x:expr) => {{
            let x: __m256d = $x;
            $acc = _mm256_add_pd($acc, _mm256_mul_pd(x, x));
        }};
    }
    let mut acc = [_mm256_setzero_pd(); 7];
    for i in (1..end).step_by(LANES) {
        let (zh, uh, wh) = (load!(z, i), load!(u, i), load!(w, i));
        let (za, ua, wa) = (load!(z, i + 1), load!(u, i + 1), load!(w, i + 1));
        let (dh, da) = (_mm256_add_pd(zh, wh), _mm256_add_pd(za, wa));
        square_into!(acc[0], zh);
        square_into!(acc[1], _mm256_sub_pd(za, zh));
        if S_R {
            square_into!(acc[2], uh);
            square_into!(acc[4], dh);
        }
        square_into!(acc[3], _mm256_sub_pd(ua, uh));
        square_into!(acc[5], _mm256_sub_pd(da, dh));
        if LOAD {
            acc[6] = _mm256_add_pd(acc[6], _mm256_mul_pd(load!(force, i), dh));
        }
    }
    let mut sums = [[0.0; LANES]; 7];
    for (lanes, v) in sums.iter_mut().zip(acc) {
        // SAFETY: `lanes` has room for four doubles.
        unsafe { _mm256_storeu_pd(lanes.as_mut_ptr(), v) };
    }
    sums
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::bar::energy::energy_sums;
    use crate::bar::matrices;

    /// Relative difference allowed between two summation orders of `n` terms: each sum carries
    /// at most about `n ε` of its absolute-value sum.
    fn sum_tol(n: usize) -> f64 {
        4.0 * n as f64 * f64::EPSILON
    }

    /// The twin agrees with the plain sums to the round-off of their summation orders, for
    /// every tail length of the four-lane loop.
    #[test]
    fn uniform_and_plain_energy_sums_agree() {
        for n in [2usize, 3, 4, 5, 6, 7, 50, 51, 52, 53] {
            let dx = 1.0 / (n - 1) as f64;
            let m = matrices::mass(matrices::MatrixVariant::Consistent, n, dx);
            let r = matrices::stiffness(matrices::MatrixVariant::Consistent, n, dx);
            let k = m.uniform().zip(r.uniform()).expect("a uniform mesh");
            let v = |a: f64| {
                (0..n)
                    .map(|i| (a * i as f64 + 0.3).sin())
                    .collect::<Vec<_>>()
            };
            let (u, z, w, f) = (v(0.7), v(1.3), v(2.1), v(0.4));
            let fast = energy_sums_uniform::<true>(&m, &r, k, &u, &z, &w, &f);
            let plain = energy_sums(&m, &r, &u, &z, &w, Some(&f));
            let pairs = [
                (fast.kinetic, plain.kinetic),
                (fast.potential, plain.potential),
                (fast.viscous, plain.viscous),
                (fast.work, plain.work),
            ];
            for (p, q) in pairs {
                // Scale: the sums of |terms| are at most of the size of the quadratic forms of
                // |x| under |A|, bounded here by ‖A‖∞ max|x|² n.
                let scale = (m.inf_norm() + r.inf_norm()) * 4.0 * n as f64;
                assert!((p - q).abs() <= sum_tol(n) * scale, "n = {n}: {p} vs {q}");
            }
            assert!(fast.kinetic != 0.0 && fast.potential != 0.0);
        }
    }

    /// The AVX blocks give the bits of the portable lanes (see [`dispatch`]), on data with
    /// large common parts and tiny differences, for every count of whole blocks.
    #[cfg(target_arch = "x86_64")]
    #[test]
    fn the_avx_blocks_have_the_bits_of_the_portable_lanes() {
        if !dispatch::has_avx() {
            eprintln!("this CPU has no AVX: only the portable lanes run, nothing to compare");
            return;
        }
        for n in [3usize, 4, 5, 6, 7, 8, 9, 10, 101, 1002] {
            let v = |a: f64, offset: f64, amp: f64| {
                (0..n)
                    .map(|i| offset + amp * (a * i as f64 + 0.3).sin())
                    .collect::<Vec<_>>()
            };
            let (u, z, w, f) = (
                v(0.7, 1e3, 1e-6),
                v(1.3, 0.0, 1.0),
                v(2.1, 1e-2, 1e-9),
                v(0.4, -1.0, 0.1),
            );
            let bits = |x: &[f64]| x.iter().map(|v| v.to_bits()).collect::<Vec<_>>();
            let blocks = (n - 2) / LANES;
            let rows = 1..1 + LANES * blocks;
            let zero = [[0.0; LANES]; 7];
            let data = (&u[..], &z[..], &w[..], &f[..]);
            let portable = [
                sums_rows::<true, true>(data, rows.clone(), zero),
                sums_rows::<true, false>(data, rows, zero),
            ];
            // SAFETY: the CPU has AVX (checked above).
            let avx = unsafe {
                [
                    sums_blocks_avx::<true, true>(&u, &z, &w, &f, blocks),
                    sums_blocks_avx::<true, false>(&u, &z, &w, &f, blocks),
                ]
            };
            for (p, q) in portable.iter().zip(&avx) {
                assert_eq!(bits(&p.concat()), bits(&q.concat()), "n = {n}");
            }
        }
    }
}
