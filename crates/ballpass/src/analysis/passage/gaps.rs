//! The dark level between the pulses, followed at the pulses' own scale:
//! the part of the baseline too fast for the splines (knots a period
//! apart), such as a drift whose period is a few ball-pass periods.
//!
//! Between two found pulses the light is dark: there, what the splines and
//! the modelled pulses leave is the baseline's fast part plus noise. Each
//! dark stretch (outside every found pulse's half-maximum span and one half
//! width either side) of at least half a template FWHM is fitted with a
//! straight line, by least squares with the samples far above the line
//! left out (a pulse not found yet only adds light). A stretch longer than
//! a period (a passage not found yet, or the record's end) takes the
//! running low quantile of [`gap_level`] instead, which such a pulse cannot
//! lift (cut into lines of at most half a period where that quantile
//! refuses). Under a pulse
//! the level is the cubic Hermite curve joining the line before it to the
//! line after (values and slopes at their ends): a drift is followed through
//! the pulse at the pulse's scale, so a drift of a period or two no longer
//! reads as part of the pulse (wider) nor hides the next one.
//!
//! A running low quantile over a window of a few pulse widths (what this
//! replaces) takes a drift whose period is about that window for noise: on
//! design records with a drift of period 0.5–3 τ_c, pulses read up to
//! +134 % wide and up to half the passages went missing.

use super::template::{Pulse, Shape};

/// Half widths either side of a found pulse's half-maximum points left out
/// (where its misfit to the template is).
const MASK_HALF_WIDTHS: f64 = 1.0;

/// Shortest dark stretch fitted, in template FWHM (its slope's standard
/// error is then `σ √12 / m^1.5` per block, m ≥ 12 blocks at 24 blocks per
/// FWHM: a tenth of the block noise across a pulse).
const MIN_STRETCH_FWHM: f64 = 0.5;

/// Shortest dark stretch fitted, blocks.
const MIN_STRETCH_BLOCKS: usize = 8;

/// Longest piece a dark stretch is fitted in, in periods (a stretch of
/// more than a period where the running quantile refuses).
const MAX_PIECE_PERIODS: f64 = 0.5;

/// Longest span between two lines, in periods (a pulse and its masks
/// cover less than one; a passage missed leaves a dark stretch, cut in
/// pieces).
const MAX_SPAN_PERIODS: f64 = 1.5;

/// Samples this many block noises above the line are left out of it
/// (plus [`CLIP_PULSE`] of the median pulse: template misfit on a
/// noise-free record is no pulse).
const CLIP_SIGMA: f64 = 3.0;

/// See [`CLIP_SIGMA`].
const CLIP_PULSE: f64 = 0.02;

/// Least-squares passes of a line, each without the samples above it.
const LINE_PASSES: usize = 6;

/// The level over one dark piece `a..=b`: a line (its values at both ends
/// and its slope per block), or the running quantile's values there
/// (`slope` then the one at `a`, `slope_b` the one at `b`).
#[derive(Debug, Clone, Copy)]
struct Line {
    a: usize,
    b: usize,
    va: f64,
    vb: f64,
    slope: f64,
    slope_b: f64,
    from_level: bool,
}

