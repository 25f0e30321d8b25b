//! Quantities as a user types them, a number and its unit (`210GPa`, `0.5 N`, `1.2um`),
//! turned into SI values; the unit tables of each kind.

use crate::ranges::InputError;

/// `text` split into its number and its unit (both trimmed): the unit starts at the first
/// character that cannot be part of a number.
pub fn number_and_unit(text: &str) -> (&str, &str) {
    let t = text.trim();
    let split = t
        .find(|c: char| !(c.is_ascii_digit() || matches!(c, '.' | 'e' | 'E' | '+' | '-')))
        .unwrap_or(t.len());
    (t[..split].trim(), t[split..].trim())
}

/// A value with a unit: `number` then one of `units` (name, factor to SI), spaces allowed.
pub fn quantity(
    option: &str,
    text: &str,
    units: &[(&str, f64)],
    what: &str,
) -> Result<f64, InputError> {
    let (number, unit) = number_and_unit(text);
    let names: Vec<&str> = units.iter().map(|(n, _)| *n).collect();
    let shown: String = text.chars().take(40).collect();
    let ellipsis = if text.chars().count() > 40 { "…" } else { "" };
    let bad = || {
        InputError(format!(
            "{option} {shown:?}{ellipsis}: {what} with its unit, one of {}",
            names.join(", ")
        ))
    };
    let value: f64 = number.parse().map_err(|_| bad())?;
    let factor = units
        .iter()
        .find(|(n, _)| *n == unit)
        .map(|(_, f)| *f)
        .ok_or_else(bad)?;
    let si = value * factor;
    if !(si.is_finite() && si > 0.0) {
        return Err(InputError(format!(
            "{option} {shown:?}{ellipsis}: must be finite and > 0"
        )));
    }
    Ok(si)
}

pub const PRESSURE: &[(&str, f64)] = &[("Pa", 1.0), ("kPa", 1e3), ("MPa", 1e6), ("GPa", 1e9)];
pub const FORCE: &[(&str, f64)] = &[
    ("N", 1.0),
    ("kN", 1e3),
    ("mN", 1e-3),
    ("uN", 1e-6),
    ("µN", 1e-6),
];

pub const LENGTH: &[(&str, f64)] = &[
    ("m", 1.0),
    ("mm", 1e-3),
    ("um", 1e-6),
    ("µm", 1e-6),
    ("nm", 1e-9),
];
pub const AREA: &[(&str, f64)] = &[
    ("m2", 1.0),
    ("mm2", 1e-6),
    ("um2", 1e-12),
    ("µm2", 1e-12),
    ("µm²", 1e-12),
    ("nm2", 1e-18),
];
