//! The engine's layering, checked from its sources and its dependency tree.
//!
//! ARCHITECTURE.md draws the engine's modules as rows, each of which may use the rows
//! below it and never those above; the rows are read from that file, so that the drawing
//! and the check cannot drift apart. Every module of the engine sits in exactly one row,
//! and modules of one row do not use each other both ways. And the engine itself draws no
//! window, talks to no GPU or terminal, plots nothing and generates no city: those
//! crates belong to `flaneur-render`, `flaneur-bench` and the command. The renderer,
//! in turn, reads no database: it draws what the walk hands it.
//!
//! The source check reads paths, not types: a `crate::…` or `super::…` path (in a `use`
//! or anywhere in the code) whose first module is a forbidden one, the root's re-exports
//! (`crate::Database`) counted as the module they come from. Comments, strings and
//! `#[cfg(test)]` items are left out, since unit tests may build on anything.

use std::collections::{BTreeMap, BTreeSet};
use std::fs;
use std::path::{Path, PathBuf};
use std::process::Command;

#[path = "layering/scan.rs"]
mod scan;
use scan::{blank_non_code, blank_test_items, is_ident, matching, skip_space};

/// Crates of the experiments and the renderer, which the engine never names.
const UPPER_CRATES: [&str; 2] = ["flaneur_bench", "flaneur_render"];

/// Packages the engine must not depend on, even indirectly.
const FORBIDDEN_PACKAGES: [&str; 7] = [
    "wgpu",
    "winit",
    "clap",
    "plotters",
    "indicatif",
    "image",
    "citygen",
];

fn workspace() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR"))
}

fn engine_src() -> PathBuf {
    workspace().join("crates/flaneur/src")
}

/// One path to a module: its line (1-based), what it names, the engine's top module it
/// reaches (or the crate, for one of [`UPPER_CRATES`]) and the whole path it names
/// below the crate root, as far as it goes before a group or an item's use.
#[derive(Debug, PartialEq)]
struct Reach {
    line: usize,
    path: String,
    top: String,
    full: Vec<String>,
}

/// The `crate::…` and `super::…` paths in the code of the module at `module` (its path
/// below the crate root, e.g. `["cache", "policy"]`), and the crates of
/// [`UPPER_CRATES`] it names; `root` maps the root's re-exported items to their
/// modules.
fn reaches(code: &[u8], module: &[String], root: &BTreeMap<String, String>) -> Vec<Reach> {
    let line_of = |at: usize| 1 + code[..at].iter().filter(|&&c| c == b'\n').count();
    let word_at = |at: usize| -> (String, usize) {
        let end = at + code[at..].iter().take_while(|&&c| is_ident(c)).count();
        (String::from_utf8_lossy(&code[at..end]).into_owned(), end)
    };
    // The position after `::` (and any space) following `at`, if one follows.
    let after_colons = |at: usize| {
        let k = skip_space(code, at);
        code[k..]
            .starts_with(b"::")
            .then(|| skip_space(code, k + 2))
    };
    let mut found = Vec::new();
    let mut i = 0;
    while i < code.len() {
        if !is_ident(code[i]) || (i > 0 && (is_ident(code[i - 1]) || code[i - 1] == b'$')) {
            i += 1;
            continue;
        }
        let (word, end) = word_at(i);
        let start = i;
        i = end;
        if UPPER_CRATES.contains(&word.as_str()) {
            found.push(Reach {
                line: line_of(start),
                path: word.clone(),
                top: word,
                full: Vec::new(),
            });
            continue;
        }
        // The module the path has reached: the root for `crate`, one up for each `super`.
        let mut base: Vec<String> = match word.as_str() {
            "crate" => Vec::new(),
            "super" => module[..module.len().saturating_sub(1)].to_vec(),
            _ => continue,
        };
        let mut prefix = word.clone();
        let Some(mut j) = after_colons(end) else {
            continue; // `pub(crate)`, `pub(super)`
        };
        while word == "super" && word_at(j).0 == "super" {
            let next = word_at(j).1;
            let Some(k) = after_colons(next) else { break };
            base.pop();
            prefix.push_str("::super");
            j = k;
        }
        // The names the path goes on with: one segment, or the first of each item of a
        // group.
        let mut heads = Vec::new();
        if code.get(j) == Some(&b'{') {
            let close = matching(code, j);
            let (mut depth, mut item_start) = (0usize, true);
            for (k, &c) in code.iter().enumerate().take(close).skip(j + 1) {
                match c {
                    b'{' => depth += 1,
                    b'}' => depth -= 1,
                    b',' if depth == 0 => item_start = true,
                    c if item_start && depth == 0 && is_ident(c) => {
                        heads.push(k);
                        item_start = false;
                    }
                    _ => {}
                }
            }
        } else if code.get(j).is_some_and(|&c| is_ident(c)) {
            heads.push(j);
        }
        for h in heads {
            let (name, mut end) = word_at(h);
            let mut full = base.clone();
            if base.is_empty() {
                full.extend(root.get(&name).cloned());
            }
            full.push(name.clone());
            while let Some(k) =
                after_colons(end).filter(|&k| code.get(k).is_some_and(|&c| is_ident(c)))
            {
                let (segment, next) = word_at(k);
                full.push(segment);
                end = next;
            }
            found.push(Reach {
                line: line_of(h),
                path: format!("{prefix}::{name}"),
                top: full[0].clone(),
                full,
            });
        }
        i = i.max(j);
    }
    found
}

