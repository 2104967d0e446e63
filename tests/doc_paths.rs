//! Every repository path the documents and comments name exists: the Markdown files, the
//! Cargo.toml files and the comments of the Rust sources (library, certificate, tests, benches,
//! examples, Python package) are scanned for words shaped like a path to a file under one of the
//! repository's folders (`src/…/….rs`, `docs/….md`, `scripts/….sh`, …), and each must resolve
//! from the repository root, the crate of the file that names it, or that file's folder.

use std::path::{Path, PathBuf};

/// The folders a repository path starts with (a member crate's own `src/`, `tests/` too).
const ROOTS: [&str; 11] = [
    "src",
    "tests",
    "benches",
    "docs",
    "scripts",
    "examples",
    "certificate",
    "python",
    "scenes",
    "snapshots",
    "proptest-regressions",
];

/// The endings of a path to a file (a folder, or a pattern such as `tests/*.rs`, is no file).
const EXTENSIONS: [&str; 11] = [
    "rs", "md", "toml", "sh", "py", "pyi", "json", "yaml", "yml", "snap", "svg",
];

/// Folders never scanned: build output, version control, virtual environments.
const SKIPPED: [&str; 5] = ["target", ".git", "venv", ".venv", "__pycache__"];

/// A path named in `file` at `line` that does not exist.
#[derive(Debug, PartialEq)]
struct Missing {
    file: String,
    line: usize,
    path: String,
}

/// Whether `c` can be part of a path word.
fn is_path_char(c: char) -> bool {
    c.is_ascii_alphanumeric() || matches!(c, '_' | '-' | '.' | '/')
}

/// The path-shaped words of `text`: a maximal run of path characters that starts with one of
/// [`ROOTS`] (or `./`, `../` before one) and ends with one of [`EXTENSIONS`].
fn path_words(text: &str) -> Vec<&str> {
    text.split(|c: char| !is_path_char(c))
        .map(|w| w.trim_end_matches(['.', '/']))
        .filter(|w| {
            let bare = w.trim_start_matches("./").trim_start_matches("../");
            let root = bare.split('/').next().unwrap_or("");
            let extension = bare.rsplit_once('.').map_or("", |(_, e)| e);
            bare.contains('/') && ROOTS.contains(&root) && EXTENSIONS.contains(&extension)
        })
        .collect()
}

/// The part of a Rust line that is a comment (doc comments included), or `None`.
fn rust_comment(line: &str) -> Option<&str> {
    line.find("//").map(|at| &line[at + 2..])
}

/// The missing paths named in `text` (the contents of `file`, relative to the repository
/// root), scanning comments only when `comments_only`; `exists` says whether a path relative to
/// the root exists.
fn missing_in(
    file: &str,
    text: &str,
    comments_only: bool,
    exists: &dyn Fn(&Path) -> bool,
) -> Vec<Missing> {
    let file_path = Path::new(file);
    let folder = file_path.parent().unwrap_or(Path::new(""));
    // A member crate's own paths (`src/lib.rs` in certificate/) resolve from its folder.
    let krate = ["certificate", "python"]
        .into_iter()
        .find(|member| file.starts_with(&format!("{member}/")))
        .map_or(PathBuf::new(), PathBuf::from);
    let mut missing = Vec::new();
    for (index, line) in text.lines().enumerate() {
        let Some(scanned) = (if comments_only {
            rust_comment(line)
        } else {
            Some(line)
        }) else {
            continue;
        };
        for word in path_words(scanned) {
            let relative = word.trim_start_matches("./");
            let found = [
                PathBuf::from(relative),
                krate.join(relative),
                folder.join(relative),
            ]
            .iter()
            .any(|p| exists(&normalise(p)));
            if !found {
                missing.push(Missing {
                    file: file.to_string(),
                    line: index + 1,
                    path: word.to_string(),
                });
            }
        }
    }
    missing
}

/// `path` with its `..` components applied; one that climbs above the root keeps its `..`
/// (and so names nothing in the repository).
fn normalise(path: &Path) -> PathBuf {
    let mut out = PathBuf::new();
    for part in path.components() {
        match part {
            std::path::Component::ParentDir => {
                let last = out.components().next_back();
                if matches!(last, None | Some(std::path::Component::ParentDir)) {
                    out.push("..");
                } else {
                    out.pop();
                }
            }
            std::path::Component::CurDir => {}
            other => out.push(other),
        }
    }
    out
}

