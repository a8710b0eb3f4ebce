//! The `use` graph between sibling modules of a Rust source tree, and its
//! cycles.
//!
//! A module's file is found the way rustc finds it (`a/b.rs` or `a/b/mod.rs`
//! below the crate's `src/`). Every path a file names that starts at
//! `crate`, `super`, `self` or one of its own child modules — in `use` trees
//! and in expressions alike — is resolved to the deepest module it names,
//! following one level of `pub use` re-exports in the module it lands on.
//! When module `a::x::…` names something in `a::y::…`, that is an edge
//! `x → y` among the children of `a`. Imports of an ancestor or a descendant
//! are not sibling edges. Comments, strings and character literals are
//! skipped, so intra-doc links do not count.

use std::collections::{BTreeMap, BTreeSet};
use std::path::{Path, PathBuf};

/// A module path below the crate root (`[]` is the root).
pub type ModPath = Vec<String>;

/// One module file: its path and the paths it names.
struct ModFile {
    path: ModPath,
    /// Each named path, already made absolute where its start was
    /// `crate`/`super`/`self`/a child module.
    names: Vec<ModPath>,
    /// `pub use` re-exports: exported name → absolute path of its source.
    reexports: BTreeMap<String, ModPath>,
}

/// The modules of one crate.
pub struct Crate {
    files: BTreeMap<ModPath, ModFile>,
}

/// A cycle among the children of `parent`: the members of one strongly
/// connected component, sorted.
#[derive(Debug, PartialEq, Eq, PartialOrd, Ord)]
pub struct Cycle {
    pub parent: ModPath,
    pub members: Vec<String>,
}

impl std::fmt::Display for Cycle {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        let parent = if self.parent.is_empty() {
            "crate".to_string()
        } else {
            self.parent.join("::")
        };
        write!(f, "{parent}: {{{}}}", self.members.join(", "))
    }
}

impl Crate {
    /// Reads every `.rs` file below `src` (a crate's `src/` folder).
    pub fn read(src: &Path) -> std::io::Result<Crate> {
        let mut sources = Vec::new();
        collect_rs(src, &mut sources)?;
        let mut raw = Vec::new();
        for file in sources {
            let rel = file.strip_prefix(src).expect("below src");
            let Some(path) = module_path(rel) else {
                continue;
            };
            let text = std::fs::read_to_string(&file)?;
            raw.push((path, text));
        }
        let known: BTreeSet<ModPath> = raw.iter().map(|(p, _)| p.clone()).collect();
        let mut files = BTreeMap::new();
        for (path, text) in raw {
            let tokens = tokenize(&text);
            let (names, reexports) = named_paths(&tokens, &path, &known);
            files.insert(
                path.clone(),
                ModFile {
                    path,
                    names,
                    reexports,
                },
            );
        }
        Ok(Crate { files })
    }

    /// The module a named path lands in: the deepest known module along
    /// it, then through that module's `pub use` of the next segment (up to
    /// a few levels).
    fn target(&self, named: &ModPath) -> ModPath {
        let mut path = named.clone();
        for _ in 0..4 {
            let mut depth = 0;
            while depth < path.len() && self.files.contains_key(&path[..=depth]) {
                depth += 1;
            }
            let module: ModPath = path[..depth].to_vec();
            let Some(next) = path.get(depth) else {
                return module;
            };
            match self.files.get(&module).and_then(|m| m.reexports.get(next)) {
                Some(source) if source != &path => {
                    let mut through = source.clone();
                    through.extend(path[depth + 1..].iter().cloned());
                    path = through;
                }
                _ => return module,
            }
        }
        path
    }

    /// Sibling edges: parent → (child → children it names).
    pub fn sibling_edges(&self) -> BTreeMap<ModPath, BTreeMap<String, BTreeSet<String>>> {
        let mut edges: BTreeMap<ModPath, BTreeMap<String, BTreeSet<String>>> = BTreeMap::new();
        for file in self.files.values() {
            for named in &file.names {
                let target = self.target(named);
                let common = file
                    .path
                    .iter()
                    .zip(&target)
                    .take_while(|(a, b)| a == b)
                    .count();
                if common == file.path.len() || common == target.len() {
                    continue; // an ancestor, a descendant or itself
                }
                edges
                    .entry(file.path[..common].to_vec())
                    .or_default()
                    .entry(file.path[common].clone())
                    .or_default()
                    .insert(target[common].clone());
            }
        }
        edges
    }

