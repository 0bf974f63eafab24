//! Seeded fuzz harness of ballpass's file loaders (issue 18).
//!
//! Mutations of valid files of every format the loaders read (the committed
//! fixtures: CSV, MAT level 5 and v7.3, TDMS, MF4; text in lab dialects;
//! profiles; manifests) and structured MAT stress files (nesting,
//! dimensions, compressed streams, lying lengths) go through every loader
//! call (`load`, `contents`, `inspect`, the two CSV readers against each
//! other, profile and manifest parsing), under a watchdog for time and a
//! counting allocator for memory: see [`harness`] for what counts as a
//! failure.
//!
//! A brief seeded run is a test of this crate (`cargo test`, seconds); the
//! long run is a bench binary:
//!
//! ```text
//! cargo bench -p ballpass-fuzz --bench fuzz -- --execs 10000000 --seed 1
//! ```

pub mod alloc;
pub mod corpus;
pub mod harness;
pub mod matgen;
pub mod mutate;
pub mod rng;
