//! The architecture's seams, checked: the numerical core depends on no IO crate, no source
//! file outgrows one head, and the application's files import each other without a circle.

use std::collections::{BTreeMap, BTreeSet};
use std::path::{Path, PathBuf};

fn root() -> PathBuf {
    crate::repo_root()
}

fn rust_files(dir: &Path, out: &mut Vec<PathBuf>) {
    for e in std::fs::read_dir(dir).unwrap() {
        let p = e.unwrap().path();
        if p.is_dir() {
            rust_files(&p, out);
        } else if p.extension().is_some_and(|x| x == "rs") {
            out.push(p);
        }
    }
}

/// `cargo tree` of the core crate lists none of the application's crates.
#[test]
fn the_core_crate_depends_on_no_table_yaml_plot_or_progress_crate() {
    let cargo = std::env::var("CARGO").unwrap_or_else(|_| "cargo".into());
    let out = std::process::Command::new(cargo)
        .current_dir(root())
        .args([
            "tree",
            "-p",
            "wearcoef-core",
            "-e",
            "normal",
            "--prefix",
            "none",
            "--offline",
        ])
        .output()
        .expect("cargo runs");
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let tree = String::from_utf8_lossy(&out.stdout);
    assert!(
        tree.contains("rustfft"),
        "the tree lists the core's crates: {tree}"
    );
    for banned in [
        "polars",
        "serde_yaml",
        "serde-saphyr",
        "plotters",
        "indicatif",
    ] {
        assert!(
            !tree.lines().any(|l| l.starts_with(&format!("{banned} "))),
            "wearcoef-core depends on {banned}"
        );
    }
}

#[test]
fn no_source_file_is_over_700_lines() {
    let mut files = Vec::new();
    rust_files(&root().join("src"), &mut files);
    rust_files(&root().join("crates"), &mut files);
    rust_files(&root().join("tests"), &mut files);
    rust_files(&root().join("benches"), &mut files);
    let long: Vec<String> = files
        .iter()
        .filter_map(|f| {
            let lines = std::fs::read_to_string(f).unwrap().lines().count();
            (lines > 700).then(|| format!("{} ({lines})", f.display()))
        })
        .collect();
    assert!(long.is_empty(), "split these: {long:?}");
}

/// `text` with comments, string literals and character literals blanked (newlines kept), so
/// that the braces left are the code's.
fn code_only(text: &str) -> String {
    let b = text.as_bytes();
    let mut out = String::with_capacity(text.len());
    let blank = |s: &str, out: &mut String| {
        out.extend(s.chars().map(|c| if c == '\n' { '\n' } else { ' ' }));
    };
    let mut i = 0;
    while i < b.len() {
        let rest = &text[i..];
        let end = if rest.starts_with("//") {
            rest.find('\n').unwrap_or(rest.len())
        } else if rest.starts_with("/*") {
            rest.find("*/").map_or(rest.len(), |e| e + 2)
        } else if let Some(hashes) = rest
            .strip_prefix('r')
            .filter(|r| r.starts_with('"') || r.starts_with("#\""))
            .map(|r| r.len() - r.trim_start_matches('#').len())
            .filter(|_| i == 0 || !(b[i - 1].is_ascii_alphanumeric() || b[i - 1] == b'_'))
        {
            let close = format!("\"{}", "#".repeat(hashes));
            let open = 2 + hashes;
            rest[open..]
                .find(&close)
                .map_or(rest.len(), |e| open + e + close.len())
        } else if rest.starts_with('"') {
            let mut j = 1;
            while j < rest.len() && rest.as_bytes()[j] != b'"' {
                j += if rest.as_bytes()[j] == b'\\' { 2 } else { 1 };
            }
            j + 1
        } else if let Some(body) = rest.strip_prefix('\'') {
            // A character literal ('x', '\n', '\u{7b}'), not a lifetime ('a).
            let len = if body.starts_with('\\') {
                body.find('\'').map(|e| e + 2)
            } else {
                body.chars()
                    .next()
                    .map(|c| c.len_utf8())
                    .filter(|&n| body[n..].starts_with('\''))
                    .map(|n| n + 2)
            };
            len.unwrap_or(0)
        } else {
            0
        };
        if end > 0 {
            blank(&rest[..end.min(rest.len())], &mut out);
            i += end.min(rest.len());
        } else {
            let c = rest.chars().next().unwrap();
            out.push(c);
            i += c.len_utf8();
        }
    }
    out
}