    /// Every cycle among sibling modules (Tarjan's strongly connected
    /// components of each parent's sibling graph, those with two or more
    /// members).
    pub fn cycles(&self) -> Vec<Cycle> {
        let mut out = Vec::new();
        for (parent, graph) in self.sibling_edges() {
            for members in strongly_connected(&graph) {
                if members.len() > 1 {
                    out.push(Cycle {
                        parent: parent.clone(),
                        members,
                    });
                }
            }
        }
        out.sort();
        out
    }
}

fn collect_rs(dir: &Path, out: &mut Vec<PathBuf>) -> std::io::Result<()> {
    let mut entries: Vec<_> = std::fs::read_dir(dir)?.collect::<Result<_, _>>()?;
    entries.sort_by_key(|e| e.path());
    for entry in entries {
        let path = entry.path();
        if path.is_dir() {
            collect_rs(&path, out)?;
        } else if path.extension().is_some_and(|e| e == "rs") {
            out.push(path);
        }
    }
    Ok(())
}

/// `a/b.rs` → `[a, b]`, `a/mod.rs` → `[a]`, `lib.rs`/`main.rs` → `[]`;
/// `bin/x.rs` and other crate roots are skipped.
fn module_path(rel: &Path) -> Option<ModPath> {
    let mut parts: Vec<String> = rel
        .iter()
        .map(|s| s.to_string_lossy().into_owned())
        .collect();
    let last = parts.pop()?;
    let stem = last.strip_suffix(".rs")?.to_string();
    if parts.first().is_some_and(|p| p == "bin") {
        return None;
    }
    match stem.as_str() {
        "lib" | "main" if parts.is_empty() => Some(parts),
        "mod" => Some(parts),
        _ => {
            parts.push(stem);
            Some(parts)
        }
    }
}

#[derive(Clone, Debug, PartialEq)]
enum Token {
    Ident(String),
    PathSep,
    Punct(char),
}

/// Identifiers, `::` and single punctuation, with comments, strings,
/// character literals and lifetimes left out.
fn tokenize(text: &str) -> Vec<Token> {
    let chars: Vec<char> = text.chars().collect();
    let mut out = Vec::new();
    let mut i = 0;
    while i < chars.len() {
        let c = chars[i];
        let next = chars.get(i + 1).copied();
        if c == '/' && next == Some('/') {
            while i < chars.len() && chars[i] != '\n' {
                i += 1;
            }
        } else if c == '/' && next == Some('*') {
            let mut depth = 0;
            while i < chars.len() {
                if chars[i] == '/' && chars.get(i + 1) == Some(&'*') {
                    depth += 1;
                    i += 2;
                } else if chars[i] == '*' && chars.get(i + 1) == Some(&'/') {
                    depth -= 1;
                    i += 2;
                    if depth == 0 {
                        break;
                    }
                } else {
                    i += 1;
                }
            }
        } else if c == 'r'
            && (next == Some('"') || next == Some('#'))
            && raw_string_len(&chars[i..]) > 0
        {
            i += raw_string_len(&chars[i..]);
        } else if c == '"' {
            i += 1;
            while i < chars.len() && chars[i] != '"' {
                i += if chars[i] == '\\' { 2 } else { 1 };
            }
            i += 1;
        } else if c == '\'' {
            // A character literal ('x', '\n', '\u{..}') or a lifetime ('a).
            if next == Some('\\') {
                i += 2;
                while i < chars.len() && chars[i] != '\'' {
                    i += 1;
                }
                i += 1;
            } else if chars.get(i + 2) == Some(&'\'') {
                i += 3;
            } else {
                i += 1;
                while i < chars.len() && (chars[i].is_alphanumeric() || chars[i] == '_') {
                    i += 1;
                }
            }
        } else if c.is_alphabetic() || c == '_' {
            let start = i;
            while i < chars.len() && (chars[i].is_alphanumeric() || chars[i] == '_') {
                i += 1;
            }
            out.push(Token::Ident(chars[start..i].iter().collect()));
        } else if c == ':' && next == Some(':') {
            out.push(Token::PathSep);
            i += 2;
        } else {
            if !c.is_whitespace() {
                out.push(Token::Punct(c));
            }
            i += 1;
        }
    }
    out
}

