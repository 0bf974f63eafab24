//! The measurement loop: template and baseline by least squares, each
//! pulse fitted against the template, a matched-filter search for the
//! pulses the seeds missed (and of either polarity), until the set of
//! pulses stops changing (module docs of [`super`], "Method").

use super::coupling::{ac_plausible, ac_rate, with_mean_ramp};
use super::edges::{ghosts, EdgeSearch};
use super::gaps::gap_lines;
use super::lsq::{Problem, Splines};
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
