//! `cargo xtask module-cycles [--edges]`: the file-level dependency graph of the `src` folder of
//! every crate (the crates `cargo xtask arch` reads: the root workspace's members and the
//! packages below its `exclude` entries), and a failure when one of them has a cycle.
//!
//! An edge A → B means file A names a path that resolves into file B: `crate::…`, `super::…`,
//! `self::…` (in `use` declarations, with `{…}` groups expanded, and inline in code), and a
//! bare `child::…` path naming a module file declared below A. A path resolves to the file of
//! its longest prefix that is a module file (a re-export through `mod.rs` is an edge to
//! `mod.rs`). Comments, string and char literals are ignored; inline `mod name { … }` blocks
//! (tests) resolve `super::` relative to themselves. Edges to the file itself are dropped.
//!
//! Invariant: purely textual, no allocation limits; a false edge can only add cycles, so "no
//! cycle" is a sound answer for the paths this scanner recognises.
use anyhow::{bail, Context, Result};
use std::collections::{BTreeMap, BTreeSet};
use std::path::{Path, PathBuf};

/// Runs the check; `--edges` also prints every edge.
pub fn module_cycles(args: &[String]) -> Result<()> {
    let print_edges = args.iter().any(|a| a == "--edges");
    let repo = crate::firmware::root();
    let mut cycles = 0;
    for folder in crate::arch::crate_folders(&repo)? {
        let src = format!("{folder}/src");
        let graph = graph(&repo.join(&src), "")?;
        let n_edges: usize = graph.values().map(BTreeSet::len).sum();
        println!("{src}/: {} files, {} edges", graph.len(), n_edges);
        if print_edges {
            for (a, bs) in &graph {
                for b in bs {
                    println!("  {a} -> {b}");
                }
            }
        }
        for scc in sccs(&graph) {
            println!("  CYCLE: {}", scc.join(" <-> "));
            cycles += 1;
        }
    }
    if cycles > 0 {
        bail!("{cycles} import cycle(s) between files");
    }
    println!("no import cycle between files");
    Ok(())
}

/// Module path (segments below the crate root) of a file relative to the root.
fn module_of(rel: &Path) -> Vec<String> {
    let mut segs: Vec<String> = rel
        .iter()
        .map(|s| s.to_string_lossy().into_owned())
        .collect();
    let last = segs.pop().unwrap_or_default();
    let stem = last.trim_end_matches(".rs");
    if !matches!(stem, "mod" | "lib" | "main") {
        segs.push(stem.to_string());
    }
    segs
}

fn rust_files(dir: &Path, out: &mut Vec<PathBuf>) -> Result<()> {
    for e in std::fs::read_dir(dir).with_context(|| format!("reading {}", dir.display()))? {
        let p = e?.path();
        if p.is_dir() {
            rust_files(&p, out)?;
        } else if p.extension().is_some_and(|x| x == "rs") {
            out.push(p);
        }
    }
    Ok(())
}

/// Edges between the files under `root/under`, named relative to `root`.
fn graph(root: &Path, under: &str) -> Result<BTreeMap<String, BTreeSet<String>>> {
    let mut files = Vec::new();
    rust_files(root, &mut files)?;
    // A `main.rs` beside a `lib.rs` is a crate of its own (the binary): it reaches the library
    // through its public API by the crate's name, and no library file can import it, so it is
    // left out (counted, its `crate::` paths would be taken for the library root's).
    if root.join("lib.rs").is_file() {
        files.retain(|f| f != &root.join("main.rs"));
    }
    let mut modules: BTreeMap<Vec<String>, String> = BTreeMap::new();
    for f in &files {
        let rel = f.strip_prefix(root)?;
        modules.insert(module_of(rel), rel.to_string_lossy().into_owned());
    }
    let mut g = BTreeMap::new();
    for f in &files {
        let rel = f.strip_prefix(root)?.to_string_lossy().into_owned();
        if !rel.starts_with(under) {
            continue;
        }
        let text = strip(&std::fs::read_to_string(f)?);
        let me = module_of(Path::new(&rel));
        let mut deps = BTreeSet::new();
        for path in paths(&text, &me, &modules) {
            if let Some(file) = resolve(&path, &modules) {
                if file != rel && file.starts_with(under) {
                    deps.insert(file);
                }
            }
        }
        g.insert(rel, deps);
    }
    Ok(g)
}

