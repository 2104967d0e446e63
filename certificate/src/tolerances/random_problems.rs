//! Random SPD tridiagonal step problems: the tests' seeded data stream and sampler, the KKT
//! residual and its per-case round-off bound, the a-posteriori distance of an answer to the
//! minimiser (checked against the dense oracle), and their worst values over seeded samples of
//! the proptests' distributions (`tests/active_set.rs`, `osqp_many_bounds.rs`,
//! `exact_solver.rs`).

use super::exact_sample_error;
use viscobar::internals::linalg::tridiag::SymTridiag;
use viscobar::scheme::RunError;

// ---- proptests on random SPD tridiagonal problems: tests/active_set.rs, osqp_many_bounds.rs ----

/// xorshift64: reproducible data from one seed (the tests' `common::stream`, which the
/// registry's seeded samples share).
pub fn stream(seed: u64) -> impl FnMut() -> f64 {
    let mut x = seed | 1;
    move || {
        x ^= x << 13;
        x ^= x >> 7;
        x ^= x << 17;
        (x >> 11) as f64 / (1u64 << 53) as f64
    }
}

/// The tests' `common::spd_tridiag(max_n)` distribution drawn from `rnd`: size `2..=max_n`,
/// off-diagonals in (−1, 1), diagonal-dominance margins in `[MIN_MARGIN, MAX_MARGIN)`.
pub fn sample_spd_tridiag(max_n: usize, rnd: &mut impl FnMut() -> f64) -> SymTridiag {
    use crate::solvers::agreement::{MAX_MARGIN, MIN_MARGIN, diagonally_dominant};
    let n = 2 + ((rnd() * (max_n - 1) as f64) as usize).min(max_n - 2);
    let off: Vec<f64> = (0..n - 1).map(|_| 2.0 * rnd() - 1.0).collect();
    let margin: Vec<f64> = (0..n)
        .map(|_| MIN_MARGIN + (MAX_MARGIN - MIN_MARGIN) * rnd())
        .collect();
    diagonally_dominant(off, &margin)
}

/// The worst KKT residual of `(z, r)` for `min ½zᵀCz − bᵀz, z_j >= lo_j (j in nodes)`,
/// relative to the data: stationarity `‖Cz − b − Σ r_j e_j‖∞`, feasibility, sign and
/// complementarity, over `1 + max(‖b‖∞, ‖lo‖∞, ‖z‖∞)`.
pub fn kkt(c: &SymTridiag, b: &[f64], nodes: &[usize], lo: &[f64], z: &[f64], r: &[f64]) -> f64 {
    use viscobar::internals::linalg::norms::max_abs;
    let scale = 1.0 + max_abs(b).max(max_abs(lo)).max(max_abs(z));
    let mut rho = c.mul(z);
    for (ri, bi) in rho.iter_mut().zip(b) {
        *ri -= bi;
    }
    for (&i, rj) in nodes.iter().zip(r) {
        rho[i] -= rj;
    }
    let mut worst = max_abs(&rho);
    for (j, &i) in nodes.iter().enumerate() {
        let g = z[i] - lo[j];
        worst = worst.max(-g).max(-r[j]).max((g * r[j]).abs() / scale);
    }
    worst / scale
}

/// The exact many-bound solver's KKT residual in units of `ε` times the problem's own scales:
/// it accepts an active set whose clamped reactions and free gaps are negative by up to
/// `TIE_ULPS ε` of `‖C‖∞‖z‖∞ + ‖b‖∞` and of `max(‖z‖∞, ‖lo‖∞)` (`step::block_pivot`), and its
/// free rows are an LDLᵀ solve of `C_FF z_F = b_F − C_FA lo_A`, backward stable with
/// `|ΔC| ≤ 4u|C|` (`|L||D||Lᵀ| = |C|` on SPD tridiagonal matrices, Higham Thm 9.14) after `γ₂`
/// in its right side; the reactions are rounded rows of `Cz − b` (`γ₃`) and recomputing
/// `Cz − b − r` here adds `γ₄`: `TIE_ULPS + 6.5` ulps, rounded up.
pub const KKT_ULPS: f64 = viscobar::internals::step::block_pivot::TIE_ULPS + 8.0;