/// Length of a raw string literal (`r"…"`, `r#"…"#`) at the start of
/// `chars`, or 0 when there is none.
fn raw_string_len(chars: &[char]) -> usize {
    let hashes = chars[1..].iter().take_while(|&&c| c == '#').count();
    if chars.get(1 + hashes) != Some(&'"') {
        return 0;
    }
    let mut i = 2 + hashes;
    while i < chars.len() {
        if chars[i] == '"'
            && chars[i + 1..]
                .iter()
                .take(hashes)
                .filter(|&&c| c == '#')
                .count()
                == hashes
        {
            return i + 1 + hashes;
        }
        i += 1;
    }
    chars.len()
}

/// The paths a file names (absolute where resolvable) and its `pub use`
/// re-exports.
fn named_paths(
    tokens: &[Token],
    here: &ModPath,
    known: &BTreeSet<ModPath>,
) -> (Vec<ModPath>, BTreeMap<String, ModPath>) {
    let resolve = |segments: &[String]| -> Option<ModPath> {
        let first = segments.first()?;
        let mut base: ModPath;
        let mut rest = segments;
        match first.as_str() {
            "crate" => {
                base = Vec::new();
                rest = &rest[1..];
            }
            "self" | "super" => {
                // `self` of `a/b.rs` is [a, b]; `super` goes up one.
                base = here.clone();
                while let Some(seg) = rest.first() {
                    match seg.as_str() {
                        "self" => rest = &rest[1..],
                        "super" => {
                            base.pop()?;
                            rest = &rest[1..];
                        }
                        _ => break,
                    }
                }
            }
            name => {
                let mut child = here.clone();
                child.push(name.to_string());
                if !known.contains(&child) {
                    return None;
                }
                base = here.clone();
            }
        }
        base.extend(rest.iter().cloned());
        Some(base)
    };
    let mut names = Vec::new();
    let mut reexports = BTreeMap::new();
    let mut i = 0;
    while i < tokens.len() {
        match &tokens[i] {
            Token::Ident(word) if word == "use" => {
                let public = i > 0
                    && (matches!(&tokens[i - 1], Token::Ident(w) if w == "pub")
                        || matches!(&tokens[i - 1], Token::Punct(')')));
                let mut leaves = Vec::new();
                i = use_tree(tokens, i + 1, Vec::new(), &mut leaves);
                while i < tokens.len() && tokens[i] != Token::Punct(';') {
                    i += 1;
                }
                for (path, alias) in leaves {
                    if let Some(abs) = resolve(&path) {
                        if public {
                            if let Some(name) = alias.or_else(|| abs.last().cloned()) {
                                if name != "*" {
                                    reexports.insert(name, abs.clone());
                                }
                            }
                        }
                        names.push(abs);
                    }
                }
            }
            Token::Ident(word)
                if matches!(word.as_str(), "crate" | "super" | "self")
                    && tokens.get(i + 1) == Some(&Token::PathSep) =>
            {
                let mut path = vec![word.clone()];
                let mut j = i + 1;
                while tokens.get(j) == Some(&Token::PathSep) {
                    match tokens.get(j + 1) {
                        Some(Token::Ident(seg)) => {
                            path.push(seg.clone());
                            j += 2;
                        }
                        _ => break,
                    }
                }
                if let Some(abs) = resolve(&path) {
                    names.push(abs);
                }
                i = j;
            }
            _ => i += 1,
        }
    }
    (names, reexports)
}

