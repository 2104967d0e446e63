//! The sums of the discrete energy balance of a step (`zᵀMz`, `|u|²_R`, `|z + w|²_R`,
//! `F·(z + w)`) in one read-only pass, quadratic forms in difference form so that rigid motion
//! adds no round-off; on a uniform mesh in four lanes with an AVX path of the same bits.

use crate::linalg::dispatch;
use crate::linalg::tridiag::{Interior, SymTridiag};
use crate::scheme::body::EnergySums;

/// The energy sums of a step, after `u += z` (so `u = u^{n+1}`), in one read-only pass; with
/// `w` the previous increment and `z` this one: `zᵀMz`, `|u|²_R`, `|z + w|²_R`, `F·(z + w)`.
/// Quadratic forms in difference form, `xᵀAx = Σ s_i x_i² − Σ A_i,i+1 (x_{i+1} − x_i)²`, so
/// rigid motion adds no round-off (see [`SymTridiag::quad`]); interior terms weighted as
/// [`Interior`] says.
#[inline(never)]
#[allow(clippy::too_many_arguments)]
pub fn measure<const LOAD: bool, K: Interior>(
    mass: &SymTridiag,
    stiffness: &SymTridiag,
    (mi, ri): (K, K),
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
    // Quantities: node and edge parts of zᵀMz, |u|²_R, |d|²_R, then F·d, over the interior
    // nodes i with their elements (i, i+1), weighted. One accumulator each: seven independent
    // addition chains keep the adders busy (more lanes measured slower here), and the order
    // is fixed, so the sums are deterministic.
    let mut acc = [0.0f64; 7];
    if K::UNIFORM {
        // R's interior rows sum to exactly 0: its node sums are then not needed.
        acc = if ri.scale_s() == 0.0 {
            uniform_measure::<LOAD, false>(u, z, w, force)
        } else {
            uniform_measure::<LOAD, true>(u, z, w, force)
        };
    } else {
        for i in 1..n.saturating_sub(1) {
            let (zi, ui, di) = (z[i], u[i], d(i));
            let (dz, du, dd) = (z[i + 1] - zi, u[i + 1] - ui, d(i + 1) - di);
            acc[0] += mi.ws(i) * zi * zi;
            acc[1] += mi.we(i) * dz * dz;
            acc[2] += ri.ws(i) * ui * ui;
            acc[3] += ri.we(i) * du * du;
            acc[4] += ri.ws(i) * di * di;
            acc[5] += ri.we(i) * dd * dd;
            if LOAD {
                acc[6] += force[i] * di;
            }
        }
    }
    let sum = |q: usize| acc[q];
    let form = |k: K, node: usize, edge: usize| k.scale_s() * sum(node) - k.scale_e() * sum(edge);
    let mut sums = EnergySums {
        kinetic: form(mi, 0, 1),
        potential: form(ri, 2, 3),
        viscous: form(ri, 4, 5),
        work: sum(6),
    };
    // End nodes with their own row sums; the element (0, 1).
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

/// Running sums of [`uniform_measure`], lane by lane.
type Lanes = [[f64; LANES]; 7];

/// The interior sums of [`measure`] on a uniform mesh (weights 1): `Σ z_i²`, `Σ (Δz_i)²`,
/// `Σ u_i²`, `Σ (Δu_i)²`, `Σ d_i²`, `Σ (Δd_i)²`, `Σ F_i d_i` over `i = 1..n−1` with `d = z + w`,
/// `Δx_i = x_{i+1} − x_i`. [`LANES`] lanes per sum, added at the end in a fixed order, which
/// shortens the additions' dependency chains; `S_R = false` skips `Σ u_i²` and `Σ d_i²` (left
/// 0). The whole blocks of [`LANES`] rows run as AVX vector instructions when the CPU has
/// them ([`measure_blocks_avx`]: the compiler does not vectorise this loop by itself, the
/// overlapping loads of rows `i` and `i + 1` defeat it), with the same bits as the portable
/// [`measure_rows`] (see [`dispatch`]).
fn uniform_measure<const LOAD: bool, const S_R: bool>(
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
        let acc = unsafe { measure_blocks_avx::<LOAD, S_R>(u, z, w, force, blocks) };
        measure_rows::<LOAD, S_R>((u, z, w, force), 1 + LANES * blocks..rows.end, acc)
    } else {
        measure_rows::<LOAD, S_R>((u, z, w, force), rows, zero)
    };
    #[cfg(not(target_arch = "x86_64"))]
    let acc = measure_rows::<LOAD, S_R>((u, z, w, force), rows, zero);
    acc.map(|[a, b, c, d]| (a + b) + (c + d))
}

