//! `cargo xtask arch [--print]` (part of `ci`): docs/ARCHITECTURE.md's crate diagram and
//! crate table against the real crate graph and module tree.
//!
//! What is read: every package of the root workspace's `members`, and every package found at
//! or one folder below an `exclude` entry (the board crates and the board emulator, which keep
//! their own workspaces). A crate's arrows are its dependencies (normal, build and
//! target-specific) on another of these packages; dev-dependencies are arrows of its tests only
//! and are checked for direction, not listed. A crate's modules are the `mod name;` items of
//! its crate root (`src/lib.rs`, or `src/main.rs` for a binary-only crate), test modules left
//! out.
//!
//! What must hold, or the step fails naming the difference:
//! 1. the table between `<!-- arch:crates -->` and `<!-- /arch:crates -->` has one row per
//!    crate, with its folder, its arrows ("depends on") and its modules, all exactly as built;
//! 2. the `mermaid` diagram between `<!-- arch:diagram -->` and `<!-- /arch:diagram -->` has
//!    exactly the arrows of the graph;
//! 3. every arrow (dev-dependencies included) runs from a higher layer to a strictly lower one,
//!    with the layers as the table numbers them;
//! 4. no arrow runs from a lower folder to a higher one, with the folders in the order the
//!    line after `<!-- arch:folders -->` lists them (bottom first).
//!
//! 5. every Rust path the page names from a crate's root (`core::rest::quiet_ceiling`,
//!    `stiffwall_tune::frontier`, `sim::exact::{Exact, PeriodAudit}`) resolves: its modules are
//!    files (or folders) of that crate, and the first item after them is defined in that module;
//!    every repository path in backquotes (`host/hostctl/src/cli_error.rs`) exists. Rule 5 also
//!    holds for README.md, docs/UI.md and docs/model-notes-sim.md.
//!
//! `--print` prints the table and the diagram as the code is (layers taken from the doc,
//! `?` for a new crate), to paste after a deliberate change.
use anyhow::{bail, Context, Result};
use std::collections::{BTreeMap, BTreeSet};
use std::path::{Path, PathBuf};

/// One crate as built.
#[derive(Debug, Clone)]
struct Crate {
    /// Folder relative to the repository root, `/`-separated.
    folder: String,
    /// Internal normal/build dependencies (package names).
    deps: BTreeSet<String>,
    /// Internal dev-dependencies (package names).
    dev_deps: BTreeSet<String>,
    /// `mod` items of the crate root.
    modules: BTreeSet<String>,
}

/// One row of the doc's table.
#[derive(Debug, Clone)]
struct Row {
    layer: u32,
    folder: String,
    deps: BTreeSet<String>,
    modules: BTreeSet<String>,
}

const DOC: &str = "docs/ARCHITECTURE.md";

/// Runs the check (or prints the doc's sections with `--print`).
pub fn arch(args: &[String]) -> Result<()> {
    let root = crate::firmware::root();
    let crates = read_crates(&root)?;
    let doc = std::fs::read_to_string(root.join(DOC)).with_context(|| format!("reading {DOC}"))?;
    if args.iter().any(|a| a == "--print") {
        print!(
            "{}",
            render(&crates, &parse_table(&doc).unwrap_or_default())
        );
        return Ok(());
    }
    let rows = parse_table(&doc)?;
    let folders = parse_folders(&doc)?;
    let edges = parse_diagram(&doc)?;
    let mut problems = check(&crates, &rows, &edges, &folders);
    problems.extend(references(&doc, &root));
    for other in ["README.md", "docs/UI.md", "docs/model-notes-sim.md"] {
        let text = std::fs::read_to_string(root.join(other))
            .with_context(|| format!("reading {other}"))?;
        problems.extend(
            references(&text, &root)
                .into_iter()
                .map(|p| format!("{other}: {p}")),
        );
    }
    if !problems.is_empty() {
        for p in &problems {
            eprintln!("xtask arch: {p}");
        }
        bail!(
            "{DOC} differs from the code in {} place(s); `cargo xtask arch --print` prints \
             the table and diagram as built",
            problems.len()
        );
    }
    eprintln!(
        "xtask arch: {DOC} matches the code: {} crates, {} arrows, every arrow runs down",
        crates.len(),
        edges.len()
    );
    Ok(())
}