/// Every function with a body in `text`: its name, first line (1-based) and length in lines,
/// from the `fn` line to its closing brace.
fn function_lengths(text: &str) -> Vec<(String, usize, usize)> {
    let code = code_only(text);
    let line_of = |at: usize| code[..at].matches('\n').count() + 1;
    let mut found = Vec::new();
    let mut from = 0;
    while let Some(k) = code[from..].find("fn ") {
        let at = from + k;
        from = at + 3;
        let word_start = at == 0
            || !code.as_bytes()[at - 1].is_ascii_alphanumeric() && code.as_bytes()[at - 1] != b'_';
        let name: String = code[at + 3..]
            .trim_start()
            .chars()
            .take_while(|c| c.is_alphanumeric() || *c == '_')
            .collect();
        if !word_start || name.is_empty() {
            continue;
        }
        // The body's brace, unless a `;` outside brackets ends a declaration first.
        let (mut depth, mut open) = (0i32, None);
        for (j, c) in code[at..].char_indices() {
            match c {
                '(' | '[' => depth += 1,
                ')' | ']' => depth -= 1,
                ';' if depth == 0 => break,
                '{' => {
                    open = Some(at + j);
                    break;
                }
                _ => {}
            }
        }
        let Some(open) = open else { continue };
        let mut braces = 0;
        for (j, c) in code[open..].char_indices() {
            match c {
                '{' => braces += 1,
                '}' => braces -= 1,
                _ => continue,
            }
            if braces == 0 {
                found.push((name, line_of(at), line_of(open + j) - line_of(at) + 1));
                break;
            }
        }
    }
    found
}

/// No function in `src/` or any crate under `crates/` is over 120 lines (CONTRIBUTING.md:
/// functions fit on a screen or two; most are under 60).
#[test]
fn no_function_is_over_120_lines() {
    let mut files = Vec::new();
    rust_files(&root().join("src"), &mut files);
    rust_files(&root().join("crates"), &mut files);
    let mut long = Vec::new();
    let mut count = 0;
    for f in &files {
        for (name, line, lines) in function_lengths(&std::fs::read_to_string(f).unwrap()) {
            count += 1;
            if lines > 120 {
                long.push(format!("{}:{line} {name} ({lines} lines)", f.display()));
            }
        }
    }
    assert!(
        count > 500,
        "only {count} functions found: the scan is broken"
    );
    assert!(long.is_empty(), "split these: {long:?}");
}

/// The function scan measures a function from its `fn` line to its closing brace, whatever
/// braces its strings, characters and comments hold, and skips bodiless declarations.
#[test]
fn the_function_scan_measures_a_fixture() {
    let body: String = (0..125)
        .map(|k| format!("    let x{k} = '{{';\n"))
        .collect();
    let text = format!(
        "trait T {{\n    fn declared(&self, x: [f64; 4]);\n}}\n\
         /// A doc comment with a brace {{\n\
         pub(super) fn long<'a>(a: &'a str) -> usize {{\n\
         {body}    let s = \"}} {{ }}\"; // }}\n    let r = r#\"}}\"#;\n    s.len()\n}}\n\
         fn short() {{ /* }} */ }}\n"
    );
    let found = function_lengths(&text);
    let names: Vec<(&str, usize)> = found.iter().map(|(n, _, l)| (n.as_str(), *l)).collect();
    assert_eq!(names, [("long", 125 + 5), ("short", 1)], "{found:?}");
}

/// The module path of a library file (`src/pipeline/plan.rs` → `pipeline::plan`).
fn module_of(file: &Path, src: &Path) -> String {
    let rel = file.strip_prefix(src).unwrap().with_extension("");
    let mut parts: Vec<String> = rel
        .components()
        .map(|c| c.as_os_str().to_string_lossy().into_owned())
        .collect();
    if parts
        .last()
        .is_some_and(|p| p == "mod" || p == "lib" || p == "main")
    {
        parts.pop();
    }
    parts.join("::")
}

/// The child modules a file declares (`mod a;`, `pub mod b;`, `pub(crate) mod c;`).
fn children_declared(code: &str) -> Vec<String> {
    code.lines()
        .filter_map(|l| {
            let l = l.trim();
            let rest = l.strip_suffix(';')?;
            let rest = rest
                .strip_prefix("pub(crate) ")
                .or_else(|| rest.strip_prefix("pub(super) "))
                .or_else(|| rest.strip_prefix("pub "))
                .unwrap_or(rest);
            let name = rest.strip_prefix("mod ")?.trim();
            name.chars()
                .all(|c| c.is_alphanumeric() || c == '_')
                .then(|| name.to_string())
        })
        .collect()
}

