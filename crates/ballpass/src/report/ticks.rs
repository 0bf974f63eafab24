//! Tick positions and tick labels for linear and base-10 log axes.
//!
//! Everything here works in *axis space*: the value itself on a linear axis,
//! `log10(value)` on a log axis.

/// Ticks of one axis, in axis space.
#[derive(Debug, Clone, PartialEq)]
pub(crate) struct Ticks {
    /// Labelled ticks: position and text.
    pub major: Vec<(f64, String)>,
    /// Unlabelled grid lines between the labelled ones.
    pub minor: Vec<f64>,
}

/// "Nice" step of about `span / target`: 1, 2, 2.5 or 5 times a power of ten.
fn nice_step(span: f64, target: usize) -> f64 {
    let raw = span / target.max(1) as f64;
    let mag = 10f64.powf(raw.log10().floor());
    let m = raw / mag;
    let nice = if m <= 1.0 {
        1.0
    } else if m <= 2.0 {
        2.0
    } else if m <= 2.5 {
        2.5
    } else if m <= 5.0 {
        5.0
    } else {
        10.0
    };
    nice * mag
}

/// Linear ticks over `[lo, hi]`: about `target` labelled ticks at multiples
/// of a nice step, and minor grid lines at a fifth (or quarter) of it.
pub(crate) fn linear(lo: f64, hi: f64, target: usize) -> Ticks {
    let step = nice_step(hi - lo, target);
    let eps = step * 1e-9;
    let first = (lo / step - 1e-9).ceil() as i64;
    let last = (hi / step + 1e-9).floor() as i64;
    let values: Vec<f64> = (first..=last)
        .map(|k| {
            let v = k as f64 * step;
            // -0.0 and 1e-17 round-off print as 0
            if v.abs() < eps {
                0.0
            } else {
                v
            }
        })
        .collect();
    let major = values
        .iter()
        .map(|&v| (v, format_tick(v, step, lo.abs().max(hi.abs()))))
        .collect();
    let mant = step / 10f64.powf(step.log10().floor());
    let sub = if (mant - 2.5).abs() < 1e-9 || (mant - 2.0).abs() < 1e-9 {
        4.0
    } else {
        5.0
    };
    let minor_step = step / sub;
    let m_first = (lo / minor_step - 1e-9).ceil() as i64;
    let m_last = (hi / minor_step + 1e-9).floor() as i64;
    let minor = (m_first..=m_last)
        .map(|k| k as f64 * minor_step)
        .filter(|v| values.iter().all(|m| (m - v).abs() > minor_step * 1e-6))
        .collect();
    Ticks { major, minor }
}

/// Text of a linear tick at `v` on an axis with tick spacing `step` and
/// largest magnitude `max_abs`: plain decimals with as many digits as the step
/// needs, scientific notation (`2.5e-6`) for very large or small magnitudes.
pub(crate) fn format_tick(v: f64, step: f64, max_abs: f64) -> String {
    if v == 0.0 {
        return "0".to_string();
    }
    if !(1e-3..1e5).contains(&max_abs) {
        // digits of the mantissa needed to tell neighbouring ticks apart
        let exp = v.abs().log10().floor();
        let rel = step / 10f64.powf(exp);
        let digits = (-(rel.log10().floor())).clamp(0.0, 6.0) as usize;
        let digits = if (step / 10f64.powf(step.log10().floor()) - 2.5).abs() < 1e-9 {
            digits + 1
        } else {
            digits
        };
        let s = format!("{:.*e}", digits, v);
        return s.replace('-', "−");
    }
    let mut digits = (-(step.log10().floor())).max(0.0) as usize;
    if (step / 10f64.powf(step.log10().floor()) - 2.5).abs() < 1e-9 {
        digits += 1;
    }
    format!("{:.*}", digits, v).replace('-', "−")
}

/// `10ⁿ` with a superscript exponent.
pub(crate) fn power_of_ten(n: i64) -> String {
    const SUP: [char; 10] = ['⁰', '¹', '²', '³', '⁴', '⁵', '⁶', '⁷', '⁸', '⁹'];
    let mut s = String::from("10");
    if n < 0 {
        s.push('⁻');
    }
    for d in n.unsigned_abs().to_string().bytes() {
        s.push(SUP[(d - b'0') as usize]);
    }
    s
}

