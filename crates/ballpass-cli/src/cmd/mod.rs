//! One module per subcommand.

pub mod analyze;
pub mod campaign;
pub mod compensate;
pub mod demo;
pub mod inspect;
pub mod model;
pub mod passage;
pub mod predict;
pub mod simulate;
pub mod validate;
