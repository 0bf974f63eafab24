//! The synchronous-average section of the analysis report: the mean
//! friction and velocity-error waveform over one ball-pass period with its
//! confidence band (thesis units: N and µm/s against the phase after the
//! passage), and a table of the figures of merit.

use crate::analysis::sync::{SyncAverage, SyncKey};
use crate::analysis::Analysis;
use crate::report::kinds::fmt_sig;
use crate::report::{Axis, Block, Figure, Marker, Panel, Rgb, Section, Series, SeriesStyle, Table};

/// The panel of one waveform: the mean, the band as two dashed lines of
/// the same colour.
fn panel(s: &SyncAverage, w: &crate::analysis::sync::SyncWaveform, i: usize) -> Panel {
    // The period closed: bin B is bin 0 again.
    let mut x = s.phases();
    x.push(1.0);
    let closed = |v: &[f64]| {
        let mut v = v.to_vec();
        v.push(v[0]);
        v
    };
    let c = Rgb::palette(i);
    let label = format!("{} ({})", w.signal.words(), w.unit);
    Panel::new(
        Axis::linear("phase after the passage", "periods").with_range(0.0, 1.0),
        Axis::linear(w.signal.words(), w.unit),
    )
    .titled(label)
    .with_series(Series::line("mean", x.clone(), closed(&w.mean)).with_color(c))
    .with_series(
        Series::line(
            format!("{:.0} % band", s.confidence * 100.0),
            x.clone(),
            closed(&w.band_low),
        )
        .with_style(SeriesStyle::DashedLine)
        .with_color(c),
    )
    .with_series(
        Series::line("", x, closed(&w.band_high))
            .with_style(SeriesStyle::DashedLine)
            .with_color(c),
    )
    .with_vlines([Marker::black_dashed(
        w.fundamental_peak_phase,
        "fundamental peak",
    )])
}

/// The section, when the analysis has a synchronous average.
pub(crate) fn section(a: &Analysis, fig_id: &str, csv: &str) -> Option<Section> {
    let s = a.sync.as_ref()?;
    let keyed = match s.key {
        SyncKey::OpticalPassage => "the optical ball passages (phase 0 = a pulse centre)",
        SyncKey::EncoderPitch => {
            "the encoder at the predicted ball pitch 2·d_avg (no optical passages: phase 0 is \
             the record's first position, not a ball)"
        }
    };
    let mut sec = Section::new("Ball-pass waveform").with(Block::Paragraph(format!(
        "Friction and velocity error averaged over {} ball-pass periods of {} s (± {} s), keyed \
         on {keyed}, each period resampled to {} phase bins ({{fig:{fig_id}}}). Band: {}.",
        s.periods_used,
        fmt_sig(s.period_s.mean, 4),
        fmt_sig(s.period_s.std, 2),
        s.bins,
        s.band
    )));
    let mut t = Table::new([
        "signal",
        "peak-to-peak",
        "fundamental",
        "fundamental peak (periods after phase 0)",
        "variance explained",
        "noise level 1/P",
    ]);
    let mut fig = Figure::new(fig_id, "Mean waveform over one ball-pass period")
        .with_caption(format!(
            "Mean (solid) and {:.0} % band (dashed) per phase bin; the dashed vertical line is \
             where the fundamental peaks.",
            s.confidence * 100.0
        ))
        .with_data(
            csv.to_string(),
            "phase, <signal>_mean, <signal>_band_low, <signal>_band_high",
        );
    for (i, w) in s.waveforms.iter().enumerate() {
        t = t.with_row([
            w.signal.words().to_string(),
            format!("{} {}", fmt_sig(w.peak_to_peak, 3), w.unit),
            format!("{} {}", fmt_sig(w.fundamental_amplitude, 3), w.unit),
            format!("{:.3}", w.fundamental_peak_phase),
            format!("{:.1} %", 100.0 * w.variance_explained),
            format!("{:.1} %", 100.0 * w.noise_fraction),
        ]);
        fig = fig.with_panel(panel(s, w, i));
    }
    sec = sec.with(Block::Table(t)).with_figure(fig);
    let mut notes = s.notes.clone();
    notes.push(s.per_ball_note.clone());
    sec = sec.with(Block::Paragraph(notes.join("; ") + "."));
    Some(sec)
}
