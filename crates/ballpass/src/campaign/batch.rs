//! Running one analysis over every recording of a campaign, in parallel.
//!
//! Each record is processed independently (read once, analysed, reduced to
//! its result); a failing record is kept as a failure with its reason and the
//! others still finish.

use std::sync::atomic::{AtomicUsize, Ordering};

use rayon::prelude::*;
use serde::Serialize;

use super::manifest::ManifestEntry;

/// What happened to one record.
#[derive(Debug, Clone, Serialize)]
pub struct RecordOutcome<T> {
    /// The manifest entry.
    pub entry: ManifestEntry,
    /// The result, or the one-line reason it failed.
    pub result: std::result::Result<T, String>,
}

/// Outcomes of a whole batch, in manifest order.
#[derive(Debug, Clone, Serialize)]
pub struct BatchOutcome<T> {
    /// One per manifest entry, in manifest order.
    pub records: Vec<RecordOutcome<T>>,
}

impl<T> BatchOutcome<T> {
    /// The records that succeeded, with their entries.
    pub fn ok(&self) -> impl Iterator<Item = (&ManifestEntry, &T)> {
        self.records
            .iter()
            .filter_map(|r| r.result.as_ref().ok().map(|t| (&r.entry, t)))
    }

    /// The records that failed, with their reasons.
    pub fn failed(&self) -> impl Iterator<Item = (&ManifestEntry, &str)> {
        self.records
            .iter()
            .filter_map(|r| r.result.as_ref().err().map(|e| (&r.entry, e.as_str())))
    }

    /// Number of failed records.
    pub fn n_failed(&self) -> usize {
        self.failed().count()
    }
}

/// Runs `work` on every entry in parallel (rayon's pool) and calls
/// `progress(done, total)` after each record finishes (from worker threads).
///
/// A panic inside `work` is not caught here: `work` must return errors.
pub fn run_batch<T, F, P>(entries: &[ManifestEntry], work: F, progress: P) -> BatchOutcome<T>
where
    T: Send,
    F: Fn(&ManifestEntry) -> crate::Result<T> + Sync,
    P: Fn(usize, usize) + Sync,
{
    let total = entries.len();
    let done = AtomicUsize::new(0);
    let records = entries
        .par_iter()
        .map(|entry| {
            let result = work(entry).map_err(|e| e.to_string());
            let d = done.fetch_add(1, Ordering::Relaxed) + 1;
            progress(d, total);
            RecordOutcome {
                entry: entry.clone(),
                result,
            }
        })
        .collect();
    BatchOutcome { records }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::Error;

    #[test]
    fn failures_are_kept_and_others_finish_in_order() {
        let entries: Vec<ManifestEntry> = (1..=20)
            .map(|i| ManifestEntry {
                path: format!("r{i}.csv").into(),
                bearing: "b".into(),
                velocity_mm_s: 1.0,
                repeat: i,
                condition: None,
                notes: None,
                plateau: None,
            })
            .collect();
        let calls = AtomicUsize::new(0);
        let out = run_batch(
            &entries,
            |e| {
                if e.repeat % 7 == 0 {
                    Err(Error::setting("x", format!("record {} is bad", e.repeat)))
                } else {
                    Ok(e.repeat * 10)
                }
            },
            |_, total| {
                assert_eq!(total, 20);
                calls.fetch_add(1, Ordering::Relaxed);
            },
        );
        assert_eq!(calls.load(Ordering::Relaxed), 20);
        assert_eq!(out.n_failed(), 2);
        let ok: Vec<u32> = out.ok().map(|(_, v)| *v).collect();
        assert_eq!(ok.len(), 18);
        assert_eq!(ok[0], 10);
        assert!(out
            .failed()
            .any(|(e, why)| e.repeat == 14 && why.contains("record 14 is bad")));
        assert_eq!(out.records[6].entry.repeat, 7);
    }
}
