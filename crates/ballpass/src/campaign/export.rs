//! Campaign tables as CSV and JSON, written atomically.
//!
//! - `records.csv`: one row per record, every scalar the analyses produced
//!   (failed records too, with their reason), ending with the plateau of a
//!   segmented multi-speed run the record is (`plateau`, ...,
//!   `direction`; empty for whole files);
//! - `sweep.csv`: one row per velocity; `diagnosis.csv`: one row per bearing;
//!   `records.csv` and `sweep.csv` end with the position-domain ripple
//!   (`ripple_<signal>_h<k>_<unit>` and its `_lower_`/`_upper_` interval);
//! - `friction_spectra.csv`: the averaged friction spectrum of each bearing
//!   (`freq_hz`, then `psd_friction_<bearing>_n2_per_hz`);
//!
//! Every column name ends in its unit, as in the analysis tables (see
//! [`crate::analysis::export`]); counts, ratios, fractions and flags have
//! none.
//! - `sweep.json` / `diagnosis.json`: everything, with the failures.

use std::fmt::Write as _;
use std::path::{Path, PathBuf};

use serde::Serialize;

use super::batch::BatchOutcome;
use super::diagnose::Diagnosis;
use super::record::RecordResult;
use super::ripple::{unit_token, RIPPLE_SIGNALS};
use super::sweep::Sweep;
use crate::error::{Error, Result};
use crate::fsutil::write_atomic;

fn opt(v: Option<f64>) -> String {
    v.map(|x| format!("{x}")).unwrap_or_default()
}

fn quote(s: &str) -> String {
    if s.contains([',', '"', '\n']) {
        format!("\"{}\"", s.replace('"', "\"\""))
    } else {
        s.to_string()
    }
}

/// `records.csv`: one row per record (failed ones with `status = failed`).
pub fn records_csv(outcome: &BatchOutcome<RecordResult>, harmonics: usize) -> String {
    let mut s = String::from(
        "path,bearing,velocity_mm_s,repeat,condition,status,error,fs_hz,duration_s,f_c_predicted_hz,\
         f_c_correlation_hz,f_c_passages_hz,passages,tau_c_s,tau_c_std_s,tau_p_s,tau_p_std_s,tau_ratio,\
         velocity_error_std_um_s,velocity_error_lowpassed_std_um_s,phase_friction_optical_deg,\
         phase_friction_velocity_error_deg,phase_velocity_error_optical_deg,friction_low_band_power_n2,\
         periods,typical_period_rise_n,period_spread_n,spikes",
    );
    for k in 1..=harmonics {
        let _ = write!(s, ",friction_h{k}_ratio_db,friction_h{k}_significant");
    }
    s.push_str(&ripple_header(harmonics));
    s.push_str(PLATEAU_HEADER);
    s.push('\n');
    for r in &outcome.records {
        let e = &r.entry;
        let _ = write!(
            s,
            "{},{},{},{},{},",
            quote(&e.path.display().to_string()),
            quote(&e.bearing),
            e.velocity_mm_s,
            e.repeat,
            quote(e.condition.as_deref().unwrap_or(""))
        );
        match &r.result {
            Err(why) => {
                let _ = write!(s, "failed,{}", quote(why));
                s.push_str(&",".repeat(21 + 2 * harmonics + 3 * RIPPLE_SIGNALS.len() * harmonics));
            }
            Ok(x) => {
                let st = x.sticking.as_ref();
                let _ = write!(
                    s,
                    "ok,,{},{},{},{},{},{},{},{},{},{},{},{},{},{},{},{},{},{},{},{},{}",
                    x.fs_hz,
                    x.duration_s,
                    x.f_c_predicted_hz,
                    opt(x.f_c_correlation_hz),
                    opt(x.f_c_passages_hz),
                    x.passages.map(|n| n.to_string()).unwrap_or_default(),
                    opt(x.tau_c_s),
                    opt(x.tau_c_std_s),
                    opt(x.tau_p_s),
                    opt(x.tau_p_std_s),
                    opt(x.tau_ratio),
                    opt(x.velocity_error_std_um_s),
                    opt(x.velocity_error_lowpassed_std_um_s),
                    opt(x.phase_friction_optical_deg),
                    opt(x.phase_friction_velocity_error_deg),
                    opt(x.phase_velocity_error_optical_deg),
                    opt(x.friction_low_band_power_n2),
                    st.map(|s| s.periods.to_string()).unwrap_or_default(),
                    opt(st.map(|s| s.typical_n)),
                    opt(st.map(|s| s.spread_n)),
                    st.map(|s| s.spikes.to_string()).unwrap_or_default(),
                );
                for k in 0..harmonics {
                    let _ = write!(
                        s,
                        ",{},{}",
                        opt(x.friction_harmonic_ratio_db.get(k).copied().flatten()),
                        x.friction_harmonic_significant
                            .get(k)
                            .copied()
                            .flatten()
                            .map(|b| b.to_string())
                            .unwrap_or_default()
                    );
                }
                s.push_str(&ripple_cells(harmonics, |sig, k| {
                    x.position_ripple
                        .iter()
                        .find(|l| l.signal == sig && l.k == k)
                        .map(|l| [Some(l.amplitude), l.amplitude_lower, l.amplitude_upper])
                }));
            }
        }
        s.push_str(&plateau_cells(e.plateau.as_ref()));
        s.push('\n');
    }
    s
}

