//! Bad input, as a hostile user would give it: one table per category, every row a command
//! that must be refused plainly (exit 2 for usage, configuration and input errors, 1 for a
//! failure of the machine or the store), with a message naming the field or the user's path,
//! no panic, and nothing written: the working directory holds exactly what it held before.
//!
//! Categories: names that become paths; degenerate surfaces; parameters outside their
//! domain; sizes that cannot fit in memory; output paths; a damaged store; closed pipes and
//! full disks. (Closed pipes: `cli::closed_stdout_pipe_exits_0_without_a_panic`.)

use std::collections::BTreeSet;
use std::path::{Path, PathBuf};

use crate::{bin, small_pipeline};

mod counts;
mod messages;
mod paths;
mod second_round;
mod store_and_disks;

/// One row: what to set up, the command, and what must come back.
struct Case {
    name: &'static str,
    /// pipeline.yaml's text (None: the small two-study pipeline).
    pipeline: Option<String>,
    /// Commands run first (each must succeed), e.g. a run that makes a store.
    before: Vec<&'static str>,
    /// Files to make first (in the working directory), after `before`.
    prepare: Option<fn(&Path)>,
    args: Vec<String>,
    env: Vec<(&'static str, &'static str)>,
    code: i32,
    /// Every one must appear in stderr.
    says: Vec<&'static str>,
    /// None may appear in stderr (library internals, temporaries' names).
    never: Vec<&'static str>,
}

fn case(name: &'static str, args: &str, code: i32, says: &[&'static str]) -> Case {
    Case {
        name,
        pipeline: None,
        before: Vec::new(),
        prepare: None,
        args: args.split_whitespace().map(String::from).collect(),
        env: Vec::new(),
        code,
        says: says.to_vec(),
        never: Vec::new(),
    }
}

/// Every file under `dir` with a hash of its bytes (directories with none).
fn contents(dir: &Path) -> std::collections::BTreeMap<PathBuf, u64> {
    use std::hash::{Hash, Hasher};
    tree(dir)
        .into_iter()
        .map(|p| {
            let mut h = std::collections::hash_map::DefaultHasher::new();
            // A symbolic link is its target's name (one may name /dev/zero).
            let full = dir.join(&p);
            match std::fs::read_link(&full) {
                Ok(target) => target.hash(&mut h),
                Err(_) => std::fs::read(&full).ok().hash(&mut h),
            }
            (p, h.finish())
        })
        .collect()
}

/// Every file and directory under `dir`, relative.
fn tree(dir: &Path) -> BTreeSet<PathBuf> {
    fn walk(root: &Path, at: &Path, out: &mut BTreeSet<PathBuf>) {
        let Ok(entries) = std::fs::read_dir(at) else {
            return;
        };
        for e in entries.flatten() {
            let p = e.path();
            out.insert(p.strip_prefix(root).unwrap().to_path_buf());
            if e.file_type().is_ok_and(|t| t.is_dir()) {
                walk(root, &p, out);
            }
        }
    }
    let mut out = BTreeSet::new();
    walk(dir, dir, &mut out);
    out
}

/// Heights files every case can name: a smooth egg-box and its degenerate variants.
fn write_inputs(dir: &Path) {
    let n = 16;
    let egg = |scale: f64| -> Vec<f64> {
        (0..n * n)
            .map(|i| {
                let (r, c) = ((i / n) as f64, (i % n) as f64);
                let k = 2.0 * std::f64::consts::PI / n as f64;
                scale * ((k * r).cos() + (k * c).cos())
            })
            .collect()
    };
    let w = |name: &str, v: Vec<f64>| wearcoef::io::write_heights(&dir.join(name), n, v).unwrap();
    w("ok.npy", egg(1.0));
    w("flat.npy", vec![0.0; n * n]);
    w("constant.npy", vec![5.0; n * n]);
    w("underflow.npy", egg(1e-200));
    w("overflow.npy", egg(1e200));
    let mut nan = egg(1.0);
    nan[3 * n + 4] = f64::NAN;
    w("nan.npy", nan);
    let mut inf = egg(1.0);
    inf[5] = f64::INFINITY;
    w("inf.npy", inf);
    // A header that promises 200000² doubles (320 GB) over 64 bytes of data.
    write_forged_npy(&dir.join("forged.npy"), "<f8", "(200000, 200000)");
    write_forged_npy(&dir.join("forged_map.npy"), "|u1", "(100000, 100000)");
    std::fs::write(dir.join("junk.npy"), b"not a numpy file").unwrap();
    std::fs::write(dir.join("junk.parquet"), b"not a parquet file").unwrap();
    std::fs::create_dir(dir.join("sub")).unwrap();
}

