//! Ready-made figures and panels for the plots ballpass draws, after the
//! thesis' figures. Each returns plain [`Figure`] / [`Panel`] data that the
//! caller may adjust (caption, ranges, extra markers) before rendering.
//!
//! All builders copy the slices they are given; lengths are checked when the
//! figure is rendered (an [`Error::Report`](crate::Error::Report) then names
//! the figure, panel and series).

use super::spec::{Axis, Figure, Marker, Panel, Rgb, Series, SeriesStyle};

/// One measured signal of a stacked time-series figure.
#[derive(Debug, Clone, Copy)]
pub struct Trace<'a> {
    /// What it is ("Friction force").
    pub label: &'a str,
    /// Unit ("N").
    pub unit: &'a str,
    /// Samples, one per time in the figure's time vector.
    pub values: &'a [f64],
}

/// Time series stacked top to bottom sharing the time axis (thesis Fig. 54:
/// load cell, encoder, photodetector).
pub fn time_series_stack(id: &str, title: &str, t_s: &[f64], traces: &[Trace<'_>]) -> Figure {
    let mut fig = Figure::new(id, title);
    for (i, tr) in traces.iter().enumerate() {
        fig.panels.push(
            Panel::new(Axis::linear("Time", "s"), Axis::linear(tr.label, tr.unit)).with_series(
                Series::line(tr.label, t_s.to_vec(), tr.values.to_vec())
                    .with_color(Rgb::palette(i)),
            ),
        );
    }
    fig.panel_height_px = 220;
    fig.interactive()
}

/// A correlation over lag, with red dashed lines at the non-zero multiples of
/// `tau_c_s` inside `range_s` (or the whole lag axis).
pub fn correlation_panel(
    lag_s: &[f64],
    r: &[f64],
    name: &str,
    y: Axis,
    tau_c_s: Option<f64>,
    range_s: Option<(f64, f64)>,
) -> Panel {
    let mut x = Axis::linear("Lag τ", "s");
    if let Some((a, b)) = range_s {
        x = x.with_range(a, b);
    }
    let (lo, hi) = range_s.unwrap_or_else(|| {
        let lo = lag_s.iter().copied().fold(f64::INFINITY, f64::min);
        let hi = lag_s.iter().copied().fold(f64::NEG_INFINITY, f64::max);
        (lo, hi)
    });
    let mut p = Panel::new(x, y).with_series(Series::line(name, lag_s.to_vec(), r.to_vec()));
    if let Some(tc) = tau_c_s {
        p = p.with_vlines(Marker::multiples(tc, lo, hi, "τc", false));
    }
    p.legend = Some(false);
    p
}

/// A correlation full range on top and zoomed to `±zoom_periods * tau_c_s`
/// below, with the multiples of `tau_c` marked in the zoom (thesis Figs.
/// 55–60). Without `tau_c_s` only the full panel is drawn.
pub fn correlation(
    id: &str,
    title: &str,
    lag_s: &[f64],
    r: &[f64],
    y: Axis,
    tau_c_s: Option<f64>,
    zoom_periods: f64,
) -> Figure {
    let mut fig = Figure::new(id, title).with_panel(
        correlation_panel(lag_s, r, &y.label, y.clone(), None, None).titled("(a) full range"),
    );
    fig.panels[0].vlines.clear();
    if let Some(tc) = tau_c_s.filter(|t| t.is_finite() && *t > 0.0) {
        let half = zoom_periods.max(1.0) * tc;
        fig.panels.push(
            correlation_panel(lag_s, r, &y.label.clone(), y, Some(tc), Some((-half, half))).titled(
                format!(
                    "(b) zoom, dashed lines at multiples of τc = {} s",
                    fmt_sig(tc, 4)
                ),
            ),
        );
    }
    fig.interactive()
}

/// What a spectrum panel marks and shows of the frequency axis.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct SpectrumView {
    /// Ball-pass frequency to mark with a red dashed line, Hz.
    pub f_c_hz: Option<f64>,
    /// How many multiples of `f_c` to mark (1 = the fundamental only).
    pub n_harmonics: usize,
    /// Visible frequency range, Hz; `None` shows all.
    pub range_hz: Option<(f64, f64)>,
    /// Whether the spectra are of unfiltered signals (a log axis then
    /// keeps more decades, see [`log_range`]).
    pub unfiltered: bool,
}

