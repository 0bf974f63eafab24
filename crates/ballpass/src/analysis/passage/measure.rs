//! The measurement loop: template and baseline by least squares, each
//! pulse fitted against the template, a matched-filter search for the
//! pulses the seeds missed (and of either polarity), until the set of
//! pulses stops changing (module docs of [`super`], "Method").

use super::gaps::gap_lines;
use super::lsq::{Problem, Solution, Splines};
use super::pulse_fit::{fit_pulse, PulseFit};
use super::scan::{scan, Seeds};
use super::signal::{box_decimate, running_integral};
use super::template::{pulse_model, Pulse, Shape, Template};
use super::PassageSettings;

/// Most rounds of the loop.
const MAX_ROUNDS: usize = 5;

/// Blocks per pulse FWHM the signal is averaged down to (at least).
pub(super) const BLOCKS_PER_FWHM: f64 = 24.0;

/// Grid points of the template per FWHM.
const GRID_PER_FWHM: f64 = 16.0;

/// Support of the template either side of its peak, in half widths at
/// half maximum (a Gaussian is at 0.2 % of its peak at 3 half widths; the
/// skewed shape's long side at 0.2 % too).
const SUPPORT_HALF_WIDTHS: f64 = 3.0;

/// Longest core support of the template, both sides together, in
/// ball-pass periods (less than one: see `Template::with_tails`).
const SUPPORT_MAX_PERIODS: f64 = 0.9;

/// Penalty on the template's second differences (relative, see
/// [`Problem::smoothness`]).
const SMOOTHNESS: f64 = 1e-2;

/// Least-squares passes per round, each with the tails of the last.
const TAIL_PASSES: usize = 3;

/// Longest tail continued past the core support, in periods from the peak.
const TAIL_REACH_PERIODS: f64 = 1.5;

/// Fastest AC coupling looked for: `T = τ_c / 50`.
const AC_MAX_RATE_PER_PERIOD: f64 = 50.0;

/// What the loop measured, in blocks of `q` samples.
pub(super) struct Measurement {
    /// Block length, samples.
    pub q: usize,
    /// The pulses, in time order, and their fits.
    pub fits: Vec<PulseFit>,
    /// The template, peak 1.
    pub template: Template,
    /// Its peak and half-maximum crossings.
    pub shape: Shape,
    /// Baseline per block of the restored signal `z + κ ∫z dt`, the
    /// integral from the record's start (not of `z − mean`: see
    /// `mean_ramp`), so that it wanders only where the light did.
    pub baseline: Vec<f64>,
    /// Baseline splines and their coefficients.
    pub splines: Splines,
    pub beta: Vec<f64>,
    /// AC-coupling rate `1/T` undone, 1/s (0: none).
    pub kappa: f64,
    /// Detection threshold, in noise std of the statistic.
    pub z: f64,
    /// Noise std of a whole pulse's amplitude from the matched filter, V.
    pub amplitude_noise: f64,
}

