//! The layer rule of `src/`: each folder is a layer, and a file may import only from its own
//! layer or from layers below it, in the order of [`LAYERS`]; inside the library no two files
//! import each other, directly or through a longer loop.
//!
//! The check reads the source as text: every `crate::…` path in code (use lines, inline paths;
//! comments and doc links excluded) outside `#[cfg(test)]` items, whose test-only imports are
//! not dependencies of the library.

use std::collections::{BTreeMap, BTreeSet};
use std::path::Path;

/// The layers, bottom first.
const LAYERS: [&str; 9] = [
    "linalg", "step", "scene", "scheme", "bar", "thermal", "plane", "output", "study",
];

/// A source file: its layer, its module name inside the layer (`mod` for `mod.rs`) and its text.
struct Source {
    layer: String,
    module: String,
    text: String,
}

fn sources(root: &Path) -> Vec<Source> {
    let mut out = Vec::new();
    for layer in std::fs::read_dir(root).unwrap() {
        let layer = layer.unwrap().path();
        if !layer.is_dir() {
            continue;
        }
        let name = layer.file_name().unwrap().to_string_lossy().to_string();
        let mut files: Vec<_> = std::fs::read_dir(&layer)
            .unwrap()
            .map(|e| e.unwrap().path())
            .collect();
        files.sort();
        for file in files {
            // A folder inside a layer is one module of it (`kernels/`), its files its parts.
            let (module, parts) = if file.is_dir() {
                let mut parts: Vec<_> = std::fs::read_dir(&file)
                    .unwrap()
                    .map(|e| e.unwrap().path())
                    .collect();
                parts.sort();
                (file.file_name().unwrap(), parts)
            } else {
                (file.file_stem().unwrap(), vec![file.clone()])
            };
            for part in parts {
                assert!(
                    part.extension().is_some_and(|e| e == "rs"),
                    "{} is not a Rust file: layers hold modules and folders of modules",
                    part.display()
                );
                out.push(Source {
                    layer: name.clone(),
                    module: module.to_string_lossy().to_string(),
                    text: std::fs::read_to_string(&part).unwrap(),
                });
            }
        }
    }
    out
}

/// The code of a file without comments and without its `#[cfg(test)]` items (each skipped up
/// to the brace that closes it).
fn library_code(text: &str) -> String {
    let mut code = String::new();
    let (mut skipping, mut depth, mut opened) = (false, 0i64, false);
    for line in text.lines() {
        let line = line.split("//").next().unwrap_or("");
        if line.trim_start().starts_with("#[cfg(test)]") {
            (skipping, depth, opened) = (true, 0, false);
            continue;
        }
        if skipping {
            for c in line.chars() {
                match c {
                    '{' => (depth, opened) = (depth + 1, true),
                    '}' => depth -= 1,
                    _ => {}
                }
            }
            if opened && depth == 0 || !opened && line.trim_end().ends_with(';') {
                skipping = false;
            }
            continue;
        }
        code.push_str(line);
        code.push('\n');
    }
    code
}

/// Every path `crate::a::b…` in `code`, brace groups of `use` trees expanded, as segment lists.
fn crate_paths(code: &str) -> Vec<Vec<String>> {
    let mut out = Vec::new();
    let mut rest = code;
    while let Some(at) = rest.find("crate::") {
        let before = rest[..at].chars().last();
        rest = &rest[at + "crate::".len()..];
        if before.is_some_and(|c| c.is_alphanumeric() || c == '_' || c == ':') {
            continue;
        }
        expand(rest, Vec::new(), &mut out);
    }
    out
}

/// Expands the use tree that starts at `text` below `prefix`.
fn expand(text: &str, prefix: Vec<String>, out: &mut Vec<Vec<String>>) {
    let ident: String = text
        .chars()
        .take_while(|c| c.is_alphanumeric() || *c == '_')
        .collect();
    let text = &text[ident.len()..];
    if ident.is_empty() {
        if let Some(group) = text.strip_prefix('{') {
            for item in split_group(group) {
                expand(item.trim(), prefix.clone(), out);
            }
        } else if !prefix.is_empty() {
            out.push(prefix);
        }
        return;
    }
    let mut path = prefix;
    path.push(ident);
    match text.strip_prefix("::") {
        Some(rest) => expand(rest, path, out),
        None => out.push(path),
    }
}

/// The top-level items of a brace group whose opening brace is already consumed.
fn split_group(text: &str) -> Vec<&str> {
    let (mut depth, mut start, mut items) = (0usize, 0usize, Vec::new());
    for (i, c) in text.char_indices() {
        match c {
            '{' => depth += 1,
            '}' if depth == 0 => {
                items.push(&text[start..i]);
                return items;
            }
            '}' => depth -= 1,
            ',' if depth == 0 => {
                items.push(&text[start..i]);
                start = i + 1;
            }
            _ => {}
        }
    }
    items
}