/// Every `.rs` file under `dir`, sorted.
fn rust_files(dir: &Path) -> Vec<PathBuf> {
    let mut files = Vec::new();
    let mut stack = vec![dir.to_path_buf()];
    while let Some(d) = stack.pop() {
        for entry in fs::read_dir(&d).unwrap_or_else(|e| panic!("{}: {e}", d.display())) {
            let path = entry.unwrap().path();
            if path.is_dir() {
                stack.push(path);
            } else if path.extension().is_some_and(|x| x == "rs") {
                files.push(path);
            }
        }
    }
    files.sort();
    files
}

/// The module a file of the engine holds: `cache/policy/mod.rs` is `cache::policy`.
fn module_of(src: &Path, file: &Path) -> Vec<String> {
    let rel = file.strip_prefix(src).unwrap().with_extension("");
    let mut parts: Vec<String> = rel
        .components()
        .map(|c| c.as_os_str().to_string_lossy().into_owned())
        .collect();
    if parts.last().is_some_and(|p| p == "mod") {
        parts.pop();
    }
    parts
}

/// The rows of ARCHITECTURE.md's drawing of the engine's layers, top first: the
/// modules each row names before its description.
fn rows() -> Vec<Vec<String>> {
    let text = fs::read_to_string(workspace().join("ARCHITECTURE.md")).unwrap();
    let section = text
        .split("## The engine's layers")
        .nth(1)
        .expect("ARCHITECTURE.md has no section \"The engine's layers\"");
    let drawing = section
        .split("```text")
        .nth(1)
        .and_then(|d| d.split("```").next())
        .expect("the layers' section of ARCHITECTURE.md has no drawing");
    drawing
        .lines()
        .filter(|l| l.chars().next().is_some_and(|c| !c.is_whitespace()))
        .map(|l| {
            let names = l.split("  ").next().unwrap_or_default();
            names
                .split(',')
                .map(|n| n.trim().to_string())
                .filter(|n| !n.is_empty())
                .collect()
        })
        .collect()
}

/// The engine's top modules: the files and folders beside `lib.rs`.
fn engine_modules(src: &Path) -> BTreeSet<String> {
    fs::read_dir(src)
        .unwrap()
        .map(|e| e.unwrap().path())
        .filter(|p| p.is_dir() || p.extension().is_some_and(|x| x == "rs"))
        .map(|p| p.file_stem().unwrap().to_string_lossy().into_owned())
        .filter(|m| m != "lib")
        .collect()
}

/// The root's re-exports (`pub use database::{Database, …}`), each item to its module.
fn root_items(src: &Path) -> BTreeMap<String, String> {
    reexported(&src.join("lib.rs"))
}