/// Runs the loop on `x` from the seeds. `hl`, `hr`: half widths left and
/// right of the seeds' peaks, samples; `tau_samples`: the period guide.
pub(super) fn measure(
    x: &[f64],
    fs: f64,
    tau_samples: f64,
    seeds: &Seeds,
    (hl, hr): (f64, f64),
    noise: f64,
    settings: &PassageSettings,
) -> Result<Measurement, String> {
    let q = (((hl + hr) / BLOCKS_PER_FWHM).floor() as usize).max(1);
    let qf = q as f64;
    let z = box_decimate(x, q);
    let nd = z.len();
    let integral = running_integral(&z, qf / fs);
    // The record's mean times its duration, V s (`ac_plausible`).
    let mean_ramp = z.iter().sum::<f64>() * qf / fs;
    let pd = tau_samples / qf;
    let splines = Splines::new(nd, pd);
    let distance = (settings.min_distance_periods * pd).max(1.0);
    // The template's core support: three half widths either side of the
    // peak, shortened (in proportion) to less than a period in all, so that
    // the least squares cannot trade a pedestal under the pulses for the
    // baseline (see `Template::with_tails`).
    let grid_for = |l: f64, r: f64| {
        let (mut l, mut r) = (l.max(2.0), r.max(2.0));
        let cap = SUPPORT_MAX_PERIODS * pd;
        if l + r > cap {
            let k = cap / (l + r);
            l *= k;
            r *= k;
        }
        let fwhm = (l + r) / SUPPORT_HALF_WIDTHS;
        let dx = (fwhm / GRID_PER_FWHM).max(0.25);
        Template::from_fn(l, r, dx, |_| 0.0)
    };
    let seed_grid = grid_for(SUPPORT_HALF_WIDTHS * hl / qf, SUPPORT_HALF_WIDTHS * hr / qf);
    let mut grid = seed_grid.clone();
    // Whether `grid` is the seeds' support (see `no_shape` below).
    let mut on_seed_grid = true;
    // Rounds allowed; one more once, for a round re-solved on the seeds'
    // support.
    let mut rounds = MAX_ROUNDS;
    let mut pulses: Vec<Pulse> = seeds
        .idx
        .iter()
        .zip(&seeds.prominence)
        .map(|(&i, &a)| Pulse {
            c: (i as f64 - 0.5 * (qf - 1.0)) / qf,
            a,
            s: 1.0,
        })
        .collect();
    let mut found_z = f64::INFINITY;
    let mut amplitude_noise = f64::NAN;
    // AC-coupling rate undone, 1/s.
    let mut kappa = 0.0;
    // Amplitudes of the pulses just outside the record (see `ghosts`).
    let mut ghost_a = [f64::NAN; 2];
    // A template with no half-maximum crossing on its support: the support
    // came from the last round's template, and that template from pulses
    // the search has since replaced (seeds on an interference fringe's
    // crests, say, with the pulses inverted beside them): the round is
    // solved again on the seeds' support, which the seeds' own widths set.
    // On the seeds' support already, the pulses have no common shape.
    macro_rules! no_shape {
        () => {{
            if !on_seed_grid {
                grid = seed_grid.clone();
                on_seed_grid = true;
                rounds = rounds.max(MAX_ROUNDS + 1);
                continue;
            }
            return Err("the pulses found have no common shape".into());
        }};
    }
    let mut round = 0;
    while round < rounds {
        round += 1;
        let ghosts = ghosts(&pulses, nd, &grid, ghost_a);
        let with_ghosts = |pulses: &[Pulse]| -> Vec<Pulse> {
            let mut all: Vec<Pulse> = pulses.to_vec();
            all.extend(ghosts.iter().flatten());
            all.sort_by(|a, b| a.c.total_cmp(&b.c));
            all
        };
        let all = with_ghosts(&pulses);
        // Template, baseline and (maybe) the AC coupling's rate; the tails
        // past the core support continued and taken out of the data.
        let solve = |rhs: &[f64]| {
            Problem {
                n: nd,
                splines,
                pulses: &all,
                grid: &grid,
                smoothness: SMOOTHNESS,
                pin_ends: false,
            }
            .solve(&[rhs])
            .map(|mut s| s.remove(0))
            .ok_or("the pulses found leave the pulse shape undetermined")
        };
        let restore = |kappa: f64| -> Vec<f64> {
            z.iter()
                .zip(&integral)
                .map(|(a, b)| a + kappa * b)
                .collect()
        };
        let mut zr = restore(kappa);
        let mut tails: Option<Template> = None;
        let mut sol = None;
        let mut full = None;
        // The part of the baseline too fast for the splines (module docs).
        let mut fast = vec![0.0; nd];
        // Inverted pulses (interference) dip below the baseline by
        // themselves: no AC coupling is looked for then.
        let inverted = pulses.iter().any(|p| p.a < 0.0);
        if inverted {
            kappa = 0.0;
            zr = restore(kappa);
        }
        // Nor unless the pulses recur at the ball-pass period (within
        // 25 %): pulses that do not (crests of an interference fringe
        // taken for pulses, say) are not the balls', and a rate read off
        // them means nothing.
        let gaps: Vec<f64> = pulses.windows(2).map(|w| w[1].c - w[0].c).collect();
        let periodic = !gaps.is_empty() && {
            let r = super::signal::median(&gaps) / pd;
            (0.8..=1.25).contains(&r)
        };
        let look_for_ac = settings.restore_ac_coupling && !inverted && periodic;
        for _pass in 0..TAIL_PASSES {
            // The recorded blocks less the tails and the fast baseline of
            // the last pass (both of the restored signal).
            let raw: Vec<f64> = match &tails {
                Some(t) => {
                    let m = pulse_model(nd, &all, t);
                    (0..nd).map(|i| z[i] - m[i] - fast[i]).collect()
                }
                None => (0..nd).map(|i| z[i] - fast[i]).collect(),
            };
            // The AC coupling's rate (`ac_rate`), every pass: the tails
            // of the neighbouring pulses, taken out, no longer lift one
            // end of the support. The template of `raw + κ I` is that of
            // `raw` plus κ times that of `I`.
            let s1 = if look_for_ac {
                let mut both = Problem {
                    n: nd,
                    splines,
                    pulses: &all,
                    grid: &grid,
                    smoothness: SMOOTHNESS,
                    pin_ends: false,
                }
                .solve(&[&raw, &integral])
                .ok_or("the pulses found leave the pulse shape undetermined")?;
                let si = both.pop().ok_or("no least-squares solution")?;
                let mut sz = both.pop().ok_or("no least-squares solution")?;
                let k = ac_rate(&sz, &si, &all, noise / qf.sqrt(), tau_samples / fs)
                    .filter(|&r| ac_plausible(r, &sz, &si, &pulses, &fast, &splines, mean_ramp))
                    .map_or(0.0, |(k, _)| k);
                if k != kappa {
                    kappa = k;
                    zr = restore(kappa);
                }
                for (v, w) in sz.template.h.iter_mut().zip(&si.template.h) {
                    *v += kappa * w;
                }
                for (v, w) in sz.beta.iter_mut().zip(&si.beta) {
                    *v += kappa * w;
                }
                sz
            } else {
                let rhs: Vec<f64> = raw
                    .iter()
                    .zip(&integral)
                    .map(|(r, i)| r + kappa * i)
                    .collect();
                solve(&rhs)?
            };
            match s1.template.with_tails(TAIL_REACH_PERIODS * pd) {
                Some((f, t)) => {
                    full = Some(f);
                    tails = Some(t);
                }
                None => {
                    full = Some(s1.template.clone());
                    tails = None;
                }
            }
            // What the splines and pulses leave, followed where the light
            // is dark (`gap_lines`), else averaged over a period (twice):
            // zero for anything that repeats every period, so it follows a
            // drift too fast for the splines but not the pulses.
            if let Some(f) = &full {
                let b = splines.eval(&s1.beta, nd);
                let m = pulse_model(nd, &all, f);
                let r: Vec<f64> = (0..nd).map(|i| zr[i] - b[i] - m[i] - fast[i]).collect();
                let gaps = if inverted {
                    None
                } else {
                    f.shape()
                        .and_then(|sh| gap_lines(&r, &all, &sh, noise / qf.sqrt(), pd))
                };
                let r = gaps.unwrap_or_else(|| period_mean(&period_mean(&r, pd), pd));
                for (f, v) in fast.iter_mut().zip(&r) {
                    *f += v;
                }
            }
            sol = Some(s1);
        }
        let sol = sol.ok_or("no least-squares pass")?;
        let mut template = full.ok_or("no least-squares pass")?;
        let Some(shape) = template.shape() else {
            no_shape!();
        };
        template.scale(1.0 / shape.peak);
        for p in pulses.iter_mut() {
            p.a *= shape.peak;
        }
        let ghosts: Vec<Option<Pulse>> = ghosts
            .iter()
            .map(|g| {
                g.map(|g| Pulse {
                    a: g.a * shape.peak,
                    ..g
                })
            })
            .collect();
        let all = {
            let mut all: Vec<Pulse> = pulses.clone();
            all.extend(ghosts.iter().flatten());
            all.sort_by(|a, b| a.c.total_cmp(&b.c));
            all
        };
        // The core support, where each pulse is fitted.
        let core = (grid.left(), grid.right());
        let baseline: Vec<f64> = splines
            .eval(&sol.beta, nd)
            .iter()
            .zip(&fast)
            .map(|(a, b)| a + b)
            .collect();
        // The restored signal without its baseline, and each pulse fitted
        // with its neighbours' modelled pulses removed.
        let d: Vec<f64> = (0..nd)
            .map(|i| z[i] + kappa * integral[i] - baseline[i])
            .collect();
        let model = pulse_model(nd, &all, &template);
        let fits: Vec<PulseFit> = pulses
            .iter()
            .map(|&p| {
                let own = |i: usize| p.a * template.value((i as f64 - p.c) / p.s);
                let f = fit_pulse(&|i| d[i] - model[i] + own(i), nd, p, &template, core);
                if f.ok {
                    f
                } else {
                    PulseFit { pulse: p, ..f }
                }
            })
            .collect();
        // The pulses just outside the record: their amplitudes only (their
        // centres are not seen), by least squares over what the record holds.
        for (side, g) in ghosts.iter().enumerate() {
            if let Some(g) = g {
                let (mut num, mut den) = (0.0, 0.0);
                let lo = (g.c + core.0).ceil().max(0.0) as usize;
                let hi = ((g.c + core.1).floor().max(0.0) as usize).min(nd - 1);
                for i in lo..=hi {
                    let h = template.value((i as f64 - g.c) / g.s);
                    num += h * (d[i] - model[i] + g.a * h);
                    den += h * h;
                }
                // A tail barely in the record says little of its pulse's
                // height: held within that of the largest pulse found.
                let cap = pulses.iter().map(|p| p.a.abs()).fold(0.0, f64::max);
                ghost_a[side] = if den > 0.0 {
                    (num / den).clamp(-cap, cap)
                } else {
                    g.a
                };
            }
        }
        pulses = fits.iter().map(|f| f.pulse).collect();
        // Keep the template's scale: mean stretch 1.
        let ok: Vec<f64> = fits.iter().filter(|f| f.ok).map(|f| f.pulse.s).collect();
        if !ok.is_empty() {
            let mean_s = ok.iter().sum::<f64>() / ok.len() as f64;
            template.stretch(mean_s);
            for p in pulses.iter_mut() {
                p.s /= mean_s;
            }
        }
        let Some(shape) = template.shape() else {
            no_shape!();
        };
        let last = round == rounds;
        if !last {
            let ghosts_now: Vec<Pulse> = ghosts
                .iter()
                .enumerate()
                .filter_map(|(side, g)| {
                    g.map(|g| Pulse {
                        a: ghost_a[side],
                        ..g
                    })
                })
                .collect();
            let mut all = pulses.clone();
            all.extend(ghosts_now);
            let model = pulse_model(nd, &all, &template);
            let resid: Vec<f64> = d.iter().zip(&model).map(|(a, b)| a - b).collect();
            let hw_l = shape.peak_u - shape.left_u;
            let hw_r = shape.right_u - shape.peak_u;
            let core_left = SUPPORT_HALF_WIDTHS * hw_l - shape.peak_u;
            let core_right = SUPPORT_HALF_WIDTHS * hw_r + shape.peak_u;
            let edges = EdgeSearch::new(&d, &baseline, &pulses, &ghosts, core, pd);
            let mut s = scan(
                &edges.signal,
                &resid,
                &template.restricted(-core_left, core_right),
                distance,
                settings.false_detections_per_record,
                settings.min_snr,
                settings.min_relative_prominence,
            );
            s.found.retain(|f| edges.keeps(f.c));
            found_z = s.z;
            amplitude_noise = s.amplitude_noise;
            // A search that finds nothing keeps what the seeds found (its
            // noise is measured on what the model leaves, which a signal
            // the model does not fit, such as an interference fringe, can
            // swamp).
            let (merged, changed) = if s.found.is_empty() {
                (pulses.clone(), false)
            } else {
                merge(&pulses, &s.found, 0.35 * pd)
            };
            // A round on the seeds' support is followed by one on the
            // template's.
            if changed || on_seed_grid {
                pulses = merged;
                grid = grid_for(core_left, core_right);
                on_seed_grid = false;
                continue;
            }
        }
        let fits = fits
            .into_iter()
            .zip(&pulses)
            .map(|(f, p)| PulseFit { pulse: *p, ..f })
            .collect();
        return Ok(Measurement {
            q,
            fits,
            template,
            shape,
            baseline: with_mean_ramp(&baseline, &z, kappa, qf / fs),
            splines,
            beta: sol.beta,
            kappa,
            z: found_z,
            amplitude_noise,
        });
    }
    Err("the pulse search did not settle".into())
}

