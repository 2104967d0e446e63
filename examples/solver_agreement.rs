//! The figures of VERIFICATION.md, section "Step solvers" (`viscobar_certificate::agreement`), printed as
//! Markdown; `viscobar verify --update VERIFICATION.md` writes the same text into the document.
//!
//!     cargo run --release --example solver_agreement

fn main() {
    match viscobar_certificate::agreement::markdown() {
        Ok(md) => print!("{md}"),
        Err(e) => {
            eprintln!("error: {e}");
            std::process::exit(e.exit_code());
        }
    }
}
