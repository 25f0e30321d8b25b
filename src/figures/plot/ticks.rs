//! Axis ranges and tick labels: numbers without e-notation, powers of ten as 10ⁿ, the ticks
//! of logarithmic axes, and the linear-then-logarithmic axis of Fig. 4b.

use std::ops::Range;

use plotters::coord::ranged1d::{DefaultFormatting, KeyPointHint, Ranged};

pub use crate::format::{interval_text, number, power_of_ten};

/// `v`, or 0 when it is only rounding error on an axis spanning `span` (a tick computed as
/// −1.4×10⁻¹⁷ for 0).
pub fn snap_zero(v: f64, span: f64) -> f64 {
    if v.abs() < 1e-9 * span.abs() {
        0.0
    } else {
        v
    }
}

/// [`snap_zero`] on an axis from `lo` to `hi`, which snaps only where the axis holds 0: a
/// logarithmic axis spanning many decades has ticks far below 1e-9 of its span (1 on an
/// axis to 10¹²), and they are not zero.
pub fn snap_zero_on(v: f64, lo: f64, hi: f64) -> f64 {
    if lo <= 0.0 && hi >= 0.0 {
        snap_zero(v, hi - lo)
    } else {
        v
    }
}

/// Whether `v` is a power of ten (to rounding).
fn is_power_of_ten(v: f64) -> bool {
    v > 0.0 && (v.log10() - v.log10().round()).abs() < 1e-9
}

/// Tick labels of an axis.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(super) enum Ticks {
    /// Every tick labelled as a plain number.
    Plain,
    /// Whole numbers only (a count); fractional ticks unlabelled.
    Integer,
    /// Logarithmic axis spanning three or more powers of ten: those labelled `10ⁿ`, the
    /// ticks in between (2…9 × 10ⁿ) drawn without labels.
    Decades,
    /// Logarithmic axis spanning less: 1, 2 and 5 × 10ⁿ labelled, the others not.
    OneTwoFive,
    /// Linear-then-logarithmic axis: 0, powers of ten as `10ⁿ`, other ticks as numbers.
    Powers,
}

impl Ticks {
    pub(super) fn label(self, v: f64) -> String {
        match self {
            Ticks::Plain => number(v),
            Ticks::Integer if v.fract() != 0.0 => String::new(),
            Ticks::Integer => number(v),
            Ticks::Decades | Ticks::Powers if is_power_of_ten(v) => {
                power_of_ten(v.log10().round() as i32)
            }
            Ticks::Decades => String::new(),
            Ticks::Powers => number(v),
            Ticks::OneTwoFive => {
                let m = v / 10f64.powf(v.log10().floor());
                if [1.0, 2.0, 5.0, 10.0].iter().any(|k| (m - k).abs() < 1e-6) {
                    number(v)
                } else {
                    String::new()
                }
            }
        }
    }

    /// Labels of a logarithmic axis from `lo` to `hi`: the powers of ten when it holds three
    /// or more, else 1, 2 and 5 × 10ⁿ when it holds two of those, else every tick.
    pub(super) fn log(lo: f64, hi: f64) -> Ticks {
        let ticks = log_key_points(lo, hi);
        let count = |t: Ticks| ticks.iter().filter(|&&v| !t.label(v).is_empty()).count();
        if count(Ticks::Decades) >= 3 {
            Ticks::Decades
        } else if count(Ticks::OneTwoFive) >= 2 {
            Ticks::OneTwoFive
        } else {
            Ticks::Plain
        }
    }
}

/// Ticks of a logarithmic axis from `lo` to `hi`: every m × 10ⁿ (m = 1…9) within it.
pub(super) fn log_key_points(lo: f64, hi: f64) -> Vec<f64> {
    let mut out = Vec::new();
    if !(lo > 0.0 && hi > lo) {
        return out;
    }
    for e in (lo.log10().floor() as i32)..=(hi.log10().ceil() as i32) {
        for m in 1..=9 {
            // Decimal text parsing gives the shortest exact value (3e-5, not 3.0000000000000004e-5).
            let v: f64 = format!("{m}e{e}").parse().unwrap_or(f64::NAN);
            if v >= lo * (1.0 - 1e-12) && v <= hi * (1.0 + 1e-12) {
                out.push(v);
            }
        }
    }
    out
}

/// Linear from 0 to `threshold`, logarithmic above: `t(y) = y/threshold` below and
/// `1 + log10(y/threshold)` above, drawn linearly in `t`.
#[derive(Clone, Debug)]
pub(super) struct LinLogCoord {
    pub(super) threshold: f64,
    pub(super) hi: f64,
}

impl LinLogCoord {
    pub(super) fn t(&self, v: f64) -> f64 {
        if v <= self.threshold {
            v / self.threshold
        } else {
            1.0 + (v / self.threshold).log10()
        }
    }
}

impl Ranged for LinLogCoord {
    type FormatOption = DefaultFormatting;
    type ValueType = f64;

    fn map(&self, value: &f64, limit: (i32, i32)) -> i32 {
        let f = self.t(*value) / self.t(self.hi);
        limit.0 + (f * (limit.1 - limit.0) as f64).round() as i32
    }

    fn key_points<H: KeyPointHint>(&self, _hint: H) -> Vec<f64> {
        let mut out = vec![0.0, self.threshold / 2.0, self.threshold];
        let mut v = self.threshold * 10.0;
        while v <= self.hi * (1.0 + 1e-12) {
            out.push(v);
            v *= 10.0;
        }
        out
    }

    fn range(&self) -> Range<f64> {
        0.0..self.hi
    }
}

/// The axis range around data from `lo` to `hi`: 5 % margins on a linear axis; on a
/// logarithmic one a factor 1.15, widened to the next power of ten when that is within a
/// third of a decade.
pub(super) fn padded(lo: f64, hi: f64, log: bool) -> (f64, f64) {
    if log {
        let (lo, hi) = if hi > lo {
            (lo / 1.15, hi * 1.15)
        } else {
            (lo / 2.0, hi * 2.0)
        };
        let (l, h) = (lo.log10(), hi.log10());
        let lo = if l - l.floor() < 0.33 {
            10f64.powf(l.floor())
        } else {
            lo
        };
        let hi = if h.ceil() - h < 0.33 {
            10f64.powf(h.ceil())
        } else {
            hi
        };
        (lo, hi)
    } else {
        let pad = if hi > lo { 0.05 * (hi - lo) } else { 1.0 };
        (lo - pad, hi + pad)
    }
}
