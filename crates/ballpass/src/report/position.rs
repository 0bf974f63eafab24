//! The position-domain spectra of `analyze`: friction, velocity error and
//! optical PSDs against the travel in cycles/mm, with `1/(2 d_avg)` and its
//! harmonics marked and each PSD's confidence band.

use super::kinds::{fmt_sig, log_range, LOG_DECADES_FILTERED};
use super::spec::{Axis, Figure, Marker, Panel, Rgb, Series};
use crate::analysis::position::PositionSpectra;
use crate::analysis::Signal;

/// Unit of a position-domain PSD.
fn unit(s: Signal) -> &'static str {
    match s {
        Signal::Friction => "N²·mm",
        Signal::VelocityError => "(mm/s)²·mm",
        Signal::Optical => "V²·mm",
    }
}

/// One panel per signal; `id` and `table` name the figure and its CSV.
pub(crate) fn figure(p: &PositionSpectra, harmonics: usize, id: String, table: String) -> Figure {
    let line = p.line_per_mm;
    let top = (harmonics as f64 + 1.0) * line;
    let lines: Vec<String> = p
        .lines
        .iter()
        .filter(|l| l.k == 1)
        .map(|l| {
            format!(
                "{} {} cycles/mm ({:+.2} %, rms {} {})",
                l.signal.words(),
                fmt_sig(l.measured_per_mm, 5),
                l.deviation_percent,
                fmt_sig(l.rms, 3),
                l.unit
            )
        })
        .collect();
    let band = p.band.map_or(String::new(), |b| {
        format!(
            " Pale lines: the {} % confidence band (chi-square, ν = {}).",
            fmt_sig(100.0 * b.confidence, 3),
            fmt_sig(b.dof, 3)
        )
    });
    let mut fig = Figure::new(id, "Spectra in the position domain")
        .with_caption(format!(
            "PSD against the travel: {} mm in {} runs of one direction (slowest {} mm/s), \
             {}-point Hann segments on a {} mm grid, resolution {} cycles/mm; dashed lines at \
             k/(2 d_avg), 1/(2 d_avg) = {} cycles/mm, where the balls pass at every speed. \
             Measured first line: {}.{band}",
            fmt_sig(p.travel_used_mm, 4),
            p.runs.iter().filter(|r| r.segments > 0).count(),
            fmt_sig(p.min_speed_mm_s, 3),
            p.nperseg,
            fmt_sig(p.dx_mm, 4),
            fmt_sig(p.resolution_per_mm, 3),
            fmt_sig(line, 5),
            if lines.is_empty() {
                "none".to_string()
            } else {
                lines.join("; ")
            }
        ))
        .with_data(table, "freq_per_mm, psd_*");
    for (s, psd) in &p.auto {
        let mut y = Axis::log(format!("PSD of {}", s.words()), unit(*s));
        if let Some((lo, hi)) = log_range(
            &p.freq_per_mm,
            &[psd],
            Some((0.0, top)),
            LOG_DECADES_FILTERED,
        ) {
            let (lo, hi) = match p.band {
                Some(b) => (lo * b.lower_factor, hi * b.upper_factor),
                None => (lo, hi),
            };
            y = y.with_range(lo, hi);
        }
        let mut panel = Panel::new(
            Axis::linear("Spatial frequency", "cycles/mm").with_range(0.0, top),
            y,
        )
        .titled(s.words())
        .with_series(Series::line(s.words(), p.freq_per_mm.clone(), psd.clone()));
        if let Some(b) = p.band {
            for f in [b.lower_factor, b.upper_factor] {
                panel = panel.with_series(
                    Series::line(
                        "",
                        p.freq_per_mm.clone(),
                        psd.iter().map(|v| v * f).collect(),
                    )
                    .with_color(Rgb(160, 190, 225)),
                );
            }
        }
        panel.legend = Some(false);
        fig = fig.with_panel(panel.with_vlines(Marker::harmonics(line, harmonics, "1/2d")));
    }
    fig.interactive()
}