fn check(
    crates: &BTreeMap<String, Crate>,
    rows: &BTreeMap<String, Row>,
    edges: &BTreeSet<(String, String)>,
    folders: &[String],
) -> Vec<String> {
    let mut out = Vec::new();
    for name in crates.keys().filter(|n| !rows.contains_key(*n)) {
        out.push(format!("crate `{name}` has no row in the table"));
    }
    for name in rows.keys().filter(|n| !crates.contains_key(*n)) {
        out.push(format!("the table lists `{name}`, which is no crate"));
    }
    let mut real_edges = BTreeSet::new();
    for (name, c) in crates {
        for d in &c.deps {
            real_edges.insert((short(name), short(d)));
        }
        let Some(row) = rows.get(name) else { continue };
        if row.folder != c.folder {
            out.push(format!(
                "`{name}`: the table says folder `{}`, it is `{}`",
                row.folder, c.folder
            ));
        }
        diff(&mut out, name, "depends on", &row.deps, &c.deps);
        diff(&mut out, name, "modules", &row.modules, &c.modules);
        for d in c.deps.iter().chain(&c.dev_deps) {
            out.extend(direction(name, c, d, crates, rows, folders));
        }
    }
    for e in real_edges.difference(edges) {
        out.push(format!("the diagram lacks the arrow `{} --> {}`", e.0, e.1));
    }
    for e in edges.difference(&real_edges) {
        out.push(format!(
            "the diagram draws `{} --> {}`, no such dependency",
            e.0, e.1
        ));
    }
    out
}

fn diff(
    out: &mut Vec<String>,
    name: &str,
    what: &str,
    doc: &BTreeSet<String>,
    real: &BTreeSet<String>,
) {
    for x in real.difference(doc) {
        out.push(format!("`{name}` {what}: `{x}` is missing from the table"));
    }
    for x in doc.difference(real) {
        out.push(format!(
            "`{name}` {what}: the table lists `{x}`, the code has none"
        ));
    }
}

/// Layer and folder direction of the arrow `name → dep`.
fn direction(
    name: &str,
    c: &Crate,
    dep: &str,
    crates: &BTreeMap<String, Crate>,
    rows: &BTreeMap<String, Row>,
    folders: &[String],
) -> Vec<String> {
    let mut out = Vec::new();
    if let (Some(a), Some(b)) = (rows.get(name), rows.get(dep)) {
        if b.layer >= a.layer {
            out.push(format!(
                "`{name}` (layer {}) depends on `{dep}` (layer {}): arrows must run down",
                a.layer, b.layer
            ));
        }
    }
    let rank = |folder: &str| {
        let top = folder.split('/').next().unwrap_or(folder);
        folders.iter().position(|f| f == top)
    };
    let Some(d) = crates.get(dep) else {
        return out;
    };
    match (rank(&c.folder), rank(&d.folder)) {
        (Some(a), Some(b)) if b > a => out.push(format!(
            "`{name}` in `{}` depends on `{dep}` in `{}`: an arrow from a lower folder up",
            c.folder, d.folder
        )),
        (None, _) => out.push(format!(
            "folder of `{name}` ({}) is not in the folder list",
            c.folder
        )),
        _ => {}
    }
    out
}

/// The folder of every crate (relative to the root), for `module-cycles`.
pub fn crate_folders(root: &Path) -> Result<Vec<String>> {
    let mut f: Vec<String> = read_crates(root)?.into_values().map(|c| c.folder).collect();
    f.sort();
    Ok(f)
}

