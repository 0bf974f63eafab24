//! One record of a campaign, from file (or simulation) to [`RecordResult`]:
//! the full analysis, the optical passages, the sticking events, and the
//! friction spectrum kept for diagnosis.

use std::borrow::Cow;
use std::path::Path;

use serde::{Deserialize, Serialize};

use super::diagnose::low_band_power;
use super::manifest::ManifestEntry;
use super::record::RecordResult;
use super::sticking::{passage_heights, StickingSettings};
use crate::analysis::load_cell::restore_friction;
use crate::analysis::preflight::{self, PreflightSettings};
use crate::analysis::{
    analyze_without_passages, detect_passages, AnalyzeSettings, PassageSettings, Signal,
};
use crate::bearing::{lookup, Geometry};
use crate::error::Result;
use crate::recording::segment::{SegmentSettings, Window};
use crate::recording::{Channel, LoadOptions, Recording};

/// Settings of the per-record work of a campaign.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(default)]
pub struct CampaignSettings {
    /// The analysis of each record.
    pub analyze: AnalyzeSettings,
    /// Ball-passage detection (`fit_pulses` 0 by default: campaigns need the
    /// passages, not the per-record pulse-train fits).
    pub passage: PassageSettings,
    /// Sticking-event detection.
    pub sticking: StickingSettings,
    /// Upper edge of the friction low band, Hz.
    pub low_band_hz: f64,
    /// Checks before the analysis: dead channels, the manifest's velocity
    /// against the encoder's ([`preflight`]).
    pub preflight: PreflightSettings,
    /// Only this time window of each record (`None`: all of it).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub window: Option<Window>,
    /// Split each file into its constant-velocity plateaus, each a record
    /// (see [`super::segments`]); `None`: each file is one record.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub segment: Option<SegmentSettings>,
}

impl Default for CampaignSettings {
    fn default() -> Self {
        Self {
            analyze: AnalyzeSettings::default(),
            passage: PassageSettings {
                fit_pulses: 0,
                ..PassageSettings::default()
            },
            sticking: StickingSettings::default(),
            low_band_hz: 25.0,
            preflight: PreflightSettings::default(),
            window: None,
            segment: None,
        }
    }
}

/// The geometry of an entry's bearing: the catalog entry of that name, else
/// `fallback` (a batch of numbered bearings of one model).
pub fn geometry_for(bearing: &str, fallback: Geometry) -> Geometry {
    lookup(bearing).map_or(fallback, |e| e.geometry)
}

/// Loads one manifest entry, cuts it to the settings' window (and to its
/// plateau, see [`super::segments::load_entry`]), runs the [`preflight`]
/// checks (dead channels left out with a warning, the manifest's velocity
/// against the encoder's) and processes it. A plateau is analysed at its
/// own measured speed; its result keeps the entry's (pooled) velocity and
/// says which plateau it was.
///
/// # Errors
/// Whatever loading, the checks or the analysis report (the message names
/// the file).
pub fn process_entry(
    entry: &ManifestEntry,
    load_options: &LoadOptions,
    fallback: Geometry,
    settings: &CampaignSettings,
) -> Result<RecordResult> {
    let geometry = geometry_for(&entry.bearing, fallback);
    let rec = super::segments::load_entry(entry, load_options, fallback, settings)?;
    // A plateau: analysed at its own speed.
    let analysed = match &entry.plateau {
        Some(p) => Cow::Owned(ManifestEntry {
            velocity_mm_s: p.plateau.speed_mm_s,
            ..entry.clone()
        }),
        None => Cow::Borrowed(entry),
    };
    let checked = preflight::check(
        vec![rec],
        Some(analysed.velocity_mm_s),
        &geometry,
        &settings.preflight,
    )?;
    let rec = &checked.recordings[0];
    let mut result = process_recording(rec, &analysed, geometry, settings)?;
    result.warnings.splice(0..0, checked.warnings);
    result.velocity_mm_s = entry.velocity_mm_s;
    result.plateau = entry.plateau.clone();
    Ok(result)
}

