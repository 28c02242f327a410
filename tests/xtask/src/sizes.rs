//! `cargo xtask sizes`: size limits on production code, so no file or function grows past what
//! a reader can hold at once, and no function hides a long argument list behind an allow.
//!
//! It fails, naming file, line and length, on
//! - a file over [`MAX_FILE_LINES`] lines before its tests (the lines before the first of the
//!   `#[cfg(test)]` items that end it, or the whole file when it ends with none);
//! - a function over [`MAX_FN_LINES`] lines, from its `fn` line to its closing brace: free
//!   functions, methods of impl blocks, default methods of traits and functions nested in other
//!   functions alike;
//! - an `#[allow(clippy::too_many_arguments)]` or `#[expect(…)]` of it (a struct carries the
//!   arguments instead).
//!
//! Production code is every `.rs` file below `crates/`, `firmware/` (the boards included),
//! `host/` (the board emulator included), `sim/` and `tests/xtask/`, examples, binaries and
//! build scripts included, except tests: `tests/` and `benches/` folders, files named
//! `tests.rs` or `*_tests.rs`, `#[cfg(test)]` items and the files of out-of-line
//! `#[cfg(test)] mod name;` declarations. `target/` folders are skipped. Files are parsed with
//! `syn` (line spans from proc-macro2's `span-locations`), so braces in strings, comments and
//! macros never count.
use anyhow::{bail, Context, Result};
use std::collections::BTreeSet;
use std::path::{Path, PathBuf};
use syn::spanned::Spanned;
use syn::visit::Visit;

/// Most lines a production file may have before its tests.
pub const MAX_FILE_LINES: usize = 700;
/// Most lines a production function may have, `fn` line and closing brace included.
pub const MAX_FN_LINES: usize = 80;

/// Folders (relative to the repository root) whose `.rs` files are production code.
const ROOTS: &[&str] = &["crates", "firmware", "host", "sim", "tests/xtask"];

/// Findings tolerated, as (file, function or "file", reason). Every entry needs its reason;
/// an empty list is the aim.
const ALLOWED: &[(&str, &str, &str)] = &[];

/// One limit broken.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Finding {
    /// Path relative to the repository root, `/`-separated.
    pub file: String,
    pub line: usize,
    /// The function's name, or `file` for a file's length and `allow` for the attribute.
    pub item: String,
    pub message: String,
}

/// Runs the check over the repository; no arguments.
pub fn sizes(_args: &[String]) -> Result<()> {
    let repo = crate::firmware::root();
    let files = production_files(&repo)?;
    let mut findings = Vec::new();
    for file in &files {
        let rel = relative(&repo, file);
        let src = std::fs::read_to_string(file).with_context(|| format!("reading {rel}"))?;
        findings.extend(check_source(&rel, &src)?);
    }
    findings.retain(|f| {
        !ALLOWED
            .iter()
            .any(|(file, item, _)| *file == f.file && *item == f.item)
    });
    findings.sort_by(|a, b| a.file.cmp(&b.file).then(a.line.cmp(&b.line)));
    for f in &findings {
        println!("{}:{}: {}", f.file, f.line, f.message);
    }
    if !findings.is_empty() {
        bail!(
            "{} size limit(s) broken in {} production files (files ≤ {MAX_FILE_LINES} lines \
             before tests, functions ≤ {MAX_FN_LINES} lines, no too_many_arguments allow)",
            findings.len(),
            files.len()
        );
    }
    println!(
        "sizes: {} production files within limits (files ≤ {MAX_FILE_LINES} lines before \
         tests, functions ≤ {MAX_FN_LINES} lines, no too_many_arguments allow)",
        files.len()
    );
    Ok(())
}

fn relative(repo: &Path, file: &Path) -> String {
    let rel = file.strip_prefix(repo).unwrap_or(file);
    rel.iter()
        .map(|s| s.to_string_lossy())
        .collect::<Vec<_>>()
        .join("/")
}