/// `baseline` plus `κ (∫z dt − ∫(z − mean z) dt)`, the integrals from
/// block 0 to block `i`: `κ × mean × i dt`.
///
/// The least squares restore `z + κ ∫(z − mean) dt`
/// ([`running_integral`]), whose baseline is the restored signal's less
/// `κ mean t`: a ramp that holds nothing of the light (an AC-coupled
/// record's mean is what its ends happen to leave, `T Δ(x − y) /
/// duration`; 0.008 V over 30 s at 1 mm/s, `T` = 1 s: a 0.23 V ramp,
/// a third of the pulse). The splines take it, so the pulses are the same
/// either way; the baseline reported gets it back.
fn with_mean_ramp(baseline: &[f64], z: &[f64], kappa: f64, dt: f64) -> Vec<f64> {
    let rate = kappa * z.iter().sum::<f64>() / z.len().max(1) as f64;
    baseline
        .iter()
        .enumerate()
        .map(|(i, b)| b + rate * i as f64 * dt)
        .collect()
}

/// Centred running mean over `period` blocks (rounded; shorter at the
/// ends): zero at the frequency `1/period` and its harmonics.
fn period_mean(x: &[f64], period: f64) -> Vec<f64> {
    let n = x.len();
    let w = (period.round() as usize).max(1);
    let half_lo = w / 2;
    let half_hi = w - half_lo;
    let mut cum = vec![0.0; n + 1];
    for (i, v) in x.iter().enumerate() {
        cum[i + 1] = cum[i] + v;
    }
    (0..n)
        .map(|i| {
            let a = i.saturating_sub(half_lo);
            let b = (i + half_hi).min(n);
            (cum[b] - cum[a]) / (b - a) as f64
        })
        .collect()
}