/// The items a module's file re-exports (`pub use buffer::{ObjectBuffer, …}`,
/// `pub(crate) use …` too), each to the child module it comes from.
fn reexported(file: &Path) -> BTreeMap<String, String> {
    let text = fs::read_to_string(file).unwrap();
    let code = String::from_utf8(blank_non_code(&text)).unwrap();
    let mut items = BTreeMap::new();
    for statement in code.split(';') {
        let statement = statement.trim().replace("pub(crate) use ", "pub use ");
        let Some(rest) = statement.strip_prefix("pub use ") else {
            continue;
        };
        let Some((module, names)) = rest.split_once("::") else {
            continue;
        };
        for name in names.split(|c: char| c == ',' || c == '{' || c == '}') {
            let name = name.trim().rsplit("::").next().unwrap_or_default();
            if !name.is_empty() {
                items.insert(name.to_string(), module.trim().to_string());
            }
        }
    }
    items
}

/// The engine's source files outside the root and its unit tests, each with its module
/// and its code (comments, strings and test items blanked).
fn engine_files(src: &Path) -> Vec<(PathBuf, Vec<String>, Vec<u8>)> {
    let mut test_only: Vec<Vec<String>> = Vec::new();
    let mut files = Vec::new();
    for file in rust_files(src) {
        let module = module_of(src, &file);
        if module == ["lib"] || test_only.iter().any(|t| module.starts_with(t)) {
            continue;
        }
        let text = fs::read_to_string(&file).unwrap();
        let mut code = blank_non_code(&text);
        for name in blank_test_items(&mut code) {
            let mut m = module.clone();
            m.push(name);
            test_only.push(m);
        }
        files.push((file, module, code));
    }
    files
}

/// The row `module` sits in, 0 the top.
fn row_of(rows: &[Vec<String>], module: &str) -> Option<usize> {
    rows.iter().position(|r| r.iter().any(|m| m == module))
}

/// The paths in `code`, of the engine's module `module`, that reach a row above its
/// own, or a crate of the experiments or the renderer.
fn upward(
    code: &[u8],
    module: &[String],
    rows: &[Vec<String>],
    root: &BTreeMap<String, String>,
) -> Vec<Reach> {
    sorted_reaches(code, module, rows, root).0
}

/// [`upward`]'s paths, and beside them the modules of `module`'s own row that it uses.
fn sorted_reaches(
    code: &[u8],
    module: &[String],
    rows: &[Vec<String>],
    root: &BTreeMap<String, String>,
) -> (Vec<Reach>, Vec<String>) {
    let mine = row_of(rows, &module[0])
        .unwrap_or_else(|| panic!("`{}` sits in no row of ARCHITECTURE.md", module[0]));
    let (mut up, mut beside) = (Vec::new(), Vec::new());
    for r in reaches(code, module, root) {
        if module.first() == Some(&r.top) {
            continue;
        }
        let row = row_of(rows, &r.top);
        if UPPER_CRATES.contains(&r.top.as_str()) || row.is_some_and(|row| row < mine) {
            up.push(r);
        } else if row == Some(mine) {
            beside.push(r.top);
        }
    }
    (up, beside)
}

/// Modules of one row that use each other, round a circle: each circle once, as the
/// modules in it.
fn circles(uses: &BTreeSet<(String, String)>) -> Vec<Vec<String>> {
    // Peel off, again and again, the modules that use none of those left or that none
    // of those left uses: what stays lies on a circle.
    let mut left: BTreeSet<&String> = uses.iter().flat_map(|(a, b)| [a, b]).collect();
    loop {
        let leaves: Vec<&String> = left
            .iter()
            .copied()
            .filter(|m| {
                let uses_one = uses.iter().any(|(a, b)| a == *m && left.contains(b));
                let used = uses.iter().any(|(a, b)| b == *m && left.contains(a));
                !(uses_one && used)
            })
            .collect();
        if leaves.is_empty() {
            break;
        }
        for m in leaves {
            left.remove(m);
        }
    }
    if left.is_empty() {
        Vec::new()
    } else {
        vec![left.into_iter().cloned().collect()]
    }
}

