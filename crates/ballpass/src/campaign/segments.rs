//! Multi-speed runs in a campaign: each file of the manifest split into its
//! constant-velocity plateaus found from the encoder
//! ([`crate::recording::segment`]), each plateau a record of the campaign.
//!
//! - Every plateau of every selected file is found first ([`segment_manifest`]);
//!   their speeds are grouped across the whole manifest
//!   ([`group_speeds`], within the velocity tolerance of the pre-verdict
//!   checks, 5 %), so a speed recorded forward and backward, in several
//!   files or on several bearings is one velocity of the campaign. The
//!   group's mean speed is the entry's `velocity_mm_s`; the plateaus of one
//!   bearing at one speed are its repeats, numbered 1, 2, … in manifest and
//!   time order.
//! - Each plateau is then analysed as a record of its own ([`load_entry`]):
//!   the file is read again, cut to the window and to the plateau (a
//!   backward one mirrored to forward motion), and analysed at the
//!   plateau's own measured speed. Its result says which plateau it was
//!   ([`PlateauSource`]: file, time range, measured velocity, direction).
//!
//! A file is read once more than it has plateaus: the plateaus are found
//! before the selection, and no file is held in memory while the others
//! are analysed.

use rayon::prelude::*;
use serde::{Deserialize, Serialize};

use super::batch::{BatchOutcome, RecordOutcome};
use super::manifest::{Manifest, ManifestEntry};
use super::record::RecordResult;
use super::run::{geometry_for, CampaignSettings};
use super::select::{select, CampaignKind, Selection};
use crate::bearing::Geometry;
use crate::error::{Error, Result};
use crate::recording::segment::{group_speeds, plateaus_found, split, window, Plateau};
use crate::recording::{load, LoadOptions, Recording};

/// Which plateau of which file a campaign record is.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct PlateauSource {
    /// The file (as the manifest names it, resolved).
    pub file: String,
    /// The plateau's number in its file (1-based, in time order).
    pub index: usize,
    /// The plateaus found in the file.
    pub of: usize,
    /// The plateau: samples, time range on the file's time axis
    /// (`start_s`–`end_s`), measured velocity (signed) and direction.
    #[serde(flatten)]
    pub plateau: Plateau,
}

/// A manifest whose files are replaced by their plateaus.
#[derive(Debug, Clone)]
pub struct SegmentedManifest {
    /// One entry per plateau (files in manifest order, plateaus in time
    /// order), with the grouped speed as its velocity.
    pub manifest: Manifest,
    /// Files that could not be segmented (unreadable, no plateau), as
    /// failed records.
    pub failed: Vec<RecordOutcome<RecordResult>>,
    /// What was done, in words (the outputs' selection notes).
    pub notes: Vec<String>,
}

/// A campaign's records, ready to run: the manifest (its files replaced by
/// their plateaus when segmenting), the selection made from it, and the
/// files that could not be segmented, as failed records.
#[derive(Debug, Clone)]
pub struct Planned {
    /// The manifest the selection was made from.
    pub manifest: Manifest,
    /// The records to process and how they were chosen (segmentation notes
    /// first).
    pub selection: Selection,
    /// Files that could not be segmented, listed as failed records.
    pub unsegmented: Vec<RecordOutcome<RecordResult>>,
}

impl Planned {
    /// The outcome of running `selection.entries`, with the files that
    /// could not be segmented appended as failed records (entries too).
    pub fn finish(
        &mut self,
        mut outcome: BatchOutcome<RecordResult>,
    ) -> BatchOutcome<RecordResult> {
        self.selection
            .entries
            .extend(self.unsegmented.iter().map(|r| r.entry.clone()));
        outcome.records.append(&mut self.unsegmented);
        outcome
    }
}