/// The pulses one period (the median spacing of the pulses found) before
/// the first and after the last, when their core support reaches into the
/// record. Outside the record, their tails are in it; left out, the
/// baseline and the template would take them. Inside (close to the start
/// or end), they hold the baseline's free end off a pulse not yet found,
/// which the search then finds. Amplitudes: `amps` (the last fit), or 0
/// before the first fit (a pulse assumed where the record holds none
/// would bend the baseline at the record's end).
fn ghosts(pulses: &[Pulse], nd: usize, grid: &Template, amps: [f64; 2]) -> [Option<Pulse>; 2] {
    if pulses.is_empty() {
        return [None, None];
    }
    let gaps: Vec<f64> = pulses.windows(2).map(|w| w[1].c - w[0].c).collect();
    if gaps.is_empty() {
        return [None, None];
    }
    let spacing = super::signal::median(&gaps);
    let amp = |k: usize| if amps[k].is_finite() { amps[k] } else { 0.0 };
    let first = pulses[0].c - spacing;
    let last = pulses[pulses.len() - 1].c + spacing;
    let end = (nd - 1) as f64;
    [
        (first + grid.right() > 0.0).then(|| Pulse {
            c: first,
            a: amp(0),
            s: 1.0,
        }),
        (last + grid.left() < end).then(|| Pulse {
            c: last,
            a: amp(1),
            s: 1.0,
        }),
    ]
}