/// The dark level of `r` (what the baseline and the modelled pulses leave),
/// one value per block (module docs). `None` when no dark stretch is long
/// enough (pulses that fill most of the period).
pub(super) fn gap_lines(
    r: &[f64],
    pulses: &[Pulse],
    shape: &Shape,
    block_noise: f64,
    pd: f64,
) -> Option<Vec<f64>> {
    let n = r.len();
    let fwhm = shape.fwhm();
    if n == 0 || fwhm.is_nan() || fwhm <= 0.0 {
        return None;
    }
    let dark = dark_mask(n, pulses, shape);
    let amps: Vec<f64> = pulses.iter().map(|p| p.a.abs()).collect();
    let med_amp = if amps.is_empty() {
        0.0
    } else {
        super::signal::median(&amps)
    };
    let clip = CLIP_SIGMA * block_noise + CLIP_PULSE * med_amp;
    let min_len = ((MIN_STRETCH_FWHM * fwhm).ceil() as usize).max(MIN_STRETCH_BLOCKS);
    let max_len = ((MAX_PIECE_PERIODS * pd).round() as usize).max(2 * min_len);
    let mut lines: Vec<Line> = Vec::new();
    let mut level: Option<Option<Vec<f64>>> = None;
    let mut i = 0;
    while i < n {
        if !dark[i] {
            i += 1;
            continue;
        }
        let a = i;
        while i < n && dark[i] {
            i += 1;
        }
        let len = i - a;
        if len < min_len {
            continue;
        }
        // A stretch longer than a period holds a passage not found yet or
        // the record's end: the running quantile there, which a pulse it
        // has not found covers at most half of (its lines otherwise).
        if len as f64 > pd {
            let lv = level.get_or_insert_with(|| gap_level(r, &dark, fwhm, block_noise, pd));
            if let Some(lv) = lv {
                let b = i - 1;
                lines.push(Line {
                    a,
                    b,
                    va: lv[a],
                    vb: lv[b],
                    slope: lv[a + 1] - lv[a],
                    slope_b: lv[b] - lv[b - 1],
                    from_level: true,
                });
                continue;
            }
        }
        let pieces = len.div_ceil(max_len);
        for k in 0..pieces {
            let pa = a + k * len / pieces;
            let pb = a + (k + 1) * len / pieces - 1;
            if let Some(l) = robust_line(r, pa, pb, clip) {
                lines.push(l);
            }
        }
    }
    // Lines further apart than a pulse and its masks (pulses that fill
    // most of the period, with a stretch long enough here and there):
    // not followed at the pulses' scale.
    let sparse = lines
        .windows(2)
        .any(|w| (w[1].a - w[0].b) as f64 > MAX_SPAN_PERIODS * pd);
    if lines.is_empty() || sparse {
        return None;
    }
    let mut out = vec![0.0; n];
    let first = lines[0];
    out[..first.a].iter_mut().for_each(|o| *o = first.va);
    for (k, l) in lines.iter().enumerate() {
        match (l.from_level, &level) {
            (true, Some(Some(lv))) => out[l.a..=l.b].copy_from_slice(&lv[l.a..=l.b]),
            _ => {
                for (j, o) in out.iter_mut().enumerate().take(l.b + 1).skip(l.a) {
                    *o = l.va + l.slope * (j - l.a) as f64;
                }
            }
        }
        let Some(next) = lines.get(k + 1) else {
            out[l.b + 1..].iter_mut().for_each(|o| *o = l.vb);
            break;
        };
        // Under the pulse between the two lines: cubic Hermite (slopes
        // kept only across less than a period, where they hold).
        let gap = (next.a - l.b) as f64;
        let (m0, m1) = if gap <= pd {
            (l.slope_b * gap, next.slope * gap)
        } else {
            (next.va - l.vb, next.va - l.vb)
        };
        for (j, o) in out.iter_mut().enumerate().take(next.a).skip(l.b + 1) {
            let t = (j - l.b) as f64 / gap;
            let (t2, t3) = (t * t, t * t * t);
            *o = (2.0 * t3 - 3.0 * t2 + 1.0) * l.vb
                + (t3 - 2.0 * t2 + t) * m0
                + (-2.0 * t3 + 3.0 * t2) * next.va
                + (t3 - t2) * m1;
        }
    }
    Some(out)
}

/// Blocks outside every found pulse's half-maximum span widened by
/// [`MASK_HALF_WIDTHS`] half widths either side (`true` = dark).
fn dark_mask(n: usize, pulses: &[Pulse], shape: &Shape) -> Vec<bool> {
    let hw_l = shape.peak_u - shape.left_u;
    let hw_r = shape.right_u - shape.peak_u;
    let mut dark = vec![true; n];
    for p in pulses {
        let a = p.c + p.s * (shape.left_u - MASK_HALF_WIDTHS * hw_l);
        let b = p.c + p.s * (shape.right_u + MASK_HALF_WIDTHS * hw_r);
        let lo = a.ceil().max(0.0) as usize;
        let hi = (b.floor().min((n - 1) as f64)).max(-1.0);
        if hi < lo as f64 {
            continue;
        }
        dark[lo..=hi as usize].iter_mut().for_each(|d| *d = false);
    }
    dark
}