/// The production `.rs` files below [`ROOTS`], sorted, without the files of out-of-line
/// `#[cfg(test)] mod name;` declarations.
fn production_files(repo: &Path) -> Result<Vec<PathBuf>> {
    let mut files = Vec::new();
    for root in ROOTS {
        walk(&repo.join(root), &mut files)?;
    }
    files.sort();
    let mut test_modules = BTreeSet::new();
    for file in &files {
        let src =
            std::fs::read_to_string(file).with_context(|| format!("reading {}", file.display()))?;
        let ast =
            syn::parse_file(&src).with_context(|| format!("parsing {}", relative(repo, file)))?;
        for name in test_mod_declarations(&ast) {
            let dir = child_dir(file);
            test_modules.insert(dir.join(format!("{name}.rs")));
            test_modules.insert(dir.join(&name).join("mod.rs"));
        }
    }
    files.retain(|f| !test_modules.contains(f));
    Ok(files)
}

/// The folder a file's child modules live in: its own folder for `mod.rs`, `lib.rs`,
/// `main.rs` and `build.rs` and for crate roots below `examples/` or `src/bin/`, else
/// the folder named after it.
fn child_dir(file: &Path) -> PathBuf {
    let dir = file.parent().unwrap_or(Path::new("")).to_path_buf();
    let stem = file.file_stem().unwrap_or_default().to_string_lossy();
    let parent = dir.file_name().unwrap_or_default().to_string_lossy();
    let root_like = matches!(stem.as_ref(), "mod" | "lib" | "main" | "build")
        || parent == "examples"
        || (parent == "bin" && dir.parent().is_some_and(|p| p.ends_with("src")));
    if root_like {
        dir
    } else {
        dir.join(stem.as_ref())
    }
}

/// Collects the `.rs` files below `dir`, leaving out test folders, test files and `target/`.
fn walk(dir: &Path, out: &mut Vec<PathBuf>) -> Result<()> {
    for e in std::fs::read_dir(dir).with_context(|| format!("reading {}", dir.display()))? {
        let p = e?.path();
        let name = p.file_name().unwrap_or_default().to_string_lossy();
        if p.is_dir() {
            if !matches!(name.as_ref(), "tests" | "benches" | "target") && !name.starts_with('.') {
                walk(&p, out)?;
            }
        } else if name.ends_with(".rs") && name != "tests.rs" && !name.ends_with("_tests.rs") {
            out.push(p);
        }
    }
    Ok(())
}

/// The names of the out-of-line `#[cfg(test)] mod name;` declarations at a file's top level.
fn test_mod_declarations(ast: &syn::File) -> Vec<String> {
    ast.items
        .iter()
        .filter_map(|item| match item {
            syn::Item::Mod(m) if m.content.is_none() && is_test_only(&m.attrs) => {
                Some(m.ident.to_string())
            }
            _ => None,
        })
        .collect()
}

/// Every limit broken in one file's source (`file` names it in the findings).
pub fn check_source(file: &str, src: &str) -> Result<Vec<Finding>> {
    let ast = syn::parse_file(src).with_context(|| format!("parsing {file}"))?;
    let mut visitor = Limits {
        file,
        findings: Vec::new(),
    };
    file_length(&mut visitor, &ast, src);
    visitor.visit_file(&ast);
    Ok(visitor.findings)
}

/// The file-length finding, if any: lines before the first top-level `#[cfg(test)]` item of
/// the run of them that ends the file (a `#[cfg(test)] mod name;` declared among production
/// items does not end the count).
fn file_length(visitor: &mut Limits, ast: &syn::File, src: &str) {
    let production_end = ast
        .items
        .iter()
        .rposition(|item| !is_test_only(item_attrs(item)))
        .map_or(0, |i| i + 1);
    let first_test = ast.items[production_end..]
        .first()
        .map(|item| line(item.span()));
    let (lines, where_) = match first_test {
        Some(l) => (l - 1, "before its tests"),
        None => (src.lines().count(), "in all"),
    };
    if lines > MAX_FILE_LINES {
        visitor.findings.push(Finding {
            file: visitor.file.to_string(),
            line: 1,
            item: "file".to_string(),
            message: format!(
                "file has {lines} lines {where_} (limit {MAX_FILE_LINES}): split it into modules"
            ),
        });
    }
}

/// The line (1-based) a span starts on.
fn line(span: proc_macro2::Span) -> usize {
    span.start().line
}