/// Processes a recording already in memory (a loaded file or a simulation).
///
/// # Errors
/// The analysis' errors (too short, missing channels, bad settings).
pub fn process_recording(
    rec: &Recording,
    entry: &ManifestEntry,
    geometry: Geometry,
    settings: &CampaignSettings,
) -> Result<RecordResult> {
    let v = entry.velocity_mm_s;
    let prediction = geometry.predict(v, settings.analyze.harmonics)?;
    // The load-cell correction once, for the analysis and the sticking
    // events alike.
    let restored = rec
        .channel(Channel::Friction)
        .map(|f| {
            restore_friction(
                f,
                rec.fs_hz(),
                prediction.tau_c_s,
                settings.analyze.load_cell,
            )
        })
        .transpose()?;
    // The passages are detected below with the campaign's settings; the
    // analysis' own summary of them would be the same work twice.
    let analysis = analyze_without_passages(
        std::slice::from_ref(rec),
        &prediction,
        &settings.analyze,
        Some(vec![restored
            .as_ref()
            .map(|(f, d)| (Cow::Borrowed(f.as_ref()), d.clone()))]),
    )?;
    let mut warnings = analysis.warnings.clone();
    let position_ripple = position_ripple(rec, &restored, &prediction, settings, &mut warnings)?;

    let passages = if rec.channel(Channel::Optical).is_some() {
        let ps = PassageSettings {
            velocity_mm_s: Some(v),
            geometry: Some(geometry),
            ..settings.passage.clone()
        };
        match detect_passages(rec, &ps) {
            Ok(p) => Some(p),
            Err(e) => {
                warnings.push(format!("passages: {e}"));
                None
            }
        }
    } else {
        None
    };

    let phase = |pair: &str| {
        analysis
            .phases
            .iter()
            .find(|p| p.pair == pair)
            .and_then(|p| p.phase_deg)
    };
    let mut harmonics: Vec<_> = analysis
        .harmonics
        .iter()
        .filter(|h| h.signal == Signal::Friction)
        .collect();
    harmonics.sort_by_key(|h| h.k);

    let (freq, psd) = match analysis.spectra.auto_of(Signal::Friction) {
        Some(p) => (analysis.spectra.freq_hz.clone(), p.to_vec()),
        None => (Vec::new(), Vec::new()),
    };
    let low_band = (!psd.is_empty()).then(|| low_band_power(&freq, &psd, settings.low_band_hz));

    let tau_for_sticking = sticking_period(
        passages.as_ref().map(|p| p.tau_c_s.mean),
        analysis.measured_period.period_s,
        prediction.tau_c_s,
    );
    let sticking = match &restored {
        Some((f, _)) => Some(passage_heights(
            f,
            rec.fs_hz(),
            tau_for_sticking,
            &settings.sticking,
        )?),
        None => None,
    };

    let ve = analysis.velocity_error.as_ref();
    Ok(RecordResult {
        path: entry.path.display().to_string(),
        bearing: entry.bearing.clone(),
        velocity_mm_s: v,
        repeat: entry.repeat,
        condition: entry.condition.clone(),
        fs_hz: rec.fs_hz(),
        duration_s: analysis.duration_analysed_s,
        f_c_predicted_hz: prediction.f_c_hz,
        f_c_correlation_hz: analysis.measured_period.f_c_hz,
        passages: passages.as_ref().map(|p| p.count),
        f_c_passages_hz: passages
            .as_ref()
            .map(|p| p.f_c_measured_hz)
            .filter(|f| f.is_finite()),
        tau_c_s: passages.as_ref().map(|p| p.tau_c_s.mean),
        tau_c_std_s: passages.as_ref().map(|p| p.tau_c_s.std),
        // Widths the passage analysis withheld (NaN) are left empty.
        tau_p_s: passages
            .as_ref()
            .map(|p| p.tau_p_s.mean)
            .filter(|t| t.is_finite()),
        tau_p_std_s: passages
            .as_ref()
            .map(|p| p.tau_p_s.std)
            .filter(|t| t.is_finite()),
        tau_ratio: passages
            .as_ref()
            .map(|p| p.tau_p_over_tau_c.mean)
            .filter(|t| t.is_finite()),
        velocity_error_std_um_s: ve.map(|s| s.std_um_s),
        velocity_error_lowpassed_std_um_s: ve.map(|s| s.lowpassed_std_um_s),
        phase_friction_optical_deg: phase("friction__optical"),
        phase_friction_velocity_error_deg: phase("friction__velocity_error"),
        phase_velocity_error_optical_deg: phase("velocity_error__optical"),
        friction_harmonic_ratio_db: harmonics
            .iter()
            .map(|h| h.value().and_then(|v| v.ratio_db))
            .collect(),
        friction_harmonic_significant: harmonics.iter().map(|h| h.significant).collect(),
        friction_low_band_power_n2: low_band,
        sticking,
        position_ripple,
        warnings,
        plateau: None,
        friction_psd_freq_hz: freq,
        friction_psd: psd,
        stage_spectra: analysis.stage_spectra.clone(),
    })
}