/// Every `crate::…`, `super::…`, `self::…` path of a file, and every path through a child
/// module it declares (`use child::X`), resolved to module paths (`{a, b}` groups split; the
/// item names at the end are kept and trimmed later).
fn paths_in(text: &str, module: &str, is_mod_file: bool) -> Vec<String> {
    let mut out = Vec::new();
    let mut code: String = text
        .lines()
        .filter(|l| !l.trim_start().starts_with("//"))
        .collect::<Vec<_>>()
        .join("\n");
    // A file's inline test module (last, by convention) is not part of the design, and its
    // `super::` is the file itself.
    let inline_tests = code
        .match_indices("#[cfg(test)]\n")
        .map(|(i, _)| i)
        .find(|&i| {
            let line = code[i..].lines().nth(1).unwrap_or("").trim();
            let line = line.strip_prefix("pub(super) ").unwrap_or(line);
            line.starts_with("mod ") && line.ends_with('{')
        });
    if let Some(i) = inline_tests {
        code.truncate(i);
    }
    let mut prefixes = vec![
        ("crate::".to_string(), String::new()),
        ("super::".to_string(), {
            // The parent of this file's module (for a mod.rs, of the directory's module).
            let mut m: Vec<&str> = module.split("::").filter(|s| !s.is_empty()).collect();
            if !is_mod_file || !m.is_empty() {
                m.pop();
            }
            m.join("::")
        }),
        ("self::".to_string(), module.to_string()),
    ];
    for child in children_declared(&code) {
        prefixes.push((format!("{child}::"), module.to_string()));
    }
    for (prefix, base) in &prefixes {
        let (prefix, base) = (prefix.as_str(), base.as_str());
        let child_prefix = !["crate::", "super::", "self::"].contains(&prefix);
        for (at, _) in code.match_indices(prefix) {
            // The character before the match in the whole file (`super::super::` is one path).
            let before = code[..at].chars().last();
            let rest = &code[at + prefix.len()..];
            // Nor is a visibility (`pub(in super::super)`) an import.
            if before.is_some_and(|c| c.is_alphanumeric() || c == '_' || c == ':')
                || code[..at].ends_with("(in ")
            {
                continue;
            }
            let end = rest
                .find(|c: char| !(c.is_alphanumeric() || c == '_' || c == ':'))
                .unwrap_or(rest.len());
            let path = rest[..end].trim_end_matches(':');
            // A child's prefix is part of the path (`child::X` is `module::child::X`).
            let path = if child_prefix {
                format!("{prefix}{path}").trim_end_matches(':').to_string()
            } else {
                path.to_string()
            };
            // `super::super::…` climbs one module more per `super`.
            let mut base: Vec<&str> = base.split("::").filter(|s| !s.is_empty()).collect();
            let mut path = path.as_str();
            if prefix == "super::" {
                while let Some(rest) = path
                    .strip_prefix("super::")
                    .or((path == "super").then_some(""))
                {
                    base.pop();
                    path = rest;
                }
            }
            let path = path.to_string();
            let full = if base.is_empty() {
                path
            } else if path.is_empty() {
                base.join("::")
            } else {
                format!("{}::{path}", base.join("::"))
            };
            out.push(full.clone());
            // `use x::{a, b::c}`: each member too.
            if rest[end..].starts_with('{') {
                let close = rest[end..].find('}').map_or(rest.len(), |j| end + j);
                for member in rest[end + 1..close].split(',') {
                    let m = member.trim().split(" as ").next().unwrap_or("").trim();
                    if !m.is_empty() && m != "self" && m != "*" {
                        out.push(format!("{full}::{m}"));
                    }
                }
            }
        }
    }
    out
}

/// The import circles among the library files of `src` (a crate's source directory), files
/// whose path starts with one of `skip` left out: each as `a -> b -> … -> a`. Module
/// granularity is the file (a `mod.rs` stands for its directory's own items).
fn import_circles(src: &Path, skip: &[PathBuf]) -> (Vec<String>, usize) {
    let mut files = Vec::new();
    rust_files(src, &mut files);
    files.retain(|f| !f.ends_with("main.rs") && !skip.iter().any(|s| f.starts_with(s)));
    circles_among(src, &files)
}

