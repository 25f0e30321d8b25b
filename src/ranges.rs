//! The accepted range of every number a user types, in one place: the command-line options
//! of `fit`, `wear`, `topography`, `run` and `submit`, and the same settings in
//! pipeline.yaml, are checked here against a range with its unit and the reason for its
//! bounds. docs/CONVENTIONS.md lists the same table (a test keeps the two equal).

/// An error that means "your input is wrong": the command exits with status 2, and the
/// Python package raises `ValueError`.
#[derive(Debug, thiserror::Error)]
#[error("{0}")]
pub struct InputError(pub String);

/// A closed range `[lo, hi]` of one quantity.
#[derive(Debug, Clone, Copy)]
pub struct Range {
    /// What the number is, in the user's words.
    pub what: &'static str,
    pub lo: f64,
    pub hi: f64,
    /// The unit the bounds are in ("" for a pure number).
    pub unit: &'static str,
    /// Why the bounds are where they are.
    pub why: &'static str,
    /// Whether the value must be a whole number.
    pub whole: bool,
}

/// Bootstrap resamples of a 95 % interval: at least 40 so that each 2.5 % tail holds a
/// resample; at most 100 000 (each refits the tail, and 10⁵ resamples already fix the
/// interval's ends to better than 1 %).
pub const RESAMPLES: Range = Range {
    what: "bootstrap resamples",
    lo: 40.0,
    hi: 100_000.0,
    unit: "",
    why: "a 95 % percentile interval needs a resample in each 2.5 % tail (≥ 40); 10⁵ fix its ends to < 1 %",
    whole: true,
};

/// The effective modulus of a measured contact, in Pa: from soft gels to diamond.
pub const E_STAR_PA: Range = Range {
    what: "effective modulus E*",
    lo: 1.0,
    hi: 1e13,
    unit: "Pa",
    why: "from 1 Pa (below the softest gels, about 100 Pa; E* = 1 Pa gives forces in units of E*) to beyond diamond (1.2 TPa)",
    whole: false,
};

/// A hardness of a measured contact, in Pa.
pub const HARDNESS_PA: Range = Range {
    what: "hardness",
    lo: 1.0,
    hi: 1e13,
    unit: "Pa",
    why: "the same span as E*; leave it out (or .inf in pipeline.yaml) for elastic contact",
    whole: false,
};

/// The effective modulus of pipeline.yaml (the unit of every pressure written).
pub const E_STAR_PIPELINE: Range = Range {
    what: "effective modulus E* (material.e_star)",
    lo: 1e-100,
    hi: 1e100,
    unit: "the pressure unit of the outputs",
    why: "a normal double whose products with loads and heights neither under- nor overflow",
    whole: false,
};

/// The solver's relative tolerance.
pub const TOLERANCE: Range = Range {
    what: "solver tolerance",
    lo: 1e-15,
    hi: 1e-2,
    unit: "",
    why: "below 1e-15 is rounding; above 1e-2 the contact set is not converged",
    whole: false,
};

/// `--memory-safety`, `cluster.memory_safety`: `--mem` is the estimate times this.
pub const MEMORY_SAFETY: Range = Range {
    what: "memory safety factor",
    lo: 1.0,
    hi: 100.0,
    unit: "",
    why: "the estimate is not a bound (≥ 1); beyond 100 the request is the estimate's error, not a margin",
    whole: false,
};

/// `--time-safety`, `cluster.time_safety`: `--time` is the estimate times this.
pub const TIME_SAFETY: Range = Range {
    what: "time safety factor",
    lo: 1.0,
    hi: 100.0,
    unit: "",
    why: "the estimate is not a bound (≥ 1); beyond 100 the request is the estimate's error, not a margin",
    whole: false,
};

/// `--min-minutes`, `cluster.min_minutes`: the least time a task asks for.
pub const MINUTES: Range = Range {
    what: "minutes of a Slurm task",
    lo: 0.1,
    hi: 525_600.0,
    unit: "min",
    why: "from 6 s to a year: no site runs a task longer",
    whole: false,
};

/// `--task-minutes`, `cluster.task_minutes`: the estimated minutes packed into one task.
pub const TASK_MINUTES: Range = Range {
    what: "estimated minutes packed into one Slurm task",
    lo: 1e-9,
    hi: 525_600.0,
    unit: "min",
    why: "any positive target (1e-9: one instance a task) up to a year",
    whole: false,
};

/// A W/W0 load of a measured map.
pub const W_OVER_W0: Range = Range {
    what: "load W/W0",
    lo: 1e-12,
    hi: 100.0,
    unit: "",
    why: "below 1e-12 no node of any map touches; past W/W0 ≈ 10 contact is complete (the solver's own bound is 100)",
    whole: false,
};

/// A pixel size of a measured map, in metres.
pub const PIXEL_M: Range = Range {
    what: "pixel size",
    lo: 1e-15,
    hi: 1.0,
    unit: "m",
    why: "from a femtometre to a metre: outside it the unit is wrong",
    whole: false,
};