fn write_forged_npy(path: &Path, descr: &str, shape: &str) {
    write_npy(path, descr, shape, &[0u8; 64]);
}

/// A `.npy` file with the given header fields and payload, whatever they promise.
fn write_npy(path: &Path, descr: &str, shape: &str, payload: &[u8]) {
    let mut header = format!("{{'descr': '{descr}', 'fortran_order': False, 'shape': {shape}, }}");
    while (10 + header.len() + 1) % 64 != 0 {
        header.push(' ');
    }
    header.push('\n');
    let mut bytes = b"\x93NUMPY\x01\x00".to_vec();
    bytes.extend((header.len() as u16).to_le_bytes());
    bytes.extend(header.as_bytes());
    bytes.extend(payload);
    std::fs::write(path, bytes).unwrap();
}

/// Run one case in a fresh directory and check its contract.
fn check(c: &Case) {
    let root = tempfile::tempdir().unwrap();
    let dir = root.path().join("work");
    std::fs::create_dir(&dir).unwrap();
    let text = c
        .pipeline
        .clone()
        .unwrap_or_else(|| small_pipeline(0.8, "x"));
    std::fs::write(dir.join("pipeline.yaml"), text).unwrap();
    write_inputs(&dir);
    for command in &c.before {
        let out = bin()
            .current_dir(&dir)
            .args(command.split_whitespace())
            .output()
            .unwrap();
        assert!(
            out.status.success(),
            "case {}: setup `{command}`: {}",
            c.name,
            String::from_utf8_lossy(&out.stderr)
        );
    }
    if let Some(prepare) = c.prepare {
        prepare(&dir);
    }
    let before = contents(root.path());
    let mut cmd = bin();
    cmd.current_dir(&dir).args(&c.args);
    for (k, v) in &c.env {
        cmd.env(k, v);
    }
    let out = cmd.output().expect("wearcoef runs");
    let stderr = String::from_utf8_lossy(&out.stderr);
    let who = format!("case {} (wearcoef {})", c.name, c.args.join(" "));
    assert_eq!(out.status.code(), Some(c.code), "{who}: stderr {stderr}");
    assert!(!stderr.contains("panicked"), "{who}: {stderr}");
    assert!(
        !stderr.contains(".tmp"),
        "{who}: names a temporary: {stderr}"
    );
    for needle in &c.says {
        assert!(
            stderr.contains(needle),
            "{who}: stderr lacks {needle:?}: {stderr}"
        );
    }
    for needle in &c.never {
        assert!(!stderr.contains(needle), "{who}: says {needle:?}: {stderr}");
    }
    // Nothing added, removed or changed (a dry run and a refusal alike).
    let after = contents(root.path());
    if c.code != 0 || c.args.iter().any(|a| a == "--dry-run") {
        assert_eq!(
            after.keys().collect::<Vec<_>>(),
            before.keys().collect::<Vec<_>>(),
            "{who}: the files changed"
        );
        let changed: Vec<_> = after.iter().filter(|(p, h)| before[*p] != **h).collect();
        assert!(changed.is_empty(), "{who}: changed {changed:?}");
    }
}