impl SpectrumView {
    fn max_decades(&self) -> f64 {
        if self.unfiltered {
            LOG_DECADES_UNFILTERED
        } else {
            LOG_DECADES_FILTERED
        }
    }

    fn apply(&self, mut panel: Panel) -> Panel {
        if let Some((a, b)) = self.range_hz {
            panel.x = panel.x.with_range(a, b);
        }
        if let Some(fc) = self.f_c_hz {
            panel = panel.with_vlines(Marker::harmonics(fc, self.n_harmonics.max(1), "f_c"));
        }
        panel
    }
}

/// A spectrum (auto or cross, magnitude) on a log y axis with `f_c` and its
/// harmonics marked (thesis Figs. 62–65). `y` is normally
/// `Axis::log("PSD", "N²/Hz")`; on a log axis its range is set by
/// [`log_range`] (the DC bin of a detrended signal, ~1e-30, would
/// otherwise stretch it over tens of decades).
pub fn spectrum_panel(f_hz: &[f64], p: &[f64], name: &str, y: Axis, view: SpectrumView) -> Panel {
    spectrum_panel_on(Axis::linear("Frequency", "Hz"), f_hz, p, name, y, view)
}

/// A full-range spectrum on log–log axes from the first bin above 0 Hz to
/// the last (thesis Figs. 62, 64: decades of frequency, so the harmonics
/// of a 1 Hz `f_c` and the white-noise floor at hundreds of Hz both read).
pub fn spectrum_panel_loglog(
    f_hz: &[f64],
    p: &[f64],
    name: &str,
    y: Axis,
    view: SpectrumView,
) -> Panel {
    // the 0 Hz bin has no place on a log axis: left out, not a drawing note
    let (f, v): (Vec<f64>, Vec<f64>) = f_hz
        .iter()
        .zip(p)
        .filter(|(f, _)| **f > 0.0)
        .map(|(f, v)| (*f, *v))
        .unzip();
    let x = Axis::log("Frequency", "Hz");
    let x = match (f.first(), f.last()) {
        (Some(&a), Some(&b)) if b > a => x.with_range(a, b),
        _ => x,
    };
    spectrum_panel_on(x, &f, &v, name, y, view)
}

fn spectrum_panel_on(
    x: Axis,
    f_hz: &[f64],
    p: &[f64],
    name: &str,
    mut y: Axis,
    view: SpectrumView,
) -> Panel {
    if y.scale == super::Scale::Log && y.range.is_none() {
        let range = view.range_hz.or(x.range);
        if let Some((lo, hi)) = log_range(f_hz, &[p], range, view.max_decades()) {
            y = y.with_range(lo, hi);
        }
    }
    let mut panel = Panel::new(x, y).with_series(Series::line(name, f_hz.to_vec(), p.to_vec()));
    panel.legend = Some(false);
    view.apply(panel)
}

/// Decades a log axis of low-passed spectra spans at most below its
/// highest value: the filter's stop band (down to 1e-25 of the peak) is cut.
pub const LOG_DECADES_FILTERED: f64 = 8.0;

/// Decades a log axis of unfiltered spectra spans at most below its highest
/// value: room for a quiet sensor's white-noise floor (the simulator's lies
/// about 11 decades below the friction peak).
pub const LOG_DECADES_UNFILTERED: f64 = 14.0;

