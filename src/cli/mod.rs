//! Command groups of the `wearcoef` binary.

pub mod plan;
