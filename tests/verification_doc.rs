//! VERIFICATION.md's generated tables must be what the certificate's `verify` computes now:
//! the certificate cannot drift from the code.

use viscobar_certificate::performance::bench_compare::{COMPARE_COMMAND, RATIO_LIMIT};
use viscobar_certificate::performance::bench_table::UPDATE_COMMAND;
use viscobar_certificate::verify;

#[test]
fn verification_md_tables_are_current() {
    let doc =
        std::fs::read_to_string(concat!(env!("CARGO_MANIFEST_DIR"), "/VERIFICATION.md")).unwrap();
    let sections = verify::sections().unwrap();
    let regenerated = verify::update_document(&doc, &sections).unwrap();
    assert!(
        regenerated == doc,
        "VERIFICATION.md is out of date: run `cargo run --release -p viscobar-certificate -- \
         verify --update VERIFICATION.md` and review the change"
    );
}

/// The text between `<!-- generated:{id} -->` and `<!-- end:{id} -->` in `doc` (of `file`).
fn generated_block<'a>(doc: &'a str, file: &str, id: &str) -> &'a str {
    let open = format!("<!-- generated:{id} -->\n");
    let start = doc
        .find(&open)
        .unwrap_or_else(|| panic!("{file} lacks {open}"));
    let body = &doc[start + open.len()..];
    let end = body
        .find(&format!("<!-- end:{id} -->"))
        .unwrap_or_else(|| panic!("{file}: block {id} is not closed"));
    &body[..end]
}

/// The timings the READMEs quote are criterion's, written by `bench-table --update` with their
/// dates (they cannot be recomputed here, unlike the tables above): each block is present,
/// filled and stamped with its provenance (the command that writes it), and nothing outside
/// them is typed in its place.
#[test]
fn readme_timings_are_written_by_bench_table() {
    for (file, ids) in [
        ("README.md", &["bench-headline"][..]),
        ("benches/README.md", &["bench-headline", "bench-table"][..]),
    ] {
        let path = format!("{}/{file}", env!("CARGO_MANIFEST_DIR"));
        let doc = std::fs::read_to_string(&path).unwrap();
        for id in ids {
            let block = generated_block(&doc, file, id);
            assert!(
                block.starts_with("Criterion medians measured ")
                    && block.contains(&format!("written by `{UPDATE_COMMAND}`")),
                "{file}: block {id} was not written by `{UPDATE_COMMAND}`"
            );
            assert!(
                block.contains("target <="),
                "{file}: block {id} has no targets"
            );
        }
    }
}

/// The side-by-side comparison with the code before and the twins' factors in benches/README.md
/// are written by `bench-compare --update` (the comparison with its verdict against the
/// limit, its dates, machine and commands), not typed.
#[test]
fn bench_comparisons_are_written_by_bench_compare() {
    let path = concat!(env!("CARGO_MANIFEST_DIR"), "/benches/README.md");
    let doc = std::fs::read_to_string(path).unwrap();
    for (id, must_hold) in [
        (
            "bench-compare",
            format!("Limit: every step within {RATIO_LIMIT}x of "),
        ),
        ("bench-twins", "| twin | plain version | step |".to_string()),
    ] {
        let block = generated_block(&doc, "benches/README.md", id);
        assert!(
            block.starts_with("Criterion medians measured ")
                && block.contains(&format!("written by `{COMPARE_COMMAND}"))
                && block.contains("UTC on "),
            "benches/README.md: block {id} was not written by `{COMPARE_COMMAND}`"
        );
        assert!(
            block.contains(&must_hold),
            "benches/README.md: block {id} lacks `{must_hold}`"
        );
    }
}