/// Names become directories (data/<profile>/, figures/<profile>/, campaigns) and file
/// names: anything but a plain word, or a name the store keeps for itself, is refused
/// before anything is written, so nothing lands outside --data or --figures.
#[test]
fn names_that_would_become_paths_are_refused() {
    let base = small_pipeline(0.8, "x");
    let with = |from: &str, to: &str| {
        assert!(base.contains(from), "{from}");
        Some(base.replace(from, to))
    };
    let cases = [
        Case {
            pipeline: with(
                "profiles: {t: \"test\"}",
                "profiles: {\"../escape\": \"test\"}",
            ),
            ..case(
                "profile ../escape",
                "run --profile ../escape",
                2,
                &["profiles.../escape", "becomes a directory"],
            )
        },
        Case {
            pipeline: with(
                "profiles: {t: \"test\"}",
                "profiles: {t: \"test\", cache: \"x\"}",
            ),
            ..case(
                "profile cache",
                "run --profile cache",
                2,
                &["profiles.cache", "rename the profile"],
            )
        },
        Case {
            pipeline: with(
                "profiles: {t: \"test\"}",
                "profiles: {t: \"test\", failed: \"x\"}",
            ),
            ..case("profile failed", "run --profile t", 2, &["profiles.failed"])
        },
        Case {
            pipeline: with(
                "profiles: {t: \"test\"}",
                "profiles: {t: \"test\", \"a/b\": \"x\"}",
            ),
            ..case("profile a/b", "run --profile t", 2, &["profiles.a/b"])
        },
        Case {
            pipeline: with("  a:\n    description", "  \"../a\":\n    description"),
            ..case("study ../a", "run --profile t", 2, &["studies.../a"])
        },
        Case {
            pipeline: with("  fig6: {kind", "  \"../fig\": {kind"),
            ..case("figure ../fig", "run --profile t", 2, &["figures.../fig"])
        },
        Case {
            pipeline: with("  fig6: {kind", "  \".hidden\": {kind"),
            ..case(
                "figure .hidden",
                "plan --profile t",
                2,
                &["figures..hidden"],
            )
        },
        case(
            "undeclared profile",
            "run --profile ../t",
            2,
            &["unknown profile '../t'"],
        ),
        case(
            "undeclared profile, plan",
            "plan --profile ../t",
            2,
            &["unknown profile"],
        ),
    ];
    for c in &cases {
        check(c);
    }
}

/// A surface with no usable W0 (flat, constant, heights whose squares under- or
/// overflow) or with non-finite heights is an input error, never a "converged" empty
/// contact.
#[test]
fn degenerate_surfaces_are_refused() {
    let cases = [
        case(
            "flat",
            "solve --json --surface flat.npy --loads 0.01",
            2,
            &["rms slope", "zero", "flat or constant"],
        ),
        case(
            "constant",
            "solve --json --surface constant.npy --loads 0.01",
            2,
            &["rms slope", "zero"],
        ),
        case(
            "underflowing heights",
            "solve --json --surface underflow.npy --loads 0.01",
            2,
            &["rms slope", "rescale the heights"],
        ),
        case(
            "overflowing heights",
            "solve --json --surface overflow.npy --loads 0.01",
            2,
            &["rms slope", "not finite"],
        ),
        case(
            "NaN height",
            "solve --json --surface nan.npy --loads 0.01",
            2,
            &["nan.npy", "row 3, column 4", "finite"],
        ),
        case(
            "infinite height",
            "solve --json --surface inf.npy --loads 0.01",
            2,
            &["inf.npy", "row 0, column 5"],
        ),
        case(
            "not a .npy",
            "solve --json --surface junk.npy --loads 0.01",
            2,
            &["junk.npy", "not a .npy file"],
        ),
        case(
            "missing surface",
            "solve --json --surface nosuch.npy --loads 0.01",
            2,
            &["nosuch.npy"],
        ),
    ];
    for c in &cases {
        check(c);
    }
}

