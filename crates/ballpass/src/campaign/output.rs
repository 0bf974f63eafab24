//! The JSON file of a campaign command (`sweep.json`, `diagnosis.json`):
//! the campaign's answer with its inputs, selection, settings, failures and
//! every record's result.

use serde::Serialize;

use super::batch::BatchOutcome;
use super::export::{failures, Failure};
use super::record::RecordResult;
use super::run::CampaignSettings;

/// Everything a campaign command writes as JSON around its answer `T`
/// ([`super::sweep::Sweep`] or [`super::diagnose::Diagnosis`]).
#[derive(Debug, Serialize)]
pub struct CampaignOutput<'a, T: Serialize> {
    /// `ballpass.sweep/1` or `ballpass.diagnosis/1`.
    pub schema: &'static str,
    /// ballpass version.
    pub version: &'static str,
    /// The manifest or folder read.
    pub source: String,
    /// Records selected.
    pub records: usize,
    /// Records that failed, with the reason.
    pub failed: Vec<Failure>,
    /// How the records were selected, in words.
    pub selection: &'a [String],
    /// Per-record settings.
    pub settings: &'a CampaignSettings,
    /// The campaign's answer.
    pub result: &'a T,
    /// The records that succeeded, in manifest order.
    pub record_results: Vec<&'a RecordResult>,
}

/// Schema tag of `sweep.json`.
pub const SWEEP_SCHEMA: &str = "ballpass.sweep/1";
/// Schema tag of `diagnosis.json`.
pub const DIAGNOSIS_SCHEMA: &str = "ballpass.diagnosis/1";

impl<'a, T: Serialize> CampaignOutput<'a, T> {
    /// The output of a batch: its failures and the records that succeeded
    /// are taken from `outcome`.
    pub fn new(
        schema: &'static str,
        source: String,
        outcome: &'a BatchOutcome<RecordResult>,
        selection: &'a [String],
        settings: &'a CampaignSettings,
        result: &'a T,
    ) -> Self {
        Self {
            schema,
            version: crate::VERSION,
            source,
            records: outcome.records.len(),
            failed: failures(outcome),
            selection,
            settings,
            result,
            record_results: outcome.ok().map(|(_, r)| r).collect(),
        }
    }
}
