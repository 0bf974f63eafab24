//! Which records of a manifest a campaign command uses.
//!
//! By default `sweep` takes the bearing recorded at the most velocities and
//! `diagnose` the velocity with the most bearings (leaving out a bearing
//! that is also recorded at other velocities, a sweep's bearing, when at
//! least two others remain); naming bearings or velocities replaces the
//! default. Each choice is explained in a note that the outputs carry, and
//! so is what folder mode left out of the folder.

use std::collections::{BTreeMap, BTreeSet};

use serde::{Deserialize, Serialize};

use super::manifest::{Manifest, ManifestEntry, OrderedVelocity};
use crate::error::{Error, Result};

/// The campaign command a selection is for.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum CampaignKind {
    /// A velocity sweep of one bearing.
    Sweep,
    /// A batch of bearings at one velocity.
    Diagnose,
}

/// The records used and the notes that explain the choice.
#[derive(Debug, Clone, PartialEq)]
pub struct Selection {
    /// Entries used, in manifest order.
    pub entries: Vec<ManifestEntry>,
    /// How they were chosen, in words (the outputs' `selection`).
    pub notes: Vec<String>,
}

/// Selects the records of `manifest` for `kind`: the default choice when
/// `only_bearings` and `only_velocities` are both empty, else every entry
/// of those bearings and velocities. The notes end with what folder mode
/// skipped ([`Manifest::skipped`]).
///
/// # Errors
/// [`Error::Format`] naming the manifest when no record is left.
pub fn select(
    manifest: &Manifest,
    kind: CampaignKind,
    only_bearings: &[String],
    only_velocities: &[f64],
) -> Result<Selection> {
    let (mut entries, mut notes) = if only_bearings.is_empty() && only_velocities.is_empty() {
        match kind {
            CampaignKind::Sweep => pick_sweep(manifest),
            CampaignKind::Diagnose => pick_diagnose(manifest),
        }
    } else {
        (manifest.entries.clone(), Vec::new())
    };
    if !only_bearings.is_empty() {
        entries.retain(|e| only_bearings.contains(&e.bearing));
        notes.push(format!("only bearings {}", only_bearings.join(", ")));
    }
    if !only_velocities.is_empty() {
        // A plateau's velocity is a measured mean: matched within the
        // tolerance its speeds were grouped with.
        let tolerance = crate::analysis::preflight::PreflightSettings::default().velocity_tolerance;
        entries.retain(|e| {
            only_velocities
                .iter()
                .any(|&v| super::segments::velocity_matches(e, v, tolerance))
        });
        notes.push(format!("only velocities {only_velocities:?} mm/s"));
    }
    notes.extend(skipped_notes(manifest));
    if entries.is_empty() {
        return Err(Error::Format {
            path: manifest.source.clone(),
            reason: "no recording left after the selection".into(),
        });
    }
    Ok(Selection { entries, notes })
}

/// What folder mode left out, as selection notes: each entry that matched
/// but is no readable file by name, the names that do not match counted.
fn skipped_notes(m: &Manifest) -> Vec<String> {
    let mut notes: Vec<String> = m
        .skipped
        .iter()
        .filter(|s| !s.reason.starts_with("does not match"))
        .map(|s| format!("skipped {}: {}", s.name, s.reason))
        .collect();
    let unmatched = m.skipped.len() - notes.len();
    if unmatched > 0 {
        notes.push(format!(
            "{unmatched} other entr{} of the folder do not match the pattern",
            if unmatched == 1 { "y" } else { "ies" }
        ));
    }
    notes
}

/// Default selection of `sweep`: the bearing recorded at the most velocities.
fn pick_sweep(m: &Manifest) -> (Vec<ManifestEntry>, Vec<String>) {
    let mut per: BTreeMap<&str, BTreeSet<OrderedVelocity>> = BTreeMap::new();
    for e in &m.entries {
        per.entry(&e.bearing)
            .or_default()
            .insert(OrderedVelocity(e.velocity_mm_s));
    }
    let Some((best, _)) = per.iter().max_by_key(|(_, v)| v.len()) else {
        return (Vec::new(), Vec::new());
    };
    let best = best.to_string();
    let entries: Vec<ManifestEntry> = m
        .entries
        .iter()
        .filter(|e| e.bearing == best)
        .cloned()
        .collect();
    let notes = if per.len() > 1 {
        vec![format!(
            "swept bearing {best} (recorded at the most velocities); --only-bearing picks another"
        )]
    } else {
        Vec::new()
    };
    (entries, notes)
}

