//! Analyses of a [`Recording`](crate::recording::Recording): the ball passages
//! seen by the optical sensor ([`passage`]).

mod lm;
pub mod passage;

pub use passage::{detect_passages, PassageAnalysis, PassageSettings};
