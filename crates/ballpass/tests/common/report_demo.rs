//! A synthetic 9 mm/s test (thesis chapter 7 shapes) and the dozen figures a
//! report of it would hold, shared by the report tests and benchmark.
//!
//! The data are closed-form stand-ins (no analysis runs here): a sinusoidal
//! friction disturbance at `f_c`, a Gaussian optical pulse train, a decaying
//! cosine correlation, Lorentzian spectral peaks at the harmonics.

#![allow(dead_code)]

use std::f64::consts::PI;

use ballpass::report::kinds::{self, Overlaid, PowerLaw, SpectrumView, Trace};
use ballpass::report::{Axis, Figure, Marker, Panel, Rgb};

/// Tracking velocity of the demo test, mm/s.
pub const V_MM_S: f64 = 9.0;
/// Ball-pass frequency, Hz: f_c = v / (2 d_avg), d_avg = 4.05556 mm.
pub const F_C_HZ: f64 = V_MM_S / (2.0 * 4.055_555_555_555_555);
/// Sampling rate, Hz.
pub const FS_HZ: f64 = 1000.0;

/// Deterministic noise in [-1, 1) (64-bit LCG, fixed seed).
pub struct Lcg(u64);
impl Lcg {
    pub fn new(seed: u64) -> Self {
        Lcg(seed)
    }
    pub fn next(&mut self) -> f64 {
        self.0 = self
            .0
            .wrapping_mul(6364136223846793005)
            .wrapping_add(1442695040888963407);
        ((self.0 >> 11) as f64 / (1u64 << 53) as f64) * 2.0 - 1.0
    }
}

fn gaussian_train(t: &[f64], period: f64, sigma: f64, amp: f64, offset: f64) -> Vec<f64> {
    t.iter()
        .map(|&ti| {
            let k = (ti / period).round();
            let d = ti - k * period;
            offset + amp * (-(d * d) / (2.0 * sigma * sigma)).exp()
        })
        .collect()
}

/// Spectrum stand-in: 1/f-ish floor plus Lorentzian peaks at k f_c; exactly
/// 0 at DC (a detrended signal), so log axes must drop one point.
fn spectrum(f: &[f64], peak: f64, floor: f64) -> Vec<f64> {
    f.iter()
        .map(|&fi| {
            if fi == 0.0 {
                return 0.0;
            }
            let mut p = floor * (1.0 + 1.0 / (1.0 + fi));
            for k in 1..=6 {
                let d = (fi - k as f64 * F_C_HZ) / 0.02;
                p += peak / (k * k) as f64 / (1.0 + d * d);
            }
            p
        })
        .collect()
}