/// Rows `rows` of [`uniform_measure`], portable, row `i` into lane `(i − 1) mod LANES` of
/// `acc`: all the rows, or the rows after [`measure_blocks_avx`]'s blocks.
fn measure_rows<const LOAD: bool, const S_R: bool>(
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

/// Rows `1..1 + LANES · blocks` of [`measure_rows`] in AVX instructions, from zero sums:
/// each lane's sums see the same operations in the same order, so the bits are the same.
#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx")]
fn measure_blocks_avx<const LOAD: bool, const S_R: bool>(
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
    // Four entries from `i`, bounds-checked (the loop's indices stay below `end + 1`). Macros,
    // not closures: a closure is not compiled for AVX, and a vector it returns would go
    // through memory.
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

/// `|u − w|²_R` in difference form (`u^{n−1} = u^n − w` for a step whose predecessor was not
/// measured; not on the per-step path).
pub fn potential_of_difference(stiffness: &SymTridiag, u: &[f64], w: &[f64]) -> f64 {
    let v = |i: usize| u[i] - w[i];
    let n = u.len();
    let mut q = 0.0;
    for i in 0..n {
        q += stiffness.row_sums()[i] * v(i) * v(i);
    }
    for i in 0..n.saturating_sub(1) {
        let d = v(i + 1) - v(i);
        q -= stiffness.off[i] * d * d;
    }
    q
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::bar::matrices;
    use crate::bar::rhs::RhsInterior;
    use crate::linalg::tridiag::Uniform;

    /// Relative difference allowed between the two summation orders of `n` terms: each sum
    /// carries at most about `n ε` of its absolute-value sum.
    fn sum_tol(n: usize) -> f64 {
        4.0 * n as f64 * f64::EPSILON
    }

    /// The uniform-mesh energy sums (four lanes, R's zero node sums skipped) agree with the
    /// row-by-row kernel, for every tail length of the four-lane loop.
    #[test]
    fn uniform_and_row_energy_sums_agree() {
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
            let uniform = measure::<true, Uniform>(&m, &r, k, &u, &z, &w, &f);
            let rows = measure::<true, _>(&m, &r, (m.rows(), r.rows()), &u, &z, &w, &f);
            let pairs = [
                (uniform.kinetic, rows.kinetic),
                (uniform.potential, rows.potential),
                (uniform.viscous, rows.viscous),
                (uniform.work, rows.work),
            ];
            for (p, q) in pairs {
                // Scale: the sums of |terms| are at most of the size of the quadratic forms of
                // |x| under |A|, bounded here by ‖A‖∞ max|x|² n.
                let scale = (m.inf_norm() + r.inf_norm()) * 4.0 * n as f64;
                assert!((p - q).abs() <= sum_tol(n) * scale, "n = {n}: {p} vs {q}");
            }
            assert!(uniform.kinetic != 0.0 && uniform.potential != 0.0);
        }
    }

    /// The AVX and the baseline builds of the streaming kernels give the same bits (see
    /// [`dispatch`]), on data with large common parts and tiny differences (the rigid-like
    /// motion where round-off would show), for every tail length of the vector loops
    /// (mutation-checked: an AVX energy sum fed the wrong difference fails it).
    #[cfg(target_arch = "x86_64")]
    #[test]
    fn kernels_give_the_same_bits_with_and_without_avx() {
        if !dispatch::has_avx() {
            eprintln!("this CPU has no AVX: only the baseline build runs, nothing to compare");
            return;
        }
        for n in [3usize, 4, 5, 6, 7, 8, 9, 10, 101, 1002] {
            let dx = 1.0 / (n - 1) as f64;
            let m = matrices::mass(matrices::MatrixVariant::Consistent, n, dx);
            let r = matrices::stiffness(matrices::MatrixVariant::Consistent, n, dx);
            let k = m.uniform().zip(r.uniform()).expect("a uniform mesh");
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
            let (c_w, inv_dt2): (f64, f64) = (-4999.5, 1.0 / (dx * dx));
            let bits = |x: &[f64]| x.iter().map(|v| v.to_bits()).collect::<Vec<_>>();
            for s_r in [false, true] {
                let (mut a, mut b) = (vec![0.0; n], vec![0.0; n]);
                let (ki, ui, wi, fi) = (k, &u[..], &w[..], &f[..]);
                macro_rules! both {
                    ($s:literal) => {
                        let kernel = |rhs| RhsInterior::<true, $s, Uniform> {
                            coefficients: ki,
                            c_w,
                            inv_dt2,
                            u: ui,
                            w: wi,
                            force: fi,
                            rhs,
                        };
                        dispatch::baseline(kernel(&mut a));
                        dispatch::run(kernel(&mut b));
                    };
                }
                if s_r {
                    both!(true);
                } else {
                    both!(false);
                }
                assert_eq!(bits(&a), bits(&b), "rhs, n = {n}, s_R {s_r}");
                let blocks = (n - 2) / LANES;
                let (p, q) = if s_r {
                    let portable = measure_rows::<true, true>(
                        (&u, &z, &w, &f),
                        1..1 + LANES * blocks,
                        [[0.0; LANES]; 7],
                    );
                    // SAFETY: the CPU has AVX (checked above).
                    let avx = unsafe { measure_blocks_avx::<true, true>(&u, &z, &w, &f, blocks) };
                    (portable, avx)
                } else {
                    let portable = measure_rows::<true, false>(
                        (&u, &z, &w, &f),
                        1..1 + LANES * blocks,
                        [[0.0; LANES]; 7],
                    );
                    // SAFETY: the CPU has AVX (checked above).
                    let avx = unsafe { measure_blocks_avx::<true, false>(&u, &z, &w, &f, blocks) };
                    (portable, avx)
                };
                let (p, q) = (p.concat(), q.concat());
                assert_eq!(bits(&p), bits(&q), "energy sums, n = {n}, s_R {s_r}");
            }
        }
    }
}
