//! The values of a channel from its runs: decoding each TDMS type in the
//! segment's byte order, and NI scaling.

use std::collections::HashMap;

use super::segments::{item_size, type_name, Object, Prop, Run, R, TY_DAQMX};
use crate::error::excerpt;

/// The size of one value of a run whose values all lie within a file of
/// `len` bytes and are of a type [`decode`] reads; 0 for an empty run.
///
/// # Errors
/// The reason, for data of another type or beyond the file.
pub(super) fn check_run(run: &Run, len: usize) -> R<usize> {
    if run.count == 0 || run.reps == 0 {
        return Ok(0);
    }
    let size = item_size(run.ty)
        .filter(|_| matches!(run.ty, 1..=10 | 0x19 | 0x1A | 0x21 | 0x44))
        .ok_or_else(|| format!("{} data is not numeric", type_name(run.ty)))?;
    // The last byte the run reads must be in the file: checked once, so the
    // loops of [`decode`] index within bounds.
    (run.reps - 1)
        .checked_mul(run.rep_stride)
        .and_then(|x| x.checked_add((run.count - 1).checked_mul(run.stride)?))
        .and_then(|x| x.checked_add(run.offset)?.checked_add(size))
        .filter(|&end| end <= len)
        .ok_or_else(|| format!("data beyond the end of the file (from byte {})", run.offset))?;
    Ok(size)
}

/// Decodes the values of one run (`ty` a numeric TDMS type).
pub(super) fn decode(
    b: &[u8],
    run: &Run,
    out: &mut Vec<f64>,
    t0: &mut Option<(i64, u64)>,
) -> R<()> {
    if check_run(run, b.len())? == 0 {
        return Ok(());
    }
    let big = run.big;
    macro_rules! each {
        ($n:expr, $f:expr) => {{
            // FnMut for time stamps (they keep the first one).
            #[allow(unused_mut)]
            let mut f = $f;
            for r in 0..run.reps {
                let base = run.offset + r * run.rep_stride;
                if run.stride == $n {
                    // Contiguous: whole values back to back.
                    out.extend(
                        b[base..base + run.count * $n]
                            .chunks_exact($n)
                            .map(|w| f(<[u8; $n]>::try_from(w).unwrap_or([0; $n]))),
                    );
                } else {
                    out.extend((0..run.count).map(|i| {
                        let at = base + i * run.stride;
                        f(<[u8; $n]>::try_from(&b[at..at + $n]).unwrap_or([0; $n]))
                    }));
                }
            }
        }};
    }
    macro_rules! num {
        ($t:ty, $n:expr) => {
            each!($n, |a: [u8; $n]| {
                (if big {
                    <$t>::from_be_bytes(a)
                } else {
                    <$t>::from_le_bytes(a)
                }) as f64
            })
        };
    }
    match run.ty {
        1 => num!(i8, 1),
        2 => num!(i16, 2),
        3 => num!(i32, 4),
        4 => num!(i64, 8),
        5 => num!(u8, 1),
        6 => num!(u16, 2),
        7 => num!(u32, 4),
        8 => num!(u64, 8),
        9 | 0x19 => num!(f32, 4),
        10 | 0x1A => num!(f64, 8),
        0x21 => each!(1, |a: [u8; 1]| f64::from(a[0] != 0)),
        0x44 => each!(16, |a: [u8; 16]| {
            let w = |k: usize| -> [u8; 8] { a[k..k + 8].try_into().unwrap_or([0; 8]) };
            let (frac, secs) = if big {
                (u64::from_be_bytes(w(8)), i64::from_be_bytes(w(0)))
            } else {
                (u64::from_le_bytes(w(0)), i64::from_le_bytes(w(8)))
            };
            // Seconds from the first time stamp, exactly where f64 allows.
            let (s0, f0) = *t0.get_or_insert((secs, frac));
            (secs.wrapping_sub(s0)) as f64
                + (frac as f64 - f0 as f64) / 18_446_744_073_709_551_616.0
        }),
        other => return Err(format!("{} data is not numeric", type_name(other))),
    }
    Ok(())
}

/// The values of a channel, scaled as its NI scaling properties say.
pub(super) fn values(b: &[u8], o: &Object) -> R<Vec<f64>> {
    let scaling = scaling(o, b.len())?;
    let mut t0 = None;
    let daqmx = o.ty == Some(TY_DAQMX);
    if !daqmx {
        let mut raw = Vec::with_capacity(o.values);
        for (_, run) in &o.runs {
            decode(b, run, &mut raw, &mut t0)?;
        }
        return scaled(scaling.as_ref(), false, raw, HashMap::new());
    }
    // DAQmx: one series per scale id.
    let mut series: HashMap<u32, Vec<f64>> = HashMap::new();
    for (id, run) in &o.runs {
        let v = series.entry(*id).or_default();
        decode(b, run, v, &mut t0)?;
    }
    scaled(scaling.as_ref(), true, Vec::new(), series)
}

/// The NI scaling of a channel, once its value count is checked against
/// the file's `len` bytes.
pub(super) fn scaling(o: &Object, len: usize) -> R<Option<Scaling>> {
    if o.values > len {
        return Err(format!(
            "claims {} values in a file of {len} bytes",
            o.values
        ));
    }
    Scaling::of(o)
}