/// The rate `κ = 1/T` of a first-order AC coupling: the `κ` whose
/// restored template `h_z + κ h_I` (`h_z`, `h_I`: the templates of the
/// blocks and of their running integral, same pulses) ends where it
/// starts, `κ = −Δh_z / Δh_I` with `Δ` the mean of the last
/// [`END_POINTS`] grid points less that of the first. A pulse of light
/// starts and ends at the level around it; an AC coupling pulls the level
/// after each pulse down by `κ_true` × its area, which `h_I` (a step of
/// the pulse's area) measures. 0 unless the step of `h_z` is down by more
/// than `max(0.5 %, 3 standard errors)` of the peak (standard error of an
/// end's mean: `block_noise / √(3 Σ a_k² dx)`, the step's `√2` that), or
/// when `κ` exceeds `50 / τ_c`, or leaves no pulse shape. (A dip after the
/// pulse is no measure: a skewed pulse's long tail fills it, and a rate
/// that merely removes it is short of the true one.) With `κ`, the restored
/// template's peak.
fn ac_rate(
    hz: &Solution,
    hi: &Solution,
    pulses: &[Pulse],
    block_noise: f64,
    tau_c_s: f64,
) -> Option<(f64, f64)> {
    let (tz, ti) = (&hz.template, &hi.template);
    let g = tz.h.len();
    if g < 2 * END_POINTS + 1 || ti.h.len() != g {
        return None;
    }
    let sh = tz.shape()?;
    let step = |h: &[f64]| -> f64 {
        let k = END_POINTS as f64;
        h[g - END_POINTS..].iter().sum::<f64>() / k - h[..END_POINTS].iter().sum::<f64>() / k
    };
    let (dz, di) = (step(&tz.h), step(&ti.h));
    if di.is_nan() || di <= 0.0 {
        return None;
    }
    // Standard error of an end's mean over `END_POINTS` grid points
    // (each point the least-squares estimate from every pulse), and of the
    // step, their difference.
    let a2: f64 = pulses.iter().map(|p| p.a * p.a).sum();
    let se_end = block_noise
        / (END_POINTS as f64 * a2 * tz.dx)
            .max(f64::MIN_POSITIVE)
            .sqrt();
    let se_step = std::f64::consts::SQRT_2 * se_end;
    if dz >= -(AC_LOBE * sh.peak).max(3.0 * se_step) {
        return None;
    }
    let kappa = -dz / di;
    if kappa > AC_MAX_RATE_PER_PERIOD / tau_c_s {
        return None;
    }
    let mut t = tz.clone();
    for (v, w) in t.h.iter_mut().zip(&ti.h) {
        *v += kappa * w;
    }
    Some((kappa, t.shape()?.peak))
}

