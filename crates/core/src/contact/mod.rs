//! Frictionless normal contact of a rigid rough surface on an elastic half-space:
//! the periodic FFT operator ([`elastic`]), the Polonsky–Keer solver ([`solver`]) under an
//! [`interface`] law, load
//! sweeps and contact-map packing ([`sweep`]) and analytic references ([`reference`]).

pub mod elastic;
pub mod interface;
pub mod padded;
pub mod reference;
pub mod solver;
pub mod sweep;
pub mod window;