/// A log-axis range for spectra: from half the 1st percentile of the
/// positive values in the frequency range (bins above 0 Hz), but at most
/// `max_decades` below the largest value, to twice the largest. A
/// low-passed spectrum's stop band and a detrended signal's DC bin fall
/// below it and are cut rather than stretching the axis; the noise floor of
/// an unfiltered one stays inside. `None` when there is no positive value.
pub fn log_range(
    f_hz: &[f64],
    spectra: &[&[f64]],
    range_hz: Option<(f64, f64)>,
    max_decades: f64,
) -> Option<(f64, f64)> {
    let (a, b) = range_hz.unwrap_or((f64::NEG_INFINITY, f64::INFINITY));
    let mut v: Vec<f64> = spectra
        .iter()
        .flat_map(|p| {
            f_hz.iter()
                .zip(p.iter())
                .filter(move |(f, x)| {
                    **f > 0.0 && **f >= a && **f <= b && x.is_finite() && **x > 0.0
                })
                .map(|(_, x)| *x)
        })
        .collect();
    if v.is_empty() {
        return None;
    }
    v.sort_by(f64::total_cmp);
    let max = v[v.len() - 1];
    let p01 = v[(v.len() - 1) / 100];
    let lo = (0.5 * p01).max(max * 10f64.powf(-max_decades));
    Some((lo, 2.0 * max))
}

/// Magnitude-squared coherence, y fixed to 0..1, with `f_c` and harmonics marked.
pub fn coherence_panel(f_hz: &[f64], coh: &[f64], name: &str, view: SpectrumView) -> Panel {
    let y = Axis::linear("Coherence", "").with_range(0.0, 1.0);
    spectrum_panel(f_hz, coh, name, y, view)
}

/// One spectrum of an overlay: legend name, values, colour, and whether it
/// is drawn thick and on top (the bad bearing of thesis Figs. 67–68).
#[derive(Debug, Clone, Copy)]
pub struct Overlaid<'a> {
    /// Legend text.
    pub name: &'a str,
    /// Values, one per frequency.
    pub values: &'a [f64],
    /// Colour (red for a bad item, see [`Rgb::CALM`] for good ones).
    pub color: Rgb,
    /// Drawn thick and on top.
    pub highlight: bool,
}