/// Crate-root aliases the page uses, and each crate's `src` folder.
const ROOTS: &[(&str, &str)] = &[
    ("core", "crates/core/src"),
    ("stiffwall_core", "crates/core/src"),
    ("proto", "crates/proto/src"),
    ("stiffwall_proto", "crates/proto/src"),
    ("sim", "sim/src"),
    ("stiffwall_sim", "sim/src"),
    ("firmware", "firmware/src"),
    ("stiffwall_firmware", "firmware/src"),
    ("stiffwall_client", "host/client/src"),
    ("stiffwall_tune", "host/tune/src"),
    ("host", "host/hostctl/src"),
    ("stiffwall_host", "host/hostctl/src"),
];

/// Folders whose paths in backquotes must exist.
const TOP: &[&str] = &["crates/", "sim/", "firmware/", "host/", "tests/", "docs/"];

/// Rule 5: the Rust paths and repository paths the page names.
fn references(doc: &str, root: &Path) -> Vec<String> {
    let mut out = Vec::new();
    for span in doc.split('`').skip(1).step_by(2) {
        let span = span.trim();
        if TOP.iter().any(|t| span.starts_with(t)) && !span.contains([' ', '*', '{', '<']) {
            let path = span.split(':').next().unwrap_or(span);
            if !root.join(path).exists() {
                out.push(format!("`{span}`: no such file or folder"));
            }
            continue;
        }
        for path in expand(span) {
            if let Err(e) = resolve_path(&path, root) {
                out.push(format!("`{path}`: {e}"));
            }
        }
    }
    out
}

/// `a::b::{c, d::e}` → `a::b::c`, `a::b::d::e`; a span that is not a path → nothing.
fn expand(span: &str) -> Vec<String> {
    let ok = |p: &str| {
        !p.is_empty()
            && p.split("::")
                .all(|s| !s.is_empty() && s.chars().all(|c| c.is_alphanumeric() || c == '_'))
    };
    if let Some((head, rest)) = span.split_once("::{") {
        let Some(inner) = rest.strip_suffix('}') else {
            return Vec::new();
        };
        return inner
            .split(',')
            .map(|x| format!("{head}::{}", x.trim()))
            .filter(|p| ok(p))
            .collect();
    }
    let span = span.trim_end_matches("::*");
    if span.contains("::") && ok(span) {
        vec![span.to_string()]
    } else {
        Vec::new()
    }
}

/// Walks a path from a crate root: module files first, then one defined item.
fn resolve_path(path: &str, root: &Path) -> Result<(), String> {
    let mut segs = path.split("::");
    let first = segs.next().unwrap_or_default();
    let Some((_, src)) = ROOTS.iter().find(|(alias, _)| *alias == first) else {
        return Ok(()); // not a path from a crate root of this repository
    };
    let mut dir = root.join(src);
    let mut file = ["lib.rs", "main.rs"]
        .iter()
        .map(|f| dir.join(f))
        .find(|f| f.is_file())
        .ok_or_else(|| format!("{src} has no crate root"))?;
    for seg in segs {
        let as_file = dir.join(format!("{seg}.rs"));
        let as_dir = dir.join(seg);
        if as_file.is_file() || as_dir.join("mod.rs").is_file() {
            file = if as_file.is_file() {
                as_file
            } else {
                as_dir.join("mod.rs")
            };
            dir = as_dir;
            continue;
        }
        let text = std::fs::read_to_string(&file).map_err(|e| e.to_string())?;
        return if defines(&text, seg) || glob_defines(&text, &dir, seg) {
            Ok(())
        } else {
            Err(format!(
                "`{seg}` is neither a module nor an item of {}",
                file.strip_prefix(root).unwrap_or(&file).display()
            ))
        };
    }
    Ok(())
}

/// Whether a `pub use child::*;` of the module (folder `dir`) brings in `name`.
fn glob_defines(text: &str, dir: &Path, name: &str) -> bool {
    text.lines()
        .filter_map(|l| l.trim().strip_prefix("pub use ")?.strip_suffix("::*;"))
        .any(|child| {
            let child = child.trim_start_matches("self::");
            [
                dir.join(format!("{child}.rs")),
                dir.join(child).join("mod.rs"),
            ]
            .iter()
            .any(|f| std::fs::read_to_string(f).is_ok_and(|t| defines(&t, name)))
        })
}

