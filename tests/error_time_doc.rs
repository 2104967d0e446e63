//! VERIFICATION.md, "Error against run time": its error block must be what the code computes
//! now. The whole study (OSQP at 800–1024 elements, three timing repeats) takes minutes and runs
//! behind `viscobar-certificate verify --timings`; this test recomputes the cheap part, the
//! exact solver and the penalty settings on every scene, with the reference run and its
//! estimated error, and finds each of their lines in the block (the OSQP rows are checked only
//! by rerunning the command). The timing block is machine-dependent and not checked.

use viscobar::study::converge::{SolverSetting, StudyOptions, study_with};
use viscobar_certificate::performance::timings::{CASES, ERRORS_ID, errors_markdown, settings_for};

#[test]
fn error_against_run_time_error_rows_of_exact_and_penalty_are_current() {
    let doc =
        std::fs::read_to_string(concat!(env!("CARGO_MANIFEST_DIR"), "/VERIFICATION.md")).unwrap();
    let open = format!("<!-- generated:{ERRORS_ID} -->\n");
    let close = format!("<!-- end:{ERRORS_ID} -->");
    let a = doc.find(&open).expect("error block opens") + open.len();
    let b = a + doc[a..].find(&close).expect("error block closes");
    let block: Vec<&str> = doc[a..b].lines().collect();
    let mut checked = 0;
    for case in CASES {
        let overrides: Vec<String> = case.overrides.iter().map(|s| s.to_string()).collect();
        let (_, base) = viscobar::scene::load(case.scene, &overrides).unwrap();
        let settings: Vec<SolverSetting> = settings_for(&base)
            .into_iter()
            .filter(|s| !matches!(s, SolverSetting::Osqp(_)))
            .collect();
        let mut options = StudyOptions::new(case.levels, None);
        options.repeats = 0;
        let study = study_with(case.scene, &base, &settings, &options).unwrap();
        for line in errors_markdown(&study).lines().filter(|l| !l.is_empty()) {
            assert!(
                block.contains(&line),
                "VERIFICATION.md's error block lacks (or has another value for)\n{line}\n\
                 run `cargo run --release -p viscobar-certificate -- verify --timings --update \
                 VERIFICATION.md --figures docs/figures` and review the change"
            );
            checked += 1;
        }
    }
    // Headers and rows of five scenes: a block that lost its rows cannot pass.
    assert!(checked > 5 * 10, "{checked} lines checked");
}