/// Several spectra overlaid with a legend, on the frequency axis `x`
/// (linear, or log for a full range); a log `y` gets its range from
/// [`log_range`] over all of them.
pub fn overlay_spectra(
    id: &str,
    title: &str,
    f_hz: &[f64],
    spectra: &[Overlaid<'_>],
    x: Axis,
    mut y: Axis,
    view: SpectrumView,
) -> Figure {
    if y.scale == super::Scale::Log && y.range.is_none() {
        let values: Vec<&[f64]> = spectra.iter().map(|s| s.values).collect();
        if let Some((lo, hi)) =
            log_range(f_hz, &values, view.range_hz.or(x.range), view.max_decades())
        {
            y = y.with_range(lo, hi);
        }
    }
    let log_x = x.scale == super::Scale::Log;
    let mut panel = Panel::new(x, y);
    for o in spectra {
        let (f, v): (Vec<f64>, Vec<f64>) = f_hz
            .iter()
            .zip(o.values)
            .filter(|(f, _)| !log_x || **f > 0.0)
            .map(|(f, v)| (*f, *v))
            .unzip();
        let mut s = Series::line(o.name, f, v).with_color(o.color);
        if o.highlight {
            s = s.highlighted();
        }
        panel.series.push(s);
    }
    panel.legend = Some(true);
    Figure::new(id, title)
        .with_panel(view.apply(panel))
        .interactive()
}

/// A measured pulse signal with fitted model curves overlaid as dashed lines
/// (thesis Figs. 47–48).
pub fn pulses_with_models(
    id: &str,
    title: &str,
    t_s: &[f64],
    measured: &[f64],
    y: Axis,
    models: &[(&str, &[f64])],
) -> Figure {
    let mut panel = Panel::new(Axis::linear("Time", "s"), y).with_series(
        Series::line("measured", t_s.to_vec(), measured.to_vec()).with_color(Rgb::BLACK),
    );
    for (i, (name, m)) in models.iter().enumerate() {
        panel.series.push(
            Series::line(*name, t_s.to_vec(), m.to_vec())
                .with_style(SeriesStyle::DashedLine)
                .with_color(Rgb::palette(i)),
        );
    }
    panel.legend = Some(true);
    Figure::new(id, title).with_panel(panel)
}

/// Bode plot: magnitude in dB above, phase in degrees below, both on a log
/// frequency axis, with optional marked frequencies (a natural frequency,
/// `f_c`) as red dashed lines (thesis Figs. 28, 41–42). Several responses may
/// be overlaid: `responses` holds `(name, magnitude_db, phase_deg)`.
pub fn bode(
    id: &str,
    title: &str,
    f_hz: &[f64],
    responses: &[(&str, &[f64], &[f64])],
    marks: &[(f64, &str)],
) -> Figure {
    let x = Axis::log("Frequency", "Hz");
    let mut mag = Panel::new(x.clone(), Axis::linear("Magnitude", "dB")).titled("magnitude");
    let mut ph = Panel::new(x, Axis::linear("Phase", "deg")).titled("phase");
    for (i, (name, m, p)) in responses.iter().enumerate() {
        mag.series
            .push(Series::line(*name, f_hz.to_vec(), m.to_vec()).with_color(Rgb::palette(i)));
        ph.series
            .push(Series::line(*name, f_hz.to_vec(), p.to_vec()).with_color(Rgb::palette(i)));
    }
    for (f, label) in marks {
        mag.vlines.push(Marker::red_dashed(*f, *label));
        ph.vlines.push(Marker::red_dashed(*f, *label));
    }
    ph.legend = Some(false);
    Figure::new(id, title).with_panel(mag).with_panel(ph)
}

/// Mean ± standard deviation against a parameter, as error bars joined by a
/// line (thesis Fig. 29: velocity-error std against tracking velocity).
pub fn error_bar_plot(
    id: &str,
    title: &str,
    x_axis: Axis,
    y_axis: Axis,
    x: &[f64],
    mean: &[f64],
    std: &[f64],
) -> Figure {
    let s = Series::line(y_axis.label.clone(), x.to_vec(), mean.to_vec()).with_style(
        SeriesStyle::ErrorBars {
            minus: std.to_vec(),
            plus: std.to_vec(),
            line: true,
        },
    );
    let mut p = Panel::new(x_axis, y_axis).with_series(s);
    p.legend = Some(false);
    Figure::new(id, title).with_panel(p)
}

/// A fitted power law `y = coefficient * x^exponent`, drawn as a straight
/// dashed line on log-log axes.
#[derive(Debug, Clone, Copy)]
pub struct PowerLaw<'a> {
    /// Legend text ("fit: τc = 4.06 / v").
    pub name: &'a str,
    /// `a` of `a * x^b`.
    pub coefficient: f64,
    /// `b` of `a * x^b`.
    pub exponent: f64,
}

/// Measured points with error bars and fitted power laws on log-log axes
/// (thesis Fig. 52: `tau_c` and `tau_p` against velocity). `data` holds
/// `(name, y, std)` sharing `x`.
pub fn loglog_fit(
    id: &str,
    title: &str,
    x_axis: Axis,
    y_axis: Axis,
    x: &[f64],
    data: &[(&str, &[f64], &[f64])],
    fits: &[PowerLaw<'_>],
) -> Figure {
    let x_axis = Axis {
        scale: super::Scale::Log,
        ..x_axis
    };
    let y_axis = Axis {
        scale: super::Scale::Log,
        ..y_axis
    };
    let mut p = Panel::new(x_axis, y_axis);
    for (i, (name, y, std)) in data.iter().enumerate() {
        p.series.push(
            Series::error_bars(*name, x.to_vec(), y.to_vec(), std.to_vec())
                .with_color(Rgb::palette(i)),
        );
    }
    let (lo, hi) = x
        .iter()
        .filter(|v| v.is_finite() && **v > 0.0)
        .fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), &v| {
            (a.min(v), b.max(v))
        });
    if lo < hi {
        let n = 50;
        let xs: Vec<f64> = (0..n)
            .map(|i| lo * (hi / lo).powf(i as f64 / (n - 1) as f64))
            .collect();
        for (i, f) in fits.iter().enumerate() {
            let ys = xs
                .iter()
                .map(|v| f.coefficient * v.powf(f.exponent))
                .collect();
            p.series.push(
                Series::line(f.name, xs.clone(), ys)
                    .with_style(SeriesStyle::DashedLine)
                    .with_color(Rgb::palette(i)),
            );
        }
    }
    p.legend = Some(true);
    Figure::new(id, title).with_panel(p)
}

