//! Numbers as a reader reads them, in figure labels, reports and messages: plain decimals
//! for moderate magnitudes, `m×10ⁿ` otherwise, a true minus sign, never an `e` exponent.

/// Unicode superscript digits of an integer (`-4` → `⁻⁴`).
fn superscript(e: i32) -> String {
    const DIGITS: [char; 10] = ['⁰', '¹', '²', '³', '⁴', '⁵', '⁶', '⁷', '⁸', '⁹'];
    let mut s = String::new();
    if e < 0 {
        s.push('⁻');
    }
    for d in e.unsigned_abs().to_string().chars() {
        s.push(DIGITS[d.to_digit(10).unwrap_or(0) as usize]);
    }
    s
}

/// `10ⁿ`.
pub fn power_of_ten(e: i32) -> String {
    format!("10{}", superscript(e))
}

/// An interval `[low, high]` for a legend, with as many decimals (2 to 6) as it takes for
/// its ends to read differently (an interval never reads `[x, x]`).
pub fn interval_text(low: f64, high: f64) -> String {
    let mut digits = 2;
    while digits < 6 && format!("{low:.digits$}") == format!("{high:.digits$}") {
        digits += 1;
    }
    format!("[{low:.digits$}, {high:.digits$}]")
}

/// A number for a label: plain decimals for moderate magnitudes, `m×10ⁿ` otherwise, with a
/// true minus sign; never an `e` exponent.
pub fn number(v: f64) -> String {
    let a = v.abs();
    if a < 1e-300 {
        return "0".into();
    }
    let sign = if v < 0.0 { "−" } else { "" };
    if (1e-3..1e4).contains(&a) {
        let s = format!("{a:.4}");
        let s = s.trim_end_matches('0').trim_end_matches('.');
        return format!("{sign}{s}");
    }
    let mut e = a.log10().floor() as i32;
    let mut m = a / 10f64.powi(e);
    // Rounding can carry the mantissa to 10.
    if (m * 100.0).round() >= 1000.0 {
        m /= 10.0;
        e += 1;
    }
    if (m - 1.0).abs() < 5e-3 {
        format!("{sign}{}", power_of_ten(e))
    } else {
        let ms = format!("{m:.2}");
        let ms = ms.trim_end_matches('0').trim_end_matches('.');
        format!("{sign}{ms}×{}", power_of_ten(e))
    }
}

#[cfg(test)]
mod interval_tests {
    use super::*;

    #[test]
    fn an_interval_never_reads_as_one_number() {
        assert_eq!(interval_text(1.3, 1.52), "[1.30, 1.52]");
        assert_eq!(interval_text(1.5061, 1.5139), "[1.506, 1.514]");
        assert_eq!(interval_text(1.5, 1.5), "[1.500000, 1.500000]");
    }
}