/// A channel's values from its decoded ones: `raw`, or for DAQmx data
/// (`daqmx`) the `series` of each scale id, scaled by `scaling`. Each value
/// depends on the values at its own place only, so a channel scaled piece
/// by piece is the channel scaled whole.
pub(super) fn scaled(
    scaling: Option<&Scaling>,
    daqmx: bool,
    raw: Vec<f64>,
    series: HashMap<u32, Vec<f64>>,
) -> R<Vec<f64>> {
    if !daqmx {
        return match scaling {
            None => Ok(raw),
            Some(s) => s.apply(&raw, &HashMap::new()),
        };
    }
    match scaling {
        Some(s) => s.apply(&[], &series),
        None => match series.len() {
            1 => Ok(series.into_values().next().unwrap_or_default()),
            n => Err(format!(
                "DAQmx data with {n} scalers and no scaling properties"
            )),
        },
    }
}

/// NI scaling: a chain of scales, the last one applied (see npTDMS).
#[derive(Debug)]
pub(super) struct Scaling {
    scales: Vec<Scale>,
}

#[derive(Debug)]
enum Scale {
    Linear {
        slope: f64,
        intercept: f64,
        input: u32,
    },
    Polynomial {
        coeffs: Vec<f64>,
        input: u32,
    },
    Daqmx(u32),
    NoOp(u32),
}

const RAW_INPUT: u32 = 0xFFFF_FFFF;

impl Scaling {
    fn of(o: &Object) -> R<Option<Scaling>> {
        let n = match o.num("NI_Number_Of_Scales") {
            Some(n) => n as usize,
            None => {
                let max = o
                    .props
                    .iter()
                    .filter_map(|(k, _)| {
                        k.strip_prefix("NI_Scale[")?
                            .strip_suffix("]_Scale_Type")?
                            .parse::<usize>()
                            .ok()
                    })
                    .max();
                match max {
                    Some(m) => m + 1,
                    None => return Ok(None),
                }
            }
        };
        if n == 0 {
            return Ok(None);
        }
        if matches!(o.prop("NI_Scaling_Status"), Some(Prop::Text(s)) if s == "scaled") {
            return Ok(None);
        }
        if n > 64 {
            return Err(format!("{n} NI scales"));
        }
        let num = |k: String| o.num(&k);
        let mut scales = Vec::with_capacity(n);
        for i in 0..n {
            let ty = match o.prop(&format!("NI_Scale[{i}]_Scale_Type")) {
                Some(Prop::Text(t)) => t.clone(),
                Some(_) => return Err(format!("NI_Scale[{i}]_Scale_Type is not text")),
                None => {
                    scales.push(Scale::Daqmx(i as u32));
                    continue;
                }
            };
            let input = |name: &str| {
                num(format!("NI_Scale[{i}]_{name}_Input_Source")).map_or(RAW_INPUT, |x| x as u32)
            };
            let need =
                |k: String| num(k.clone()).ok_or_else(|| format!("scaling property {k} missing"));
            scales.push(match ty.as_str() {
                "Linear" => Scale::Linear {
                    slope: need(format!("NI_Scale[{i}]_Linear_Slope"))?,
                    intercept: need(format!("NI_Scale[{i}]_Linear_Y_Intercept"))?,
                    input: input("Linear"),
                },
                "Polynomial" => {
                    let m = num(format!("NI_Scale[{i}]_Polynomial_Coefficients_Size"))
                        .map_or(4, |m| m as usize);
                    if m > 64 {
                        return Err(format!("a polynomial scale of {m} coefficients"));
                    }
                    Scale::Polynomial {
                        coeffs: (0..m)
                            .map(|j| need(format!("NI_Scale[{i}]_Polynomial_Coefficients[{j}]")))
                            .collect::<R<_>>()?,
                        input: input("Polynomial"),
                    }
                }
                "AdvancedAPI" => Scale::NoOp(input("AdvancedAPI")),
                other => {
                    return Err(format!(
                        "NI scaling '{}' is not supported (linear, polynomial and DAQmx \
                         scalers are); give the channel's scale instead",
                        excerpt(other)
                    ))
                }
            });
        }
        Ok(Some(Scaling { scales }))
    }

    fn apply(&self, raw: &[f64], scalers: &HashMap<u32, Vec<f64>>) -> R<Vec<f64>> {
        self.compute(self.scales.len() as u32 - 1, raw, scalers, 0)
    }

    fn compute(
        &self,
        i: u32,
        raw: &[f64],
        scalers: &HashMap<u32, Vec<f64>>,
        depth: usize,
    ) -> R<Vec<f64>> {
        if depth > self.scales.len() {
            return Err("NI scales refer to each other in a loop".into());
        }
        if i == RAW_INPUT {
            if raw.is_empty() && !scalers.is_empty() {
                return Err("an NI scale reads raw data of DAQmx scalers".into());
            }
            return Ok(raw.to_vec());
        }
        let scale = self
            .scales
            .get(i as usize)
            .ok_or_else(|| format!("NI scale {i} does not exist"))?;
        Ok(match scale {
            Scale::Daqmx(id) => scalers
                .get(id)
                .cloned()
                .ok_or_else(|| format!("no DAQmx scaler with scale id {id}"))?,
            Scale::NoOp(input) => self.compute(*input, raw, scalers, depth + 1)?,
            Scale::Linear {
                slope,
                intercept,
                input,
            } => self
                .compute(*input, raw, scalers, depth + 1)?
                .into_iter()
                .map(|x| x * slope + intercept)
                .collect(),
            Scale::Polynomial { coeffs, input } => self
                .compute(*input, raw, scalers, depth + 1)?
                .into_iter()
                .map(|x| {
                    // numpy's polyval (Horner from the highest coefficient).
                    let mut y = coeffs.last().copied().unwrap_or(0.0);
                    for c in coeffs.iter().rev().skip(1) {
                        y = c + y * x;
                    }
                    if coeffs.is_empty() {
                        0.0
                    } else {
                        y
                    }
                })
                .collect(),
        })
    }
}