/// A ratio with error bars and its mean as a black dashed line (thesis Fig.
/// 53: `tau_p / tau_c` against velocity). The mean is of the finite ratios.
pub fn ratio_with_mean(
    id: &str,
    title: &str,
    x_axis: Axis,
    y_axis: Axis,
    x: &[f64],
    ratio: &[f64],
    std: &[f64],
) -> Figure {
    let finite: Vec<f64> = ratio.iter().copied().filter(|v| v.is_finite()).collect();
    let mut p = Panel::new(x_axis, y_axis.clone()).with_series(Series::error_bars(
        y_axis.label.clone(),
        x.to_vec(),
        ratio.to_vec(),
        std.to_vec(),
    ));
    if !finite.is_empty() {
        let mean = finite.iter().sum::<f64>() / finite.len() as f64;
        p.hlines.push(Marker::black_dashed(
            mean,
            format!("mean {}", fmt_sig(mean, 3)),
        ));
    }
    p.legend = Some(false);
    Figure::new(id, title).with_panel(p)
}

/// A value and its uncertainty in the report's one notation, `m ± u`: the
/// uncertainty to two significant digits, the value rounded to the same
/// decimal place (`0.15463 ± 0.00284` → `0.1546 ± 0.0028`). A zero or
/// non-finite uncertainty leaves the value to `sig` significant digits
/// and writes the uncertainty as is.
pub fn fmt_pm(value: f64, uncertainty: f64, sig: usize) -> String {
    if !(uncertainty.is_finite() && uncertainty > 0.0 && value.is_finite()) {
        return format!("{} ± {}", fmt_sig(value, sig), fmt_sig(uncertainty, 2));
    }
    let mag_u = uncertainty.log10().floor() as i32;
    let mag_v = if value == 0.0 {
        mag_u
    } else {
        value.abs().log10().floor() as i32
    };
    if (-4..6).contains(&mag_v) {
        let decimals = 1 - mag_u;
        if decimals >= 0 {
            let d = decimals.min(15) as usize;
            return format!("{} ± {uncertainty:.d$}", minus(&format!("{value:.d$}")));
        }
        // an uncertainty of tens or more: round both to its second digit
        let q = 10f64.powi(-decimals);
        return format!(
            "{} ± {:.0}",
            minus(&format!("{:.0}", (value / q).round() * q)),
            (uncertainty / q).round() * q
        );
    }
    // very large or small values: the value's power of ten outside,
    // the uncertainty still to two significant digits
    let e = 10f64.powi(mag_v);
    let d = (mag_v - mag_u + 1).clamp(0, 15) as usize;
    format!(
        "({} ± {:.d$})e{}",
        minus(&format!("{:.d$}", value / e)),
        uncertainty / e,
        minus(&mag_v.to_string())
    )
}

/// Text with a typographic minus sign.
fn minus(s: &str) -> String {
    s.replacen('-', "−", 1)
}