/// [`kkt`] over its per-case bound: `KKT_ULPS ε` times `‖C‖∞‖z‖∞ + ‖b‖∞ + ‖r‖∞` (stationarity,
/// clamped reactions) and times `max(‖z‖∞, ‖lo‖∞)` (a free gap), over `kkt`'s scale. The
/// proptests assert it is at most 1 (they asserted `kkt <= 1e-9` before).
pub fn kkt_ratio(
    c: &SymTridiag,
    b: &[f64],
    nodes: &[usize],
    lo: &[f64],
    z: &[f64],
    r: &[f64],
) -> f64 {
    use viscobar::internals::linalg::norms::max_abs;
    let scale = 1.0 + max_abs(b).max(max_abs(lo)).max(max_abs(z));
    let data =
        (c.inf_norm() * max_abs(z) + max_abs(b) + max_abs(r)).max(max_abs(z).max(max_abs(lo)));
    let bound = KKT_ULPS * f64::EPSILON * data / scale;
    let value = kkt(c, b, nodes, lo, z, r);
    if value == 0.0 { 0.0 } else { value / bound }
}

/// Cases of the seeded samples of the proptests' distributions.
pub const KKT_SAMPLE_CASES: usize = 200;

/// The worst [`kkt_ratio`] and the worst [`kkt`] of the exact many-bound solver over a seeded
/// sample of the distributions of `tests/active_set.rs`'s `large_problems_satisfy_kkt` (n up to
/// 3000, every node bounded) and `tests/osqp_many_bounds.rs` (n up to 400, every node or a
/// random half, two problems in a row: the second warm-started).
pub fn random_kkt_worst() -> Result<(f64, f64), RunError> {
    use viscobar::internals::step::block_pivot::BlockPivoting;
    use viscobar::step::StepSolver;
    let mut rnd = stream(2026);
    let (mut ratio, mut worst) = (0.0f64, 0.0f64);
    for case in 0..KKT_SAMPLE_CASES {
        let large = case % 4 == 0;
        let c = sample_spd_tridiag(if large { 3000 } else { 400 }, &mut rnd);
        let n = c.dim();
        let every_node = large || case % 2 == 1;
        let nodes: Vec<usize> = (0..n).filter(|_| every_node || rnd() < 0.5).collect();
        let k = nodes.len();
        let mut solver = BlockPivoting::new(&c, &nodes)?;
        for _ in 0..if large { 1 } else { 2 } {
            let b: Vec<f64> = (0..n).map(|_| 4.0 * rnd() - 2.0).collect();
            let lo: Vec<f64> = (0..k).map(|_| 2.0 * rnd() - 1.0).collect();
            let (mut z, mut r) = (vec![0.0; n], vec![0.0; k]);
            solver
                .solve(&b, &lo, &mut z, &mut r)
                .map_err(exact_sample_error(case))?;
            ratio = ratio.max(kkt_ratio(&c, &b, &nodes, &lo, &z, &r));
            worst = worst.max(kkt(&c, &b, &nodes, &lo, &z, &r));
        }
    }
    Ok((ratio, worst))
}

// ---- tests/exact_solver.rs: the exact solver against the dense brute-force oracle -------------

/// Feasibility slack with which the dense oracle accepts a candidate active set (its dense LU
/// rounds the gaps of the right set to about `ε (1 + ‖z‖∞)`): a selection threshold, not a
/// check; whatever infeasibility it lets through enters [`oracle_distance_bound`].
pub const ORACLE_FEASIBILITY_SLACK: f64 = 1e-9;

/// Roundings in a computed stationarity entry `(Cz)_i − b_i − r_j` of a tridiagonal row: three
/// products, four additions (Higham, *Accuracy and Stability*, Lemma 3.1: `γ₇`, rounded up).
pub const RESIDUAL_ENTRY_ROUNDINGS: f64 = 8.0;

