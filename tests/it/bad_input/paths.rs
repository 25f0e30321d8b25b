//! Nothing lost: `clean` removes only a store, no output overwrites an input or lands in a
//! store's cache, whatever names the user gives.

use std::path::Path;

use super::{case, check, Case};

const RUN: &str = "run --profile t --quiet";

fn thesis(dir: &Path) {
    std::fs::create_dir(dir.join("thesis")).unwrap();
    std::fs::write(dir.join("thesis/ch1.tex"), "\\chapter{Wear}").unwrap();
}

fn thesis_with_cache(dir: &Path) {
    thesis(dir);
    std::fs::create_dir(dir.join("thesis/cache")).unwrap();
}

fn store_with_notes(dir: &Path) {
    std::fs::write(dir.join("data/notes.txt"), "mine").unwrap();
}

fn hard_link(dir: &Path) {
    std::fs::hard_link(dir.join("ok.npy"), dir.join("link.npy")).unwrap();
}

/// `clean` removes a directory only when it is a store and nothing but a store; it says
/// what it removes, and `--dry-run` removes nothing.
#[test]
fn clean_removes_only_a_store() {
    let cases = [
        Case {
            prepare: Some(thesis),
            ..case(
                "a directory of other files",
                "clean --data thesis",
                2,
                &["--data thesis", "no store there"],
            )
        },
        Case {
            prepare: Some(thesis_with_cache),
            ..case(
                "a cache/ beside other files",
                "clean --data thesis",
                2,
                &["--data thesis", "ch1.tex", "nothing was removed"],
            )
        },
        Case {
            before: vec![RUN],
            prepare: Some(store_with_notes),
            ..case(
                "a store holding a user's file",
                "clean",
                2,
                &["notes.txt", "not something a wearcoef store holds"],
            )
        },
        case(
            "the working directory",
            "clean --data .",
            2,
            &["--data .", "no store there"],
        ),
        case(
            "a directory that does not exist",
            "clean --data nosuch",
            2,
            &["--data nosuch", "no store there"],
        ),
        Case {
            before: vec![RUN],
            ..case("a dry run", "clean --dry-run", 0, &[])
        },
    ];
    for c in &cases {
        check(c);
    }
    // The real thing: the store goes, and only the store; the message says what went.
    let (_t, dir) = crate::workdir(&crate::small_pipeline(0.8, "x"));
    assert!(crate::run_in(&dir, &["run", "--profile", "t", "--quiet"])
        .status
        .success());
    let dry = crate::run_in(&dir, &["clean", "--dry-run"]);
    let said = String::from_utf8_lossy(&dry.stdout);
    assert!(
        said.contains("would remove the store data") && said.contains("entries"),
        "{said}"
    );
    assert!(dir.join("data/cache").is_dir());
    let out = crate::run_in(&dir, &["clean"]);
    let said = String::from_utf8_lossy(&out.stdout);
    assert!(
        out.status.success() && said.contains("removed the store data"),
        "{said}"
    );
    assert!(!dir.join("data").exists());
    assert!(dir.join("pipeline.yaml").is_file());
}

/// An output is never one of the command's inputs (by any name, hard links included), and
/// never inside a store's cache or failure records.
#[test]
fn outputs_never_overwrite_inputs_or_the_store() {
    let cases = [
        case(
            "pressure onto the surface",
            "solve --surface ok.npy --loads 0.01 --pressure-out ok.npy",
            2,
            &["--pressure-out ok.npy", "is the file --surface reads"],
        ),
        Case {
            prepare: Some(hard_link),
            ..case(
                "contact onto a hard link of the surface",
                "solve --surface ok.npy --loads 0.01 --contact-out link.npy",
                2,
                &["--contact-out link.npy", "is the file --surface reads"],
            )
        },
        case(
            "plan onto its pipeline",
            "plan --profile t --config pipeline.yaml --out ./pipeline.yaml",
            2,
            &["--out ./pipeline.yaml", "is the file --config reads"],
        ),
        Case {
            before: vec![RUN],
            ..case(
                "catalog onto its pipeline",
                "catalog --profile t --config pipeline.yaml -o pipeline.yaml",
                2,
                &["--output pipeline.yaml", "is the file --config reads"],
            )
        },
        Case {
            before: vec![RUN],
            ..case(
                "catalog into the cache",
                "catalog --profile t -o data/cache/surface/c.csv",
                2,
                &["--output data/cache/surface/c.csv", "lies inside the store"],
            )
        },
        Case {
            before: vec![RUN],
            ..case(
                "surface into the cache",
                "surface --n 16 --lambda-l-px 8 --lambda-s-px 2 --hurst 0.8 -o data/cache/h.npy",
                2,
                &["--output data/cache/h.npy", "lies inside the store"],
            )
        },
        Case {
            before: vec![RUN],
            ..case(
                "figures into the cache",
                "run --profile t --figures data/cache/figures",
                2,
                &["--figures data/cache/figures", "lies inside the store"],
            )
        },
        Case {
            before: vec![RUN],
            ..case(
                "figures into the failure records",
                "run --profile t --figures data/failed/new",
                2,
                &["--figures data/failed/new", "lies inside the store"],
            )
        },
        case(
            "figures onto the data directory",
            "run --profile t --figures data --data data",
            2,
            &["--figures data", "is the data directory"],
        ),
        case(
            "a file name longer than a file system allows",
            &format!(
                "surface --n 16 --lambda-l-px 8 --lambda-s-px 2 --hurst 0.8 -o {}.npy",
                "a".repeat(300)
            ),
            2,
            &["more than the 255 a file system allows"],
        ),
        case(
            "a solve that writes nothing",
            "solve --surface ok.npy --loads 0.01",
            2,
            &["nothing to write", "--pressure-out", "--json"],
        ),
    ];
    for c in &cases {
        check(c);
    }
}