/// A use tree (or one element of a `{…}` group) after the segments in
/// `prefix`: pushes each leaf path with its `as` alias and returns the index
/// of the token that ends it (`;`, `,` or `}`).
fn use_tree(
    tokens: &[Token],
    mut i: usize,
    mut prefix: Vec<String>,
    leaves: &mut Vec<(Vec<String>, Option<String>)>,
) -> usize {
    let start_len = prefix.len();
    let mut alias = None;
    loop {
        match tokens.get(i) {
            Some(Token::Ident(seg)) if seg == "as" => {
                if let Some(Token::Ident(a)) = tokens.get(i + 1) {
                    alias = Some(a.clone());
                }
                i += 2;
            }
            Some(Token::Ident(seg)) => {
                // `a::{self}` names `a` itself.
                if !(seg == "self" && start_len > 0 && prefix.len() == start_len) {
                    prefix.push(seg.clone());
                }
                i += 1;
            }
            Some(Token::PathSep) => i += 1,
            Some(Token::Punct('*')) => {
                prefix.push("*".to_string());
                i += 1;
            }
            Some(Token::Punct('{')) => {
                i += 1;
                let base = prefix.clone();
                loop {
                    i = use_tree(tokens, i, base.clone(), leaves);
                    match tokens.get(i) {
                        Some(Token::Punct(',')) => {
                            i += 1;
                            if tokens.get(i) == Some(&Token::Punct('}')) {
                                return i + 1;
                            }
                        }
                        Some(Token::Punct('}')) => return i + 1,
                        _ => return i,
                    }
                }
            }
            _ => {
                leaves.push((prefix, alias));
                return i;
            }
        }
    }
}

/// Tarjan's strongly connected components of a small graph (node names →
/// successor names); each component's members sorted.
fn strongly_connected(graph: &BTreeMap<String, BTreeSet<String>>) -> Vec<Vec<String>> {
    let mut nodes: BTreeSet<&String> = graph.keys().collect();
    for successors in graph.values() {
        nodes.extend(successors.iter());
    }
    let nodes: Vec<&String> = nodes.into_iter().collect();
    let index_of: BTreeMap<&String, usize> =
        nodes.iter().enumerate().map(|(i, n)| (*n, i)).collect();
    let succ: Vec<Vec<usize>> = nodes
        .iter()
        .map(|n| {
            graph
                .get(*n)
                .map(|s| s.iter().map(|m| index_of[m]).collect())
                .unwrap_or_default()
        })
        .collect();
    struct State {
        index: Vec<Option<usize>>,
        low: Vec<usize>,
        on_stack: Vec<bool>,
        stack: Vec<usize>,
        next: usize,
        out: Vec<Vec<usize>>,
    }
    fn visit(v: usize, succ: &[Vec<usize>], s: &mut State) {
        s.index[v] = Some(s.next);
        s.low[v] = s.next;
        s.next += 1;
        s.stack.push(v);
        s.on_stack[v] = true;
        for &w in &succ[v] {
            match s.index[w] {
                None => {
                    visit(w, succ, s);
                    s.low[v] = s.low[v].min(s.low[w]);
                }
                Some(iw) if s.on_stack[w] => s.low[v] = s.low[v].min(iw),
                _ => {}
            }
        }
        if Some(s.low[v]) == s.index[v] {
            let mut component = Vec::new();
            while let Some(w) = s.stack.pop() {
                s.on_stack[w] = false;
                component.push(w);
                if w == v {
                    break;
                }
            }
            s.out.push(component);
        }
    }
    let n = nodes.len();
    let mut state = State {
        index: vec![None; n],
        low: vec![0; n],
        on_stack: vec![false; n],
        stack: Vec::new(),
        next: 0,
        out: Vec::new(),
    };
    for v in 0..n {
        if state.index[v].is_none() {
            visit(v, &succ, &mut state);
        }
    }
    state
        .out
        .into_iter()
        .map(|c| {
            let mut names: Vec<String> = c.into_iter().map(|i| nodes[i].clone()).collect();
            names.sort();
            names
        })
        .collect()
}