/// An a-posteriori bound on the distance of an approximate KKT point `(z, r)` of
/// `min ½ zᵀCz − bᵀz, z[nodes[j]] >= lo[j]` (`C` SPD) to the exact minimiser `(z*, r*)`, from
/// its own residuals only: no active set, no κ, no a-priori size.
///
/// Derivation. With `ρ = Cz − b − Eᵀ… r` (E the bound columns), `g = Eᵀz − lo`, `d = z − z*`
/// and `Cz* − b = E r*`, `r* >= 0`, `g* >= 0`, `r*·g* = 0`:
/// `dᵀCd = dᵀρ + (r − r*)·(g − g*) = dᵀρ + r·g − r·g* − r*·g`. With `g* = g − Eᵀd` and
/// `r*_j = ρ_{n_j} + r_j − (Cd)_{n_j}` (every bound's node, active or not), the negative parts
/// `g⁻ = max(0, −g)`, `r⁻ = max(0, −r)` give
/// `λ‖d‖² <= β‖d‖ + γ`, `β = ‖ρ‖₂ + ‖C‖₂‖g⁻‖₁ + ‖r⁻‖₁`,
/// `γ = max(0, r·g) + Σ g⁻_j |ρ_{n_j} + r_j| + Σ r⁻_j |g_j|`, so
/// `‖d‖₂ <= (β + √(β² + 4λγ)) / (2λ)` with `λ` a lower bound on `λ_min(C)`; and
/// `|r_j − r*_j| <= |ρ_{n_j}| + ‖C‖₂ ‖d‖₂`. `ρ` is the computed residual plus its rounding
/// (`RESIDUAL_ENTRY_ROUNDINGS · u · (|C||z| + |b| + |r|)` entrywise); `‖C‖₂ <= ‖C‖∞`; `λ` is
/// the bisection's smallest eigenvalue less its error bound
/// ([`viscobar::internals::linalg::spectrum::reference::STURM_ERROR_ULPS`] `ε ‖C‖∞`). For an exactly
/// feasible, complementary answer (`g, r >= 0`, `r·g = 0`) it is the classic `‖ρ‖₂ / λ_min`.
/// Returns the bound on `‖d‖₂` and the bounds on `|r_j − r*_j|`; infinite when `λ <= 0`.
pub fn oracle_distance_bound(
    c: &SymTridiag,
    b: &[f64],
    nodes: &[usize],
    lo: &[f64],
    z: &[f64],
    r: &[f64],
) -> (f64, Vec<f64>) {
    let n = c.dim();
    let u = f64::EPSILON / 2.0;
    let mut rho = c.mul(z);
    let mut size: Vec<f64> = (0..n)
        .map(|i| {
            let mut s = c.diag[i].abs() * z[i].abs() + b[i].abs();
            if i > 0 {
                s += c.off[i - 1].abs() * z[i - 1].abs();
            }
            if i + 1 < n {
                s += c.off[i].abs() * z[i + 1].abs();
            }
            s
        })
        .collect();
    for (ri, bi) in rho.iter_mut().zip(b) {
        *ri -= bi;
    }
    for (&node, rj) in nodes.iter().zip(r) {
        rho[node] -= rj;
        size[node] += rj.abs();
    }
    // |ρ| entrywise, with the rounding of its computation.
    let rho_abs: Vec<f64> = rho
        .iter()
        .zip(&size)
        .map(|(x, s)| x.abs() + RESIDUAL_ENTRY_ROUNDINGS * u * s)
        .collect();
    let c_norm = c.inf_norm();
    let lambda = viscobar::internals::linalg::spectrum::smallest_eigenvalue_spd(c)
        - viscobar::internals::linalg::spectrum::reference::STURM_ERROR_ULPS
            * f64::EPSILON
            * c_norm;
    if lambda <= 0.0 || !lambda.is_finite() {
        return (f64::INFINITY, vec![f64::INFINITY; nodes.len()]);
    }
    let rho_norm = rho_abs.iter().map(|x| x * x).sum::<f64>().sqrt();
    let (mut g_minus, mut r_minus, mut rg, mut gamma_rest) = (0.0, 0.0, 0.0, 0.0);
    for (j, &node) in nodes.iter().enumerate() {
        let g = z[node] - lo[j];
        let gm = (-g).max(0.0);
        let rm = (-r[j]).max(0.0);
        g_minus += gm;
        r_minus += rm;
        rg += r[j] * g;
        // |ρ_{n_j} + r_j| <= |ρ_{n_j}| + |r_j|.
        gamma_rest += gm * (rho_abs[node] + r[j].abs()) + rm * g.abs();
    }
    let beta = rho_norm + c_norm * g_minus + r_minus;
    let gamma = rg.max(0.0) + gamma_rest;
    let d = (beta + (beta * beta + 4.0 * lambda * gamma).sqrt()) / (2.0 * lambda);
    let reactions = nodes
        .iter()
        .map(|&node| rho_abs[node] + c_norm * d)
        .collect();
    (d, reactions)
}

