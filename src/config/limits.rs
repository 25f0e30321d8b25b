//! Bounds of the counts `pipeline.yaml` may ask for, derived from this machine, and the YAML
//! parser's messages in the user's terms.

use super::error::ConfigError;

/// The plan holds every realization's instances and their loads in memory (a few KiB each,
/// and ~100 bytes a load): refused before it is built if that cannot fit in an eighth of
/// this machine's memory.
pub(super) fn check_realizations(
    pbase: &str,
    realizations: u32,
    loads: usize,
    profile: &str,
    origin: &str,
) -> Result<(), ConfigError> {
    let budget = crate::machine::memory_or_default() / 8;
    let per_realization = 16_384 + 128 * loads as u64;
    let needed = u64::from(realizations).saturating_mul(per_realization);
    if needed <= budget {
        return Ok(());
    }
    Err(ConfigError::Invalid {
        path: origin.to_string(),
        field: format!("{pbase}.realizations"),
        value: realizations.to_string(),
        allowed: format!(
            "a plan of that many realizations of {loads} loads needs about {} KiB, more than this machine's memory allows a plan (an eighth of it, {} KiB); at most {} realizations here (profile {profile})",
            needed / 1024,
            budget / 1024,
            budget / per_realization
        ),
    })
}

/// Each load is a contact map, a row of every table and a value in the plan's jobs (~1 KiB
/// in all while the plan is built): a `count` is bounded by the machine's memory, checked
/// before the loads are made.
pub(super) fn check_load_count(count: u32, field: &str, origin: &str) -> Result<(), ConfigError> {
    let most = crate::machine::memory_or_default() / 8 / 1024;
    if u64::from(count) <= most {
        return Ok(());
    }
    Err(ConfigError::Invalid {
        path: origin.to_string(),
        field: format!("{field}.count"),
        value: count.to_string(),
        allowed: format!("at most {most} loads fit in this machine's memory"),
    })
}

/// The YAML parser's message without its own "error: " prefix and without advice about the
/// parser's options (a key given twice is an error, full stop).
pub(super) fn plain_yaml_error(message: &str) -> String {
    message.trim_start_matches("error: ").replace(
        ", set DuplicateKeyPolicy in Options if acceptable",
        " (each key may appear once in a mapping: remove or rename one)",
    )
}
