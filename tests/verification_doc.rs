//! VERIFICATION.md's generated tables must be what `viscobar verify` computes now: the
//! certificate cannot drift from the code.

#[test]
fn verification_md_tables_are_current() {
    let doc =
        std::fs::read_to_string(concat!(env!("CARGO_MANIFEST_DIR"), "/VERIFICATION.md")).unwrap();
    let sections = viscobar::study::verify::sections().unwrap();
    let regenerated = viscobar::study::verify::update_document(&doc, &sections).unwrap();
    assert!(
        regenerated == doc,
        "VERIFICATION.md is out of date: run `cargo run --release -- verify --update VERIFICATION.md` \
         and review the change"
    );
}