fn item_attrs(item: &syn::Item) -> &[syn::Attribute] {
    match item {
        syn::Item::Const(i) => &i.attrs,
        syn::Item::Enum(i) => &i.attrs,
        syn::Item::ExternCrate(i) => &i.attrs,
        syn::Item::Fn(i) => &i.attrs,
        syn::Item::ForeignMod(i) => &i.attrs,
        syn::Item::Impl(i) => &i.attrs,
        syn::Item::Macro(i) => &i.attrs,
        syn::Item::Mod(i) => &i.attrs,
        syn::Item::Static(i) => &i.attrs,
        syn::Item::Struct(i) => &i.attrs,
        syn::Item::Trait(i) => &i.attrs,
        syn::Item::TraitAlias(i) => &i.attrs,
        syn::Item::Type(i) => &i.attrs,
        syn::Item::Union(i) => &i.attrs,
        syn::Item::Use(i) => &i.attrs,
        _ => &[],
    }
}

/// Whether the attributes hold `#[cfg(test)]` or `#[cfg(all(test, …))]`.
fn is_test_only(attrs: &[syn::Attribute]) -> bool {
    attrs.iter().any(|a| {
        a.path().is_ident("cfg")
            && a.parse_args::<syn::Meta>()
                .is_ok_and(|meta| requires_test(&meta))
    })
}

/// Whether a `cfg` predicate holds only under `test`.
fn requires_test(meta: &syn::Meta) -> bool {
    match meta {
        syn::Meta::Path(p) => p.is_ident("test"),
        syn::Meta::List(list) if list.path.is_ident("all") => list
            .parse_args_with(
                syn::punctuated::Punctuated::<syn::Meta, syn::Token![,]>::parse_terminated,
            )
            .is_ok_and(|metas| metas.iter().any(requires_test)),
        _ => false,
    }
}

/// The visitor: functions and attributes outside `#[cfg(test)]` items.
struct Limits<'a> {
    file: &'a str,
    findings: Vec<Finding>,
}

impl Limits<'_> {
    fn function(&mut self, name: &syn::Ident, fn_token: &syn::token::Fn, body: &syn::Block) {
        let start = line(fn_token.span);
        let end = line(body.brace_token.span.close());
        let lines = end + 1 - start;
        if lines > MAX_FN_LINES {
            self.findings.push(Finding {
                file: self.file.to_string(),
                line: start,
                item: name.to_string(),
                message: format!(
                    "fn `{name}` has {lines} lines (limit {MAX_FN_LINES}): split it into named steps"
                ),
            });
        }
    }
}