/// Whether `text` defines or re-exports `name` (an fn, type, const, static, macro or `use`).
fn defines(text: &str, name: &str) -> bool {
    const KINDS: [&str; 8] = [
        "fn ", "struct ", "enum ", "trait ", "const ", "static ", "type ", "mod ",
    ];
    // A `use` over several lines (`pub use a::{\n B,\n C,\n};`) counts as one line.
    let mut lines: Vec<String> = Vec::new();
    let mut open_use = false;
    for l in text.lines().map(str::trim) {
        if open_use {
            if let Some(last) = lines.last_mut() {
                last.push(' ');
                last.push_str(l);
            }
        } else {
            lines.push(l.to_string());
        }
        open_use =
            (open_use || l.starts_with("use ") || l.starts_with("pub use ")) && !l.ends_with(';');
    }
    lines.iter().map(String::as_str).any(|l| {
        let word_at = |i: usize| {
            l[i..].starts_with(name)
                && !l[i + name.len()..].starts_with(|c: char| c.is_alphanumeric() || c == '_')
        };
        KINDS
            .iter()
            .any(|k| l.match_indices(k).any(|(i, _)| word_at(i + k.len())))
            || (l.contains("use ") && l.match_indices(name).any(|(i, _)| word_at(i)))
    })
}

/// `stiffwall-core` → `core`, `stiffwall-board-qemu-an386` → `board_qemu_an386` (a mermaid id).
fn short(name: &str) -> String {
    name.trim_start_matches("stiffwall-").replace('-', "_")
}

fn section<'a>(doc: &'a str, tag: &str) -> Result<&'a str> {
    let open = format!("<!-- arch:{tag} -->");
    let close = format!("<!-- /arch:{tag} -->");
    let start = doc
        .find(&open)
        .with_context(|| format!("{DOC} has no `{open}`"))?
        + open.len();
    let len = doc[start..]
        .find(&close)
        .with_context(|| format!("{DOC} has no `{close}` after `{open}`"))?;
    Ok(&doc[start..start + len])
}

fn parse_folders(doc: &str) -> Result<Vec<String>> {
    let s = section(doc, "folders")?;
    let folders: Vec<String> = s
        .split('`')
        .skip(1)
        .step_by(2)
        .map(|f| f.trim_end_matches('/').to_string())
        .collect();
    if folders.is_empty() {
        bail!("{DOC}: the arch:folders section names no folder in `backquotes`");
    }
    Ok(folders)
}

fn parse_diagram(doc: &str) -> Result<BTreeSet<(String, String)>> {
    let mut edges = BTreeSet::new();
    for line in section(doc, "diagram")?.lines() {
        if let Some((a, b)) = line.split_once("-->") {
            edges.insert((a.trim().to_string(), b.trim().to_string()));
        }
    }
    Ok(edges)
}

/// Backquoted names of one table cell (`—` for none).
fn names(cell: &str) -> BTreeSet<String> {
    cell.split('`')
        .skip(1)
        .step_by(2)
        .map(str::to_string)
        .collect()
}

fn parse_table(doc: &str) -> Result<BTreeMap<String, Row>> {
    let mut rows = BTreeMap::new();
    for line in section(doc, "crates")?.lines() {
        let cells: Vec<&str> = line.trim().trim_matches('|').split('|').collect();
        if cells.len() != 5 || !cells[0].trim().chars().all(|c| c.is_ascii_digit()) {
            continue;
        }
        let Ok(layer) = cells[0].trim().parse() else {
            continue;
        };
        let name = names(cells[1])
            .into_iter()
            .next()
            .with_context(|| format!("{DOC}: a table row without a `crate`: {line}"))?;
        let folder = names(cells[2]).into_iter().next().unwrap_or_default();
        let deps = names(cells[3]).iter().map(|d| long(d)).collect();
        let row = Row {
            layer,
            folder,
            deps,
            modules: names(cells[4]),
        };
        if rows.insert(name.clone(), row).is_some() {
            bail!("{DOC}: `{name}` has two rows");
        }
    }
    if rows.is_empty() {
        bail!("{DOC}: the arch:crates table has no row");
    }
    Ok(rows)
}

