//! The perfectly plastic interface: the pressure saturates at a ceiling, `0 ≤ p ≤ p_max`
//! (Stanley & Kato 1997; Almqvist et al. 2007), `p_max` the hardness.
//!
//! Complementarity at the solution, with `ℓ` the rigid-body level of `w = u − h`:
//! `p = 0 → w ≥ ℓ` (a gap), `0 < p < p_max → w = ℓ` (contact), `p = p_max → w ≤ ℓ` (the
//! interpenetration `ℓ − w` is the plastic displacement). The solver's error measure on both
//! bounds, its start and its load restoration by offset are its part in the solve
//! (`law.rs`, [`super::complementarity::Complementarity`]); docs/CONVENTIONS.md states them.
//! Its rules at a node are in `rules.rs`, written once over lanes.

mod law;
mod rules;
#[cfg(test)]
mod tests;

pub use rules::Ceiling;
