//! VERIFICATION.md's generated tables must be what the certificate's `verify` computes now:
//! the certificate cannot drift from the code.

use viscobar_certificate::bench_table::UPDATE_COMMAND;
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
            let open = format!("<!-- generated:{id} -->\n");
            let start = doc
                .find(&open)
                .unwrap_or_else(|| panic!("{file} lacks {open}"));
            let body = &doc[start + open.len()..];
            let end = body
                .find(&format!("<!-- end:{id} -->"))
                .unwrap_or_else(|| panic!("{file}: block {id} is not closed"));
            let block = &body[..end];
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