/// The import circles among `files` of the crate rooted at `src`.
fn circles_among(src: &Path, files: &[PathBuf]) -> (Vec<String>, usize) {
    let modules: BTreeMap<String, PathBuf> = files
        .iter()
        .map(|f| (module_of(f, src), f.clone()))
        .collect();
    let resolve = |path: &str| -> Option<String> {
        let parts: Vec<&str> = path.split("::").collect();
        (1..=parts.len())
            .rev()
            .map(|k| parts[..k].join("::"))
            .find(|m| modules.contains_key(m))
    };
    let mut edges: BTreeMap<String, BTreeSet<String>> = BTreeMap::new();
    for (module, file) in &modules {
        let text = std::fs::read_to_string(file).unwrap();
        let is_mod = file.ends_with("mod.rs");
        for p in paths_in(&text, module, is_mod) {
            if let Some(target) = resolve(&p).filter(|t| t != module && !t.is_empty()) {
                edges.entry(module.clone()).or_default().insert(target);
            }
        }
    }
    // A module depending on its parent (its `mod.rs`) and the parent naming the child is
    // the module tree, not an import circle; every other cycle is reported.
    fn visit(
        m: &str,
        edges: &BTreeMap<String, BTreeSet<String>>,
        state: &mut BTreeMap<String, u8>,
        stack: &mut Vec<String>,
        cycles: &mut Vec<String>,
    ) {
        state.insert(m.to_string(), 1);
        stack.push(m.to_string());
        for t in edges.get(m).into_iter().flatten() {
            match state.get(t.as_str()) {
                Some(1) => {
                    let from = stack.iter().position(|s| s == t).unwrap();
                    cycles.push(format!("{} -> {t}", stack[from..].join(" -> ")));
                }
                Some(_) => {}
                None => visit(t, edges, state, stack, cycles),
            }
        }
        stack.pop();
        state.insert(m.to_string(), 2);
    }
    let mut state = BTreeMap::new();
    let mut cycles = Vec::new();
    for m in modules.keys() {
        if !state.contains_key(m.as_str()) {
            visit(m, &edges, &mut state, &mut Vec::new(), &mut cycles);
        }
    }
    (cycles, edges.values().map(BTreeSet::len).sum())
}

/// Modules whose `mod.rs` still holds items its children import while it imports them back
/// (a parent-and-child knot; each to be untied by moving those items into a child of their
/// own, so that the parent only declares and re-exports), in the application (src/) and in
/// the core crate. The scan must find exactly these: a new circle fails, and so does a knot
/// untied but still listed.
const APP_KNOTS_LEFT: [&str; 0] = [];
const CORE_KNOTS_LEFT: [&str; 0] = [];

/// The circles' outermost modules (`a -> a::b -> a` is a knot at `a`).
fn knots(cycles: &[String]) -> BTreeSet<String> {
    cycles
        .iter()
        .filter_map(|c| {
            c.split(" -> ")
                .min_by_key(|m| (m.matches("::").count(), m.to_string()))
                .map(str::to_string)
        })
        .collect()
}

/// Each circle found is a knot `listed`, and each knot listed is still found.
fn check_circles(cycles: &[String], listed: &[&str], place: &str) {
    let found = knots(cycles);
    let unknown: Vec<&String> = found
        .iter()
        .filter(|k| !listed.contains(&k.as_str()))
        .collect();
    assert!(unknown.is_empty(), "import circles in {place}: {cycles:#?}");
    let untied: Vec<&&str> = listed.iter().filter(|k| !found.contains(**k)).collect();
    assert!(
        untied.is_empty(),
        "{place}: {untied:?} no longer knotted: remove them from the knots left"
    );
}

#[test]
fn the_application_modules_import_each_other_without_a_circle() {
    let src = root().join("src");
    // Library files only (main.rs and cli/ are the binary, a crate of their own).
    let (cycles, edges) = import_circles(&src, &[src.join("cli")]);
    assert!(edges > 20, "the scan finds the imports ({edges} edges)");
    check_circles(&cycles, &APP_KNOTS_LEFT, "src/");
}

/// The binary (src/main.rs and the commands under src/cli/) is a crate of its own: its
/// modules import each other without a circle too.
#[test]
fn the_command_line_modules_import_each_other_without_a_circle() {
    let src = root().join("src");
    let mut files = vec![src.join("main.rs")];
    rust_files(&src.join("cli"), &mut files);
    let (cycles, edges) = circles_among(&src, &files);
    assert!(edges > 8, "the scan finds the imports ({edges} edges)");
    assert!(cycles.is_empty(), "import circles in src/cli/: {cycles:#?}");
}

