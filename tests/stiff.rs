//! The stiff and extreme case matrix in reduced size (meshes up to 1e5 elements, drift runs of 1e5
//! steps; the full matrix is `cargo run --release -p viscobar-certificate -- verify --stiff`):
//! every case finite, within its round-off tolerances, or stopped with an error naming its step.
//! The exact solver must complete every case but the overflowing ones, which every solver must
//! refuse.

use viscobar_certificate::bar::stiff::{Family, Size, cases, verdict};
use viscobar_certificate::bar::stiff_runs::run_case;

#[test]
fn every_stiff_case_is_correct_or_reported() {
    let list = cases(Size::Reduced);
    assert!(list.len() >= 40, "the issue asks for at least 40 cases");
    let mut failures = Vec::new();
    for case in &list {
        let result = run_case(case);
        for run in &result.runs {
            if let Some(why) = verdict(&result, run) {
                failures.push(format!("{} / {}: {why}", case.id(), run.solver));
            }
        }
    }
    assert!(failures.is_empty(), "{}", failures.join("\n"));
}

/// The independent probe found OSQP reporting "solved" far from the solution at α = 1e6,
/// Δt = 100 Δx (κ(C) ≈ 4.1e9): viscobar's audit must turn that into an error naming the step.
#[test]
fn osqp_at_alpha_1e6_dt_100_dx_is_reported_as_a_failure() {
    let case = cases(Size::Reduced)
        .into_iter()
        .find(|c| c.family == Family::Impact && c.alpha == 1e6 && c.ratio == 100.0)
        .expect("case in the matrix");
    let result = run_case(&case);
    let kappa = result.kappa.expect("C is SPD");
    // Same order as the independent figure 4.1e9 (measured 4.2e9 on 20 elements).
    assert!((1e9..1e10).contains(&kappa), "cond(C) = {kappa:e}");
    let osqp = result.runs.iter().find(|r| r.solver == "osqp").unwrap();
    let error = osqp.error.as_deref().expect("OSQP must not pass here");
    assert!(error.starts_with("error at step "), "{error}");
    // Stopped by the audit (OSQP says "solved" or runs out of iterations nearby).
    assert!(error.contains("audit"), "{error}");
}

/// Overflowing data: every solver stops with a non-finite or status error at step 1, never a
/// NaN in the output.
#[test]
fn overflowing_forcing_stops_every_solver_at_its_first_step() {
    for case in cases(Size::Reduced)
        .into_iter()
        .filter(|c| c.family == Family::Overflow)
    {
        let result = run_case(&case);
        for run in &result.runs {
            let e = run.error.as_deref().unwrap_or("completed");
            assert!(
                e.starts_with("error at step 1:"),
                "{} / {}: {e}",
                case.id(),
                run.solver
            );
        }
    }
}