/// The source without comments, string literals and char literals (each replaced by a space).
fn strip(src: &str) -> String {
    let b: Vec<char> = src.chars().collect();
    let mut out = String::with_capacity(src.len());
    let mut i = 0;
    while i < b.len() {
        let c = b[i];
        let next = b.get(i + 1).copied();
        if c == '/' && next == Some('/') {
            while i < b.len() && b[i] != '\n' {
                i += 1;
            }
        } else if c == '/' && next == Some('*') {
            i += 2;
            while i + 1 < b.len() && !(b[i] == '*' && b[i + 1] == '/') {
                i += 1;
            }
            i += 2;
            out.push(' ');
        } else if c == '"' {
            i = skip_string(&b, i);
            out.push(' ');
        } else if c == 'r' && (next == Some('"') || next == Some('#')) && raw_start(&b, i) {
            i = skip_raw_string(&b, i);
            out.push(' ');
        } else if c == '\'' && is_char_literal(&b, i) {
            i += if b.get(i + 1) == Some(&'\\') { 3 } else { 2 };
            while i < b.len() && b[i] != '\'' {
                i += 1;
            }
            i += 1;
            out.push(' ');
        } else {
            out.push(c);
            i += 1;
        }
    }
    out
}

fn skip_string(b: &[char], mut i: usize) -> usize {
    i += 1;
    while i < b.len() && b[i] != '"' {
        i += if b[i] == '\\' { 2 } else { 1 };
    }
    i + 1
}

fn raw_start(b: &[char], i: usize) -> bool {
    let prev_ident = i > 0 && (b[i - 1].is_alphanumeric() || b[i - 1] == '_');
    let mut j = i + 1;
    while b.get(j) == Some(&'#') {
        j += 1;
    }
    !prev_ident && b.get(j) == Some(&'"')
}

fn skip_raw_string(b: &[char], i: usize) -> usize {
    let mut j = i + 1;
    let mut hashes = 0;
    while b.get(j) == Some(&'#') {
        hashes += 1;
        j += 1;
    }
    j += 1;
    while j < b.len() {
        if b[j] == '"' && (0..hashes).all(|k| b.get(j + 1 + k) == Some(&'#')) {
            return j + 1 + hashes;
        }
        j += 1;
    }
    j
}

/// A char literal (not a lifetime): `'x'` or `'\…'`.
fn is_char_literal(b: &[char], i: usize) -> bool {
    matches!(
        (b.get(i + 1), b.get(i + 2)),
        (Some('\\'), _) | (Some(_), Some('\''))
    )
}

fn is_ident(c: char) -> bool {
    c.is_alphanumeric() || c == '_'
}

/// Absolute module paths named in `text` (a file of module `me`).
fn paths(text: &str, me: &[String], modules: &BTreeMap<Vec<String>, String>) -> Vec<Vec<String>> {
    let b: Vec<char> = text.chars().collect();
    let mut out = Vec::new();
    // Inline modules: (name, brace depth at which the block opened).
    let mut inline: Vec<(String, usize)> = Vec::new();
    let mut depth = 0usize;
    let mut i = 0;
    while i < b.len() {
        let c = b[i];
        if c == '{' {
            depth += 1;
        } else if c == '}' {
            depth = depth.saturating_sub(1);
            if inline.last().is_some_and(|(_, d)| *d == depth) {
                inline.pop();
            }
        }
        let starts_word = is_ident(c) && (i == 0 || !is_ident(b[i - 1]) && b[i - 1] != ':');
        if !starts_word {
            i += 1;
            continue;
        }
        let mut j = i;
        while j < b.len() && is_ident(b[j]) {
            j += 1;
        }
        let word: String = b[i..j].iter().collect();
        if word == "mod" {
            if let Some((name, open)) = inline_mod(&b, j) {
                inline.push((name, depth));
                depth += 1;
                i = open + 1;
                continue;
            }
        }
        let mut here: Vec<String> = me.to_vec();
        here.extend(inline.iter().map(|(n, _)| n.clone()));
        let is_child = {
            let mut p = me.to_vec();
            p.push(word.clone());
            modules.contains_key(&p) && inline.is_empty()
        };
        if matches!(word.as_str(), "crate" | "super" | "self") || is_child {
            let (tree, end) = parse_tree(&b, i, 2);
            for p in tree {
                if let Some(abs) = absolute(&p, &here) {
                    out.push(abs);
                }
            }
            i = end.max(j);
        } else {
            i = j;
        }
    }
    out
}

