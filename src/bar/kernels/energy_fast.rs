//! The optimised twin of [`super::energy`] on a uniform mesh: the interior sums unweighted in
//! four lanes (scaled once by the two interior coefficients), the whole blocks of four rows
//! compiled for AVX when the CPU has it (`dispatch::run`). Agrees with the plain
//! [`energy_sums`](super::energy::energy_sums) to round-off (another summation order).

use crate::linalg::kernels::dispatch;
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
/// The whole blocks of [`LANES`] rows run through [`dispatch::run`] ([`SumsBlocks`]: a block's
/// rows as operations on arrays of four, which the compiler turns into vector instructions),
/// the rest row by row ([`sums_rows`]); each lane sees the same operations in the same order.
fn uniform_sums<const LOAD: bool, const S_R: bool>(
    u: &[f64],
    z: &[f64],
    w: &[f64],
    force: &[f64],
) -> [f64; 7] {
    let rows = 1..u.len().saturating_sub(1);
    let blocks = rows.len() / LANES;
    let acc = dispatch::run(SumsBlocks::<LOAD, S_R> {
        u,
        z,
        w,
        force,
        blocks,
    });
    let acc = sums_rows::<LOAD, S_R>((u, z, w, force), 1 + LANES * blocks..rows.end, acc);
    acc.map(|[a, b, c, d]| (a + b) + (c + d))
}

/// Rows `rows` of [`uniform_sums`], portable, row `i` into lane `(i − 1) mod LANES` of `acc`.
fn sums_rows<const LOAD: bool, const S_R: bool>(
    (u, z, w, force): (&[f64], &[f64], &[f64], &[f64]),
    rows: std::ops::Range<usize>,
    mut acc: Lanes,
) -> Lanes {
    for i in rows {
        let f = if LOAD { force[i] } else { 0.0 };
        let row = [z[i], u[i], w[i], f, z[i + 1], u[i + 1], w[i + 1]];
        add_row::<LOAD, S_R>(&mut acc, (i - 1) % LANES, row);
    }
    acc
}

/// Adds row `i`'s terms into `lane` of `acc` from `[z_i, u_i, w_i, F_i, z_i+1, u_i+1, w_i+1]`
/// (`F_i` read only when `LOAD`).
#[inline(always)]
fn add_row<const LOAD: bool, const S_R: bool>(acc: &mut Lanes, lane: usize, row: [f64; 7]) {
    let [zi, ui, wi, fi, za, ua, wa] = row;
    let di = zi + wi;
    let (dz, du, dd) = (za - zi, ua - ui, (za + wa) - di);
    acc[0][lane] += zi * zi;
    acc[1][lane] += dz * dz;
    if S_R {
        acc[2][lane] += ui * ui;
        acc[4][lane] += di * di;
    }
    acc[3][lane] += du * du;
    acc[5][lane] += dd * dd;
    if LOAD {
        acc[6][lane] += fi * di;
    }
}

/// Rows `1..1 + LANES · blocks` of [`sums_rows`] from zero sums, for [`dispatch::run`]: block
/// by block, each of its rows into its own lane as operations on arrays of [`LANES`] (the
/// compiler does not vectorise [`sums_rows`], whose overlapping reads of rows `i` and `i + 1`
/// defeat it). Each lane's sums see the operations of [`sums_rows`] in its order: the bits are
/// the same.
struct SumsBlocks<'a, const LOAD: bool, const S_R: bool> {
    u: &'a [f64],
    z: &'a [f64],
    w: &'a [f64],
    force: &'a [f64],
    blocks: usize,
}

impl<const LOAD: bool, const S_R: bool> dispatch::Kernel for SumsBlocks<'_, LOAD, S_R> {
    type Output = Lanes;

    /// No closure in the loop (one would be compiled for the baseline only): the reads of
    /// four entries are a macro, the row an `#[inline(always)]` function.
    #[inline(always)]
    fn call(self) -> Lanes {
        let end = 1 + LANES * self.blocks;
        let (u, z, w) = (&self.u[..end + 1], &self.z[..end + 1], &self.w[..end + 1]);
        let force = if LOAD { &self.force[..end] } else { &[][..] };
        macro_rules! four {
            ($x:expr, $i:expr) => {{
                let four: [f64; LANES] = $x[$i..$i + LANES].try_into().expect("four entries");
                four
            }};
        }
        let mut acc = [[0.0; LANES]; 7];
        for i in (1..end).step_by(LANES) {
            let (zh, uh, wh) = (four!(z, i), four!(u, i), four!(w, i));
            let (za, ua, wa) = (four!(z, i + 1), four!(u, i + 1), four!(w, i + 1));
            let fh = if LOAD { four!(force, i) } else { [0.0; LANES] };
            for l in 0..LANES {
                let row = [zh[l], uh[l], wh[l], fh[l], za[l], ua[l], wa[l]];
                add_row::<LOAD, S_R>(&mut acc, l, row);
            }
        }
        acc
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::bar::kernels::energy::energy_sums;
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

    /// The blocks of four rows, dispatched (AVX where the CPU has it) and as built, give the
    /// bits of the row-by-row lanes, on data with large common parts and tiny differences, for
    /// every count of whole blocks.
    #[test]
    fn the_blocks_have_the_bits_of_the_row_by_row_lanes() {
        use dispatch::Kernel;
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
            let bits = |x: &Lanes| x.concat().iter().map(|v| v.to_bits()).collect::<Vec<_>>();
            let blocks = (n - 2) / LANES;
            let rows = 1..1 + LANES * blocks;
            let zero = [[0.0; LANES]; 7];
            let data = (&u[..], &z[..], &w[..], &f[..]);
            let (u, z, w, force) = data;
            let by_rows = [
                sums_rows::<true, true>(data, rows.clone(), zero),
                sums_rows::<true, false>(data, rows.clone(), zero),
                sums_rows::<false, true>(data, rows, zero),
            ];
            let blocked = |dispatched: bool| {
                if dispatched {
                    [
                        dispatch::run(SumsBlocks::<true, true> {
                            u,
                            z,
                            w,
                            force,
                            blocks,
                        }),
                        dispatch::run(SumsBlocks::<true, false> {
                            u,
                            z,
                            w,
                            force,
                            blocks,
                        }),
                        dispatch::run(SumsBlocks::<false, true> {
                            u,
                            z,
                            w,
                            force,
                            blocks,
                        }),
                    ]
                } else {
                    [
                        SumsBlocks::<true, true> {
                            u,
                            z,
                            w,
                            force,
                            blocks,
                        }
                        .call(),
                        SumsBlocks::<true, false> {
                            u,
                            z,
                            w,
                            force,
                            blocks,
                        }
                        .call(),
                        SumsBlocks::<false, true> {
                            u,
                            z,
                            w,
                            force,
                            blocks,
                        }
                        .call(),
                    ]
                }
            };
            for dispatched in [false, true] {
                for (p, q) in by_rows.iter().zip(&blocked(dispatched)) {
                    assert_eq!(bits(p), bits(q), "n = {n}, dispatched {dispatched}");
                }
            }
        }
    }
}
