//! Frictionless normal contact of a rigid rough surface on an elastic half-space:
//! the periodic FFT operator ([`elastic`]), the Polonsky–Keer solver ([`solver`]) and
//! analytic references ([`reference`]).

pub mod elastic;
pub mod reference;
pub mod solver;
