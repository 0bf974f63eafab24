//! One module per subcommand.

pub mod predict;
pub mod simulate;
