//! `sin`, `cos` and `exp` over a block of values, branch-free so that the loops vectorise, for
//! the compiled load loops of [`crate::scene::nodal`] only ([`crate::scene::Expression::eval`]
//! keeps the platform's functions through Rust's `std` and stays the reference).
//!
//! The algorithms and constants are fdlibm's (Sun Microsystems, 1993; as kept in FreeBSD's
//! msun: `e_rem_pio2.c`'s medium path, `k_sin.c`, `k_cos.c`, `e_exp.c`), written anew here
//! with the branches replaced by arithmetic selections. Only `f64` additions, multiplications
//! and divisions in a fixed order, never fused (Rust does not contract `a*b + c`), and integer
//! operations on the bits: the same bits on every x86-64, in a vector lane or alone, so at any
//! block split. Arguments outside the kernels' ranges (large, NaN, ±∞; `exp`'s below
//! [`EXP_ZERO`] give `+0` in the vector pass) take `std`'s value in a second pass over the
//! block. Error: at most [`MAX_ULPS`] from `std` (tests/expressions.rs
//! measures it over millions of arguments).

// fdlibm's constants as published (the nearest doubles), to be checked against the source.
#![allow(clippy::excessive_precision)]

/// Largest distance in units in the last place from `std`'s value (glibc's, correctly rounded
/// in practice): fdlibm's kernels are within 1 ulp of the exact value.
pub const MAX_ULPS: u64 = 1;

/// `1.5 · 2^52`: adding it to `|v| < 2^51` rounds `v` to the nearest integer, whose low bits
/// are then the low bits of the sum's mantissa.
const TOINT: f64 = 6_755_399_441_055_744.0;

/// Largest `|x|` reduced by [`sin`] and [`cos`]: `n = round(x·2/π) < 2^20`, so the products of
/// `n` with the 33-bit parts of `π/2` are exact (fdlibm's medium range, `|x| < 2^20·π/2`).
pub const TRIG_MAX: f64 = 1.6e6;

/// fdlibm's `invpio2`, the nearest double to `2/π`.
const INV_PIO2: f64 = std::f64::consts::FRAC_2_PI;
/// `π/2` in three 33-bit parts and the tail after them.
const PIO2_1: f64 = 1.570_796_326_734_125_614_17;
const PIO2_2: f64 = 6.077_100_506_303_965_976_60e-11;
const PIO2_3: f64 = 2.022_266_248_711_166_455_80e-21;
const PIO2_3T: f64 = 8.478_427_660_368_899_569_97e-32;

const S1: f64 = -1.666_666_666_666_663_243_48e-1;
const S2: f64 = 8.333_333_333_322_489_461_24e-3;
const S3: f64 = -1.984_126_982_985_794_931_34e-4;
const S4: f64 = 2.755_731_370_707_006_767_89e-6;
const S5: f64 = -2.505_076_025_340_686_341_95e-8;
const S6: f64 = 1.589_690_995_211_550_102_21e-10;

const C1: f64 = 4.166_666_666_666_660_190_37e-2;
const C2: f64 = -1.388_888_888_887_410_957_49e-3;
const C3: f64 = 2.480_158_728_947_672_941_78e-5;
const C4: f64 = -2.755_731_435_139_066_330_35e-7;
const C5: f64 = 2.087_572_321_298_174_827_90e-9;
const C6: f64 = -1.135_964_755_778_819_482_65e-11;

/// `x = n·π/2 + y0 + y1` with `|y0 + y1| ≤ π/4` (a little more), `|x| ≤` [`TRIG_MAX`]:
/// Cody–Waite with `π/2` in three parts (fdlibm's three rounds, done always instead of when a
/// cancellation calls for them), `n mod 4` from the rounding's bits.
#[inline(always)]
fn reduce(x: f64) -> (u64, f64, f64) {
    let shifted = x * INV_PIO2 + TOINT;
    let q = shifted.to_bits() & 3;
    let n = shifted - TOINT;
    // Exact: `n·PIO2_1` has at most 53 bits and is within a factor 2 of `x` (Sterbenz).
    let r1 = x - n * PIO2_1;
    // Each round subtracts an exact product and keeps its rounding error `e` (Fast2Sum).
    let w2 = n * PIO2_2;
    let r2 = r1 - w2;
    let e2 = (r1 - r2) - w2;
    let w3 = n * PIO2_3;
    let r = r2 - w3;
    let e3 = (r2 - r) - w3;
    // `x − n·π/2 = r + w` to about 151 bits.
    let w = (n * PIO2_3T - e3) - e2;
    let y0 = r - w;
    (q, y0, (r - y0) - w)
}

/// `sin(x + y)` for `|x + y| ≤ π/4`, `y` a correction of `x` (fdlibm's `__kernel_sin`):
/// `x + x³(S1 + x²(S2 + … + x⁸S6))`, with the tail `y` folded in to first order.
#[inline(always)]
fn kernel_sin(x: f64, y: f64) -> f64 {
    let z = x * x;
    let w = z * z;
    let r = S2 + z * (S3 + z * S4) + z * w * (S5 + z * S6);
    let v = z * x;
    x - ((z * (0.5 * y - v * r) - y) - v * S1)
}