/// Every module of the engine sits in one row of ARCHITECTURE.md's drawing and uses only
/// its own row and those below; inside a row, no modules use each other round a circle.
#[test]
fn every_module_uses_only_its_row_and_those_below() {
    let src = engine_src();
    let (rows, root) = (rows(), root_items(&src));
    assert!(
        rows.len() >= 8,
        "ARCHITECTURE.md draws {} rows: {rows:?}",
        rows.len()
    );
    let modules = engine_modules(&src);
    for m in &modules {
        let n = rows.iter().flatten().filter(|d| *d == m).count();
        assert_eq!(
            n, 1,
            "`{m}` sits in {n} rows of ARCHITECTURE.md's layers, not one"
        );
    }
    for d in rows.iter().flatten() {
        assert!(
            modules.contains(d),
            "ARCHITECTURE.md's layers draw `{d}`, which is no module of the engine"
        );
    }
    let (mut scanned, mut violations) = (0, Vec::new());
    let mut same_row = BTreeSet::new();
    for (file, module, code) in engine_files(&src) {
        let (up, beside) = sorted_reaches(&code, &module, &rows, &root);
        for r in up {
            violations.push(format!(
                "{}:{}: `{}` reaches up from `{}` to `{}`",
                file.strip_prefix(workspace()).unwrap().display(),
                r.line,
                r.path,
                module.join("::"),
                r.top
            ));
        }
        for top in beside {
            same_row.insert((module[0].clone(), top));
        }
        scanned += 1;
    }
    assert!(scanned >= 200, "only {scanned} files scanned");
    for circle in circles(&same_row) {
        violations.push(format!(
            "{} use each other round a circle, in one row",
            circle.join(", ")
        ));
    }
    assert!(
        violations.is_empty(),
        "the engine's modules must use only their own row of ARCHITECTURE.md's layers \
         and those below it:\n{}",
        violations.join("\n")
    );
}

/// Every module of the engine's `files`, and what each module's file re-exports.
type ModuleMap = (
    BTreeSet<Vec<String>>,
    BTreeMap<Vec<String>, BTreeMap<String, String>>,
);

fn module_map(files: &[(PathBuf, Vec<String>, Vec<u8>)]) -> ModuleMap {
    let modules: BTreeSet<Vec<String>> = files
        .iter()
        .flat_map(|(_, m, _)| (1..=m.len()).map(|n| m[..n].to_vec()))
        .collect();
    let exports: BTreeMap<Vec<String>, BTreeMap<String, String>> = files
        .iter()
        .filter(|(f, _, _)| f.ends_with("mod.rs"))
        .map(|(f, m, _)| (m.clone(), reexported(f)))
        .collect();
    (modules, exports)
}

/// Where the module `from` names the path `to` inside its own top module: the two
/// children of their deepest common module that they lie under, when they differ (an
/// item re-exported by that module counted as the child it comes from).
fn sibling_use(
    from: &[String],
    to: &[String],
    modules: &BTreeSet<Vec<String>>,
    exports: &BTreeMap<Vec<String>, BTreeMap<String, String>>,
) -> Option<(Vec<String>, Vec<String>)> {
    let d = from.iter().zip(to).take_while(|(a, b)| a == b).count();
    if d >= from.len() || d >= to.len() {
        return None;
    }
    let parent = &from[..d];
    let mut target = to[..=d].to_vec();
    if !modules.contains(&target) {
        target[d] = exports.get(parent)?.get(&to[d])?.clone();
    }
    (modules.contains(&target) && target[d] != from[d]).then(|| (from[..=d].to_vec(), target))
}

