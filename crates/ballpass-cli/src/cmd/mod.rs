//! One module per subcommand.

pub mod analyze;
pub mod inspect;
pub mod model;
pub mod passage;
pub mod predict;
pub mod simulate;
