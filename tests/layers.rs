//! The layering guard: a module of the library imports only from the layers below its
//! own (DESIGN.md, and the top of `src/lib.rs`). Reads the sources as text: every
//! `crate::LAYER` path in code that is not a comment or a unit test names the layer it
//! reaches into.

use std::collections::BTreeSet;
use std::path::{Path, PathBuf};

/// Each top-level module of `src/`, bottom to top, with the layers it may use.
const LAYERS: &[(&str, &[&str])] = &[
    ("model", &[]),
    ("spatial", &["model"]),
    ("edit", &["model"]),
    ("store", &["model", "edit"]),
    ("mesh", &["model"]),
    ("camera", &["model"]),
    ("render", &["model", "spatial", "camera"]),
    ("solve", &["model", "spatial", "camera", "render"]),
    ("vision", &["model", "spatial", "camera", "render"]),
    (
        "server",
        &[
            "model", "spatial", "edit", "store", "mesh", "camera", "render", "solve", "vision",
        ],
    ),
];

/// The `.rs` files below `dir`, recursively.
fn sources(dir: &Path, out: &mut Vec<PathBuf>) {
    for entry in std::fs::read_dir(dir).unwrap_or_else(|e| panic!("{}: {e}", dir.display())) {
        let path = entry.expect("a directory entry").path();
        if path.is_dir() {
            sources(&path, out);
        } else if path.extension().is_some_and(|e| e == "rs") {
            out.push(path);
        }
    }
}

/// The layers `text` reaches into through `crate::NAME`, outside comments and outside
/// unit tests: a file named `tests.rs`, an item declared under `#[cfg(test)]` (`mod
/// tests;`), or an inline test module under it (by convention the end of its file).
fn reached(text: &str) -> BTreeSet<String> {
    let mut layers = BTreeSet::new();
    let mut under_cfg_test = false;
    for line in text.lines() {
        let code = line.trim_start();
        if code.starts_with("//") || code.is_empty() {
            continue;
        }
        if code.starts_with("#[cfg(test)]") {
            under_cfg_test = true;
            continue;
        }
        if under_cfg_test && !code.starts_with("#[") {
            if code.trim_end().ends_with(';') {
                // A test-only declaration: skip it, read on.
                under_cfg_test = false;
                continue;
            }
            // An inline test module: the rest of the file is tests.
            break;
        }
        let mut rest = code;
        while let Some(at) = rest.find("crate::") {
            rest = &rest[at + "crate::".len()..];
            let name: String = rest
                .chars()
                .take_while(|c| c.is_ascii_alphanumeric() || *c == '_')
                .collect();
            if !name.is_empty() {
                layers.insert(name);
            }
        }
    }
    layers
}

/// Every `file → layer` import that goes up or sideways, as the guard words it.
fn upward_imports(src: &Path) -> Vec<String> {
    let mut found = Vec::new();
    for &(layer, allowed) in LAYERS {
        let mut files = Vec::new();
        let dir = src.join(layer);
        if dir.is_dir() {
            sources(&dir, &mut files);
        }
        let file = src.join(format!("{layer}.rs"));
        if file.is_file() {
            files.push(file);
        }
        files.sort();
        for f in files {
            if f.file_name().is_some_and(|n| n == "tests.rs") {
                continue;
            }
            let text = std::fs::read_to_string(&f).expect("a source file reads");
            for other in reached(&text) {
                if other != layer && !allowed.contains(&other.as_str()) {
                    let shown = f.strip_prefix(src.parent().expect("src has a parent"));
                    found.push(format!("{} → {other}", shown.unwrap_or(&f).display()));
                }
            }
        }
    }
    found
}

#[test]
fn every_layer_imports_only_from_the_layers_below_it() {
    let src = Path::new(env!("CARGO_MANIFEST_DIR")).join("src");
    let found = upward_imports(&src);
    assert!(
        found.is_empty(),
        "imports from a layer above (see LAYERS in tests/layers.rs and DESIGN.md): {found:#?}"
    );
}

#[test]
fn every_top_level_module_has_a_layer() {
    let src = Path::new(env!("CARGO_MANIFEST_DIR")).join("src");
    let lib = std::fs::read_to_string(src.join("lib.rs")).expect("src/lib.rs reads");
    for line in lib.lines() {
        if let Some(name) = line.trim().strip_prefix("pub mod ") {
            let name = name.trim_end_matches(';');
            assert!(
                LAYERS.iter().any(|(l, _)| *l == name),
                "module {name} has no place in LAYERS"
            );
        }
    }
}

#[test]
fn the_guard_sees_an_upward_import() {
    let code = "#[cfg(test)]\nmod tests;\nuse crate::model::World;\nuse crate::server::edit::Edit;\n// crate::render\n#[cfg(test)]\nmod t {\nuse crate::solve;";
    let reached = reached(code);
    assert_eq!(
        reached.into_iter().collect::<Vec<_>>(),
        vec!["model".to_owned(), "server".to_owned()]
    );
}