/// The last columns of `records.csv`: which plateau of a multi-speed run
/// the record is (empty for a whole file): its number in the file, its time
/// range on the file's time axis, the measured velocity (signed, mm/s) and
/// the direction (`forward`, `backward`).
const PLATEAU_HEADER: &str =
    ",plateau,plateaus_in_file,plateau_start_s,plateau_end_s,plateau_velocity_mm_s,direction";

fn plateau_cells(p: Option<&super::segments::PlateauSource>) -> String {
    match p {
        None => ",,,,,,".into(),
        Some(p) => format!(
            ",{},{},{},{},{},{}",
            p.index,
            p.of,
            p.plateau.start_s,
            p.plateau.end_s,
            p.plateau.velocity_mm_s,
            match p.plateau.direction {
                crate::recording::segment::Direction::Forward => "forward",
                crate::recording::segment::Direction::Backward => "backward",
            }
        ),
    }
}

/// Header cells of the position-domain ripple, for `harmonics` lines of
/// each [`RIPPLE_SIGNALS`] signal: `,ripple_friction_h1_n,
/// ripple_friction_h1_lower_n,ripple_friction_h1_upper_n,...`.
fn ripple_header(harmonics: usize) -> String {
    let mut s = String::new();
    for (sig, unit, _) in RIPPLE_SIGNALS {
        let u = unit_token(unit);
        for k in 1..=harmonics {
            let n = sig.name();
            let _ = write!(
                s,
                ",ripple_{n}_h{k}_{u},ripple_{n}_h{k}_lower_{u},ripple_{n}_h{k}_upper_{u}"
            );
        }
    }
    s
}

/// The cells under [`ripple_header`]: amplitude, lower, upper of each line
/// `get` finds (empty cells where it finds none).
fn ripple_cells(
    harmonics: usize,
    get: impl Fn(crate::analysis::Signal, usize) -> Option<[Option<f64>; 3]>,
) -> String {
    let mut s = String::new();
    for (sig, _, _) in RIPPLE_SIGNALS {
        for k in 1..=harmonics {
            let [a, lo, hi] = get(sig, k).unwrap_or([None; 3]);
            let _ = write!(s, ",{},{},{}", opt(a), opt(lo), opt(hi));
        }
    }
    s
}

/// `sweep.csv`: one row per velocity.
pub fn sweep_csv(sweep: &Sweep) -> String {
    let harmonics = sweep
        .velocities
        .iter()
        .flat_map(|r| r.ripple.iter().map(|l| l.k))
        .max()
        .unwrap_or(0);
    let mut s = String::from(
        "velocity_mm_s,records,f_c_predicted_hz,f_c_measured_hz,f_c_measured_std_hz,\
         velocity_error_std_um_s,velocity_error_std_spread_um_s,tau_c_s,tau_c_spread_s,\
         tau_p_s,tau_p_spread_s,tau_ratio,tau_ratio_spread",
    );
    s.push_str(&ripple_header(harmonics));
    s.push('\n');
    for r in &sweep.velocities {
        let m = |x: Option<crate::stats::MeanStd>| (opt(x.map(|m| m.mean)), opt(x.map(|m| m.std)));
        let (fc, fcs) = m(r.f_c_measured_hz);
        let (ve, ves) = m(r.velocity_error_std_um_s);
        let (tc, tcs) = m(r.tau_c_s);
        let (tp, tps) = m(r.tau_p_s);
        let (ra, ras) = m(r.tau_ratio);
        let _ = write!(
            s,
            "{},{},{},{fc},{fcs},{ve},{ves},{tc},{tcs},{tp},{tps},{ra},{ras}",
            r.velocity_mm_s, r.records, r.f_c_predicted_hz
        );
        s.push_str(&ripple_cells(harmonics, |sig, k| {
            r.ripple
                .iter()
                .find(|l| l.signal == sig && l.k == k)
                .map(|l| [Some(l.amplitude), l.amplitude_lower, l.amplitude_upper])
        }));
        s.push('\n');
    }
    s
}