/// The record's ripple in the position domain (friction restored from the
/// load cell as for the analysis), or none with a warning saying why when
/// the record has an encoder but too little travel in one direction.
///
/// # Errors
/// A bad low-pass setting (the analysis would have failed on it first).
/// The ball-pass period the per-period heights are cut with: the optical
/// passages' mean interval when it agrees with the period the
/// correlations measured within 2 % (a missed passage makes one interval
/// double and moves the mean by `1/n`; interference that hides half the
/// passages doubles it), else the measured period, else the passages',
/// else the prediction. Periods cut at a wrong length fold the ripple
/// onto a sliding phase, and the heights then scatter like sticking.
fn sticking_period(passages_s: Option<f64>, measured_s: Option<f64>, predicted_s: f64) -> f64 {
    let usable = |t: &f64| t.is_finite() && *t > 0.0;
    let passages_s = passages_s.filter(usable);
    let measured_s = measured_s.filter(usable);
    match (passages_s, measured_s) {
        (Some(p), Some(m)) if (p / m - 1.0).abs() <= 0.02 => p,
        (_, Some(m)) => m,
        (Some(p), None) => p,
        (None, None) => predicted_s,
    }
}

fn position_ripple(
    rec: &Recording,
    restored: &Option<(Cow<'_, [f64]>, crate::analysis::load_cell::DcRestoration)>,
    prediction: &crate::bearing::Prediction,
    settings: &CampaignSettings,
    warnings: &mut Vec<String>,
) -> Result<Vec<super::ripple::RippleLine>> {
    if rec.channel(Channel::Position).is_none() {
        return Ok(Vec::new());
    }
    let a = &settings.analyze;
    let filter = crate::analysis::preprocess::lowpass_filter(a, rec.fs_hz())?;
    let trim = ((a.trim_start_s * rec.fs_hz()).round() as usize).min(rec.len());
    let part = (
        rec,
        restored.as_ref().map(|(f, _)| f.as_ref()),
        trim..rec.len(),
    );
    match crate::analysis::position::compute_with(
        &[part],
        a,
        filter.as_ref(),
        prediction.d_avg_mm,
        crate::analysis::position::Detail::Amplitudes,
    ) {
        Ok(p) => Ok(super::ripple::record_lines(&p)),
        Err(e) => {
            warnings.push(format!("no position-domain ripple: {e}"));
            Ok(Vec::new())
        }
    }
}

/// A manifest entry for a recording that did not come from a manifest.
pub fn entry_for(path: &Path, bearing: &str, velocity_mm_s: f64, repeat: u32) -> ManifestEntry {
    ManifestEntry {
        path: path.to_path_buf(),
        bearing: bearing.to_string(),
        velocity_mm_s,
        repeat,
        condition: None,
        notes: None,
        plateau: None,
    }
}

/// The manifest entry of a planned simulation (`path` is the plan's relative
/// path with `.csv`).
pub fn entry_of_simulation(c: &crate::sim::campaign::CampaignEntry) -> ManifestEntry {
    ManifestEntry {
        path: format!("{}.csv", c.path).into(),
        bearing: c.bearing.clone(),
        velocity_mm_s: c.velocity_mm_s,
        repeat: c.repeat,
        condition: Some(c.condition.name().to_string()),
        notes: None,
        plateau: None,
    }
}

/// Simulates one planned record in memory and processes it, as if its file
/// had been loaded (the built-in data of `ballpass demo` and the oracle of
/// the campaign tests).
///
/// # Errors
/// The simulator's or the analysis' errors.
pub fn process_simulation(
    c: &crate::sim::campaign::CampaignEntry,
    fallback: Geometry,
    settings: &CampaignSettings,
) -> Result<(Recording, RecordResult)> {
    let sim = crate::sim::simulate(&c.settings)?;
    let entry = entry_of_simulation(c);
    let result = process_recording(
        &sim.recording,
        &entry,
        geometry_for(&c.bearing, fallback),
        settings,
    )?;
    Ok((sim.recording, result))
}

#[cfg(test)]
mod tests {
    /// The passages' period where it agrees with the correlations', the
    /// correlations' where half the passages were missed (session 18: a
    /// good bearing behind optical interference was called bad on periods
    /// 1.7 and 2 times too long), and the fallbacks.
    #[test]
    fn the_sticking_period_trusts_passages_that_agree() {
        use super::sticking_period;
        assert_eq!(sticking_period(Some(2.65), Some(2.647), 2.6), 2.65);
        assert_eq!(sticking_period(Some(5.13), Some(2.647), 2.6), 2.647);
        assert_eq!(sticking_period(Some(4.46), Some(2.647), 2.6), 2.647);
        assert_eq!(sticking_period(Some(2.65), None, 2.6), 2.65);
        assert_eq!(sticking_period(None, Some(2.647), 2.6), 2.647);
        assert_eq!(sticking_period(Some(f64::NAN), None, 2.6), 2.6);
        assert_eq!(sticking_period(None, None, 2.6), 2.6);
    }

    use super::*;
    use crate::sim::{simulate, Condition, SimSettings};

    fn sim(v: f64, condition: Condition, seed: u64) -> Recording {
        let mut s = SimSettings::for_bearing("sr25w", v).unwrap();
        s.condition = condition;
        s.seed = seed;
        simulate(&s).unwrap().recording
    }

    /// A simulated good record: every field the sweep needs is filled and
    /// agrees with the simulator's design (tau_c = 2 d_avg / v within the
    /// spacing band, tau_p/tau_c near 0.155, no sticking spikes).
    #[test]
    fn a_simulated_record_gives_every_scalar() {
        let g = lookup("sr25w").unwrap().geometry;
        let rec = sim(9.0, Condition::Good, 7);
        let e = entry_for(Path::new("sim"), "sr25w", 9.0, 1);
        let r = process_recording(&rec, &e, g, &CampaignSettings::default()).unwrap();
        let tau = r.tau_c_s.unwrap();
        // The spacing band at 9 mm/s: 2(d_avg ± d_var)/v = 0.889 .. 0.914 s.
        assert!((0.889..=0.914).contains(&tau), "tau_c {tau}");
        assert!(
            (r.tau_ratio.unwrap() - 0.155).abs() < 0.155 * 0.05,
            "{:?}",
            r.tau_ratio
        );
        assert!(r.velocity_error_std_um_s.unwrap() > 20.0);
        assert_eq!(r.friction_harmonic_ratio_db.len(), 5);
        let st = r.sticking.as_ref().unwrap();
        // 30 s at 9 mm/s: 33 whole periods after the first half.
        assert!(st.periods >= 32 && st.spikes == 0, "{st:?}");
        assert!(!r.friction_psd.is_empty() && r.friction_low_band_power_n2.unwrap() > 0.0);
    }

    /// The simulator's sticking bearing spikes on 60 % of its passages, up
    /// to ten times the friction: its typical period rises, and scatters,
    /// several times a good bearing's on the same bench (what the batch
    /// rule of the diagnosis reads).
    #[test]
    fn a_sticking_record_rises_and_scatters_far_above_a_good_one() {
        let g = lookup("sr25w").unwrap().geometry;
        let e = entry_for(Path::new("sim"), "b4", 20.0, 1);
        let s = CampaignSettings::default();
        let bad = process_recording(&sim(20.0, Condition::Sticking, 11), &e, g, &s).unwrap();
        let good = process_recording(&sim(20.0, Condition::Good, 11), &e, g, &s).unwrap();
        let (b, o) = (bad.sticking.unwrap(), good.sticking.unwrap());
        assert!(b.typical_n > 2.0 * o.typical_n, "{b:?}\n{o:?}");
        assert!(b.spread_n > 3.0 * o.spread_n, "{b:?}\n{o:?}");
    }
}
