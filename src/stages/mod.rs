//! The stage contract and the registry of stages.
//!
//! A stage is a pure function from a serialisable job and the stored outputs of its inputs
//! to files in a fresh directory. Its key is the SHA-256 of canonical JSON of
//! `{salt, stage, version, params, inputs}` ([`crate::store::hash::instance_key`]), where
//! `params` is the job serialised: a parameter cannot change an output without being in the
//! key, and nothing but the job's own fields is. Input keys are not part of the job; the
//! plan lists them beside it (in the order the stage reads them), and they enter the key
//! through `inputs`.
//!
//! The runner knows no stage by name: it looks the instance's stage up in the registry
//! ([`crate::pipeline::registry`]), which deserialises the job and calls [`Stage::compute`].
//! Adding a stage is one file here with a `Stage` impl, and one line in the registry.

pub use crate::store::inputs::{InputRef, Inputs};
pub use stage::{keyed, DynStage, Registered, Stage};

pub mod analytic;
pub mod audits;
pub mod clusters;
pub mod contact;
pub mod figures;
mod stage;
pub mod statistics;
pub mod surface;