/// The table names dependencies as the diagram does (`core`); back to package names.
fn long(short_name: &str) -> String {
    if short_name == "xtask" {
        return short_name.to_string();
    }
    format!("stiffwall-{}", short_name.replace('_', "-"))
}

fn render(crates: &BTreeMap<String, Crate>, rows: &BTreeMap<String, Row>) -> String {
    let mut order: Vec<(&String, &Crate)> = crates.iter().collect();
    let layer = |n: &str| rows.get(n).map(|r| r.layer);
    order.sort_by_key(|(n, c)| (layer(n).unwrap_or(u32::MAX), c.folder.clone()));
    let list = |s: &BTreeSet<String>| {
        if s.is_empty() {
            "—".to_string()
        } else {
            s.iter()
                .map(|x| format!("`{x}`"))
                .collect::<Vec<_>>()
                .join(", ")
        }
    };
    let mut t = String::from(
        "<!-- arch:crates -->\n| layer | crate | folder | depends on | modules |\n|---|---|---|---|---|\n",
    );
    let mut d = String::from("<!-- arch:diagram -->\n```mermaid\ngraph BT\n");
    for (n, c) in &order {
        let l = layer(n).map_or("?".to_string(), |l| l.to_string());
        let deps: BTreeSet<String> = c.deps.iter().map(|x| short(x)).collect();
        t += &format!(
            "| {l} | `{n}` | `{}` | {} | {} |\n",
            c.folder,
            list(&deps),
            list(&c.modules)
        );
        for x in &deps {
            d += &format!("  {} --> {x}\n", short(n));
        }
    }
    t += "<!-- /arch:crates -->\n";
    d += "```\n<!-- /arch:diagram -->\n";
    format!("{d}\n{t}")
}

fn manifest(path: &Path) -> Result<toml::Table> {
    let text =
        std::fs::read_to_string(path).with_context(|| format!("reading {}", path.display()))?;
    toml::from_str(&text).with_context(|| format!("parsing {}", path.display()))
}

/// Every package of the root workspace and below its `exclude` entries.
fn read_crates(root: &Path) -> Result<BTreeMap<String, Crate>> {
    let top = manifest(&root.join("Cargo.toml"))?;
    let ws = top
        .get("workspace")
        .and_then(|w| w.as_table())
        .context("root Cargo.toml has no [workspace]")?;
    let strings = |key: &str| -> Vec<String> {
        ws.get(key)
            .and_then(|v| v.as_array())
            .map(|a| {
                a.iter()
                    .filter_map(|s| s.as_str().map(str::to_string))
                    .collect()
            })
            .unwrap_or_default()
    };
    let mut dirs: Vec<PathBuf> = strings("members").iter().map(|m| root.join(m)).collect();
    for ex in strings("exclude") {
        let p = root.join(&ex);
        if p.join("Cargo.toml").is_file() {
            dirs.push(p);
        } else if let Ok(entries) = std::fs::read_dir(&p) {
            let mut subs: Vec<PathBuf> = entries
                .filter_map(|e| e.ok().map(|e| e.path()))
                .filter(|s| s.join("Cargo.toml").is_file())
                .collect();
            subs.sort();
            dirs.extend(subs);
        }
    }
    let ws_deps = ws
        .get("dependencies")
        .and_then(|d| d.as_table())
        .cloned()
        .unwrap_or_default();
    let mut raw = Vec::new();
    for dir in dirs {
        let m = manifest(&dir.join("Cargo.toml"))?;
        let Some(name) = m
            .get("package")
            .and_then(|p| p.get("name"))
            .and_then(|n| n.as_str())
        else {
            continue;
        };
        raw.push((name.to_string(), dir, m));
    }
    let known: BTreeSet<String> = raw.iter().map(|(n, _, _)| n.clone()).collect();
    let mut out = BTreeMap::new();
    for (name, dir, m) in raw {
        let folder = dir
            .strip_prefix(root)
            .unwrap_or(&dir)
            .to_string_lossy()
            .replace('\\', "/");
        let (deps, dev_deps) = internal_deps(&m, &ws_deps, &known);
        let modules = root_modules(&dir)?;
        out.insert(
            name,
            Crate {
                folder,
                deps,
                dev_deps,
                modules,
            },
        );
    }
    Ok(out)
}