/// What the exact solver's agreement with the dense brute-force oracle is held to, for its
/// `(z, r)` on one problem (`tests/exact_solver.rs`, and `tests/active_set.rs`'s small
/// problems for the many-bound solver): the largest of `‖z − z_o‖∞` over the sum of the two
/// answers' [`oracle_distance_bound`]s and `|r_j − r_o,j|` over the sum of theirs (both are
/// within their bound of the one minimiser). At most 1 whenever both bounds hold, so it checks
/// the bound's implementation and the oracle, not the solver: the solver's answer is held by
/// its KKT residuals ([`kkt_ratio`]), which the bound turns into a distance. Infinite when the
/// oracle finds no feasible active set.
pub fn oracle_agreement(
    c: &SymTridiag,
    b: &[f64],
    nodes: &[usize],
    lower: &[f64],
    z: &[f64],
    r: &[f64],
) -> f64 {
    let zscale = 1.0 + viscobar::internals::linalg::norms::max_abs(z);
    let Ok(Some(oracle)) = crate::solvers::oracle::brute_force(
        &c.to_dense(),
        b,
        nodes,
        lower,
        ORACLE_FEASIBILITY_SLACK * zscale,
    ) else {
        return f64::INFINITY;
    };
    let (dz, dr) = oracle_distance_bound(c, b, nodes, lower, z, r);
    let (oz, or) = oracle_distance_bound(c, b, nodes, lower, &oracle.z, &oracle.reactions);
    let ratio = |v: f64, bound: f64| if v == 0.0 { 0.0 } else { v / bound };
    let mut worst = 0.0f64;
    for (zi, oi) in z.iter().zip(&oracle.z) {
        worst = worst.max(ratio((zi - oi).abs(), dz + oz));
    }
    for (j, (rj, oj)) in r.iter().zip(&oracle.reactions).enumerate() {
        worst = worst.max(ratio((rj - oj).abs(), dr[j] + or[j]));
    }
    worst
}

/// The worst of [`oracle_agreement`] and [`kkt_ratio`] of the exact solver over a seeded sample of
/// `tests/exact_solver.rs`'s distribution: n up to 23, no bound, either end or both, two
/// problems in a row (the second `s b` with bounds moved by `t`: warm-started).
pub fn oracle_agreement_worst() -> Result<f64, RunError> {
    use viscobar::internals::step::end_enumeration::EndEnumeration;
    use viscobar::step::StepSolver;
    let mut rnd = stream(22);
    let mut worst = 0.0f64;
    for case in 0..KKT_SAMPLE_CASES * 5 {
        let c = sample_spd_tridiag(23, &mut rnd);
        let n = c.dim();
        let b: Vec<f64> = (0..n).map(|_| 10.0 * rnd() - 5.0).collect();
        let nodes: Vec<usize> = match case % 4 {
            0 => vec![],
            1 => vec![0],
            2 => vec![n - 1],
            _ => vec![0, n - 1],
        };
        let lower: Vec<f64> = nodes.iter().map(|_| 4.0 * rnd() - 2.0).collect();
        let (s, t) = (0.5 + rnd(), 0.4 * rnd() - 0.2);
        let mut solver = EndEnumeration::new(&c, &nodes)?;
        let (mut z, mut r) = (vec![0.0; n], vec![0.0; nodes.len()]);
        let b2: Vec<f64> = b.iter().map(|v| s * v).collect();
        let lower2: Vec<f64> = lower.iter().map(|v| v + t).collect();
        for (bb, ll) in [(&b, &lower), (&b2, &lower2)] {
            solver
                .solve(bb, ll, &mut z, &mut r)
                .map_err(exact_sample_error(case))?;
            worst = worst
                .max(oracle_agreement(&c, bb, &nodes, ll, &z, &r))
                .max(kkt_ratio(&c, bb, &nodes, ll, &z, &r));
        }
    }
    Ok(worst)
}