/// After `mod`: `name {` of an inline module → (name, index of `{`).
fn inline_mod(b: &[char], mut j: usize) -> Option<(String, usize)> {
    while j < b.len() && b[j].is_whitespace() {
        j += 1;
    }
    let s = j;
    while j < b.len() && is_ident(b[j]) {
        j += 1;
    }
    let name: String = b[s..j].iter().collect();
    while j < b.len() && b[j].is_whitespace() {
        j += 1;
    }
    (!name.is_empty() && b.get(j) == Some(&'{')).then_some((name, j))
}

/// Parses `a::b::{c, d::e}` from `i`: the expanded paths (segments) and the end index; nothing
/// when the first word is not followed by `::` (`pub(super)`, `self.x`).
fn parse_tree(b: &[char], mut i: usize, min_len: usize) -> (Vec<Vec<String>>, usize) {
    let mut prefix: Vec<String> = Vec::new();
    loop {
        let s = i;
        while i < b.len() && is_ident(b[i]) {
            i += 1;
        }
        prefix.push(b[s..i].iter().collect::<String>());
        let mut k = i;
        while k < b.len() && b[k].is_whitespace() {
            k += 1;
        }
        if b.get(k) == Some(&':') && b.get(k + 1) == Some(&':') {
            k += 2;
            while k < b.len() && b[k].is_whitespace() {
                k += 1;
            }
            if b.get(k) == Some(&'{') {
                let (items, end) = parse_group(b, k + 1);
                let paths = items
                    .into_iter()
                    .map(|it| prefix.iter().cloned().chain(it).collect())
                    .collect();
                return (paths, end);
            }
            if b.get(k).is_some_and(|c| is_ident(*c)) {
                i = k;
                continue;
            }
            if b.get(k) == Some(&'*') {
                return (vec![prefix], k + 1);
            }
        }
        if prefix.len() < min_len {
            return (Vec::new(), i);
        }
        return (vec![prefix], i);
    }
}

/// Items of a `{…}` group starting after the `{`; returns them and the index after `}`.
fn parse_group(b: &[char], mut i: usize) -> (Vec<Vec<String>>, usize) {
    let mut items = Vec::new();
    while i < b.len() {
        let c = b[i];
        if c == '}' {
            return (items, i + 1);
        }
        if is_ident(c) {
            let (sub, end) = parse_tree(b, i, 1);
            for p in sub {
                // `self` inside a group names the prefix itself.
                items.push(p.into_iter().filter(|s| s != "self").collect());
            }
            i = end;
            // Skip `as alias`.
            continue;
        }
        if c == '{' {
            let (sub, end) = parse_group(b, i + 1);
            items.extend(sub);
            i = end;
            continue;
        }
        i += 1;
    }
    (items, i)
}

/// Resolves `crate`/`super`/`self`/child prefixes against the module `here`.
fn absolute(p: &[String], here: &[String]) -> Option<Vec<String>> {
    let mut out: Vec<String> = here.to_vec();
    let mut rest = p;
    match p.first()?.as_str() {
        "crate" => {
            out.clear();
            rest = &p[1..];
        }
        "self" => rest = &p[1..],
        "super" => {
            while rest.first().is_some_and(|s| s == "super") {
                out.pop()?;
                rest = &rest[1..];
            }
        }
        _ => {}
    }
    out.extend(rest.iter().cloned());
    Some(out)
}

/// The file of the longest module-file prefix of `path`.
fn resolve(path: &[String], modules: &BTreeMap<Vec<String>, String>) -> Option<String> {
    (0..=path.len())
        .rev()
        .find_map(|n| modules.get(&path[..n]).cloned())
}

