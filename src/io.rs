//! Plain-file input and output of fields as `.npy` (float64, C order), readable by
//! `numpy.load`.

pub mod atomic;
mod disk;
mod error;
mod gsf;
pub mod guard;
pub mod measured;
mod netcdf;
mod npy;
pub mod prepare;
mod read;
mod sdf;
pub mod sniff;
pub mod text;
mod x3p;
mod xyz;

pub use disk::{cannot_write, disk_note};
pub use error::IoError;
pub use npy::*;
pub use read::{read_map_text, read_measured};