/// Whether undoing an AC coupling of rate `kappa` leaves a light level a
/// photodetector could have seen.
///
/// A first-order coupling removes the light's running mean over `T`, so the
/// recorded signal's mean over the record is the change of that running
/// mean between its ends: the light's drift between them, and at most the
/// pulses' own mean (under half a pulse) while the coupling settles. The
/// level restored is the least squares' baseline `b` (of `z + κ ∫(z − mean)
/// dt`) plus the ramp `κ × mean(z) × t` ([`with_mean_ramp`]). A coupling
/// read off a DC-coupled record (the step of wide pulses' tails, say)
/// turns the record's DC level into a ramp of `duration / T` times that
/// level, which no drift seen in `b` explains. The coupling is plausible
/// when the ramp exceeds the range of `b` by less than
/// [`AC_RAMP_EXCESS`] pulse heights.
///
/// `peak`: the restored template's peak (pulse amplitudes are in its
/// units); `mean_ramp`: the record's mean of `z` times its duration, V s.
fn ac_plausible(
    (kappa, peak): (f64, f64),
    hz: &Solution,
    hi: &Solution,
    pulses: &[Pulse],
    fast: &[f64],
    splines: &Splines,
    mean_ramp: f64,
) -> bool {
    let nd = fast.len();
    let amps: Vec<f64> = pulses.iter().map(|p| p.a.abs()).collect();
    let height = super::signal::median(&amps) * peak;
    if height.is_nan() || height <= 0.0 || nd == 0 {
        return true;
    }
    let beta: Vec<f64> = hz
        .beta
        .iter()
        .zip(&hi.beta)
        .map(|(a, b)| a + kappa * b)
        .collect();
    let b = splines.eval(&beta, nd);
    let (lo, hi_b) = b
        .iter()
        .zip(fast)
        .map(|(a, f)| a + f)
        .fold((f64::INFINITY, f64::NEG_INFINITY), |(lo, hi), v| {
            (lo.min(v), hi.max(v))
        });
    let ramp = (kappa * mean_ramp).abs();
    ramp - (hi_b - lo) < AC_RAMP_EXCESS * height
}

/// Largest excess, in pulse heights, of the restored level's mean ramp over
/// the baseline's own range for an AC coupling to be kept
/// ([`ac_plausible`]): twice the most the pulses' mean can explain.
const AC_RAMP_EXCESS: f64 = 1.0;

/// Grid points averaged at each end of the template for its step.
const END_POINTS: usize = 3;

/// Smallest step down across the template, in pulse heights, that counts as
/// an AC coupling's (at least; three standard errors when more).
const AC_LOBE: f64 = 0.005;

/// The pulses of `found` (matched-filter detections), each keeping the
/// fitted parameters of a pulse within `tol` blocks of it; whether the set
/// changed (a detection without a pulse, or a pulse without a detection).
fn merge(pulses: &[Pulse], found: &[super::scan::Found], tol: f64) -> (Vec<Pulse>, bool) {
    let mut used = vec![false; pulses.len()];
    let mut out = Vec::with_capacity(found.len());
    let mut changed = false;
    for f in found {
        let near = pulses
            .iter()
            .enumerate()
            .filter(|(k, p)| !used[*k] && (p.c - f.c).abs() <= tol)
            .min_by(|a, b| (a.1.c - f.c).abs().total_cmp(&(b.1.c - f.c).abs()));
        match near {
            Some((k, p)) if p.a.signum() == f.a.signum() => {
                used[k] = true;
                out.push(*p);
            }
            _ => {
                changed = true;
                out.push(Pulse {
                    c: f.c,
                    a: f.a,
                    s: 1.0,
                });
            }
        }
    }
    if used.iter().any(|u| !u) {
        changed = true;
    }
    out.sort_by(|a, b| a.c.total_cmp(&b.c));
    (out, changed)
}