/// `v` with `sig` significant digits (integer digits are never dropped:
/// `1234.4` → `1234`), in scientific notation below 1e-4 and from 1e6 on.
pub fn fmt_sig(v: f64, sig: usize) -> String {
    if v == 0.0 || !v.is_finite() {
        return format!("{v}");
    }
    let mag = v.abs().log10().floor() as i32;
    if !(-4..6).contains(&mag) {
        return format!("{:.*e}", sig.saturating_sub(1), v);
    }
    let decimals = (sig as i32 - 1 - mag).max(0) as usize;
    format!("{v:.decimals$}")
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn fmt_sig_rounds_to_significant_digits() {
        assert_eq!(fmt_sig(0.9010, 4), "0.9010");
        assert_eq!(fmt_sig(1.110, 3), "1.11");
        assert_eq!(fmt_sig(1234.4, 3), "1234");
        assert_eq!(fmt_sig(2.5e-7, 2), "2.5e-7");
    }

    #[test]
    fn plus_minus_rounds_the_value_to_the_uncertainty() {
        assert_eq!(fmt_pm(0.15463, 0.00284, 4), "0.1546 ± 0.0028");
        assert_eq!(fmt_pm(97.83, 4.12, 3), "97.8 ± 4.1");
        assert_eq!(fmt_pm(-154.2, 12.7, 3), "−154 ± 13");
        assert_eq!(fmt_pm(4.05598, 0.00071, 5), "4.05598 ± 0.00071");
        assert_eq!(fmt_pm(1234.0, 56.0, 3), "1234 ± 56");
        assert_eq!(fmt_pm(12345.0, 678.0, 3), "12350 ± 680");
        assert_eq!(fmt_pm(3.2e-7, 4.5e-8, 3), "(3.20 ± 0.45)e−7");
        // a tiny uncertainty on an ordinary value stays in plain decimals
        assert_eq!(fmt_pm(1.232887, 0.0000391, 5), "1.232887 ± 0.000039");
        assert_eq!(fmt_pm(0.9, 0.0, 3), "0.900 ± 0");
    }

    #[test]
    fn log_range_cuts_the_dc_bin_and_the_stop_band() {
        let f: Vec<f64> = (0..1000).map(f64::from).collect();
        // a peak of 1, a floor of 1e-3, a stop band falling to 1e-30
        let p: Vec<f64> = f
            .iter()
            .map(|&x| {
                if x == 0.0 {
                    1e-32
                } else if x == 10.0 {
                    1.0
                } else if x < 100.0 {
                    1e-3
                } else {
                    1e-3 * 10f64.powf(-(x - 100.0) / 30.0)
                }
            })
            .collect();
        let (lo, hi) = log_range(&f, &[&p], None, LOG_DECADES_FILTERED).unwrap();
        assert_eq!(hi, 2.0);
        // eight decades below the peak (powf rounding: a relative 1e-12)
        assert!((lo / 1e-8 - 1.0).abs() < 1e-12, "{lo}");
        // an unfiltered spectrum: the floor stays inside, with room
        let (lo, _) = log_range(&f[..100], &[&p[..100]], None, LOG_DECADES_FILTERED).unwrap();
        assert!((lo / 0.5e-3 - 1.0).abs() < 1e-12, "{lo}");
    }

    #[test]
    fn correlation_zoom_marks_multiples_only_in_the_zoom() {
        let lag: Vec<f64> = (-1000..=1000).map(|i| i as f64 * 0.01).collect();
        let r: Vec<f64> = lag.iter().map(|t| (t * 7.0).cos()).collect();
        let f = correlation(
            "c",
            "C",
            &lag,
            &r,
            Axis::linear("R", "N²"),
            Some(0.901),
            3.0,
        );
        assert_eq!(f.panels.len(), 2);
        assert!(f.panels[0].vlines.is_empty());
        // ±1, ±2, ±3 τc (3 τc = 2.703 s lies inside ±2.703 s)
        assert_eq!(f.panels[1].vlines.len(), 6);
        // 3 * 0.901 in floating point: compare to 1e-12 s, far below a pixel
        let (lo, hi) = f.panels[1].x.range.unwrap();
        assert!(
            (lo + 2.703).abs() < 1e-12 && (hi - 2.703).abs() < 1e-12,
            "{lo} {hi}"
        );
    }

    #[test]
    fn ratio_mean_line_is_the_mean_of_finite_ratios() {
        let f = ratio_with_mean(
            "r",
            "R",
            Axis::linear("v", "mm/s"),
            Axis::linear("τp/τc", ""),
            &[1.0, 2.0, 3.0],
            &[0.3, 0.5, f64::NAN],
            &[0.01, 0.01, 0.01],
        );
        // exact: (0.3 + 0.5) / 2 in binary is 0.4 to the last bit
        assert_eq!(f.panels[0].hlines[0].at, 0.4);
    }
}