/// Default selection of `diagnose`: the velocity with the most bearings,
/// leaving out a bearing that is also recorded at other velocities (the
/// sweep's bearing) when at least two others remain.
fn pick_diagnose(m: &Manifest) -> (Vec<ManifestEntry>, Vec<String>) {
    let mut per: BTreeMap<OrderedVelocity, BTreeSet<&str>> = BTreeMap::new();
    for e in &m.entries {
        per.entry(OrderedVelocity(e.velocity_mm_s))
            .or_default()
            .insert(&e.bearing);
    }
    let Some((v, bearings)) = per.iter().max_by_key(|(v, b)| (b.len(), *v)) else {
        return (Vec::new(), Vec::new());
    };
    let swept: BTreeSet<&str> = bearings
        .iter()
        .copied()
        .filter(|b| {
            m.entries
                .iter()
                .any(|e| e.bearing == *b && e.velocity_mm_s != v.0)
        })
        .collect();
    let mut notes = vec![format!(
        "diagnosed the batch at {} mm/s (the velocity with the most bearings)",
        v.0
    )];
    let keep_swept = bearings.len() - swept.len() < 2;
    if !keep_swept && !swept.is_empty() {
        notes.push(format!(
            "left out {} (also recorded at other velocities: a sweep, not the batch); --only-bearing includes it",
            swept.iter().copied().collect::<Vec<_>>().join(", ")
        ));
    }
    let entries = m
        .entries
        .iter()
        .filter(|e| e.velocity_mm_s == v.0 && (keep_swept || !swept.contains(e.bearing.as_str())))
        .cloned()
        .collect();
    (entries, notes)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn entry(bearing: &str, v: f64, repeat: u32) -> ManifestEntry {
        super::super::run::entry_for(std::path::Path::new("r.csv"), bearing, v, repeat)
    }

    fn manifest() -> Manifest {
        // b1 swept over three velocities; b2..b4 only at 9 mm/s.
        let mut entries = vec![
            entry("b1", 3.0, 1),
            entry("b1", 6.0, 1),
            entry("b1", 9.0, 1),
        ];
        for b in ["b2", "b3", "b4"] {
            entries.push(entry(b, 9.0, 1));
            entries.push(entry(b, 9.0, 2));
        }
        Manifest {
            source: "m.csv".into(),
            entries,
            skipped: Vec::new(),
        }
    }

    #[test]
    fn defaults_pick_the_sweep_and_the_batch() {
        let m = manifest();
        let s = select(&m, CampaignKind::Sweep, &[], &[]).unwrap();
        assert!(s.entries.iter().all(|e| e.bearing == "b1") && s.entries.len() == 3);
        let d = select(&m, CampaignKind::Diagnose, &[], &[]).unwrap();
        assert_eq!(d.entries.len(), 6, "{:?}", d.notes);
        assert!(d.entries.iter().all(|e| e.bearing != "b1"));
        assert!(d.notes[1].contains("left out b1"), "{:?}", d.notes);
    }

    #[test]
    fn named_bearings_replace_the_default_and_empty_is_an_error() {
        let m = manifest();
        let d = select(&m, CampaignKind::Diagnose, &["b1".into()], &[9.0]).unwrap();
        assert_eq!(d.entries.len(), 1);
        assert_eq!(d.notes.len(), 2);
        let err = select(&m, CampaignKind::Sweep, &["zz".into()], &[]).unwrap_err();
        assert!(
            err.to_string().contains("m.csv: no recording left"),
            "{err}"
        );
    }

    #[test]
    fn what_folder_mode_skipped_ends_the_notes() {
        let skipped = |name: &str, reason: &str| super::super::manifest::Skipped {
            name: name.into(),
            reason: reason.into(),
        };
        let m = Manifest {
            skipped: vec![
                skipped("old", "a folder"),
                skipped("a.txt", "does not match the pattern"),
                skipped("b.txt", "does not match the pattern"),
            ],
            ..manifest()
        };
        let s = select(&m, CampaignKind::Sweep, &["b2".into()], &[]).unwrap();
        assert_eq!(
            s.notes,
            [
                "only bearings b2",
                "skipped old: a folder",
                "2 other entries of the folder do not match the pattern"
            ]
        );
    }
}