/// (normal + build, dev) dependencies on packages of `known`.
fn internal_deps(
    m: &toml::Table,
    ws_deps: &toml::Table,
    known: &BTreeSet<String>,
) -> (BTreeSet<String>, BTreeSet<String>) {
    let mut roots: Vec<&toml::Table> = vec![m];
    if let Some(targets) = m.get("target").and_then(|t| t.as_table()) {
        roots.extend(targets.values().filter_map(|t| t.as_table()));
    }
    let mut tables: Vec<(&toml::Table, bool)> = Vec::new();
    for t in roots {
        for (key, dev) in [
            ("dependencies", false),
            ("build-dependencies", false),
            ("dev-dependencies", true),
        ] {
            if let Some(d) = t.get(key).and_then(|d| d.as_table()) {
                tables.push((d, dev));
            }
        }
    }
    let (mut deps, mut dev) = (BTreeSet::new(), BTreeSet::new());
    for (table, is_dev) in tables {
        for (key, spec) in table {
            let from_ws = spec.get("workspace").and_then(|w| w.as_bool()) == Some(true);
            let spec = if from_ws {
                ws_deps.get(key)
            } else {
                Some(spec)
            };
            let package = spec
                .and_then(|s| s.get("package"))
                .and_then(|p| p.as_str())
                .unwrap_or(key);
            if known.contains(package) {
                if is_dev {
                    dev.insert(package.to_string());
                } else {
                    deps.insert(package.to_string());
                }
            }
        }
    }
    (deps, dev)
}

/// The `mod name;` items of a crate root, test modules left out.
fn root_modules(dir: &Path) -> Result<BTreeSet<String>> {
    let lib = dir.join("src/lib.rs");
    let path = if lib.is_file() {
        lib
    } else {
        dir.join("src/main.rs")
    };
    let text =
        std::fs::read_to_string(&path).with_context(|| format!("reading {}", path.display()))?;
    Ok(mod_items(&text))
}

