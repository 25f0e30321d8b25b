//! Every count a user can type is bounded by what this machine can do, and refused before
//! any work (never an abort on allocation, never thousands of threads).

use super::{case, check, Case};
use crate::small_pipeline;

fn with(from: &str, to: &str) -> Option<String> {
    let base = small_pipeline(0.8, "x");
    assert!(base.contains(from), "{from}");
    Some(base.replace(from, to))
}

#[test]
fn counts_beyond_the_machine_are_refused_before_any_work() {
    let cases = [
        case(
            "a thousand jobs",
            "run --profile t --jobs 1000000",
            2,
            &["--jobs 1000000", "threads", "choose at most"],
        ),
        case(
            "exec on a million threads",
            "exec --plan p.json --jobs 100000 --at-once 100000",
            2,
            &["--jobs 100000 --at-once 100000", "threads"],
        ),
        Case {
            pipeline: with("realizations: 3", "realizations: 4000000000"),
            ..case(
                "four billion realizations",
                "run --profile t",
                2,
                &[
                    "studies.a.profiles.t.realizations",
                    "more than this machine's memory allows a plan",
                ],
            )
        },
        Case {
            pipeline: with(
                "loads: {values: [0.01, 0.02]}",
                "loads: {min: 0.01, max: 0.02, count: 4000000000}",
            ),
            ..case(
                "four billion loads",
                "plan --profile t",
                2,
                &["loads.count", "4000000000", "fit in this machine's memory"],
            )
        },
        Case {
            pipeline: with("max_iterations: 1000", "max_iterations: 4000000000"),
            ..case(
                "an iteration cap that is no cap (allowed: nothing is reserved for it)",
                "plan --profile t",
                0,
                &[],
            )
        },
        case(
            "solve with an iteration cap of 2^64 − 1",
            "solve --json --surface ok.npy --loads 0.01 --max-iter 18446744073709551615",
            0,
            &[],
        ),
    ];
    for c in &cases {
        check(c);
    }
}