/// Every range, for the table of docs/CONVENTIONS.md.
pub const ALL: [(&str, Range); 11] = [
    ("--resamples (fit and wear)", RESAMPLES),
    ("--e-star (wear)", E_STAR_PA),
    ("--hardness (wear)", HARDNESS_PA),
    ("material.e_star", E_STAR_PIPELINE),
    ("--tolerance (wear)", TOLERANCE),
    ("--memory-safety, cluster.memory_safety", MEMORY_SAFETY),
    ("--time-safety, cluster.time_safety", TIME_SAFETY),
    ("--min-minutes, cluster.min_minutes", MINUTES),
    ("--task-minutes, cluster.task_minutes", TASK_MINUTES),
    ("--loads (wear)", W_OVER_W0),
    (
        "--pixel-size, pixel_size (in m once its unit applies)",
        PIXEL_M,
    ),
];

/// A number as a person reads it: at most 6 significant digits, and an exponent outside
/// [1e-4, 1e6).
pub fn show(v: f64) -> String {
    let a = v.abs();
    if v == 0.0 || !v.is_finite() {
        return v.to_string();
    }
    let trim = |t: &str| -> String {
        if t.contains('.') {
            t.trim_end_matches('0').trim_end_matches('.').to_string()
        } else {
            t.to_string()
        }
    };
    if (1e-4..1e6).contains(&a) {
        let decimals = (5 - a.log10().floor() as i32).max(0) as usize;
        trim(&format!("{v:.decimals$}"))
    } else {
        // The shortest form that reads back as `v` when it is short (1e-320, not the
        // subnormal's 9.99989e-321), else six significant digits.
        let shortest = format!("{v:e}");
        if shortest.split('e').next().is_some_and(|m| m.len() <= 8) {
            return shortest;
        }
        let s = format!("{v:.5e}");
        let (m, e) = s.split_once('e').expect("an exponent");
        format!("{}e{e}", trim(m))
    }
}

/// The rows of docs/CONVENTIONS.md's table of ranges, one per entry of [`ALL`].
pub fn table_rows() -> Vec<String> {
    ALL.iter()
        .map(|(names, r)| {
            let names: Vec<String> = names.split(", ").map(|n| format!("`{n}`")).collect();
            let unit = if r.unit.starts_with("the ") {
                format!(" ({})", r.unit)
            } else {
                String::new()
            };
            format!(
                "| {} | {}{unit}{} | {} |",
                names.join(", "),
                r.span(),
                if r.whole { ", whole" } else { "" },
                r.why
            )
        })
        .collect()
}

impl Range {
    /// The range as the docs and messages write it: `[40, 100000]` with its unit.
    pub fn span(&self) -> String {
        let unit = if self.unit.is_empty() || self.unit.starts_with("the ") {
            String::new()
        } else {
            format!(" {}", self.unit)
        };
        format!("[{}, {}]{unit}", show(self.lo), show(self.hi))
    }

    /// `value` (for `option`, as typed: `given`) inside the range, or an error naming the
    /// option, the value as a person reads it, the range and why.
    pub fn check(&self, option: &str, value: f64) -> Result<f64, String> {
        let whole_ok = !self.whole || value.fract() == 0.0;
        if value.is_finite() && (self.lo..=self.hi).contains(&value) && whole_ok {
            return Ok(value);
        }
        let unit = if self.unit.is_empty() || self.unit.starts_with("the ") {
            String::new()
        } else {
            format!(" {}", self.unit)
        };
        Err(format!(
            "{option} {}{unit}: the {} must be {}in {} ({})",
            show(value),
            self.what,
            if self.whole { "a whole number " } else { "" },
            self.span(),
            self.why
        ))
    }

    /// [`Self::check`] for a count.
    pub fn check_count(&self, option: &str, value: u64) -> Result<usize, String> {
        self.check(option, value as f64).map(|v| v as usize)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn numbers_read_as_a_person_reads_them() {
        assert_eq!(show(1.3), "1.3");
        assert_eq!(show(100_000.0), "100000");
        assert_eq!(show(1e-320), "1e-320");
        assert_eq!(show(1.234_567_89e300), "1.23457e300");
        assert_eq!(show(-2.5e-7), "-2.5e-7");
        assert_eq!(show(0.010_000_000_000_000_002), "0.01");
    }

    /// docs/CONVENTIONS.md lists every range as this file states it.
    #[test]
    fn conventions_list_every_range() {
        let doc =
            std::fs::read_to_string(concat!(env!("CARGO_MANIFEST_DIR"), "/docs/CONVENTIONS.md"))
                .unwrap();
        for row in table_rows() {
            assert!(
                doc.contains(&row),
                "docs/CONVENTIONS.md lacks the row\n{row}"
            );
        }
    }

    #[test]
    fn values_outside_their_range_are_named_with_it() {
        assert_eq!(RESAMPLES.check("--resamples", 200.0), Ok(200.0));
        let e = RESAMPLES.check("--resamples", 1.0).unwrap_err();
        assert!(
            e.contains(
                "--resamples 1: the bootstrap resamples must be a whole number in [40, 100000]"
            ),
            "{e}"
        );
        let e = E_STAR_PA.check("--e-star", 1e-320).unwrap_err();
        assert!(
            e.contains("--e-star 1e-320 Pa") && e.contains("[1, 1e13] Pa"),
            "{e}"
        );
        assert!(MEMORY_SAFETY.check("--memory-safety", 1e20).is_err());
        assert!(MEMORY_SAFETY.check("--memory-safety", f64::NAN).is_err());
    }
}