/// `cos(x + y)` for `|x + y| ≤ π/4` (fdlibm's `__kernel_cos`): `1 − x²/2 + x⁴(C1 + … + x¹⁰C6)`
/// with `1 − x²/2` summed in two parts and the tail `−x·y`.
#[inline(always)]
fn kernel_cos(x: f64, y: f64) -> f64 {
    let z = x * x;
    let w = z * z;
    let r = z * (C1 + z * (C2 + z * C3)) + w * w * (C4 + z * (C5 + z * C6));
    let hz = 0.5 * z;
    let w = 1.0 - hz;
    w + (((1.0 - w) - hz) + (z * r - x * y))
}

/// `sin(x + k·π/2)` from the reduced `x = n·π/2 + y`: `k + n mod 4` picks `±sin y` or
/// `±cos y`, by masks on the bits.
#[inline(always)]
fn sin_quadrant(x: f64, k: u64) -> f64 {
    let (q, y0, y1) = reduce(x);
    let q = q + k;
    let (s, c) = (kernel_sin(y0, y1).to_bits(), kernel_cos(y0, y1).to_bits());
    let odd = 0u64.wrapping_sub(q & 1);
    f64::from_bits(((s & !odd) | (c & odd)) ^ ((q & 2) << 62))
}

/// Applies `kernel` to every value of `v` that is `inside`, `fallback` to the others in a
/// second pass over the block only when there are any.
#[inline(always)]
fn map(
    v: &mut [f64],
    inside: impl Fn(f64) -> bool,
    kernel: impl Fn(f64) -> f64,
    fallback: fn(f64) -> f64,
) {
    // `|` rather than `any`: no early exit, so the check vectorises.
    if v.iter().fold(false, |out, &x| out | !inside(x)) {
        v.iter_mut()
            .for_each(|x| *x = if inside(*x) { kernel(*x) } else { fallback(*x) });
    } else {
        v.iter_mut().for_each(|x| *x = kernel(*x));
    }
}

/// `v[i] = sin(v[i])`.
pub fn sin(v: &mut [f64]) {
    map(v, |x| x.abs() <= TRIG_MAX, |x| sin_quadrant(x, 0), f64::sin);
}

/// `v[i] = cos(v[i])`, as `sin(x + π/2)` with the quarter turn added exactly to the quadrant.
pub fn cos(v: &mut [f64]) {
    map(v, |x| x.abs() <= TRIG_MAX, |x| sin_quadrant(x, 1), f64::cos);
}

const LN2_HI: f64 = 6.931_471_803_691_238_164_90e-1;
const LN2_LO: f64 = 1.908_214_929_270_587_700_02e-10;
/// fdlibm's `invln2`, the nearest double to `1/ln 2`.
const INV_LN2: f64 = std::f64::consts::LOG2_E;
const P1: f64 = 1.666_666_666_666_660_190_37e-1;
const P2: f64 = -2.777_777_777_701_559_338_42e-3;
const P3: f64 = 6.613_756_321_437_934_361_17e-5;
const P4: f64 = -1.653_390_220_546_525_153_90e-6;
const P5: f64 = 4.138_136_797_057_238_460_39e-8;

/// Range of [`exp`]'s kernel: the result is a normal number, `2^k` with `−1021 ≤ k ≤ 1023`
/// built from its exponent bits; beyond it (subnormal, ∞) `std` takes over.
pub const EXP_MIN: f64 = -708.0;
pub const EXP_MAX: f64 = 709.0;
/// Below it `e^x` rounds to `+0` (`e^x < 2^−1075` from `x < −745.14`): selected in the
/// vector pass, as a load `exp(−(x − t)²)` far from its centre gives it at every node.
pub const EXP_ZERO: f64 = -746.0;

/// `e^x = 2^k e^r`, `k = round(x/ln 2)`, `r = x − k·ln2_hi − k·ln2_lo` (`ln2_hi` has 32 bits,
/// so `k·ln2_hi` is exact), `|r| ≤ ln2/2`; `e^r = 1 + r + r·c/(2 − c)` with
/// `c = r − r²(P1 + … + r⁸P5)` (fdlibm's `e_exp.c`, a Remez fit of `r(e^r+1)/(e^r−1)`).
#[inline(always)]
fn exp_kernel(x: f64) -> f64 {
    let shifted = x * INV_LN2 + TOINT;
    let k = shifted.to_bits().wrapping_sub(TOINT.to_bits());
    let kf = shifted - TOINT;
    let hi = x - kf * LN2_HI;
    let lo = kf * LN2_LO;
    let r = hi - lo;
    let t = r * r;
    let c = r - t * (P1 + t * (P2 + t * (P3 + t * (P4 + t * P5))));
    let y = 1.0 - ((lo - (r * c) / (2.0 - c)) - hi);
    y * f64::from_bits(k.wrapping_add(1023) << 52)
}

/// `v[i] = e^{v[i]}`.
pub fn exp(v: &mut [f64]) {
    map(
        v,
        |x| (EXP_MIN..=EXP_MAX).contains(&x) || x < EXP_ZERO,
        |x| {
            let y = exp_kernel(x.max(EXP_MIN));
            if x < EXP_ZERO { 0.0 } else { y }
        },
        f64::exp,
    );
}
