//! Command groups of the `wearcoef` binary: running and inspecting a store ([`store`]),
//! plans and their execution ([`plan`]), Slurm campaigns ([`submit`]), single-stage tools on
//! plain files ([`tools`]), measured maps ([`topography`], [`wear`]); the arguments and
//! checks they share ([`checks`]). This file declares them only: no command imports it.

/// `println!` that returns the write's error instead of panicking: a reader that closes the
/// pipe early (`wearcoef status | head -1`) ends the command cleanly (exit 0, see `main`).
macro_rules! out {
    () => {{
        use std::io::Write as _;
        writeln!(std::io::stdout().lock())
    }};
    ($($arg:tt)*) => {{
        use std::io::Write as _;
        writeln!(std::io::stdout().lock(), $($arg)*)
    }};
}

pub mod checks;
pub mod fit;
pub mod plan;
pub mod store;
pub mod submit;
pub mod tools;
pub mod topography;
pub mod wear;