/// Least-squares line through `r[a..=b]`, refitted without the samples more
/// than `clip` above it until they stop changing.
fn robust_line(r: &[f64], a: usize, b: usize, clip: f64) -> Option<Line> {
    let ys = &r[a..=b];
    let mid = 0.5 * (ys.len() - 1) as f64;
    let mut keep = vec![true; ys.len()];
    let mut fit = None;
    for _ in 0..LINE_PASSES {
        let (mut s0, mut sx, mut sy, mut sxx, mut sxy) = (0.0, 0.0, 0.0, 0.0, 0.0);
        for (j, (&y, &k)) in ys.iter().zip(&keep).enumerate() {
            if k {
                let x = j as f64 - mid;
                s0 += 1.0;
                sx += x;
                sy += y;
                sxx += x * x;
                sxy += x * y;
            }
        }
        if s0 < 3.0 {
            break;
        }
        let det = s0 * sxx - sx * sx;
        let (c0, c1) = if det > 0.0 {
            ((sy * sxx - sx * sxy) / det, (s0 * sxy - sx * sy) / det)
        } else {
            (sy / s0, 0.0)
        };
        fit = Some((c0, c1));
        let mut changed = false;
        for (j, (&y, k)) in ys.iter().zip(keep.iter_mut()).enumerate() {
            let below = y - (c0 + c1 * (j as f64 - mid)) <= clip;
            if below != *k {
                *k = below;
                changed = true;
            }
        }
        if !changed {
            break;
        }
    }
    let (c0, c1) = fit?;
    Some(Line {
        a,
        b,
        va: c0 - c1 * mid,
        vb: c0 + c1 * mid,
        slope: c1,
        slope_b: c1,
        from_level: false,
    })
}

/// Half length of [`gap_level`]'s window, in template FWHM: the window is
/// twice a pulse's support (three half widths either side of its peak), so
/// that a pulse not yet found covers at most half of it.
const GAP_WINDOW_FWHM: f64 = 3.0;

/// Quantile of the dark samples [`gap_level`] takes.
const GAP_QUANTILE: f64 = 0.25;

