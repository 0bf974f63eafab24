//! ballpass: finds and characterises the periodic disturbances that balls cause
//! in linear ball bearings.
//!
//! Data flows one way (see `shared/design/ARCHITECTURE.md`):
//! recording files → [`recording::Recording`] → preprocessing → analyses →
//! results (serde structs) → reports. This crate never prints, never exits and
//! never parses argv: it returns values and typed [`Error`]s.

pub mod analysis;
pub mod bearing;
pub mod campaign;
pub mod demo;
pub mod error;
pub mod fsutil;
pub mod model;
pub mod outdir;
pub mod recording;
pub mod report;
pub mod sim;
pub mod stats;
pub mod validate;

/// Self-removing scratch folders for the unit tests (the same file serves
/// the integration and end-to-end tests).
#[cfg(test)]
#[path = "../tests/common/scratch.rs"]
pub(crate) mod test_scratch;

pub use error::{Error, Result};

/// Version of ballpass, recorded in every output.
pub const VERSION: &str = env!("CARGO_PKG_VERSION");
