//! The synchronous average of an analysis' records: keys from the optical
//! passages the analysis found, else from the encoder at the predicted
//! ball pitch.

use super::{encoder_keys, synchronous_average, SyncAverage, SyncInput, SyncKey, SyncSettings};
use crate::analysis::preprocess::Prepared;
use crate::analysis::Signal;
use crate::bearing::Prediction;
use crate::recording::{Channel, Recording};

/// The average over `recs` (prepared as `prepared`, `trim` samples dropped
/// at the start); `passage_times_s[i]` are record `i`'s optical passages
/// (s, on the record's own clock) or why there are none. `Err` says in
/// words why no average was made.
pub(crate) fn for_records(
    recs: &[Recording],
    prepared: &[Prepared],
    passage_times_s: &[Result<Vec<f64>, String>],
    pred: &Prediction,
    trim: usize,
    settings: &SyncSettings,
) -> Result<SyncAverage, String> {
    let optical = passage_times_s
        .iter()
        .all(|t| t.as_ref().is_ok_and(|t| t.len() >= 3));
    let mut notes = Vec::new();
    let pitch = 2.0 * pred.d_avg_mm;
    let mut inputs = Vec::new();
    for (i, (r, p)) in recs.iter().zip(prepared).enumerate() {
        let fs = p.fs_hz;
        let t0 = trim as f64 / fs;
        let key_times_s = if optical {
            let start = r.meta.start_time_s;
            passage_times_s[i]
                .as_ref()
                .map(|t| t.iter().map(|t| t - start - t0).collect())
                .unwrap_or_default()
        } else {
            let Some(pos) = r.channel(Channel::Position) else {
                return Err(format!(
                    "no optical passages and no encoder position in {}",
                    r.source_name()
                ));
            };
            if i > 0 {
                notes.push(format!(
                    "keyed on the encoder, each record's phase 0 is its own first position: only \
                     the first record ({}) is averaged, {} left out",
                    recs[0].source_name(),
                    recs.len() - 1
                ));
                break;
            }
            encoder_keys(&pos[trim..trim + p.n], fs, pitch)
        };
        inputs.push(SyncInput {
            source: r.source_name(),
            fs_hz: fs,
            friction_n: p.signal(Signal::Friction),
            velocity_error_mm_s: p.signal(Signal::VelocityError),
            key_times_s,
        });
    }
    if !optical {
        let why: Vec<String> = recs
            .iter()
            .zip(passage_times_s)
            .filter_map(|(r, t)| match t {
                Err(e) => Some(format!("{}: {e}", r.source_name())),
                Ok(t) if t.len() < 3 => Some(format!("{}: {} passages", r.source_name(), t.len())),
                Ok(_) => None,
            })
            .collect();
        notes.insert(0, encoder_note(pitch, &why));
    }
    let balls = pred.balls_in_race;
    let key = if optical {
        SyncKey::OpticalPassage
    } else {
        SyncKey::EncoderPitch
    };
    let mut avg = synchronous_average(&inputs, key, balls, settings).map_err(|e| e.to_string())?;
    if !optical {
        avg.pitch_mm = Some(pitch);
    }
    notes.append(&mut avg.notes);
    avg.notes = notes;
    Ok(avg)
}

/// The note of an average keyed on the encoder at `pitch_mm` of travel,
/// with why each record gave no passages to key on.
pub(crate) fn encoder_note(pitch_mm: f64, why: &[String]) -> String {
    format!(
        "keyed on the encoder at the predicted ball pitch 2·d_avg = {pitch_mm:.4} mm, not on ball \
         passages ({})",
        why.join("; ")
    )
}
