//! Drawing: each paper figure from stored tables as PNG and SVG, with the plotted data as CSV
//! beside it. Figures read tables (statistics, analytic, audits) and draw; every number they
//! show was computed by a stage before them. One module per figure family; [`plot`] holds
//! the plot types and their style.

pub mod appendix;
mod common;
pub mod convergence;
pub mod fig2;
pub mod fig3_4a;
pub mod fig45;
pub mod plastic;
pub mod plot;
pub mod spectrum;

pub use common::{
    pick_loads, realizations_of, rows_at, tolerance_line, write, CcdfTable, Drawn, NpyData,
};
