//! Silent accepts made loud, and messages in the user's terms: each names the field or file
//! and the fix, never a library's internals.

use std::path::Path;

use super::{case, check, write_npy, Case};
use crate::small_pipeline;

fn with(from: &str, to: &str) -> Option<String> {
    let base = small_pipeline(0.8, "x");
    assert!(base.contains(from), "{from}");
    Some(base.replace(from, to))
}

fn odd_files(dir: &Path) {
    // A 2 × 4 × 4 stack of float64 heights; a 12 × 12 map bit-packed into 12 × 2 bytes (4
    // padding bits a row) with a padding bit of row 5 set; integer heights; fractional areas.
    write_npy(
        &dir.join("stack.npy"),
        "<f8",
        "(2, 4, 4)",
        &[0u8; 2 * 16 * 8],
    );
    let mut packed = vec![0u8; 12 * 2];
    packed[0] = 0b1000_0000;
    packed[5 * 2 + 1] = 0b0000_0001;
    write_npy(&dir.join("padded.npy"), "|u1", "(12, 2)", &packed);
    write_npy(&dir.join("ints.npy"), "<i8", "(4, 4)", &[0u8; 16 * 8]);
    let df = wearcoef::store::table::col("area_px", vec![1.0f64, 0.5]);
    let df = polars::prelude::DataFrame::new(2, vec![df]).unwrap();
    wearcoef::store::table::write_with_metadata(&dir.join("areas.parquet"), df, Vec::new())
        .unwrap();
}

#[test]
fn silent_accepts_are_refused() {
    let twice = with(
        "  fig6: {kind: fig6, profiles: [t]}",
        "  fig6: {kind: fig6, profiles: [t]}\n  conv: {kind: convergence, studies: [a, a, b], profiles: [t]}",
    );
    let same_kind = with(
        "  fig6: {kind: fig6, profiles: [t]}",
        "  fig6: {kind: fig6, profiles: [t]}\n  again: {kind: fig6, profiles: [t]}",
    );
    let named_like_fig4b = with(
        "  fig6: {kind: fig6, profiles: [t]}",
        "  fig6: {kind: fig6, profiles: [t]}\n  k: {kind: fig45, study: a, profiles: [t]}\n  fig4b: {kind: convergence, studies: [a, b], profiles: [t]}",
    );
    let empty_profile = with(
        "profiles: {t: \"test\"}",
        "profiles: {t: \"test\", e: \"empty\"}",
    );
    // Wavenumbers 1.05 to 1.3125 (units of 2π/L) on a 42² grid: between |k| = 1 and √2.
    let no_mode = with(
        "lambda_l_over_lambda_s: 4\n    seed: 8",
        "lambda_l_over_lambda_s: 1.25\n    seed: 8",
    )
    .map(|t| {
        t.replace(
            "t: {l_over_lambda_l: 2, lambda_s_over_dl: 8, realizations: 2}",
            "t: {l_over_lambda_l: 1.05, lambda_s_over_dl: 32, realizations: 2}",
        )
    });
    let cases = [
        Case {
            pipeline: twice,
            ..case(
                "a study listed twice in a figure",
                "plan --profile t",
                2,
                &["figures.conv.studies[1]", "listed twice"],
            )
        },
        Case {
            pipeline: same_kind,
            ..case(
                "two figures writing the same files",
                "run --profile t",
                2,
                &["figures.fig6", "'again'", "also writes fig6.*"],
            )
        },
        Case {
            pipeline: named_like_fig4b,
            ..case(
                "a convergence figure named like another figure's files",
                "plan --profile t",
                2,
                &["figures.k", "'fig4b'", "also writes fig4b.*"],
            )
        },
        Case {
            pipeline: empty_profile,
            ..case(
                "a profile that builds nothing",
                "run --profile e",
                2,
                &["profile e builds nothing", "studies.<name>.profiles.e"],
            )
        },
        Case {
            pipeline: no_mode,
            ..case(
                "a spectral band without a Fourier mode",
                "run --profile t",
                2,
                &["studies.b.profiles.t", "holds no Fourier mode"],
            )
        },
        case(
            "the same from the command line",
            "surface --n 16 --lambda-l-px 15.24 --lambda-s-px 11.85 --hurst 0.8 -o e.npy",
            2,
            &["lambda_s_px = 11.85", "holds no Fourier mode"],
        ),
        Case {
            prepare: Some(odd_files),
            ..case(
                "padding bits set in a packed map",
                "clusters --contact padded.npy",
                2,
                &["padded.npy", "row 5", "padding"],
            )
        },
        case(
            "standard input as a surface",
            "solve --json --surface /dev/stdin --loads 0.01",
            2,
            &["/dev/stdin", "not a regular file"],
        ),
    ];
    for c in &cases {
        check(c);
    }
}

#[test]
fn messages_name_the_users_terms_not_a_librarys() {
    let dup = "schema_version: 1\nschema_version: 1\n".to_string() + &small_pipeline(0.8, "x");
    let tiny = "solve --json --surface ok.npy --loads 1e-300 --max-iter 1 --plain-cg";
    let cases = [
        Case {
            pipeline: Some(dup),
            never: vec!["DuplicateKeyPolicy", "Options", "error: error"],
            ..case(
                "a key given twice",
                "plan --profile t",
                2,
                &[
                    "duplicate mapping key: schema_version",
                    "each key may appear once",
                ],
            )
        },
        Case {
            never: vec!["(os error 21): Is a directory"],
            ..case(
                "a directory as the pipeline",
                "plan --profile t --config .",
                2,
                &["--config .", "Is a directory", "name a pipeline file"],
            )
        },
        case(
            "an endless pipeline",
            "plan --profile t --config /dev/zero",
            2,
            &["--config /dev/zero", "longer than 16 MiB"],
        ),
        Case {
            prepare: Some(odd_files),
            never: vec!["NDIM", "Some("],
            ..case(
                "a 3-D array as heights",
                "solve --json --surface stack.npy --loads 0.01",
                2,
                &["stack.npy", "shape (2, 4, 4)", "square 2-D array"],
            )
        },
        Case {
            prepare: Some(odd_files),
            never: vec!["descriptor", "Some("],
            ..case(
                "integers as heights",
                "solve --json --surface ints.npy --loads 0.01",
                2,
                &["ints.npy", "'<i8'", "float64"],
            )
        },
        Case {
            prepare: Some(odd_files),
            never: vec!["incorrect descriptor"],
            ..case(
                "heights as a contact map",
                "clusters --contact stack.npy",
                2,
                &["stack.npy", "shape (2, 4, 4)"],
            )
        },
        Case {
            prepare: Some(odd_files),
            never: vec!["Some("],
            ..case(
                "fractional cluster areas",
                "fit --areas areas.parquet",
                2,
                &[
                    "areas.parquet",
                    "row 1 of 'area_px' is 0.5",
                    "whole numbers",
                ],
            )
        },
        Case {
            never: vec!["0.000000000000000000000"],
            ..case(
                "a tiny load that does not converge in one iteration",
                tiny,
                1,
                &["W/W0 = 1e-300", "did not converge"],
            )
        },
    ];
    for c in &cases {
        check(c);
    }
}