/// The files scanned, relative to `root`, each with whether only its comments are read.
fn scanned_files(root: &Path) -> Vec<(String, bool)> {
    let mut files = Vec::new();
    let mut folders = vec![PathBuf::new()];
    while let Some(folder) = folders.pop() {
        let mut entries: Vec<_> = std::fs::read_dir(root.join(&folder))
            .expect("readable folder")
            .map(|e| e.expect("readable entry"))
            .collect();
        entries.sort_by_key(|e| e.file_name());
        for entry in entries {
            let name = entry.file_name().to_string_lossy().into_owned();
            let relative = folder.join(&name);
            if entry.file_type().expect("file type").is_dir() {
                if !SKIPPED.contains(&name.as_str()) && !name.starts_with('.') {
                    folders.push(relative);
                }
            } else if name.ends_with(".md") || name == "Cargo.toml" {
                files.push((relative.to_string_lossy().into_owned(), false));
            } else if name.ends_with(".rs") {
                files.push((relative.to_string_lossy().into_owned(), true));
            }
        }
    }
    files
}

#[test]
fn every_path_the_documents_and_comments_name_exists() {
    let root = Path::new(env!("CARGO_MANIFEST_DIR"));
    let files = scanned_files(root);
    // The scan reaches each kind of file it is meant to read.
    for expected in [
        "README.md",
        "docs/sparse-cholesky.md",
        "Cargo.toml",
        "src/lib.rs",
    ] {
        assert!(
            files.iter().any(|(f, _)| f == expected),
            "{expected} not scanned"
        );
    }
    let exists = |p: &Path| root.join(p).is_file();
    let mut missing = Vec::new();
    for (file, comments_only) in &files {
        let text = std::fs::read_to_string(root.join(file)).expect("readable file");
        missing.extend(missing_in(file, &text, *comments_only, &exists));
    }
    let report: Vec<String> = missing
        .iter()
        .map(|m| format!("{}:{}: {}", m.file, m.line, m.path))
        .collect();
    assert!(
        report.is_empty(),
        "paths that do not exist:\n{}",
        report.join("\n")
    );
}

/// The scanner finds a fabricated missing path in prose, in a Rust comment and behind `../`,
/// and passes existing ones, code outside comments, folders and patterns.
#[test]
fn the_scanner_reports_a_fabricated_missing_path() {
    let exists = |p: &Path| p == Path::new("src/lib.rs") || p == Path::new("docs/a.md");
    let prose = "See `src/lib.rs` and src/nowhere/missing.rs; tests/*.rs, docs/ and \
                 [a](../docs/a.md), [b](../docs/b.md).";
    let found = missing_in("benches/README.md", prose, false, &exists);
    let paths: Vec<&str> = found.iter().map(|m| m.path.as_str()).collect();
    assert_eq!(paths, ["src/nowhere/missing.rs", "../docs/b.md"]);
    assert_eq!(found[0].line, 1);

    // Assembled, so that this file's own scan does not read the fabricated path.
    let rust = [
        "let p = \"src/gone.rs\";\n/// Derived in docs/",
        "gone.md.\nfn f() {} // src/lib.rs",
    ]
    .concat();
    let found = missing_in("src/x.rs", &rust, true, &exists);
    assert_eq!(
        found,
        [Missing {
            file: "src/x.rs".into(),
            line: 2,
            path: "docs/gone.md".into(),
        }]
    );

    // `../` climbs from the naming file's folder, never above the root.
    let link = ["//! [d](../docs/", "a.md), [e](../../docs/", "a.md)"].concat();
    let found = missing_in("src/step/x.rs", &link, true, &exists);
    let paths: Vec<&str> = found.iter().map(|m| m.path.as_str()).collect();
    assert_eq!(paths, ["../docs/a.md"]);
    assert_eq!(
        normalise(Path::new("../../docs/a.md")),
        Path::new("../../docs/a.md")
    );

    // A member crate's `src/` resolves from the member's folder.
    let exists = |p: &Path| p == Path::new("certificate/src/main.rs");
    assert!(missing_in("certificate/src/lib.rs", "// src/main.rs", true, &exists).is_empty());
    assert_eq!(
        missing_in("src/lib.rs", "// src/main.rs", true, &exists).len(),
        1
    );
}
