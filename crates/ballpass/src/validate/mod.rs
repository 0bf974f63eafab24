//! Validation of every verdict on randomized benches: the simulator and the
//! analyses run together on benches drawn from a [`bench::Domain`], and each
//! verdict is scored against the simulator's truth (false-alarm and
//! detection rates with their binomial intervals).

pub mod bench;
pub mod compensation;
pub mod compensation_fc;
pub mod compensation_guard;
pub mod compensation_near_stall;
pub mod compensation_second;
pub mod compensation_stall;
pub mod compensation_tau;
pub mod estimate;
pub mod fleets;
pub mod passages;
pub mod score;
pub mod suite;
pub mod thesis_batch;

pub use bench::{BearingDraw, Bench, Domain, Range, Sticking};
pub use estimate::{estimate_domain, DomainEstimate};
pub use score::Rate;
pub use suite::{run, SuiteSettings, ValidationReport};
