//! The documentation that states what the code is: docs/BENCHMARKS.md generated from the
//! dated runs under docs/benchmarks/ with no dated prose, and docs/ARCHITECTURE.md's code
//! excerpts found verbatim in the files they name.

use crate::repo_root;
use std::process::Command;

/// `scripts/benchmarks.py` with `args` (on the repository's docs unless `--dir` and `--out`
/// say otherwise).
fn benchmarks(args: &[&str]) -> std::process::Output {
    Command::new("python3")
        .arg(repo_root().join("scripts/benchmarks.py"))
        .args(args)
        .output()
        .expect("python3 runs scripts/benchmarks.py")
}

#[test]
fn the_benchmarks_page_is_generated_from_its_runs() {
    let out = benchmarks(&["--check"]);
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
}

/// The check fails on a topic's text that carries a date, a version or a commit, and on a
/// page that is not what the runs give (a run appended to a CSV and not redrawn).
#[test]
fn the_benchmarks_check_refuses_dated_prose_and_a_stale_page() {
    let dir = tempfile::tempdir().unwrap();
    let copy = dir.path().join("benchmarks");
    std::fs::create_dir(&copy).unwrap();
    for e in std::fs::read_dir(repo_root().join("docs/benchmarks")).unwrap() {
        let p = e.unwrap().path();
        std::fs::copy(&p, copy.join(p.file_name().unwrap())).unwrap();
    }
    let page = dir.path().join("BENCHMARKS.md");
    std::fs::copy(repo_root().join("docs/BENCHMARKS.md"), &page).unwrap();
    let run = || {
        let out = benchmarks(&[
            "--check",
            "--dir",
            copy.to_str().unwrap(),
            "--out",
            page.to_str().unwrap(),
        ]);
        (
            out.status.code(),
            String::from_utf8_lossy(&out.stderr).into_owned(),
        )
    };
    assert_eq!(
        run().0,
        Some(0),
        "the copy checks as the original: {}",
        run().1
    );
    let text = copy.join("fft.md");
    let original = std::fs::read_to_string(&text).unwrap();
    for (dated, what) in [
        ("Measured 2026-12-01.", "a date"),
        ("As of version 12.", "a stage version"),
        ("At c9d576a.", "a commit"),
    ] {
        std::fs::write(&text, format!("{original}\n{dated}\n")).unwrap();
        let (code, err) = run();
        assert_eq!(code, Some(1), "{dated}: {err}");
        assert!(
            err.contains("fft.md") && err.contains(what),
            "{dated}: {err}"
        );
    }
    std::fs::write(&text, &original).unwrap();
    // A newer run of one row: the page must be redrawn.
    let csv = copy.join("labelling.csv");
    let mut rows = std::fs::read_to_string(&csv).unwrap();
    let last = rows.lines().last().unwrap().to_string();
    rows.push_str(&format!(
        "{}\n",
        last.replacen(&last[..10], "2099-01-01", 1)
    ));
    std::fs::write(&csv, rows).unwrap();
    let (code, err) = run();
    assert_eq!(code, Some(1), "{err}");
    assert!(err.contains("make benchmarks"), "{err}");
}

/// Each ```rust block of docs/ARCHITECTURE.md that opens with `// <path>: …` is a verbatim
/// excerpt of that file.
#[test]
fn the_architecture_excerpts_are_the_code() {
    let doc = std::fs::read_to_string(repo_root().join("docs/ARCHITECTURE.md")).unwrap();
    let mut checked = 0;
    for block in doc.split("```rust\n").skip(1) {
        let block = block.split("```").next().unwrap();
        let (first, code) = block.split_once('\n').unwrap();
        let Some(path) = first.strip_prefix("// ").and_then(|r| r.split(':').next()) else {
            continue;
        };
        let file = std::fs::read_to_string(repo_root().join(path))
            .unwrap_or_else(|e| panic!("docs/ARCHITECTURE.md names {path}: {e}"));
        assert!(
            file.contains(code),
            "docs/ARCHITECTURE.md's excerpt of {path} is not in it:\n{code}"
        );
        checked += 1;
    }
    assert!(checked > 0, "no excerpt found");
}