/// `diagnosis.csv`: one row per bearing, worst first.
pub fn diagnosis_csv(d: &Diagnosis) -> String {
    let mut s = String::from(
        "rank,bearing,verdict,records,manifest_condition,periods,typical_period_rise_n,\
         period_spread_n,spikes,spikes_for_bad,spikes_for_suspect,typical_over_batch,\
         spread_over_batch,low_band_power_n2,low_band_ratio,f_c_ratio_db,evidence\n",
    );
    for b in &d.bearings {
        let _ = writeln!(
            s,
            "{},{},{},{},{},{},{},{},{},{},{},{},{},{},{},{},{}",
            b.rank,
            quote(&b.bearing),
            b.verdict.name(),
            b.records,
            quote(b.manifest_condition.as_deref().unwrap_or("")),
            b.periods,
            b.typical_n,
            b.spread_n,
            b.spikes,
            b.spikes_for_bad,
            b.spikes_for_suspect,
            opt(b.typical_over_batch),
            opt(b.spread_over_batch),
            b.low_band_power_n2,
            b.low_band_ratio,
            opt(b.harmonics.first().and_then(|h| h.ratio_db)),
            quote(&b.evidence.join("; "))
        );
    }
    s
}

/// `friction_spectra.csv`: `freq_hz` then one column per bearing (worst
/// first), `psd_friction_<bearing>_n2_per_hz`.
pub fn friction_spectra_csv(d: &Diagnosis) -> String {
    let mut s = String::from("freq_hz");
    for b in &d.bearings {
        let _ = write!(s, ",{}", quote(&friction_psd_column(&b.bearing)));
    }
    s.push('\n');
    for (i, f) in d.freq_hz.iter().enumerate() {
        let _ = write!(s, "{f}");
        for p in &d.friction_psd {
            let _ = write!(s, ",{}", p.get(i).copied().unwrap_or(f64::NAN));
        }
        s.push('\n');
    }
    s
}

/// Column of a bearing's averaged friction auto-spectrum in
/// `friction_spectra.csv`: `psd_friction_<bearing>_n2_per_hz` (N²/Hz).
pub fn friction_psd_column(bearing: &str) -> String {
    format!("psd_friction_{bearing}_n2_per_hz")
}

/// A failed record in the JSON.
#[derive(Debug, Serialize)]
pub struct Failure {
    /// File.
    pub path: String,
    /// The plateau of a segmented run that failed.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub plateau: Option<super::segments::PlateauSource>,
    /// Why.
    pub reason: String,
}

/// The failures of a batch.
pub fn failures(outcome: &BatchOutcome<RecordResult>) -> Vec<Failure> {
    outcome
        .failed()
        .map(|(e, why)| Failure {
            path: e.path.display().to_string(),
            plateau: e.plateau.clone(),
            reason: why.to_string(),
        })
        .collect()
}

/// Writes `name` under `dir` atomically and returns its path.
///
/// # Errors
/// [`Error::Io`] naming the file.
pub fn write_text(dir: &Path, name: &str, text: &str) -> Result<PathBuf> {
    let p = dir.join(name);
    write_atomic(&p, text.as_bytes())?;
    Ok(p)
}

/// Writes a serde value as pretty JSON under `dir`.
///
/// # Errors
/// [`Error::Io`] naming the file, or a serialisation failure.
pub fn write_json<T: Serialize>(dir: &Path, name: &str, value: &T) -> Result<PathBuf> {
    let text = serde_json::to_string_pretty(value).map_err(|e| Error::Format {
        path: dir.join(name),
        reason: format!("cannot serialise: {e}"),
    })?;
    write_text(dir, name, &(text + "\n"))
}

#[cfg(test)]
mod tests {
    use super::super::batch::RecordOutcome;
    use super::super::sweep::tests::record;
    use super::*;

    #[test]
    fn friction_spectra_columns_carry_the_unit() {
        assert_eq!(
            friction_psd_column("bearing4"),
            "psd_friction_bearing4_n2_per_hz"
        );
    }

    /// Every row of records.csv has as many fields as the header, for good
    /// and failed records alike.
    #[test]
    fn records_csv_rows_match_the_header() {
        let good = record(9.0, 1);
        let entry = super::super::run::entry_for(Path::new("a,b.csv"), "sr25w", 9.0, 1);
        let outcome = BatchOutcome {
            records: vec![
                RecordOutcome {
                    entry: entry.clone(),
                    result: Ok(good),
                },
                RecordOutcome {
                    entry,
                    result: Err("x.csv:3: bad \"cell\"".into()),
                },
            ],
        };
        let text = records_csv(&outcome, 1);
        let mut rd = ::csv::ReaderBuilder::new().from_reader(text.as_bytes());
        let n = rd.headers().unwrap().len();
        let rows: Vec<::csv::StringRecord> = rd.records().map(|r| r.unwrap()).collect();
        assert_eq!(rows.len(), 2);
        assert!(rows.iter().all(|r| r.len() == n), "{text}");
        assert_eq!(&rows[0][0], "a,b.csv");
        assert_eq!(&rows[0][5], "ok");
        assert_eq!(&rows[1][6], "x.csv:3: bad \"cell\"");
        assert_eq!(
            rows[0][13].parse::<f64>().unwrap(),
            record(9.0, 1).tau_c_s.unwrap()
        );
    }
}