/// Layer order violations and module-level import loops among `sources`.
fn violations(sources: &[Source]) -> Vec<String> {
    let rank = |layer: &str| LAYERS.iter().position(|l| *l == layer);
    let mut found = Vec::new();
    let modules: BTreeSet<(String, String)> = sources
        .iter()
        .map(|s| (s.layer.clone(), s.module.clone()))
        .collect();
    // An item named at a layer's root (a re-export) belongs to the file that defines it.
    let defined_in = |layer: &str, item: &str| -> Option<String> {
        let patterns = ["struct", "enum", "fn", "const", "trait", "type", "static"]
            .map(|k| format!("pub {k} {item}"));
        sources
            .iter()
            .filter(|s| s.layer == layer && s.module != "mod")
            .find(|s| {
                patterns.iter().any(|p| {
                    s.text.match_indices(p.as_str()).any(|(i, _)| {
                        s.text[i + p.len()..]
                            .chars()
                            .next()
                            .is_some_and(|c| !(c.is_alphanumeric() || c == '_'))
                    })
                })
            })
            .map(|s| s.module.clone())
    };
    let mut edges: BTreeMap<(String, String), BTreeSet<(String, String)>> = BTreeMap::new();
    for s in sources {
        let Some(own) = rank(&s.layer) else {
            found.push(format!("src/{}/ is not a known layer {LAYERS:?}", s.layer));
            continue;
        };
        for path in crate_paths(&library_code(&s.text)) {
            let Some(target) = rank(&path[0]) else {
                found.push(format!(
                    "src/{}/{}.rs imports crate::{}, outside every layer",
                    s.layer, s.module, path[0]
                ));
                continue;
            };
            if target > own {
                found.push(format!(
                    "src/{}/{}.rs imports crate::{} (layer `{}` is above `{}`)",
                    s.layer,
                    s.module,
                    path.join("::"),
                    path[0],
                    s.layer
                ));
            }
            let module = match path.get(1) {
                Some(m) if modules.contains(&(path[0].clone(), m.clone())) => Some(m.clone()),
                Some(item) => defined_in(&path[0], item),
                None => None,
            };
            if let Some(module) = module {
                let from = (s.layer.clone(), s.module.clone());
                let to = (path[0].clone(), module);
                if from != to && s.module != "mod" {
                    edges.entry(from).or_default().insert(to);
                }
            }
        }
    }
    // Loops: a depth-first search that meets a module still on its stack.
    fn visit(
        node: &(String, String),
        edges: &BTreeMap<(String, String), BTreeSet<(String, String)>>,
        state: &mut BTreeMap<(String, String), u8>,
        stack: &mut Vec<(String, String)>,
        found: &mut Vec<String>,
    ) {
        state.insert(node.clone(), 1);
        stack.push(node.clone());
        for next in edges.get(node).into_iter().flatten() {
            match state.get(next) {
                Some(1) => {
                    let start = stack.iter().position(|n| n == next).unwrap();
                    let names: Vec<String> = stack[start..]
                        .iter()
                        .chain([next])
                        .map(|(l, m)| format!("{l}::{m}"))
                        .collect();
                    found.push(format!("import loop: {}", names.join(" -> ")));
                }
                Some(_) => {}
                None => visit(next, edges, state, stack, found),
            }
        }
        stack.pop();
        state.insert(node.clone(), 2);
    }
    let mut state = BTreeMap::new();
    for node in edges.keys() {
        if !state.contains_key(node) {
            visit(node, &edges, &mut state, &mut Vec::new(), &mut found);
        }
    }
    found
}

#[test]
fn every_import_points_down_the_layers_and_no_module_loops() {
    let root = Path::new(env!("CARGO_MANIFEST_DIR")).join("src");
    let sources = sources(&root);
    let layers: BTreeSet<&str> = sources.iter().map(|s| s.layer.as_str()).collect();
    assert_eq!(
        layers,
        LAYERS.into_iter().collect(),
        "src/ holds exactly the layers"
    );
    let found = violations(&sources);
    assert!(found.is_empty(), "layer rule broken:\n{}", found.join("\n"));
}

fn source(layer: &str, module: &str, text: &str) -> Source {
    Source {
        layer: layer.into(),
        module: module.into(),
        text: text.into(),
    }
}

/// The checker itself: it must see an upward import inside a brace group, an import loop
/// through a re-exported name, and ignore test modules and comments.
#[test]
fn the_checker_catches_an_upward_import_and_a_loop() {
    let upward = [
        source("linalg", "tridiag", "use crate::{step::{exact::{X, Y}}};\n"),
        source("step", "exact", "pub struct X;\npub struct Y;\n"),
    ];
    let found = violations(&upward);
    assert_eq!(found.len(), 2, "{found:?}");
    assert!(found[0].contains("crate::step::exact::X"), "{found:?}");

    let looped = [
        source(
            "step",
            "audit",
            "use crate::step::Report;\npub struct Audit;\n",
        ),
        source(
            "step",
            "report",
            "pub struct Report(crate::step::audit::Audit);\n",
        ),
        source("step", "mod", "pub use report::Report;\n"),
    ];
    let found = violations(&looped);
    assert_eq!(found.len(), 1, "{found:?}");
    assert!(found[0].starts_with("import loop"), "{found:?}");

    let ignored = [source(
        "linalg",
        "tridiag",
        "// see crate::study::x\n#[cfg(test)]\nmod tests {\n use crate::study::x;\n}\n",
    )];
    assert!(violations(&ignored).is_empty());
    let after_test_item = [source(
        "linalg",
        "tridiag",
        "#[cfg(test)]\nfn helper() {\n    crate::study::x();\n}\nuse crate::study::y;\n",
    )];
    assert_eq!(violations(&after_test_item).len(), 1);
}
