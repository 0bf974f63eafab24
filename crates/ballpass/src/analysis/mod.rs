//! Analyses of a [`Recording`](crate::recording::Recording): the ball passages
//! seen by the optical sensor ([`passage`]).

pub mod passage;
mod train_fit;

pub use passage::{detect_passages, PassageAnalysis, PassageSettings};