/// Twelve figures of every kind the report layer offers.
pub fn figures() -> Vec<Figure> {
    let tau_c = 1.0 / F_C_HZ;
    let mut rng = Lcg::new(42);
    let n = 30_000;
    let t: Vec<f64> = (0..n).map(|i| i as f64 / FS_HZ).collect();
    let friction: Vec<f64> = t
        .iter()
        .map(|&ti| 2.0 + 0.05 * (2.0 * PI * F_C_HZ * ti).sin() + 0.02 * rng.next())
        .collect();
    let position: Vec<f64> = t
        .iter()
        .map(|&ti| V_MM_S * ti + 0.001 * rng.next())
        .collect();
    let optical = gaussian_train(&t, tau_c, 0.3 * tau_c / 2.3548, 0.8, 0.1);

    let lag: Vec<f64> = (-(n as i64 - 1)..n as i64)
        .map(|i| i as f64 / FS_HZ)
        .collect();
    let r: Vec<f64> = lag
        .iter()
        .map(|&l| (1.0 - l.abs() / 30.0) * (2.0 * PI * F_C_HZ * l).cos() * 1e-3 + 2e-5 * rng.next())
        .collect();

    let df = FS_HZ / 32_768.0;
    let f: Vec<f64> = (0..=16_384).map(|i| i as f64 * df).collect();
    let pff = spectrum(&f, 1e-2, 1e-7);
    let pee = spectrum(&f, 3e-4, 1e-8);
    let coh: Vec<f64> = f
        .iter()
        .map(|&fi| {
            let d = ((fi / F_C_HZ) - (fi / F_C_HZ).round()) / 0.05;
            (0.9 / (1.0 + d * d) + 0.05 * (rng.next() + 1.0)).min(1.0)
        })
        .collect();

    let tp: Vec<f64> = t[..4000].to_vec();
    let measured: Vec<f64> = optical[..4000]
        .iter()
        .map(|v| v + 0.01 * rng.next())
        .collect();
    let gauss = gaussian_train(&tp, tau_c, 0.3 * tau_c / 2.3548, 0.8, 0.1);
    let rect: Vec<f64> = tp
        .iter()
        .map(|&ti| {
            let duty = 0.3;
            let mut v = 0.1 + 0.8 * duty;
            for k in 1..=20 {
                let kf = k as f64;
                v += 0.8 * 2.0 / (kf * PI)
                    * (kf * PI * duty).sin()
                    * (2.0 * PI * kf * ti / tau_c).cos();
            }
            v
        })
        .collect();

    let fb: Vec<f64> = (0..400)
        .map(|i| 10f64.powf(-2.0 + 4.0 * i as f64 / 399.0))
        .collect();
    let (fnat, zeta) = (3.0, 0.3);
    let (mag, ph): (Vec<f64>, Vec<f64>) = fb
        .iter()
        .map(|&fi| {
            let u = fi / fnat;
            let re = 1.0 - u * u;
            let im = 2.0 * zeta * u;
            (
                -10.0 * (re * re + im * im).log10(),
                -im.atan2(re).to_degrees(),
            )
        })
        .unzip();

    let v: Vec<f64> = (1..=20).map(f64::from).collect();
    let std_ve: Vec<f64> = v
        .iter()
        .map(|&vi| 0.02 + 0.01 * (-(vi - 9.0).powi(2) / 8.0).exp())
        .collect();
    let sd: Vec<f64> = v.iter().map(|_| 0.002).collect();
    let tau_cs: Vec<f64> = v.iter().map(|&vi| 8.111 / vi).collect();
    let tau_ps: Vec<f64> = tau_cs.iter().map(|tc| 0.31 * tc).collect();
    let err_c: Vec<f64> = tau_cs.iter().map(|tc| 0.02 * tc).collect();
    let err_p: Vec<f64> = tau_ps.iter().map(|tp| 0.05 * tp).collect();
    let ratio: Vec<f64> = v
        .iter()
        .enumerate()
        .map(|(i, _)| 0.31 + 0.01 * ((i * 37 % 11) as f64 / 11.0 - 0.5))
        .collect();

    let fleet: Vec<Vec<f64>> = (0..5)
        .map(|b| {
            spectrum(
                &f,
                if b == 3 {
                    1e-1
                } else {
                    2e-3 * (1.0 + b as f64 * 0.2)
                },
                1e-7,
            )
        })
        .collect();
    let fleet_refs: Vec<(String, &[f64])> = fleet
        .iter()
        .enumerate()
        .map(|(i, s)| (format!("bearing {}", i + 1), s.as_slice()))
        .collect();
    let fleet_named: Vec<Overlaid<'_>> = fleet_refs
        .iter()
        .enumerate()
        .map(|(i, (n, s))| Overlaid {
            name: n.as_str(),
            values: s,
            color: if i == 3 { Rgb::RED } else { Rgb::calm(i) },
            highlight: i == 3,
        })
        .collect();

    let psd = || Axis::log("PSD", "N²/Hz");
    let full = SpectrumView {
        f_c_hz: Some(F_C_HZ),
        n_harmonics: 3,
        range_hz: None,
        unfiltered: false,
    };
    let zoom = SpectrumView {
        range_hz: Some((0.0, 10.0)),
        n_harmonics: 8,
        ..full
    };
    vec![
        kinds::time_series_stack(
            "signals",
            "Signals at 9 mm/s",
            &t,
            &[
                Trace {
                    label: "Friction force",
                    unit: "N",
                    values: &friction,
                },
                Trace {
                    label: "Position",
                    unit: "mm",
                    values: &position,
                },
                Trace {
                    label: "Optical sensor",
                    unit: "V",
                    values: &optical,
                },
            ],
        )
        .with_caption("Raw signals (thesis Fig. 54)."),
        kinds::correlation(
            "corr_ff",
            "Autocorrelation of friction force",
            &lag,
            &r,
            Axis::linear("R_FF", "N²"),
            Some(tau_c),
            3.0,
        ),
        Figure::new("spectrum_ff", "Auto-spectrum of friction force")
            .with_panel(
                kinds::spectrum_panel(&f, &pff, "P_FF", psd(), full).titled("(a) full range"),
            )
            .with_panel(kinds::spectrum_panel(&f, &pff, "P_FF", psd(), zoom).titled("(b) 0–10 Hz")),
        Figure::new("cross_fe", "Cross-spectrum friction / velocity error").with_panel(
            kinds::spectrum_panel(&f, &pee, "|P_Fe|", Axis::log("|CSD|", "N·mm/s/Hz"), zoom),
        ),
        Figure::new("coherence_fe", "Coherence friction / velocity error")
            .with_panel(kinds::coherence_panel(&f, &coh, "C_Fe", zoom)),
        kinds::pulses_with_models(
            "pulses",
            "Optical pulses and models",
            &tp,
            &measured,
            Axis::linear("Photodetector", "V"),
            &[("Gaussian train", &gauss), ("rectangular, 20 terms", &rect)],
        ),
        kinds::bode(
            "bode_xf",
            "Stage response G_xf",
            &fb,
            &[("G_xf", &mag, &ph)],
            &[(fnat, "f_n"), (F_C_HZ, "f_c")],
        ),
        kinds::error_bar_plot(
            "ve_std",
            "Velocity-error standard deviation",
            Axis::linear("Tracking velocity", "mm/s"),
            Axis::linear("std of velocity error", "mm/s"),
            &v,
            &std_ve,
            &sd,
        ),
        kinds::loglog_fit(
            "tau_vs_v",
            "τc and τp against velocity",
            Axis::linear("Tracking velocity", "mm/s"),
            Axis::linear("Time", "s"),
            &v,
            &[("τc", &tau_cs, &err_c), ("τp", &tau_ps, &err_p)],
            &[
                PowerLaw {
                    name: "fit τc = 8.11 / v",
                    coefficient: 8.111,
                    exponent: -1.0,
                },
                PowerLaw {
                    name: "fit τp = 2.51 / v",
                    coefficient: 2.514,
                    exponent: -1.0,
                },
            ],
        ),
        kinds::ratio_with_mean(
            "tau_ratio",
            "Ratio τp / τc",
            Axis::linear("Tracking velocity", "mm/s"),
            Axis::linear("τp / τc", ""),
            &v,
            &ratio,
            &sd,
        ),
        kinds::overlay_spectra(
            "fleet",
            "Friction spectra of five bearings at 20 mm/s",
            &f,
            &fleet_named,
            Axis::linear("Frequency", "Hz"),
            psd(),
            zoom,
        ),
        Figure::new("markers", "Marker styles").with_panel(
            Panel::new(Axis::linear("x", "m"), Axis::linear("y", "N"))
                .with_series(ballpass::report::Series::points(
                    "pts",
                    vec![0.0, 1.0, 2.0],
                    vec![1.0, 3.0, 2.0],
                ))
                .with_hlines([Marker::black_dashed(2.0, "mean 2")])
                .with_vlines([Marker::red_dashed(1.0, "f_c")]),
        ),
    ]
}