#[test]
fn the_workspace_crates_import_their_modules_without_a_circle() {
    let mut checked = 0;
    for e in std::fs::read_dir(root().join("crates")).unwrap() {
        let src = e.unwrap().path().join("src");
        if !src.is_dir() {
            continue;
        }
        let (cycles, edges) = import_circles(&src, &[]);
        // A crate of one file (the Python package's conversions) has no module to import.
        let mut files = Vec::new();
        rust_files(&src, &mut files);
        let files = files.len();
        assert!(
            files == 1 || edges > 10,
            "{}: the scan finds the imports ({edges} edges in {files} files)",
            src.display()
        );
        let listed: &[&str] = if src.ends_with("core/src") {
            &CORE_KNOTS_LEFT
        } else {
            &[]
        };
        check_circles(&cycles, listed, &src.display().to_string());
        checked += 1;
    }
    assert!(checked > 0, "no crate under crates/");
}

/// The imports of `files` (of the crate rooted at `src`) that point up: to an item of an
/// ancestor's own file (a `mod.rs`; the crate root is not counted), as `module -> path`. A parent
/// declares and re-exports its children; what they share is in a sibling. A child's test
/// file (`tests.rs`, `test_support.rs`) may read its parent's items.
fn arrows_up(src: &Path, files: &[PathBuf]) -> Vec<String> {
    let modules: BTreeSet<String> = files.iter().map(|f| module_of(f, src)).collect();
    let mut up = Vec::new();
    for f in files {
        let module = module_of(f, src);
        let last = module.rsplit("::").next().unwrap_or("");
        if last == "tests" || last == "test_support" {
            continue;
        }
        let text = std::fs::read_to_string(f).unwrap();
        for p in paths_in(&text, &module, f.ends_with("mod.rs")) {
            let parts: Vec<&str> = p.split("::").collect();
            // The crate root re-exports and holds the crate's macros; it is not counted.
            let Some(target) = (1..=parts.len())
                .rev()
                .map(|k| parts[..k].join("::"))
                .find(|m| modules.contains(m))
            else {
                continue;
            };
            if module.starts_with(&format!("{target}::")) {
                up.push(format!("{module} -> {p}"));
            }
        }
    }
    up.sort();
    up.dedup();
    up
}

/// No module of the workspace's crates or of the application imports an item from an
/// ancestor's own file.
#[test]
fn no_module_imports_from_its_ancestors() {
    let mut found = Vec::new();
    let mut dirs = vec![root().join("src")];
    for e in std::fs::read_dir(root().join("crates")).unwrap() {
        dirs.push(e.unwrap().path().join("src"));
    }
    for src in dirs.iter().filter(|d| d.is_dir()) {
        let mut files = Vec::new();
        rust_files(src, &mut files);
        files.retain(|f| !f.ends_with("main.rs"));
        found.extend(arrows_up(src, &files));
    }
    assert!(found.is_empty(), "imports from an ancestor: {found:#?}");
}

/// The arrow scan finds a child importing its parent's item, and not a child importing a
/// sibling through the parent's path.
#[test]
fn the_arrow_scan_finds_a_child_importing_its_parent() {
    let dir = tempfile::tempdir().unwrap();
    let src = dir.path();
    std::fs::create_dir_all(src.join("whole")).unwrap();
    let write = |p: &str, text: &str| std::fs::write(src.join(p), text).unwrap();
    write("lib.rs", "pub mod whole;\n");
    write("whole/mod.rs", "mod part;\nmod base;\npub struct Whole;\n");
    write("whole/base.rs", "pub struct Base;\n");
    write(
        "whole/part.rs",
        "use super::Whole;\nuse super::base::Base;\n",
    );
    let files: Vec<PathBuf> = ["lib.rs", "whole/mod.rs", "whole/base.rs", "whole/part.rs"]
        .iter()
        .map(|p| src.join(p))
        .collect();
    assert_eq!(arrows_up(src, &files), ["whole::part -> whole::Whole"]);
    write("whole/part.rs", "use super::base::Base;\n");
    assert!(arrows_up(src, &files).is_empty());
}

