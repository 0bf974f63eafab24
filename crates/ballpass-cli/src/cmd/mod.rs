//! One module per subcommand.

pub mod model;
pub mod passage;
pub mod predict;
