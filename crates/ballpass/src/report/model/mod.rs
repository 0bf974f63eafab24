//! Figures of `ballpass model`: Bode plots of the PD stage (thesis Figs.
//! 41–42), centred vs forward differences (Fig. 28), the Gaussian train's
//! Fourier coefficients (Fig. 49), the one-period velocity response (Fig. 51),
//! the synthesised pulse trains and the model correlations.

use super::kinds::{bode, fmt_sig};
use super::spec::{Axis, Figure, Marker, MarkerStyle, Panel, Rgb, Series, SeriesStyle};
use crate::model::stage::{BodeRow, DifferenceRow, VelocityResponse};

mod reports;

pub use reports::{pulses_report, signals_report, stage_report};

/// Bode plots of `G_xr`, `G_xf` and `G_vf` (ids `bode_g_xr`, `bode_g_xf`,
/// `bode_g_vf`), each with the natural frequency `f_n_hz` marked, and the
/// ball-pass frequency when given.
pub fn stage_bode_figures(rows: &[BodeRow], f_n_hz: f64, f_c_hz: Option<f64>) -> Vec<Figure> {
    let f: Vec<f64> = rows.iter().map(|r| r.f_hz).collect();
    let mut marks = vec![(f_n_hz, "f_n")];
    if let Some(fc) = f_c_hz {
        marks.push((fc, "f_c"));
    }
    let col = |g: fn(&BodeRow) -> f64| rows.iter().map(g).collect::<Vec<f64>>();
    let specs = [
        (
            "bode_g_xr",
            "G_xr = x/r: position response to the reference (thesis Fig. 41)",
            "G_xr",
            col(|r| r.g_xr_db),
            col(|r| r.g_xr_phase_deg),
        ),
        (
            "bode_g_xf",
            "G_xf = x/f: position response to friction, dB re 1 m/N (thesis Fig. 42)",
            "G_xf",
            col(|r| r.g_xf_db),
            col(|r| r.g_xf_phase_deg),
        ),
        (
            "bode_g_vf",
            "G_vf = v/f: velocity response to friction, dB re 1 (m/s)/N (thesis Fig. 42)",
            "G_vf",
            col(|r| r.g_vf_db),
            col(|r| r.g_vf_phase_deg),
        ),
    ];
    specs
        .iter()
        .map(|(id, title, name, m, p)| {
            bode(id, title, &f, &[(name, m, p)], &marks).with_caption(format!(
                "Natural frequency f_n = {} Hz marked{}.",
                fmt_sig(f_n_hz, 4),
                f_c_hz.map_or(String::new(), |f| format!(
                    "; ball-pass frequency f_c = {} Hz",
                    fmt_sig(f, 4)
                ))
            ))
        })
        .collect()
}

/// Gain and phase of the centred and forward differences against the ideal
/// differentiator `jω` (thesis Fig. 28), id `difference`: the gain as a
/// ratio to `ω`, the phase as the error against the ideal +90°.
pub fn difference_figure(rows: &[DifferenceRow], fs_hz: f64) -> Figure {
    let f: Vec<f64> = rows.iter().map(|r| r.f_hz).collect();
    let col = |g: fn(&DifferenceRow) -> f64| rows.iter().map(g).collect::<Vec<f64>>();
    let x = Axis::linear("Frequency", "Hz");
    let gain = Panel::new(x.clone(), Axis::linear("Gain / ω", ""))
        .titled("gain relative to jω")
        .with_series(
            Series::line(
                "centred (numpy.gradient)",
                f.clone(),
                col(|r| r.centred_gain_ratio),
            )
            .with_color(Rgb::palette(0)),
        )
        .with_series(
            Series::line("forward", f.clone(), col(|r| r.forward_gain_ratio))
                .with_color(Rgb::palette(1)),
        );
    let mut phase = Panel::new(x, Axis::linear("Phase − 90°", "deg"))
        .titled("phase error relative to jω (ideal +90°)")
        .with_series(
            Series::line(
                "centred (numpy.gradient)",
                f.clone(),
                col(|r| r.centred_phase_deg - 90.0),
            )
            .with_color(Rgb::palette(0)),
        )
        .with_series(
            Series::line("forward", f, col(|r| r.forward_phase_deg - 90.0))
                .with_color(Rgb::palette(1)),
        )
        .with_hlines([Marker {
            at: 0.0,
            label: String::new(),
            style: MarkerStyle::GreySolid,
        }]);
    phase.legend = Some(false);
    Figure::new(
        "difference",
        "Centred vs forward difference as differentiators (thesis Fig. 28)",
    )
    .with_caption(format!(
        "F_s = {} Hz, up to the Nyquist frequency. The centred difference has no phase error \
         (its phase is +90° exactly) and loses gain as sin(ωT)/(ωT); the forward difference \
         leads by 180°·f/F_s and loses gain as sinc(ωT/2).",
        fmt_sig(fs_hz, 4)
    ))
    .with_panel(gain)
    .with_panel(phase)
}