/// Inside every module of the engine, its files and folders use each other one way,
/// never round a circle: `walk::review` may use `walk::buffer`, but then not be used by
/// it, directly or through others.
#[test]
fn no_module_s_parts_use_each_other_round_a_circle() {
    let src = engine_src();
    let root = root_items(&src);
    let files = engine_files(&src);
    let (modules, exports) = module_map(&files);
    let mut uses: BTreeMap<Vec<String>, BTreeSet<(String, String)>> = BTreeMap::new();
    let mut where_used = BTreeMap::new();
    for (file, module, code) in &files {
        for r in reaches(code, module, &root) {
            if let Some((a, b)) = sibling_use(module, &r.full, &modules, &exports) {
                let parent = a[..a.len() - 1].to_vec();
                let pair = (a.join("::"), b.join("::"));
                let at = format!("{}:{}", file.strip_prefix(&src).unwrap().display(), r.line);
                where_used.entry(pair.clone()).or_insert(at);
                uses.entry(parent).or_default().insert(pair);
            }
        }
    }
    assert!(
        uses.len() >= 10,
        "only {} modules' parts use each other",
        uses.len()
    );
    // Each circle with the uses that close it, where each is first written.
    let found: Vec<String> = uses
        .values()
        .flat_map(circles)
        .map(|c| {
            let inside = where_used
                .iter()
                .filter(|((a, b), _)| c.contains(a) && c.contains(b))
                .map(|((a, b), at)| format!("  {a} uses {b} ({at})"));
            std::iter::once(c.join(", "))
                .chain(inside)
                .collect::<Vec<_>>()
                .join("\n")
        })
        .collect();
    assert!(
        found.is_empty(),
        "these parts of one module use each other round a circle:\n{}",
        found.join("\n")
    );
}

/// A use between two parts of one module is found at the depth where they part, a
/// re-exported item counted as the file it comes from; a use of a parent is none.
#[test]
fn uses_between_parts_are_found_where_they_part() {
    let src = engine_src();
    let files = engine_files(&src);
    let (modules, exports) = module_map(&files);
    let path = |p: &str| p.split("::").map(String::from).collect::<Vec<_>>();
    let found = |from: &str, to: &str| {
        sibling_use(&path(from), &path(to), &modules, &exports)
            .map(|(a, b)| (a.join("::"), b.join("::")))
    };
    let pair = |a: &str, b: &str| Some((a.to_string(), b.to_string()));
    // A planted use of REVIEW's mode in its config, the reverse of the one it has.
    assert_eq!(
        found("walk::review::config", "walk::review::mode::Review"),
        pair("walk::review::config", "walk::review::mode")
    );
    assert_eq!(
        found("walk::review::mode", "walk::ObjectBuffer"),
        pair("walk::review", "walk::buffer")
    );
    assert_eq!(found("walk::review::mode", "walk::review::Counts"), None);
}

/// The check fails where a module reaches up: a use of the walk, and of the database
/// through the root's re-export, planted in the store's header.
#[test]
fn a_planted_upward_import_is_found() {
    let src = engine_src();
    let (rows, root) = (rows(), root_items(&src));
    let file = src.join("store/header.rs");
    let module = module_of(&src, &file);
    let text = fs::read_to_string(&file).unwrap();
    assert!(upward(&blank_non_code(&text), &module, &rows, &root).is_empty());
    let planted =
        format!("{text}\nuse crate::walk::ObjectBuffer;\nfn planted(_: &crate::Database) {{}}\n");
    let found = upward(&blank_non_code(&planted), &module, &rows, &root);
    let tops: Vec<(&str, &str)> = found
        .iter()
        .map(|r| (r.path.as_str(), r.top.as_str()))
        .collect();
    assert_eq!(
        tops,
        [("crate::walk", "walk"), ("crate::Database", "database")]
    );
}

/// Two modules of one row that use each other are a circle; a chain is not.
#[test]
fn circles_are_found() {
    let pair = |a: &str, b: &str| (a.to_string(), b.to_string());
    let chain: BTreeSet<_> = [pair("a", "b"), pair("b", "c")].into();
    assert!(circles(&chain).is_empty());
    let round: BTreeSet<_> = [
        pair("a", "b"),
        pair("b", "c"),
        pair("c", "a"),
        pair("d", "a"),
    ]
    .into();
    assert_eq!(circles(&round), [["a", "b", "c"]]);
}