/// Strongly connected components with more than one file (Tarjan, recursive: graphs are small).
fn sccs(g: &BTreeMap<String, BTreeSet<String>>) -> Vec<Vec<String>> {
    struct T<'a> {
        g: &'a BTreeMap<String, BTreeSet<String>>,
        index: BTreeMap<&'a str, usize>,
        low: BTreeMap<&'a str, usize>,
        stack: Vec<&'a str>,
        on: BTreeSet<&'a str>,
        out: Vec<Vec<String>>,
    }
    fn visit<'a>(t: &mut T<'a>, v: &'a str) {
        let n = t.index.len();
        t.index.insert(v, n);
        t.low.insert(v, n);
        t.stack.push(v);
        t.on.insert(v);
        for w in t.g.get(v).into_iter().flatten() {
            let w = w.as_str();
            if !t.index.contains_key(w) {
                visit(t, w);
                let lw = t.low[w];
                let lv = t.low.get_mut(v).expect("visited");
                *lv = (*lv).min(lw);
            } else if t.on.contains(w) {
                let iw = t.index[w];
                let lv = t.low.get_mut(v).expect("visited");
                *lv = (*lv).min(iw);
            }
        }
        if t.low[v] == t.index[v] {
            let mut comp = Vec::new();
            while let Some(w) = t.stack.pop() {
                t.on.remove(w);
                comp.push(w.to_string());
                if w == v {
                    break;
                }
            }
            if comp.len() > 1 {
                comp.sort();
                t.out.push(comp);
            }
        }
    }
    let mut t = T {
        g,
        index: BTreeMap::new(),
        low: BTreeMap::new(),
        stack: Vec::new(),
        on: BTreeSet::new(),
        out: Vec::new(),
    };
    for v in g.keys() {
        if !t.index.contains_key(v.as_str()) {
            visit(&mut t, v);
        }
    }
    t.out
}

#[cfg(test)]
mod tests {
    use super::*;

    fn files(src: &str, me: &[&str], mods: &[&[&str]]) -> BTreeSet<String> {
        let modules: BTreeMap<Vec<String>, String> = mods
            .iter()
            .map(|m| {
                let v: Vec<String> = m.iter().map(|s| s.to_string()).collect();
                let name = if v.is_empty() {
                    "lib".to_string()
                } else {
                    v.join("/")
                };
                (v, name)
            })
            .collect();
        let me: Vec<String> = me.iter().map(|s| s.to_string()).collect();
        paths(&strip(src), &me, &modules)
            .iter()
            .filter_map(|p| resolve(p, &modules))
            .collect()
    }

    #[test]
    fn groups_super_children_and_inline_modules_resolve_to_files() {
        let mods: &[&[&str]] = &[&[], &["x"], &["x", "y"], &["x", "a"], &["x", "c"], &["z"]];
        let src = "use super::{a::B, c};\nuse crate::z::{self, W};\n\
                   pub(super) fn f() { self.g(); }\n// crate::nope\nconst S: &str = \"crate::q\";\n\
                   #[cfg(test)]\nmod tests {\n    use super::*;\n}\n";
        let got = files(src, &["x", "y"], mods);
        let want: BTreeSet<String> = ["x/a", "x/c", "z", "x/y"].map(String::from).into();
        assert_eq!(got, want);
        // A parent naming its child module by its bare name.
        let got = files("pub use y::T;\nfn f() { let y = 1; }\n", &["x"], mods);
        assert_eq!(got, ["x/y".to_string()].into());
    }

    #[test]
    fn a_two_file_cycle_is_one_component() {
        let mut g: BTreeMap<String, BTreeSet<String>> = BTreeMap::new();
        g.insert("a".into(), ["b".to_string()].into());
        g.insert("b".into(), ["a".to_string(), "c".to_string()].into());
        g.insert("c".into(), BTreeSet::new());
        assert_eq!(sccs(&g), vec![vec!["a".to_string(), "b".to_string()]]);
        g.get_mut("b").unwrap().remove("a");
        assert!(sccs(&g).is_empty());
    }
}