/// `|C_n| / P` of the Gaussian train on a log axis (thesis Fig. 49), with
/// the thesis' printed values when given, id `gaussian_coefficients`.
pub fn gaussian_coefficients_figure(
    n: &[f64],
    c_over_p: &[f64],
    thesis_printed: Option<&[f64]>,
    sigma_ratio: f64,
) -> Figure {
    let mut p = Panel::new(Axis::linear("Harmonic n", ""), Axis::log("|C_n| / P", "")).with_series(
        Series::line("|C_n|/P, corrected", n.to_vec(), c_over_p.to_vec())
            .with_style(SeriesStyle::Stem)
            .with_color(Rgb::palette(0)),
    );
    if let Some(t) = thesis_printed {
        p.series.push(
            Series::line("as printed in the thesis", n.to_vec(), t.to_vec())
                .with_style(SeriesStyle::Points)
                .with_color(Rgb::palette(1)),
        );
    }
    p.legend = Some(true);
    Figure::new(
        "gaussian_coefficients",
        "Fourier coefficients of the Gaussian pulse train (thesis Fig. 49)",
    )
    .with_caption(format!(
        "C_n = √(2π) P r exp(−2π² n² r²), r = σ/τc = {} (the thesis' Eq. 6.28 corrected, see the method notes); they fall by orders of magnitude within a few harmonics.",
        fmt_sig(sigma_ratio, 4)
    ))
    .with_panel(p)
}

/// Friction pulses and the stage's velocity response over one period
/// (thesis Fig. 51), id `velocity_response`.
pub fn velocity_response_figure(r: &VelocityResponse) -> Figure {
    let t = &r.time_s;
    let x = Axis::linear("Time", "s");
    let mut f = Panel::new(x.clone(), Axis::linear("Friction", "N")).with_series(
        Series::line("friction pulse", t.clone(), r.friction_n.clone()).with_color(Rgb::BLACK),
    );
    f.legend = Some(false);
    let v = Panel::new(x, Axis::linear("Velocity error", "mm/s"))
        .with_series(
            Series::line(
                "D_n = C_n G_vf (complex)",
                t.clone(),
                r.velocity_mm_s.clone(),
            )
            .with_color(Rgb::palette(0)),
        )
        .with_series(
            Series::line(
                "thesis' magnitude-only D_n",
                t.clone(),
                r.velocity_magnitude_only_mm_s.clone(),
            )
            .with_style(SeriesStyle::DashedLine)
            .with_color(Rgb::palette(1)),
        )
        .with_hlines([Marker::red_dashed(0.0, "")]);
    let mut fig = Figure::new(
        "velocity_response",
        "Velocity response to one period of friction pulses (thesis Fig. 51)",
    )
    .with_caption(format!(
        "f_c = {} Hz; velocity {} mm/s peak to peak. The magnitude-only sum (thesis) is off by {}% of the peak.",
        fmt_sig(r.f_c_hz, 4),
        fmt_sig(r.velocity_peak_to_peak_mm_s, 3),
        fmt_sig(100.0 * r.magnitude_only_error_of_peak, 2)
    ))
    .with_panel(f)
    .with_panel(v);
    fig.panel_height_px = 220;
    fig
}

/// Exact and truncated-series pulse trains over time, id `trains`.
pub fn trains_figure(t_s: &[f64], series: &[(&str, &[f64], bool)]) -> Figure {
    let mut p = Panel::new(Axis::linear("Time", "s"), Axis::linear("Signal", ""));
    for (i, (name, y, dashed)) in series.iter().enumerate() {
        let mut s = Series::line(*name, t_s.to_vec(), y.to_vec()).with_color(Rgb::palette(i));
        if *dashed {
            s = s.with_style(SeriesStyle::DashedLine);
        }
        p.series.push(s);
    }
    p.legend = Some(true);
    Figure::new(
        "trains",
        "Gaussian and rectangular pulse trains and their Fourier series (thesis Figs. 47–48)",
    )
    .with_panel(p)
}

/// Correlations of the sinusoid model signals over lag, one panel per
/// pair, with the multiples of `tau_c_s` marked; id `correlations`.
pub fn correlations_figure(tau_s: &[f64], pairs: &[(&str, &[f64])], tau_c_s: f64) -> Figure {
    let lo = tau_s.first().copied().unwrap_or(0.0);
    let hi = tau_s.last().copied().unwrap_or(0.0);
    let mut fig = Figure::new(
        "correlations",
        "Correlations of the sinusoid model signals (thesis Eqs. 6.10–6.17)",
    );
    for (i, (name, r)) in pairs.iter().enumerate() {
        let mut p = Panel::new(Axis::linear("Lag τ", "s"), Axis::linear(*name, ""))
            .with_series(
                Series::line(*name, tau_s.to_vec(), r.to_vec()).with_color(Rgb::palette(i)),
            )
            .with_vlines(Marker::multiples(tau_c_s, lo, hi, "τc", false));
        p.legend = Some(false);
        fig.panels.push(p);
    }
    fig.panel_height_px = 160;
    fig
}
