//! The layering guard: a module of the library imports only from the layers below its
//! own (DESIGN.md, and the top of `src/lib.rs`). Reads the sources as text: every
//! `crate::LAYER` path in code that is not a comment or a unit test names the layer it
//! reaches into.
//!
//! Inside `render`, the modules that share a parent import one another without a
//! circle: the `super::…` and `crate::render::…` paths of each file, read the same way,
//! make a graph between sibling modules that has no cycle.

use std::collections::{BTreeMap, BTreeSet};
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
    ("vision", &["model", "spatial", "camera", "render"]),
    (
        "server",
        &[
            "model", "spatial", "edit", "store", "mesh", "camera", "render", "vision",
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

/// The lines of `text` that are code, outside comments and outside unit tests: an item
/// declared under `#[cfg(test)]` (`mod tests;`) is skipped, and an inline test module
/// under it ends the code (by convention it is the end of its file). Files named
/// `tests.rs` are unit tests as a whole; the callers leave them out.
fn code_lines(text: &str) -> Vec<&str> {
    let mut lines = Vec::new();
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
        lines.push(code);
    }
    lines
}

/// The layers `text` reaches into through `crate::NAME`, in its [`code_lines`].
fn reached(text: &str) -> BTreeSet<String> {
    let mut layers = BTreeSet::new();
    for code in code_lines(text) {
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

/// A module's path below `src/`, its names in order (`["render", "raster", "shade"]`).
type Module = Vec<String>;

/// The module that source file `f` (below `src`) defines: `a/b.rs` and `a/b/mod.rs` are
/// both `a::b`.
fn module_of(src: &Path, f: &Path) -> Module {
    let rel = f.strip_prefix(src).expect("a file below src");
    let mut names: Module = rel
        .components()
        .map(|c| c.as_os_str().to_string_lossy().into_owned())
        .collect();
    let last = names.pop().expect("a file name");
    let stem = last.trim_end_matches(".rs");
    if stem != "mod" {
        names.push(stem.to_owned());
    }
    names
}

/// Length of the identifier at the start of `s`.
fn ident_len(s: &str) -> usize {
    s.find(|c: char| !(c.is_ascii_alphanumeric() || c == '_'))
        .unwrap_or(s.len())
}

/// The paths named by the use tree or path expression at the start of `s`, each with
/// `prefix` before it and every group expanded (`a::{b, c::{d, self}}` gives `a::b`,
/// `a::c::d` and `a::c`); and what follows it.
fn use_paths<'a>(s: &'a str, prefix: &[String], out: &mut Vec<Module>) -> &'a str {
    let s = s.trim_start();
    if let Some(mut rest) = s.strip_prefix('{') {
        loop {
            rest = rest.trim_start();
            if let Some(after) = rest.strip_prefix('}') {
                return after;
            }
            if rest.is_empty() {
                return rest;
            }
            rest = use_paths(rest, prefix, out).trim_start();
            // Past an `as` alias, up to the next tree or the end of the group.
            let next = rest.find([',', '}']).unwrap_or(rest.len());
            rest = &rest[next..];
            rest = rest.strip_prefix(',').unwrap_or(rest);
        }
    }
    let n = ident_len(s);
    if n == 0 {
        // A glob (`*`) or the end of the path: the path so far.
        out.push(prefix.to_vec());
        return s.strip_prefix('*').unwrap_or(s);
    }
    let (name, rest) = s.split_at(n);
    let mut path = prefix.to_vec();
    if name != "self" {
        path.push(name.to_owned());
    }
    match rest.trim_start().strip_prefix("::") {
        Some(rest) => use_paths(rest, &path, out),
        None => {
            out.push(path);
            rest
        }
    }
}

/// The modules that the code of `text`, the source of module `at`, names through paths
/// that begin with `super::` or `crate::`, as paths from the crate root; each path stops
/// at the deepest of `modules` it reaches (an item's path gives its module). Paths that
/// reach none of `modules` are left out.
fn named_modules(text: &str, at: &[String], modules: &BTreeSet<Module>) -> BTreeSet<Module> {
    let code = code_lines(text).join("\n");
    let mut found = BTreeSet::new();
    let mut from = 0;
    while let Some(k) = code[from..].find(['s', 'c']).map(|k| from + k) {
        from = k + 1;
        let rest = &code[k..];
        let starts_path = rest.starts_with("super::") || rest.starts_with("crate::");
        let before = code[..k].chars().next_back();
        if !starts_path || before.is_some_and(|c| c.is_ascii_alphanumeric() || c == '_' || c == ':')
        {
            continue;
        }
        let mut paths = Vec::new();
        use_paths(rest, &[], &mut paths);
        for path in paths {
            let ups = path.iter().take_while(|n| *n == "super").count();
            let full: Module = if path.first().is_some_and(|n| n == "crate") {
                path[1..].to_vec()
            } else if ups > at.len() {
                continue;
            } else {
                let mut full = at[..at.len() - ups].to_vec();
                full.extend_from_slice(&path[ups..]);
                full
            };
            let deepest = (1..=full.len())
                .rev()
                .map(|n| full[..n].to_vec())
                .find(|m| modules.contains(m));
            found.extend(deepest);
        }
    }
    found
}

/// Imports between sibling modules, each with a file that makes it (shown as given): a
/// file of module `m` naming module `t` imports, from the child of their deepest common
/// ancestor on `m`'s side, the child on `t`'s side. A module naming one of its ancestors
/// or descendants (a `mod.rs` using its children, a child using its parent's items)
/// makes no such import. `files` are (module, shown name, source text).
fn sibling_imports(files: &[(Module, String, String)]) -> BTreeMap<(Module, Module), String> {
    let modules: BTreeSet<Module> = files.iter().map(|(m, _, _)| m.clone()).collect();
    let mut imports = BTreeMap::new();
    for (at, shown, text) in files {
        for target in named_modules(text, at, &modules) {
            let common = at.iter().zip(&target).take_while(|(a, b)| a == b).count();
            if common == at.len() || common == target.len() {
                continue;
            }
            let edge = (at[..=common].to_vec(), target[..=common].to_vec());
            imports.entry(edge).or_insert_with(|| shown.clone());
        }
    }
    imports
}

/// A cycle of `imports`, as the modules along it with the first repeated at the end, if
/// there is one.
fn circle(imports: &BTreeMap<(Module, Module), String>) -> Option<Vec<Module>> {
    let mut next: BTreeMap<&Module, Vec<&Module>> = BTreeMap::new();
    for (a, b) in imports.keys() {
        next.entry(a).or_default().push(b);
    }
    /// Depth first from `m`, with `path` the modules on the way to it; `done` those
    /// whose every import has been followed without finding a cycle.
    fn from<'a>(
        m: &'a Module,
        next: &BTreeMap<&'a Module, Vec<&'a Module>>,
        path: &mut Vec<&'a Module>,
        done: &mut BTreeSet<&'a Module>,
    ) -> Option<Vec<Module>> {
        if let Some(at) = path.iter().position(|p| *p == m) {
            let mut cycle: Vec<Module> = path[at..].iter().map(|p| (*p).clone()).collect();
            cycle.push(m.clone());
            return Some(cycle);
        }
        if done.contains(m) {
            return None;
        }
        path.push(m);
        for n in next.get(m).into_iter().flatten() {
            if let Some(cycle) = from(n, next, path, done) {
                return Some(cycle);
            }
        }
        path.pop();
        done.insert(m);
        None
    }
    let mut done = BTreeSet::new();
    next.keys()
        .find_map(|m| from(m, &next, &mut Vec::new(), &mut done))
}