/// Periods from the outermost pulse to the record's end within which that
/// end is searched as in [`EdgeSearch`].
const EDGE_PERIODS: f64 = 1.5;

/// The search's view of the record's ends. Past the outermost pulses'
/// support the baseline splines are held by nothing but the data, and bend
/// to take a pulse the search has not found yet (one cut by the record's
/// start or end, with the ghost there too weak to hold them off). There
/// the search sees the signal against the baseline continued in a straight
/// line from the half period before, and keeps a pulse only where the next
/// one is due: within a quarter period of the ghost's centre, which must
/// lie inside the record.
struct EdgeSearch {
    /// The baseline-removed signal, the ends against the straight baseline.
    signal: Vec<f64>,
    /// Blocks before `lo` and after `hi` are the ends.
    lo: f64,
    hi: f64,
    /// Where a pulse is due at each end (`None`: no ghost inside the record).
    due: [Option<f64>; 2],
    /// Tolerance on `due`, blocks.
    tol: f64,
}

impl EdgeSearch {
    fn new(
        d: &[f64],
        baseline: &[f64],
        pulses: &[Pulse],
        ghosts: &[Option<Pulse>],
        core: (f64, f64),
        pd: f64,
    ) -> Self {
        let nd = d.len();
        let end = nd.saturating_sub(1) as f64;
        let mut signal = d.to_vec();
        let (Some(first), Some(last)) = (pulses.first(), pulses.last()) else {
            return Self {
                signal,
                lo: f64::NEG_INFINITY,
                hi: f64::INFINITY,
                due: [None, None],
                tol: 0.0,
            };
        };
        let lo = first.c + core.0;
        let hi = last.c + core.1;
        let inside = |g: &Option<Pulse>| g.map(|g| g.c).filter(|c| (0.0..=end).contains(c));
        // Only where the record ends within one and a half periods of the
        // outermost pulse: further out, pulses are missing (the seeds found
        // part of the record), and the search is left as it is.
        let due = [
            ghosts
                .first()
                .and_then(inside)
                .filter(|c| *c < first.c && first.c <= EDGE_PERIODS * pd),
            ghosts
                .get(1)
                .and_then(inside)
                .filter(|c| *c > last.c && end - last.c <= EDGE_PERIODS * pd),
        ];
        let span = (0.5 * pd).max(4.0);
        // Least-squares line through the baseline over `a..=b` (blocks).
        let line = |a: f64, b: f64| -> Option<(f64, f64)> {
            let a = a.max(0.0).ceil() as usize;
            let b = (b.min(end).floor().max(0.0)) as usize;
            if b < a + 2 || b >= nd {
                return None;
            }
            let xs: Vec<f64> = (a..=b).map(|i| i as f64).collect();
            let fit = crate::stats::linear_fit(&xs, &baseline[a..=b])?;
            Some((fit.intercept, fit.slope))
        };
        if due[1].is_some() {
            if let Some((c0, c1)) = line(hi - span, hi) {
                let from = hi.max(0.0).ceil() as usize;
                for i in from.min(nd)..nd {
                    signal[i] = d[i] + baseline[i] - (c0 + c1 * i as f64);
                }
            }
        }
        if due[0].is_some() {
            if let Some((c0, c1)) = line(lo, lo + span) {
                let to = (lo.floor().max(-1.0) + 1.0) as usize;
                for i in 0..to.min(nd) {
                    signal[i] = d[i] + baseline[i] - (c0 + c1 * i as f64);
                }
            }
        }
        Self {
            signal,
            lo,
            hi,
            due,
            tol: 0.25 * pd,
        }
    }

    /// Whether a pulse found at `c` is kept.
    fn keeps(&self, c: f64) -> bool {
        let near = |g: f64| (c - g).abs() <= self.tol;
        match (c < self.lo, c > self.hi) {
            (true, _) => self.due[0].is_none_or(near),
            (_, true) => self.due[1].is_none_or(near),
            _ => true,
        }
    }
}