/// The level of `r` (what the baseline and the modelled pulses leave)
/// where the light is dark: a running low quantile of the samples outside
/// every found pulse (its half-maximum span and one half width either
/// side), over a window of [`GAP_WINDOW_FWHM`] template FWHM either side,
/// longer where that holds too few dark samples (up to a period either
/// side), lifted by the noise's own quantile (white noise of
/// `block_noise` per block). A window needs enough dark samples that a
/// pulse not found yet covers less than `1 − GAP_QUANTILE` of them.
///
/// A pulse of light only adds to the dark level, so a low quantile stays
/// on the dark level under a pulse the search has not found yet (it covers
/// at most half the window); the window follows a drift as fast as a few
/// pulse widths, where a running mean over a period cannot. `None` when
/// some window holds too few dark samples (pulses that fill most of the
/// period: the period mean is used then).
///
/// `fwhm`: the template's, positive and finite, and `r` not empty (as
/// [`gap_lines`] checks before calling).
fn gap_level(r: &[f64], dark: &[bool], fwhm: f64, block_noise: f64, pd: f64) -> Option<Vec<f64>> {
    let n = r.len();
    let w = (GAP_WINDOW_FWHM * fwhm).min(pd).max(4.0).round() as usize;
    // −Φ⁻¹(GAP_QUANTILE): the noise's quantile below its median.
    let lift = 0.674_489_750_196_081_7 * block_noise;
    let stride = (w / 4).max(1);
    let mut anchors: Vec<usize> = (0..n).step_by(stride).collect();
    if anchors.last() != Some(&(n - 1)) {
        anchors.push(n - 1);
    }
    // A pulse not found yet lifts the low quantile once it covers more
    // than `1 − GAP_QUANTILE` of the dark samples: a window needs that many
    // more than the span a pulse covers (the span left out of a found one).
    let span = (1.0 + MASK_HALF_WIDTHS) * fwhm;
    let need = (span / (1.0 - GAP_QUANTILE)).max(8.0);
    // Dark samples before each block (to size each window).
    let mut cum = vec![0usize; n + 1];
    for (j, d) in dark.iter().enumerate() {
        cum[j + 1] = cum[j] + usize::from(*d);
    }
    // The longest window allowed: a period either side.
    let w_max = (pd.round() as usize).max(w);
    let mut buf = Vec::with_capacity(2 * w_max + 1);
    let mut values = Vec::with_capacity(anchors.len());
    for &i in &anchors {
        // The shortest window from `w` either side (kept whole at the
        // record's ends) up to `w_max` holding `need` dark samples.
        let mut half = w;
        let (a, b) = loop {
            let len = (2 * half + 1).min(n);
            let a = i.saturating_sub(half).min(n - len);
            let b = a + len - 1;
            if (cum[b + 1] - cum[a]) as f64 >= need || half >= w_max || len == n {
                break (a, b);
            }
            half = (half + stride).min(w_max);
        };
        buf.clear();
        buf.extend((a..=b).filter(|&j| dark[j]).map(|j| r[j]));
        if (buf.len() as f64) < need {
            return None;
        }
        let k = ((GAP_QUANTILE * (buf.len() - 1) as f64).round() as usize).min(buf.len() - 1);
        let (_, v, _) = buf.select_nth_unstable_by(k, f64::total_cmp);
        values.push(*v + lift);
    }
    let mut out = vec![0.0; n];
    for (k, pair) in anchors.windows(2).enumerate() {
        let (i0, i1) = (pair[0], pair[1]);
        let (v0, v1) = (values[k], values[k + 1]);
        for (j, o) in out.iter_mut().enumerate().take(i1 + 1).skip(i0) {
            *o = v0 + (v1 - v0) * (j - i0) as f64 / (i1 - i0) as f64;
        }
    }
    if anchors.len() == 1 {
        out[0] = values[0];
    }
    Some(out)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::analysis::passage::template::Template;

    /// A drift of period 1.2 periods under pulses 0.2 period wide: the lines
    /// between the pulses and the Hermite curves under them follow it to
    /// within 45 % of its amplitude at worst (measured 38 %: each 60-block
    /// dark stretch is fitted as two 30-block lines, whose slopes are the
    /// chords' and not the tangents at their ends; a tracker that averages
    /// over a period, as a window of a few pulse widths does here, leaves
    /// the whole amplitude).
    #[test]
    fn follows_a_drift_of_about_a_period_under_the_pulses() {
        let pd = 100.0;
        let n = 1000;
        let t = Template::from_fn(30.0, 30.0, 0.5, |u| {
            (-0.5 * (u / (20.0 / 2.354_820_045)).powi(2)).exp()
        });
        let sh = t.shape().expect("a Gaussian has a shape");
        let pulses: Vec<Pulse> = (0..10)
            .map(|k| Pulse {
                c: 50.0 + pd * k as f64,
                a: 1.0,
                s: 1.0,
            })
            .collect();
        let drift = |i: usize| 0.3 * (std::f64::consts::TAU * i as f64 / 120.0).sin();
        let r: Vec<f64> = (0..n).map(drift).collect();
        let got = gap_lines(&r, &pulses, &sh, 1e-3, pd).expect("dark stretches");
        let worst = (0..n)
            .map(|i| (got[i] - drift(i)).abs())
            .fold(0.0, f64::max);
        assert!(worst < 0.45 * 0.3, "worst {worst}");
    }

    /// A pulse not found yet (not in `pulses`) in a dark stretch is left
    /// out of the line: the level stays within 2 % of the pulse of the dark
    /// one.
    #[test]
    fn a_pulse_not_found_is_left_out_of_the_line() {
        let n = 400;
        let r: Vec<f64> = (0..n)
            .map(|i| {
                let u = (i as f64 - 200.0) / (20.0 / 2.354_820_045);
                0.5 + (-0.5 * u * u).exp()
            })
            .collect();
        let t = Template::from_fn(30.0, 30.0, 0.5, |u| {
            (-0.5 * (u / (20.0 / 2.354_820_045)).powi(2)).exp()
        });
        let sh = t.shape().expect("a Gaussian has a shape");
        let got = gap_lines(&r, &[], &sh, 1e-3, 400.0).expect("dark stretches");
        for (i, v) in got.iter().enumerate() {
            assert!((v - 0.5).abs() < 0.02, "at {i}: {v}");
        }
    }
}
