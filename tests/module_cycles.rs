//! Imports point down: no module of the workspace names a sibling module
//! that names it back, directly or through other siblings.

#[path = "support/module_graph.rs"]
mod module_graph;

use module_graph::Crate;
use std::path::Path;

/// Writes `files` (path below `src`, text) into a fresh crate folder.
fn crate_of(files: &[(&str, &str)]) -> (tempfile::TempDir, Crate) {
    let dir = tempfile::tempdir().unwrap();
    for (path, text) in files {
        let file = dir.path().join(path);
        std::fs::create_dir_all(file.parent().unwrap()).unwrap();
        std::fs::write(file, text).unwrap();
    }
    let parsed = Crate::read(dir.path()).unwrap();
    (dir, parsed)
}

fn cycles_of(files: &[(&str, &str)]) -> Vec<String> {
    let (_dir, parsed) = crate_of(files);
    parsed.cycles().iter().map(|c| c.to_string()).collect()
}

#[test]
fn the_checker_finds_the_cycles_of_a_known_tree() {
    // Cycles by every spelling: `super::` paths in expressions, a grouped
    // `use crate::…::{…}`, a path through the parent's re-export, and a
    // child-module start inside mod.rs; plus edges that are not cycles.
    let files = [
        ("lib.rs", "pub mod a;\npub mod b;\npub mod c;\n"),
        (
            "a/mod.rs",
            "mod x;\nmod y;\nmod z;\npub use y::Thing;\nuse x::Helper;\n",
        ),
        ("a/x.rs", "pub fn f() { super::Thing::new(); }\n"),
        (
            "a/y.rs",
            "use crate::a::{z::{self, Z}, w};\npub struct Thing;\n",
        ),
        ("a/z.rs", "pub fn g() { super::x::f(); }\n"),
        ("b.rs", "use crate::c::C;\n/// Not an edge: [`crate::a::x`].\n"),
        (
            "c.rs",
            "pub struct C;\nconst S: &str = \"crate::b::nothing\";\nfn h<'a>(_: &'a str) { let _c = 'b'; }\n",
        ),
    ];
    assert_eq!(cycles_of(&files), vec!["a: {x, y, z}".to_string()]);

    // The same tree with the back edge removed has no cycle.
    let mut acyclic = files;
    acyclic[4] = ("a/z.rs", "pub fn g() {}\n");
    assert_eq!(cycles_of(&acyclic), Vec::<String>::new());

    // A cycle between top-level modules through `crate::` in expressions.
    let top = [
        ("lib.rs", "mod p;\nmod q;\n"),
        ("p.rs", "fn f() { crate::q::g() }\n"),
        ("q.rs", "pub fn g() {}\nfn h() { crate::p::f() }\n"),
    ];
    assert_eq!(cycles_of(&top), vec!["crate: {p, q}".to_string()]);
}

#[test]
fn no_module_cycles_in_the_workspace() {
    let root = Path::new(env!("CARGO_MANIFEST_DIR"));
    let mut sources = vec![root.join("src"), root.join("python/src")];
    let mut crates: Vec<_> = std::fs::read_dir(root.join("crates"))
        .unwrap()
        .map(|e| e.unwrap().path().join("src"))
        .collect();
    crates.sort();
    sources.extend(crates);
    let mut found = Vec::new();
    for src in &sources {
        assert!(src.is_dir(), "missing source folder {}", src.display());
        let parsed = Crate::read(src).unwrap();
        let name = src
            .parent()
            .unwrap()
            .strip_prefix(root)
            .unwrap()
            .display()
            .to_string();
        for cycle in parsed.cycles() {
            found.push(format!("{} ({name})", cycle));
        }
    }
    assert!(
        found.is_empty(),
        "module cycles (siblings that import each other):\n{}",
        found.join("\n")
    );
}