/// The records `ballpass sweep` or `ballpass diagnose` process from
/// `manifest`: with `settings.segment`, every file split into its plateaus
/// first ([`segment_manifest`]); then the selection for `kind`
/// ([`select`]).
///
/// # Errors
/// The selection's errors, and [`Error::InvalidRecording`] naming each
/// file's reason when segmenting finds no plateau in any file.
pub fn plan(
    manifest: Manifest,
    kind: CampaignKind,
    only_bearings: &[String],
    only_velocities: &[f64],
    load_options: &LoadOptions,
    fallback: Geometry,
    settings: &CampaignSettings,
) -> Result<Planned> {
    let (manifest, unsegmented, segment_notes) = if settings.segment.is_some() {
        let s = segment_manifest(&manifest, load_options, fallback, settings);
        if s.manifest.entries.is_empty() {
            let why: Vec<String> = s
                .failed
                .iter()
                .filter_map(|r| r.result.as_ref().err().cloned())
                .collect();
            return Err(Error::InvalidRecording {
                source_name: manifest.source.display().to_string(),
                reason: format!("no plateau found in any file: {}", why.join("; ")),
            });
        }
        (s.manifest, s.failed, s.notes)
    } else {
        (manifest, Vec::new(), Vec::new())
    };
    let mut selection = select(&manifest, kind, only_bearings, only_velocities)?;
    selection.notes.splice(0..0, segment_notes);
    Ok(Planned {
        manifest,
        selection,
        unsegmented,
    })
}

/// The options an entry's file is loaded with: its bearing and geometry,
/// and the velocity when known (the loader checks the record's length
/// against it).
fn options_for(
    entry: &ManifestEntry,
    velocity_mm_s: Option<f64>,
    load_options: &LoadOptions,
    fallback: Geometry,
) -> LoadOptions {
    LoadOptions {
        velocity_mm_s,
        bearing: Some(entry.bearing.clone()),
        geometry: Some(geometry_for(&entry.bearing, fallback)),
        ..load_options.clone()
    }
}

/// Loads an entry's file and cuts it to the settings' window.
fn load_windowed(
    entry: &ManifestEntry,
    opts: &LoadOptions,
    settings: &CampaignSettings,
) -> Result<Recording> {
    let rec = load(&entry.path, opts)?;
    match &settings.window {
        Some(w) => window(&rec, w),
        None => Ok(rec),
    }
}

/// Splits every file of `manifest` into its plateaus (see the module docs);
/// the plateaus are found with `settings.segment` (default settings when
/// it is `None`) and their speeds grouped within
/// `settings.preflight.velocity_tolerance`.
///
/// Runs on rayon's pool, one file per task; each file is dropped once its
/// plateaus are known.
pub fn segment_manifest(
    manifest: &Manifest,
    load_options: &LoadOptions,
    fallback: Geometry,
    settings: &CampaignSettings,
) -> SegmentedManifest {
    let seg = settings.segment.unwrap_or_default();
    let found: Vec<Result<Vec<Plateau>>> = manifest
        .entries
        .par_iter()
        .map(|e| {
            // The velocity is what is being measured: no length check
            // against it here (the plateaus are checked when analysed).
            let rec = load_windowed(e, &options_for(e, None, load_options, fallback), settings)?;
            plateaus_found(&rec, &seg)
        })
        .collect();
    let mut failed = Vec::new();
    let mut plateaus: Vec<(&ManifestEntry, usize, usize, Plateau)> = Vec::new();
    for (e, f) in manifest.entries.iter().zip(found) {
        match f {
            Ok(ps) => {
                let of = ps.len();
                plateaus.extend(ps.into_iter().enumerate().map(|(i, p)| (e, i + 1, of, p)));
            }
            Err(err) => failed.push(RecordOutcome {
                entry: e.clone(),
                result: Err(err.to_string()),
            }),
        }
    }
    let speeds: Vec<f64> = plateaus.iter().map(|(_, _, _, p)| p.speed_mm_s).collect();
    let tolerance = settings.preflight.velocity_tolerance;
    let (group, means) = group_speeds(&speeds, tolerance);
    let mut repeats: std::collections::BTreeMap<(String, usize), u32> = Default::default();
    let entries: Vec<ManifestEntry> = plateaus
        .into_iter()
        .zip(&group)
        .map(|((e, index, of, p), &g)| {
            let r = repeats.entry((e.bearing.clone(), g)).or_insert(0);
            *r += 1;
            ManifestEntry {
                velocity_mm_s: means[g],
                repeat: *r,
                plateau: Some(PlateauSource {
                    file: e.path.display().to_string(),
                    index,
                    of,
                    plateau: p,
                }),
                ..e.clone()
            }
        })
        .collect();
    let files = manifest.entries.len() - failed.len();
    let list: Vec<String> = means.iter().map(|m| format!("{m:.2}")).collect();
    let mut notes = vec![format!(
        "segmented {files} file(s) into {} constant-velocity plateaus at {} mm/s (speeds within \
         {:.0} % pooled; each plateau analysed at its own measured speed)",
        entries.len(),
        list.join(", "),
        100.0 * tolerance
    )];
    if !failed.is_empty() {
        notes.push(format!(
            "{} file(s) could not be segmented (listed as failed)",
            failed.len()
        ));
    }
    SegmentedManifest {
        manifest: Manifest {
            source: manifest.source.clone(),
            entries,
            skipped: manifest.skipped.clone(),
        },
        failed,
        notes,
    }
}