/// Log ticks over `[lo, hi]` given in decades (`log10` of the values).
///
/// About 2.5 decades or more: labelled ticks at powers of ten (every k-th decade
/// when there are many, `10ⁿ` labels) and grid lines at 2..9 times them.
/// Less: labelled ticks at 1, 2, 5 (or 1..9) times powers of ten with plain
/// numbers; a range narrower than that falls back to linear ticks on the
/// values.
pub(crate) fn log(lo: f64, hi: f64, target: usize) -> Ticks {
    let d_lo = lo.ceil() as i64;
    let d_hi = hi.floor() as i64;
    let n_decades = d_hi - d_lo + 1;
    // from about 2.5 decades on, powers of ten alone label the axis well
    if n_decades >= 3 || (n_decades >= 2 && hi - lo >= 2.5) {
        let every = ((n_decades as f64 / target.max(1) as f64).ceil() as i64).max(1);
        let major = (d_lo..=d_hi)
            .filter(|d| d.rem_euclid(every) == 0)
            .map(|d| (d as f64, power_of_ten(d)))
            .collect::<Vec<_>>();
        let mut minor = Vec::new();
        if hi - lo <= 8.0 {
            for d in (lo.floor() as i64)..=d_hi {
                for m in 2..=9 {
                    let v = d as f64 + (m as f64).log10();
                    if v >= lo && v <= hi {
                        minor.push(v);
                    }
                }
            }
        }
        // decades that are not labelled still get a grid line
        minor.extend(
            (d_lo..=d_hi)
                .filter(|d| d.rem_euclid(every) != 0)
                .map(|d| d as f64),
        );
        return Ticks { major, minor };
    }
    for mults in [
        &[1.0, 2.0, 5.0][..],
        &[1.0, 2.0, 3.0, 4.0, 5.0, 6.0, 7.0, 8.0, 9.0][..],
    ] {
        let mut vals = Vec::new();
        for d in (lo.floor() as i64)..=(hi.ceil() as i64) {
            for &m in mults {
                let v = d as f64 + f64::log10(m);
                if v >= lo - 1e-12 && v <= hi + 1e-12 {
                    vals.push((v, m * 10f64.powi(d as i32)));
                }
            }
        }
        if vals.len() >= 3 {
            let max_abs = 10f64.powf(hi);
            let major = vals
                .iter()
                .map(|&(v, x)| {
                    let step = 10f64.powf(v.floor());
                    (v, format_tick(x, step, max_abs))
                })
                .collect();
            return Ticks {
                major,
                minor: Vec::new(),
            };
        }
    }
    // narrower than a factor of ~3: linear ticks on the values themselves
    let (a, b) = (10f64.powf(lo), 10f64.powf(hi));
    let lin = linear(a, b, target);
    Ticks {
        major: lin
            .major
            .into_iter()
            .filter(|(v, _)| *v > 0.0)
            .map(|(v, s)| (v.log10(), s))
            .collect(),
        minor: lin
            .minor
            .into_iter()
            .filter(|v| *v > 0.0)
            .map(f64::log10)
            .collect(),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn labels(t: &Ticks) -> Vec<&str> {
        t.major.iter().map(|(_, s)| s.as_str()).collect()
    }

    #[test]
    fn linear_ticks_are_nice_and_inside() {
        let t = linear(-2.7, 2.7, 6);
        assert_eq!(labels(&t), ["−2", "−1", "0", "1", "2"]);
        let t = linear(0.0, 0.9, 6);
        assert_eq!(labels(&t), ["0", "0.2", "0.4", "0.6", "0.8"]);
        let t = linear(0.0, 10.0, 4);
        assert_eq!(labels(&t), ["0", "2.5", "5.0", "7.5", "10.0"]);
        for (v, _) in &t.major {
            assert!((0.0..=10.0).contains(v));
        }
    }

    #[test]
    fn tiny_and_huge_values_use_scientific_notation() {
        let t = linear(0.0, 3e-6, 3);
        assert_eq!(labels(&t), ["0", "1e−6", "2e−6", "3e−6"]);
        let t = linear(1e6, 3e6, 2);
        assert_eq!(labels(&t), ["1e6", "2e6", "3e6"]);
    }

    #[test]
    fn log_ticks_label_decades_with_superscripts() {
        let t = log(-3.2, 1.5, 8);
        assert_eq!(labels(&t), ["10⁻³", "10⁻²", "10⁻¹", "10⁰", "10¹"]);
        // 2..9 times each decade are grid lines
        assert!(t.minor.iter().any(|v| (v - 2f64.log10()).abs() < 1e-12));
        // many decades: every other one labelled
        let t = log(-12.0, 3.0, 8);
        assert!(t.major.len() <= 8, "{:?}", labels(&t));
    }

    #[test]
    fn log_ticks_over_a_decade_or_two_label_1_2_5() {
        let t = log(0.0, 20f64.log10(), 8); // 1 .. 20 (tau_c against velocity)
        assert_eq!(labels(&t), ["1", "2", "5", "10", "20"]);
    }

    #[test]
    fn log_ticks_within_one_decade_use_plain_numbers() {
        let t = log(0.0, 0.9, 8); // 1 .. 7.9
        assert_eq!(labels(&t), ["1", "2", "5"]);
        let t = log(2f64.log10(), 4f64.log10(), 6); // 2 .. 4
        assert!(t.major.len() >= 2, "{:?}", labels(&t));
    }

    #[test]
    fn power_of_ten_formats_negative_exponents() {
        assert_eq!(power_of_ten(-12), "10⁻¹²");
        assert_eq!(power_of_ten(0), "10⁰");
        assert_eq!(power_of_ten(3), "10³");
    }
}