fn mod_items(text: &str) -> BTreeSet<String> {
    let mut out = BTreeSet::new();
    let mut after_cfg_test = false;
    for line in text.lines().map(str::trim) {
        let rest = line
            .strip_prefix("pub(crate) ")
            .or_else(|| line.strip_prefix("pub "))
            .unwrap_or(line);
        if let Some(name) = rest.strip_prefix("mod ").and_then(|r| r.strip_suffix(';')) {
            if !after_cfg_test {
                out.insert(name.trim().to_string());
            }
        }
        if !line.is_empty() && !line.starts_with("//") {
            after_cfg_test = line == "#[cfg(test)]";
        }
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn mod_items_are_the_file_modules_without_test_ones() {
        let src = "//! x\npub mod a;\nmod b;\npub(crate) mod c;\n#[cfg(test)]\nmod tests;\n\
                   mod inline {\n}\npub use a::X;\n";
        let got: Vec<String> = mod_items(src).into_iter().collect();
        assert_eq!(got, ["a", "b", "c"]);
    }

    fn krate(folder: &str, deps: &[&str]) -> Crate {
        Crate {
            folder: folder.into(),
            deps: deps.iter().map(|d| d.to_string()).collect(),
            dev_deps: BTreeSet::new(),
            modules: BTreeSet::new(),
        }
    }

    fn row(layer: u32, folder: &str, deps: &[&str]) -> Row {
        Row {
            layer,
            folder: folder.into(),
            deps: deps.iter().map(|d| d.to_string()).collect(),
            modules: BTreeSet::new(),
        }
    }

    #[test]
    fn an_arrow_up_a_layer_or_a_folder_fails_and_a_true_doc_passes() {
        let folders: Vec<String> = ["crates", "sim", "host"].map(String::from).to_vec();
        let crates = BTreeMap::from([
            ("stiffwall-core".to_string(), krate("crates/core", &[])),
            (
                "stiffwall-sim".to_string(),
                krate("sim", &["stiffwall-core"]),
            ),
        ]);
        let rows = BTreeMap::from([
            ("stiffwall-core".to_string(), row(0, "crates/core", &[])),
            (
                "stiffwall-sim".to_string(),
                row(1, "sim", &["stiffwall-core"]),
            ),
        ]);
        let edges = BTreeSet::from([("sim".to_string(), "core".to_string())]);
        assert!(check(&crates, &rows, &edges, &folders).is_empty());
        // The same layer is not "down".
        let mut flat = rows.clone();
        flat.get_mut("stiffwall-sim").unwrap().layer = 0;
        assert_eq!(check(&crates, &flat, &edges, &folders).len(), 1);
        // A crate in a lower folder depending on one in a higher folder.
        let mut up = crates.clone();
        up.get_mut("stiffwall-core").unwrap().folder = "host/core".into();
        let mut up_rows = rows.clone();
        up_rows.get_mut("stiffwall-core").unwrap().folder = "host/core".into();
        let p = check(&up, &up_rows, &edges, &folders);
        assert!(p.iter().any(|m| m.contains("lower folder up")), "{p:?}");
        // The diagram missing an arrow, and the table missing a dependency.
        assert_eq!(check(&crates, &rows, &BTreeSet::new(), &folders).len(), 1);
        let mut stale = rows.clone();
        stale.get_mut("stiffwall-sim").unwrap().deps.clear();
        assert_eq!(check(&crates, &stale, &edges, &folders).len(), 1);
    }

    #[test]
    fn paths_expand_and_resolve_against_the_real_crates() {
        assert_eq!(expand("core::rest::{comes_to_rest, Chatter}").len(), 2);
        assert_eq!(expand("core::describing::*"), ["core::describing"]);
        assert!(expand("a b").is_empty());
        let root = crate::process::root();
        assert!(resolve_path("core::rest::quiet_ceiling", &root).is_ok());
        assert!(resolve_path("core::rest::no_such_fn", &root).is_err());
        assert!(resolve_path("stiffwall_tune::procedure::frontier_search", &root).is_err());
        assert!(resolve_path("elsewhere::x", &root).is_ok());
        assert!(defines("pub fn quiet_ceiling(c: f64)", "quiet_ceiling"));
        assert!(!defines("pub fn quiet_ceiling_x()", "quiet_ceiling"));
        assert!(defines("pub use crate::a::{B, quiet};", "quiet"));
        assert!(defines(
            "pub use a::{\n    B,\n    quiet as loud,\n};",
            "loud"
        ));
    }

    #[test]
    fn the_doc_tables_parse() {
        let doc = "<!-- arch:folders -->\nbottom first: `crates`, `sim/`\n\
                   <!-- /arch:folders -->\n<!-- arch:diagram -->\n```mermaid\ngraph BT\n  sim --> core\n\
                   ```\n<!-- /arch:diagram -->\n<!-- arch:crates -->\n\
                   | layer | crate | folder | depends on | modules |\n|---|---|---|---|---|\n\
                   | 0 | `stiffwall-core` | `crates/core` | — | `a`, `b` |\n\
                   | 1 | `stiffwall-sim` | `sim` | `core` | `m` |\n<!-- /arch:crates -->\n";
        assert_eq!(parse_folders(doc).unwrap(), ["crates", "sim"]);
        assert_eq!(parse_diagram(doc).unwrap().len(), 1);
        let rows = parse_table(doc).unwrap();
        assert_eq!(rows["stiffwall-sim"].deps.len(), 1);
        assert!(rows["stiffwall-sim"].deps.contains("stiffwall-core"));
        assert_eq!(rows["stiffwall-core"].modules.len(), 2);
    }
}