/// Every tool holds its parameters to their domain as strictly as pipeline.yaml does.
#[test]
fn parameters_outside_their_domain_are_refused_on_every_tool() {
    let s = "solve --json --surface ok.npy --loads 0.01";
    let surf = "surface --n 16 --lambda-l-px 8 --lambda-s-px 2 --hurst 0.8 -o h.npy";
    let model = "model --a-s 1 --a-m 100";
    let big_load = small_pipeline(0.8, "x").replace("values: [0.01, 0.02]", "values: [0.01, 500]");
    let tol = small_pipeline(0.8, "x").replace("tolerance: 1.0e-10", "tolerance: 1.5");
    let cases = vec![
        case(
            "tolerance ≥ 1",
            &format!("{s} --tol 1.5"),
            2,
            &["--tol 1.5", "(0, 1)"],
        ),
        case("tolerance 0", &format!("{s} --tol 0"), 2, &["--tol 0"]),
        case(
            "tolerance NaN",
            &format!("{s} --tol NaN"),
            2,
            &["--tol NaN"],
        ),
        case(
            "no iterations",
            &format!("{s} --max-iter 0"),
            2,
            &["--max-iter 0"],
        ),
        case("modulus 0", &format!("{s} --e-star 0"), 2, &["--e-star 0"]),
        case(
            "coarse block off the cells",
            &format!("{s} --coarse-block 100"),
            2,
            &["--coarse-block 100", "multiple of 16"],
        ),
        case(
            "entry margin out of range",
            &format!("{s} --entry-margin 2"),
            2,
            &["--entry-margin 2", "[0, 1]"],
        ),
        case(
            "negative load",
            "solve --json --surface ok.npy --loads=-0.1",
            2,
            &["load 1 is -0.1"],
        ),
        case(
            "NaN load",
            "solve --json --surface ok.npy --loads NaN",
            2,
            &["load 1 is NaN"],
        ),
        case(
            "load past complete contact",
            "solve --json --surface ok.npy --loads 0.01,1e300",
            2,
            &["load 2 is 1e300", "≤ 100"],
        ),
        case("Hurst 1", &surf.replace("0.8", "1"), 2, &["hurst = 1"]),
        case(
            "λs below Nyquist",
            &surf.replace("--lambda-s-px 2", "--lambda-s-px 1"),
            2,
            &["lambda_s_px = 1"],
        ),
        case(
            "λl above the box",
            &surf.replace("--lambda-l-px 8", "--lambda-l-px 32"),
            2,
            &["lambda_l_px = 32"],
        ),
        case(
            "odd grid",
            &surf.replace("--n 16", "--n 17"),
            2,
            &["n = 17"],
        ),
        case(
            "roll-off below λl",
            &format!("{surf} --rolloff-lambda-px 4"),
            2,
            &["rolloff_lambda_px = 4"],
        ),
        case(
            "α NaN",
            &format!("{model} --alpha NaN --a-star 10"),
            2,
            &["alpha = NaN"],
        ),
        case(
            "A_s 0",
            "model --alpha 1.5 --a-s 0 --a-m 100 --a-star 10",
            2,
            &["A_s = 0"],
        ),
        case(
            "A_m below A_s",
            "model --alpha 1.5 --a-s 10 --a-m 1 --a-star 10",
            2,
            &["A_m = 1"],
        ),
        case(
            "negative A*",
            &format!("{model} --alpha 1.5 --a-star=-1"),
            2,
            &["A* = -1"],
        ),
        case(
            "connectivity 6",
            "clusters --contact ok.npy --connectivity 6",
            2,
            &["--connectivity"],
        ),
        case(
            "map of heights",
            "clusters --contact ok.npy",
            2,
            &["ok.npy", "contact map"],
        ),
        case(
            "too few resamples",
            "fit --areas junk.parquet --resamples 0",
            2,
            &["--resamples 0"],
        ),
        case(
            "not a table",
            "fit --areas junk.parquet",
            2,
            &["junk.parquet"],
        ),
        case("jobs 0", "run --profile t --jobs 0", 2, &["--jobs"]),
        Case {
            pipeline: Some(big_load),
            ..case(
                "pipeline load past complete contact",
                "run --profile t",
                2,
                &["studies.a.loads.values[1]", "(0, 100]"],
            )
        },
        Case {
            pipeline: Some(tol),
            ..case(
                "pipeline tolerance ≥ 1",
                "run --profile t",
                2,
                &["solver.tolerance"],
            )
        },
    ];
    for c in &cases {
        check(c);
    }
}