/// The renderer draws what the walk selected and never reads the database: its code
/// names neither the `Database` nor the engine's `database` and `store` modules, so
/// that every page a walk reads is the walk's, counted in its figures, and a frame's
/// data flows one way.
#[test]
fn the_renderer_never_reads_the_database() {
    let src = workspace().join("crates/flaneur-render/src");
    let mut violations = Vec::new();
    let files = rust_files(&src);
    assert!(files.len() >= 10, "only {} renderer files", files.len());
    for file in files {
        let text = fs::read_to_string(&file).unwrap();
        let code = String::from_utf8(blank_non_code(&text)).unwrap();
        for (n, line) in code.lines().enumerate() {
            let squeezed: String = line.chars().filter(|c| !c.is_whitespace()).collect();
            let names_database = line
                .split(|c: char| !(c.is_ascii_alphanumeric() || c == '_'))
                .any(|w| w == "Database");
            if names_database
                || squeezed.contains("flaneur::database")
                || squeezed.contains("flaneur::store")
            {
                violations.push(format!(
                    "{}:{}: {}",
                    file.strip_prefix(workspace()).unwrap().display(),
                    n + 1,
                    line.trim()
                ));
            }
        }
    }
    assert!(
        violations.is_empty(),
        "the renderer must draw what the walk hands it, not read the database:\n{}",
        violations.join("\n")
    );
}

/// The checker itself: it finds each way of writing a forbidden path and nothing in
/// comments, strings or unit tests.
#[test]
fn the_checker_sees_forbidden_paths() {
    let code = r##"
use crate::store::Store;
use crate::walk::Walk;
use crate::{geom::Aabb, database::Database};
use crate::{
    error::Result,
    prefetch::pvs::{Cell, Snp},
};
use super::super::build::BuildOptions;
use super::frames::Frames;
fn f() -> crate::catalog::KindCounts { todo!() }
// use crate::walk::Comment;
const S: &str = "crate::walk::String";
const R: &str = r#"crate::build::Raw"#;
fn g<'a>(x: &'a str) -> char { 'x' }
#[cfg(test)]
mod tests {
    use crate::database::Database;
}
#[cfg(test)]
mod more_tests;
"##;
    let mut blanked = blank_non_code(code);
    let test_modules = blank_test_items(&mut blanked);
    assert_eq!(test_modules, ["more_tests"]);
    let module = ["cache".to_string(), "pool".to_string()];
    let found = upward(&blanked, &module, &rows(), &root_items(&engine_src()));
    let got: Vec<(usize, &str)> = found.iter().map(|r| (r.line, r.path.as_str())).collect();
    assert_eq!(
        got,
        [
            (3, "crate::walk"),
            (4, "crate::database"),
            (7, "crate::prefetch"),
            (9, "super::super::build"),
            (11, "crate::catalog"),
        ]
    );
}

#[test]
fn the_engine_depends_on_no_front_end_crate() {
    let manifest = workspace().join("Cargo.toml");
    let out = Command::new(env!("CARGO"))
        .args([
            "tree", "-p", "flaneur", "-e", "normal", "--prefix", "none", "--locked",
        ])
        .arg("--manifest-path")
        .arg(&manifest)
        .output()
        .unwrap_or_else(|e| panic!("cannot run cargo tree: {e}"));
    assert!(
        out.status.success(),
        "cargo tree failed ({}):\n{}",
        out.status,
        String::from_utf8_lossy(&out.stderr)
    );
    let tree = String::from_utf8_lossy(&out.stdout);
    assert!(
        tree.lines().any(|l| l.starts_with("flaneur v")),
        "cargo tree did not list the engine:\n{tree}"
    );
    let found: Vec<&str> = tree
        .lines()
        .filter(|l| {
            l.split_whitespace()
                .next()
                .is_some_and(|name| FORBIDDEN_PACKAGES.contains(&name))
        })
        .collect();
    assert!(
        found.is_empty(),
        "the engine depends on {}, which belong to the front ends:\n{}",
        found.join(", "),
        tree
    );
}
