//! Campaigns: many recordings of one bench (velocity sweeps, bearing batches)
//! turned into campaign answers (thesis Figs. 29, 52, 53 and chapter 8).

pub mod batch;
pub mod diagnose;
pub mod export;
pub mod manifest;
pub mod output;
pub mod pattern;
pub mod record;
pub mod ripple;
pub mod run;
pub mod segments;
pub mod select;
pub mod sticking;
pub mod sweep;

pub use batch::{run_batch, BatchOutcome, RecordOutcome};
pub use manifest::{from_directory, manifest_csv, read_manifest, Manifest, ManifestEntry, Skipped};
pub use output::CampaignOutput;
pub use select::{select, CampaignKind, Selection};