/// The scan itself finds a circle: three files importing each other in a ring (by `crate::`
/// and by `super::`), beside a file outside it.
#[test]
fn the_circle_scan_finds_a_small_circle() {
    let dir = tempfile::tempdir().unwrap();
    let src = dir.path();
    std::fs::create_dir_all(src.join("ring")).unwrap();
    let write = |p: &str, text: &str| std::fs::write(src.join(p), text).unwrap();
    write("lib.rs", "pub mod ring;\npub mod alone;\n");
    write("alone.rs", "use crate::ring::a::A;\n");
    write("ring/mod.rs", "pub mod a;\npub mod b;\npub mod c;\n");
    write("ring/a.rs", "use super::b::B;\npub struct A;\n");
    write("ring/b.rs", "use crate::ring::c::{C, D};\npub struct B;\n");
    write(
        "ring/c.rs",
        "// use crate::alone;\nuse crate::ring::a::A;\npub struct C;\n",
    );
    let (cycles, edges) = import_circles(src, &[]);
    assert_eq!(
        cycles,
        ["ring::a -> ring::b -> ring::c -> ring::a"],
        "{edges} edges"
    );
    // Broken ring: no circle.
    write("ring/c.rs", "pub struct C;\n");
    assert!(import_circles(src, &[]).0.is_empty());
}

/// The scan reads a parent's imports of its own children: a `mod.rs` that re-exports its
/// child while the child imports the parent is a circle (the solver's knot, in small).
#[test]
fn the_circle_scan_finds_a_parent_and_child_knot() {
    let dir = tempfile::tempdir().unwrap();
    let src = dir.path();
    std::fs::create_dir_all(src.join("knot")).unwrap();
    let write = |p: &str, text: &str| std::fs::write(src.join(p), text).unwrap();
    write("lib.rs", "pub mod knot;\n");
    write(
        "knot/mod.rs",
        "mod part;\npub use part::Part;\npub struct Whole;\n",
    );
    write(
        "knot/part.rs",
        "use super::Whole;\npub struct Part(Whole);\n",
    );
    let (cycles, _) = import_circles(src, &[]);
    assert_eq!(cycles, ["knot -> knot::part -> knot"]);
    // The parent only declaring its child, the child importing the parent: no circle.
    write("knot/mod.rs", "pub mod part;\npub struct Whole;\n");
    assert!(import_circles(src, &[]).0.is_empty());
}

/// The application's layers (src/lib.rs): a module imports its own layer and lower ones only,
/// and the plan and the report do not import the drawing code.
#[test]
fn the_application_modules_import_only_their_layer_and_lower_ones() {
    let layer = |top: &str| -> Option<u8> {
        Some(match top {
            // The core crate's modules, re-exported.
            "analytic" | "clusters" | "contact" | "grid" | "pages" | "powerlaw" | "psd"
            | "resample" | "spectral" | "statistics" | "surface" | "topography" => 0,
            // `note!`, the crate's stderr macro, belongs to the lowest layer.
            "io" | "machine" | "format" | "ranges" | "units" | "tail" | "note" => 1,
            "store" | "config" | "solve" => 2,
            "stages" | "figures" => 3,
            "pipeline" | "wear" => 4,
            _ => return None,
        })
    };
    let src = root().join("src");
    let mut files = Vec::new();
    rust_files(&src, &mut files);
    files.retain(|f| {
        !f.ends_with("main.rs") && !f.ends_with("lib.rs") && !f.starts_with(src.join("cli"))
    });
    let mut wrong = Vec::new();
    let mut seen = 0;
    for f in &files {
        let module = module_of(f, &src);
        let top = module.split("::").next().unwrap_or("").to_string();
        let Some(own) = layer(&top) else {
            wrong.push(format!("{module}: module {top} has no layer in this test"));
            continue;
        };
        let text = std::fs::read_to_string(f).unwrap();
        for p in paths_in(&text, &module, f.ends_with("mod.rs")) {
            let target = p.split("::").next().unwrap_or("");
            if target.is_empty() || target == top {
                continue;
            }
            seen += 1;
            match layer(target) {
                Some(l) if l > own => wrong.push(format!("{module} imports {p} (a higher layer)")),
                None => wrong.push(format!("{module} imports {p}, of no layer")),
                _ => {}
            }
            let drawing = ["pipeline::plan", "pipeline::report"];
            if target == "figures" && drawing.iter().any(|d| module.starts_with(d)) {
                wrong.push(format!("{module} imports the drawing code ({p})"));
            }
        }
    }
    assert!(seen > 50, "the scan finds the imports ({seen})");
    assert!(wrong.is_empty(), "layering: {wrong:#?}");
}