/// An entry's record as the campaign analyses it: its file loaded (at the
/// entry's velocity), cut to the window and, for a plateau, to the plateau
/// (mirrored when backward, velocity its measured speed).
///
/// # Errors
/// Loading's and the window's errors; [`Error::InvalidRecording`] when the
/// file no longer holds the plateau found in it, or when an entry without
/// a velocity is not a plateau.
pub fn load_entry(
    entry: &ManifestEntry,
    load_options: &LoadOptions,
    fallback: Geometry,
    settings: &CampaignSettings,
) -> Result<Recording> {
    let velocity = match &entry.plateau {
        Some(p) => p.plateau.speed_mm_s,
        None if entry.velocity_mm_s.is_finite() => entry.velocity_mm_s,
        None => {
            return Err(Error::setting(
                "velocity",
                format!(
                    "{}: the manifest gives no velocity for this record; give one, or segment \
                     the run into its plateaus (--segment) to use their measured speeds",
                    entry.path.display()
                ),
            ))
        }
    };
    let opts = options_for(entry, Some(velocity), load_options, fallback);
    let rec = load_windowed(entry, &opts, settings)?;
    let Some(p) = &entry.plateau else {
        return Ok(rec);
    };
    let moved = (rec.time_s(p.plateau.start) - p.plateau.start_s).abs() > 0.5 / rec.fs_hz();
    if p.plateau.end > rec.len() || moved {
        return Err(Error::InvalidRecording {
            source_name: rec.source_name(),
            reason: format!(
                "no longer holds plateau {} ({:.3}–{:.3} s) found in it: the file changed",
                p.index, p.plateau.start_s, p.plateau.end_s
            ),
        });
    }
    let mut parts = split(&rec, std::slice::from_ref(&p.plateau))?;
    Ok(parts.remove(0))
}

/// Selection-time match of a velocity asked for (`--only-velocity`) with an
/// entry's: exact for a whole file, within the grouping tolerance for a
/// plateau (its velocity is a measured mean).
pub fn velocity_matches(entry: &ManifestEntry, wanted: f64, tolerance: f64) -> bool {
    if entry.plateau.is_some() {
        (entry.velocity_mm_s - wanted).abs() <= tolerance * wanted
    } else {
        entry.velocity_mm_s == wanted
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::campaign::manifest::parse_manifest;
    use std::path::Path;

    /// A manifest row names one run of a TDMS file (`FILE#GROUP`, relative
    /// to the manifest); the record read is that group's.
    #[test]
    fn a_manifest_names_a_run_inside_a_file() {
        let dir = Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/data");
        let m = parse_manifest(
            &dir.join("m.csv"),
            "path,bearing,velocity_mm_s,repeat\ntdms_runs.tdms#Run 3,sr25w,27,1\n",
        )
        .unwrap();
        let g = crate::bearing::lookup("sr25w").unwrap().geometry;
        // 0.16 s: shorter than the loader's default 3 periods at 27 mm/s.
        let opts = LoadOptions {
            min_periods: 0.1,
            ..LoadOptions::default()
        };
        let rec = load_entry(&m.entries[0], &opts, g, &CampaignSettings::default()).unwrap();
        assert_eq!(rec.len(), 160);
        assert!(rec.source_name().ends_with("tdms_runs.tdms#Run 3"));
        assert_eq!(rec.meta.velocity_mm_s, Some(27.0));
        // An empty velocity without a plateau says how to proceed.
        let mut e = m.entries[0].clone();
        e.velocity_mm_s = f64::NAN;
        let err = load_entry(&e, &opts, g, &CampaignSettings::default()).unwrap_err();
        assert!(err.to_string().contains("--segment"), "{err}");
    }
}