impl<'ast> Visit<'ast> for Limits<'_> {
    fn visit_item(&mut self, item: &'ast syn::Item) {
        if !is_test_only(item_attrs(item)) {
            syn::visit::visit_item(self, item);
        }
    }

    fn visit_impl_item(&mut self, item: &'ast syn::ImplItem) {
        let attrs = match item {
            syn::ImplItem::Fn(f) => &f.attrs[..],
            syn::ImplItem::Const(c) => &c.attrs[..],
            _ => &[],
        };
        if !is_test_only(attrs) {
            syn::visit::visit_impl_item(self, item);
        }
    }

    fn visit_item_fn(&mut self, f: &'ast syn::ItemFn) {
        self.function(&f.sig.ident, &f.sig.fn_token, &f.block);
        syn::visit::visit_item_fn(self, f);
    }

    fn visit_impl_item_fn(&mut self, f: &'ast syn::ImplItemFn) {
        self.function(&f.sig.ident, &f.sig.fn_token, &f.block);
        syn::visit::visit_impl_item_fn(self, f);
    }

    fn visit_trait_item_fn(&mut self, f: &'ast syn::TraitItemFn) {
        if let Some(body) = &f.default {
            self.function(&f.sig.ident, &f.sig.fn_token, body);
        }
        syn::visit::visit_trait_item_fn(self, f);
    }

    fn visit_attribute(&mut self, attr: &'ast syn::Attribute) {
        let path = attr.path();
        let lint_attr =
            path.is_ident("allow") || path.is_ident("expect") || path.is_ident("cfg_attr");
        let names_lint = match &attr.meta {
            syn::Meta::List(list) => list.tokens.to_string().contains("too_many_arguments"),
            _ => false,
        };
        if lint_attr && names_lint {
            self.findings.push(Finding {
                file: self.file.to_string(),
                line: line(attr.pound_token.span),
                item: "allow".to_string(),
                message: "allows clippy::too_many_arguments: pass a struct instead".to_string(),
            });
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A function of `n` lines, `fn` line and closing brace included.
    fn function(name: &str, n: usize) -> String {
        let mut s = format!("fn {name}() {{\n");
        for i in 0..n - 2 {
            s.push_str(&format!("    let _x{i} = {i};\n"));
        }
        s.push_str("}\n");
        s
    }

    fn items(src: &str) -> Vec<(String, usize)> {
        check_source("x.rs", src)
            .unwrap()
            .into_iter()
            .map(|f| (f.item, f.line))
            .collect()
    }

    #[test]
    fn an_81_line_function_fails_and_an_80_line_one_passes() {
        let src = format!("// head\n{}{}", function("short", 80), function("long", 81));
        assert_eq!(items(&src), [("long".to_string(), 82)]);
    }

    #[test]
    fn methods_trait_defaults_and_nested_functions_count() {
        let body = function("inner", 81).replace('\n', "\n    ");
        let src = format!(
            "impl S {{\n{}}}\ntrait T {{\n{}}}\nfn outer() {{\n    {body}}}\n",
            function("method", 81),
            function("default", 81),
        );
        let names: Vec<String> = items(&src).into_iter().map(|(n, _)| n).collect();
        assert_eq!(names, ["method", "default", "outer", "inner"]);
    }

    #[test]
    fn test_modules_and_items_are_skipped() {
        let src = format!(
            "fn ok() {{}}\n#[cfg(test)]\nmod tests {{\n{}}}\n#[cfg(all(test, feature = \"x\"))]\n{}\
             impl S {{\n#[cfg(test)]\n{}}}\n#[cfg(not(test))]\n{}",
            function("in_tests", 200),
            function("test_only", 90),
            function("test_method", 90),
            function("production", 90),
        );
        assert_eq!(items(&src), [("production".to_string(), 390)]);
    }

    #[test]
    fn the_too_many_arguments_allow_is_caught() {
        let src = "#[allow(clippy::too_many_arguments)]\nfn f(a: u8) {}\n\
                   #[expect(clippy::too_many_arguments, reason = \"x\")]\nfn g() {}\n\
                   #[allow(dead_code)]\nfn h() {}\n\
                   #[cfg(test)]\nmod tests {\n#[allow(clippy::too_many_arguments)]\nfn t() {}\n}\n";
        assert_eq!(
            items(src),
            [("allow".to_string(), 1), ("allow".to_string(), 3)]
        );
    }

    #[test]
    fn file_length_counts_the_lines_before_the_tests() {
        let body: String = (0..700).map(|i| format!("const C{i}: u8 = 0;\n")).collect();
        let tests = format!("#[cfg(test)]\nmod tests {{\n{}}}\n", "// t\n".repeat(100));
        assert!(items(&format!("{body}{tests}")).is_empty());
        let found = items(&format!("{body}const X: u8 = 0;\n{tests}"));
        assert_eq!(found, [("file".to_string(), 1)]);
        let msg = &check_source("x.rs", &format!("{body}// one more\n")).unwrap()[0].message;
        assert!(msg.contains("701 lines in all"), "{msg}");
        // A test module declared at the top does not end the count; the trailing one does.
        let top = format!("#[cfg(test)]\nmod fixture;\n{body}{tests}");
        let msg = &check_source("x.rs", &top).unwrap()[0].message;
        assert!(msg.contains("702 lines before its tests"), "{msg}");
    }

    #[test]
    fn strings_and_macros_do_not_confuse_the_spans() {
        let src = format!(
            "fn f() {{\n    let _s = \"}}\";\n    m!{{ }} }}\n{}",
            function("g", 81)
        );
        assert_eq!(items(&src), [("g".to_string(), 4)]);
    }

    #[test]
    fn child_dirs_follow_the_module_rules() {
        assert_eq!(child_dir(Path::new("a/src/lib.rs")), Path::new("a/src"));
        assert_eq!(
            child_dir(Path::new("a/src/servo.rs")),
            Path::new("a/src/servo")
        );
        assert_eq!(
            child_dir(Path::new("a/examples/x.rs")),
            Path::new("a/examples")
        );
        assert_eq!(
            child_dir(Path::new("a/src/bin/x.rs")),
            Path::new("a/src/bin")
        );
    }
}
