//! The registry of stages: how the executors find a stage by the name a plan gives.

use crate::stages::{
    analytic, audits, clusters, contact, figures, statistics, surface, DynStage, Registered,
};

/// Every stage, in the order a run's levels usually list them.
pub static REGISTRY: &[&dyn DynStage] = &[
    &Registered::<surface::Surface>::new(),
    &Registered::<contact::Contact>::new(),
    &Registered::<clusters::Clusters>::new(),
    &Registered::<statistics::Statistics>::new(),
    &Registered::<analytic::Analytic>::new(),
    &Registered::<audits::Audits>::new(),
    &Registered::<figures::Figures>::new(),
];

/// The registered stage called `name`.
pub fn find(name: &str) -> Option<&'static dyn DynStage> {
    REGISTRY.iter().copied().find(|s| s.name() == name)
}

/// Names of every registered stage, in registry order.
pub fn names() -> Vec<&'static str> {
    REGISTRY.iter().map(|s| s.name()).collect()
}
