//! What the solver refuses before solving.

/// Invalid input to the solver.
#[derive(Debug, thiserror::Error, PartialEq)]
pub enum ContactError {
    #[error("heights have {got} values but the grid has {expected} (n × n)")]
    BadLength { expected: usize, got: usize },
    #[error("height at row {row}, column {col} is {value}: heights must be finite")]
    NonFinite { row: usize, col: usize, value: f64 },
    #[error("start pressure at row {row}, column {col} is {value}: it must be finite and ≥ 0")]
    BadStart { row: usize, col: usize, value: f64 },
    #[error("mean pressure {0} is invalid: it must be finite and ≥ 0")]
    BadLoad(f64),
    #[error(
        "mean pressure {mean} is above the pressure ceiling {ceiling}: no pressure field \
         bounded by the ceiling carries it (lower the load or raise the hardness)"
    )]
    AboveCeiling { mean: f64, ceiling: f64 },
    #[error("solver settings invalid: {0}")]
    BadConfig(String),
}
