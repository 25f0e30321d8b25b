//! The law of the interface between the rigid surface and the half-space: what bounds the
//! contact pressure. Made (and validated) once, where a hardness is read; past that point
//! it is the only thing that carries a hardness, and [`Interface::dispatch`] is the one
//! place that turns it into the solver's constraint, for the periodic sweep and the window
//! alike.
//!
//! A new law (adhesion, a hardening cap) is a variant here, its constraint in the solver's
//! folder, and its field in the configuration.

use super::solver::{Ceiling, Complementarity, ContactError, NonNegative};

/// What bounds the contact pressure.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub enum Interface {
    /// Frictionless, non-adhesive elastic contact: `p ≥ 0`.
    #[default]
    Elastic,
    /// Perfectly plastic: `0 ≤ p ≤ 𝓗` with `𝓗 = hardness·E*·rms slope`, the hardness in
    /// the units of W/W0 (so that `p̄/𝓗 = (W/W0)/hardness`). Made by
    /// [`Interface::from_hardness`], which checks it.
    PerfectlyPlastic { hardness: f64 },
}

/// Something run with the constraint of an interface: generic over the constraint, so that
/// each interface's solve is compiled for its own constraint.
pub trait ConstraintTask {
    type Output;
    fn run<C: Complementarity>(self, constraint: C) -> Self::Output;
}

impl Interface {
    /// The interface of an optional hardness (units of W/W0): none, or `inf`, is elastic;
    /// otherwise the hardness must be finite and > 0.
    pub fn from_hardness(hardness: Option<f64>) -> Result<Self, ContactError> {
        match hardness {
            None => Ok(Self::Elastic),
            Some(h) if h == f64::INFINITY => Ok(Self::Elastic),
            Some(h) if h.is_finite() && h > 0.0 => Ok(Self::PerfectlyPlastic { hardness: h }),
            Some(h) => Err(ContactError::BadConfig(format!(
                "hardness {h} must be > 0 (in units of E*·rms slope, as W/W0; absent or inf is elastic)"
            ))),
        }
    }

    /// The hardness (units of W/W0), if the pressure is capped.
    pub fn hardness(&self) -> Option<f64> {
        match *self {
            Self::Elastic => None,
            Self::PerfectlyPlastic { hardness } => Some(hardness),
        }
    }

    /// Whether the contact is elastic (no bound on the pressure above).
    pub fn is_elastic(&self) -> bool {
        *self == Self::Elastic
    }

    /// The first load (index, W/W0) that the interface cannot carry: a mean pressure above
    /// the hardness.
    pub fn first_load_above(&self, loads: &[f64]) -> Option<(usize, f64)> {
        let h = self.hardness()?;
        loads
            .iter()
            .enumerate()
            .find(|(_, &w)| w > h)
            .map(|(i, &w)| (i, w))
    }

    /// Run `task` with this interface's constraint; `ceiling` turns the hardness into the
    /// pressure ceiling in the solve's units (`hardness·E*·rms slope`, written by the caller
    /// in the order its rounding has always had).
    pub fn dispatch<T: ConstraintTask>(
        &self,
        ceiling: impl FnOnce(f64) -> f64,
        task: T,
    ) -> Result<T::Output, ContactError> {
        Ok(match *self {
            Self::Elastic => task.run(NonNegative),
            Self::PerfectlyPlastic { hardness } => task.run(Ceiling::new(ceiling(hardness))?),
        })
    }
}

/// Written as its hardness, absent (`null`) when elastic: the form the stage keys have
/// always had.
impl serde::Serialize for Interface {
    fn serialize<S: serde::Serializer>(&self, s: S) -> Result<S::Ok, S::Error> {
        self.hardness().serialize(s)
    }
}

impl<'de> serde::Deserialize<'de> for Interface {
    fn deserialize<D: serde::Deserializer<'de>>(d: D) -> Result<Self, D::Error> {
        let hardness = Option::<f64>::deserialize(d)?;
        Self::from_hardness(hardness).map_err(serde::de::Error::custom)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    struct Ceil;
    impl ConstraintTask for Ceil {
        type Output = f64;
        fn run<C: Complementarity>(self, c: C) -> f64 {
            c.project(1e300)
        }
    }

    #[test]
    fn a_hardness_is_checked_once_and_dispatched_to_its_constraint() {
        assert_eq!(Interface::from_hardness(None).unwrap(), Interface::Elastic);
        assert_eq!(
            Interface::from_hardness(Some(f64::INFINITY)).unwrap(),
            Interface::Elastic
        );
        for bad in [0.0, -1.0, f64::NAN, f64::NEG_INFINITY] {
            let e = Interface::from_hardness(Some(bad)).unwrap_err().to_string();
            assert!(e.contains("must be > 0"), "{e}");
        }
        let plastic = Interface::from_hardness(Some(0.25)).unwrap();
        assert_eq!(plastic.hardness(), Some(0.25));
        // The ceiling is the hardness times E*·rms slope; elastic pressures are unbounded.
        assert_eq!(plastic.dispatch(|h| h * 4.0, Ceil).unwrap(), 1.0);
        assert_eq!(
            Interface::Elastic.dispatch(|h| h * 4.0, Ceil).unwrap(),
            1e300
        );
        assert_eq!(plastic.first_load_above(&[0.1, 0.25, 0.3]), Some((2, 0.3)));
        assert_eq!(Interface::Elastic.first_load_above(&[1e9]), None);
    }
}