/// Work that cannot fit in memory is refused from its estimate, before anything is
/// allocated; a file whose header promises more than it holds is never believed.
#[test]
fn sizes_that_cannot_fit_are_refused_before_allocating() {
    let small_machine = vec![("WEARCOEF_MEMORY_BYTES", "1000000000")];
    let cases = [
        case(
            "grid above the limit",
            "surface --n 1048576 --lambda-l-px 8 --lambda-s-px 2 --hurst 0.8 -o h.npy",
            2,
            &["--n 1048576", "32768"],
        ),
        Case {
            env: small_machine.clone(),
            ..case(
                "surface beyond memory",
                "surface --n 32768 --lambda-l-px 8 --lambda-s-px 2 --hurst 0.8 -o h.npy",
                2,
                &["32768² surface", "GiB, more than this machine's"],
            )
        },
        Case {
            env: vec![("WEARCOEF_MEMORY_BYTES", "1000")],
            ..case(
                "pipeline beyond memory",
                "run --profile t",
                2,
                &["more than this machine's", "profile t"],
            )
        },
        case(
            "forged header",
            "solve --json --surface forged.npy --loads 0.01",
            2,
            &["forged.npy", "promises shape (200000, 200000)"],
        ),
        case(
            "forged map header",
            "clusters --contact forged_map.npy",
            2,
            &["forged_map.npy", "holds 64 bytes"],
        ),
    ];
    for c in &cases {
        check(c);
    }
    // With room to spare the same kind of estimate lets the work through.
    let dir = tempfile::tempdir().unwrap();
    write_inputs(dir.path());
    let out = bin()
        .current_dir(dir.path())
        .args(["solve", "--json", "--surface", "ok.npy", "--loads", "0.01"])
        .env("WEARCOEF_MEMORY_BYTES", "1000000000")
        .output()
        .unwrap();
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
}

/// Output paths are checked before any work, and errors name the user's path (never a
/// temporary file's): a missing directory, a directory or device in place of a file, two
/// outputs at one path.
#[test]
fn bad_output_paths_are_refused_before_any_work() {
    let s = "solve --surface ok.npy --loads 0.01,0.02";
    let surf = "surface --n 16 --lambda-l-px 8 --lambda-s-px 2 --hurst 0.8";
    let cases = [
        case(
            "missing directory",
            &format!("{surf} -o no/such/dir/h.npy"),
            2,
            &["--output no/such/dir/h.npy", "does not exist"],
        ),
        case(
            "a directory",
            &format!("{surf} -o sub"),
            2,
            &["--output sub", "not a regular file"],
        ),
        case(
            "a device",
            &format!("{surf} -o /dev/null"),
            2,
            &["--output /dev/null", "device"],
        ),
        case(
            "two outputs, one path",
            &format!("{s} --pressure-out f.npy --contact-out ./f.npy"),
            2,
            &["--contact-out ./f.npy", "also the path of --pressure-out"],
        ),
        case(
            "pressure into a missing directory",
            &format!("{s} --pressure-out nodir/p.npy"),
            2,
            &["--pressure-out nodir/p.npy"],
        ),
        case(
            "catalog into a missing directory",
            "catalog --profile t --data . -o nodir/c.csv",
            2,
            &["--output nodir/c.csv"],
        ),
        case(
            "figures onto a file",
            "run --profile t --figures ok.npy",
            2,
            &["--figures ok.npy", "not a directory"],
        ),
        case(
            "data onto a file",
            "run --profile t --data ok.npy/store",
            2,
            &["--data ok.npy/store", "not a directory"],
        ),
    ];
    for c in &cases {
        check(c);
    }
    // /dev/null is still a device afterwards (an atomic rename over it would replace it).
    let meta = std::fs::metadata("/dev/null").unwrap();
    assert!(!meta.is_file());
}