/// A cycle as the guard words it: the modules in turn, and a file making each import.
fn describe(cycle: &[Module], imports: &BTreeMap<(Module, Module), String>) -> String {
    let names: Vec<String> = cycle.iter().map(|m| m.join("::")).collect();
    let files: Vec<String> = cycle
        .windows(2)
        .map(|w| {
            let file = &imports[&(w[0].clone(), w[1].clone())];
            format!("{} → {} in {file}", w[0].join("::"), w[1].join("::"))
        })
        .collect();
    format!("{} ({})", names.join(" → "), files.join("; "))
}

/// Every source file of `src/render` but the unit-test files, as `sibling_imports`
/// takes them.
fn render_files(src: &Path) -> Vec<(Module, String, String)> {
    let mut files = Vec::new();
    sources(&src.join("render"), &mut files);
    files.sort();
    files
        .into_iter()
        .filter(|f| f.file_name().is_none_or(|n| n != "tests.rs"))
        .map(|f| {
            let text = std::fs::read_to_string(&f).expect("a source file reads");
            let shown = f.strip_prefix(src.parent().expect("src has a parent"));
            let shown = shown.unwrap_or(&f).display().to_string();
            (module_of(src, &f), shown, text)
        })
        .collect()
}

#[test]
fn the_modules_of_render_import_one_another_without_a_circle() {
    let src = Path::new(env!("CARGO_MANIFEST_DIR")).join("src");
    let imports = sibling_imports(&render_files(&src));
    assert!(
        !imports.is_empty(),
        "no imports between the modules of src/render: the guard reads nothing"
    );
    if let Some(cycle) = circle(&imports) {
        panic!(
            "a circle of imports between modules of src/render: {}",
            describe(&cycle, &imports)
        );
    }
}

#[test]
fn the_guard_sees_a_circle_of_imports() {
    let file = |m: &str, text: &str| {
        let module: Module = m.split("::").map(str::to_owned).collect();
        (module, m.to_owned(), text.to_owned())
    };
    let files = [
        // A parent using its children and children using their parent: no import
        // between siblings.
        file("render::b", "mod c;\nmod d;\npub use c::Z;\nuse d::W;"),
        file("render::b::d", "use super::{Frame, c::{self, X}};\n"),
        file(
            "render::b::c",
            "use super::super::{\n    a::Y,\n};\n// use super::d;\n#[cfg(test)]\nmod t {\nuse super::super::d;\n}",
        ),
        file("render::a", "fn f() { crate::render::b::d::g(); }"),
    ];
    let imports = sibling_imports(&files);
    let shown: Vec<(String, String)> = imports
        .keys()
        .map(|(a, b)| (a.join("::"), b.join("::")))
        .collect();
    let pair = |a: &str, b: &str| (a.to_owned(), b.to_owned());
    assert_eq!(
        shown,
        vec![
            pair("render::a", "render::b"),
            pair("render::b", "render::a"),
            pair("render::b::d", "render::b::c"),
        ]
    );
    let cycle = circle(&imports).expect("the circle a → b → a");
    assert_eq!(
        describe(&cycle, &imports),
        "render::a → render::b → render::a (render::a → render::b in render::a; \
         render::b → render::a in render::b::c)"
    );
    let without: BTreeMap<_, _> = imports
        .into_iter()
        .filter(|((a, _), _)| a.join("::") != "render::a")
        .collect();
    assert_eq!(circle(&without), None);
}
