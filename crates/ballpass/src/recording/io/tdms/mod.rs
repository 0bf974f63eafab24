//! NI TDMS files (LabVIEW, DAQmx, npTDMS): our own reader, bounded by the file.
//!
//! A TDMS file is a chain of segments: a 28-byte lead-in (`TDSm`, table of
//! contents, version, offsets), metadata (objects `/'Group'/'Channel'` with their
//! raw data index and properties) and raw data, written in chunks. Objects
//! and their raw data indexes carry over from segment to segment unless a
//! segment replaces them.
//!
//! Read: every segment layout (new or carried-over object lists, several
//! chunks per segment, an unfinished last segment), contiguous and
//! interleaved raw data, big-endian segments, and DAQmx raw data with
//! format-changing scalers; channels of integer, float, boolean and
//! timestamp type. NI scaling properties (`NI_Scale[k]_...`: linear,
//! polynomial and DAQmx scalers, chained as NI defines) are applied as
//! npTDMS applies them. The time base is `wf_increment` (the rate, stated)
//! and `wf_start_offset` of the channels used; channels whose `wf_start_time`
//! differ by half a sample or more are refused.
//!
//! Why not the `tdms-rs` crate: it allocates buffers of any size a length
//! field claims (a 4 GB path length aborts the process), reads only the
//! first chunk of a segment (later chunks are silently lost) and neither
//! interleaved nor DAQmx data; a reader that checks every length against
//! the file is shorter than the pre-validation it would need.
//!
//! Bounds: every length and count is checked against the bytes that remain
//! before anything is allocated from it; the data of a channel is kept as a
//! few runs per segment (offset, count, stride, repetitions), so a segment
//! of a million tiny chunks costs no more than one of a single chunk.

mod segments;
pub mod stream;
mod values;
mod write;

pub use write::write_tdms;

use std::path::Path;

use self::segments::{type_name, Object, Prop, Tdms, R};
use super::names::{self, Candidate};
use super::{LoadOptions, Locator, RawColumn, RawTable};
use crate::error::{excerpt, Error, Result};
use crate::recording::Channel;

fn format_err(path: &Path, reason: impl Into<String>) -> Error {
    Error::Format {
        path: path.to_path_buf(),
        reason: reason.into(),
    }
}

fn open(path: &Path, bytes: &[u8]) -> Result<Tdms> {
    read(path, &mut &bytes[..])
}

/// The segment chain of the file at `path` from `src`: an error naming the
/// file when it is not a TDMS file or is damaged.
fn read(path: &Path, src: &mut dyn segments::Bytes) -> Result<Tdms> {
    let size = src.size();
    let head = src
        .get(0, size.min(4))
        .map_err(|r| format_err(path, r))?
        .into_owned();
    if head != b"TDSm" {
        return Err(format_err(
            path,
            if size == 0 {
                "file is empty; expected an NI TDMS file".to_string()
            } else {
                "not an NI TDMS file (it does not start with 'TDSm')".to_string()
            },
        ));
    }
    segments::read(src).map_err(|r| format_err(path, format!("damaged TDMS file: {r}")))
}

/// The groups that hold channels, in file order.
fn groups(t: &Tdms) -> Vec<String> {
    let mut g: Vec<String> = Vec::new();
    for o in t.objects.iter().filter(|o| o.channel.is_some()) {
        if !g.contains(&o.group) {
            g.push(o.group.clone());
        }
    }
    g
}

/// The groups of a file for a message: `'Run 1' (3 channels), ...`.
fn list_groups(t: &Tdms) -> String {
    let g: Vec<String> = groups(t)
        .iter()
        .map(|g| {
            let n = t
                .objects
                .iter()
                .filter(|o| o.channel.is_some() && &o.group == g)
                .count();
            format!(
                "'{}' ({n} channel{})",
                excerpt(g),
                if n == 1 { "" } else { "s" }
            )
        })
        .collect();
    if g.is_empty() {
        "no group with channels".into()
    } else {
        g.join(", ")
    }
}

/// The group `record` names (its name ignoring case).
///
/// # Errors
/// The reason, listing the file's groups, when none has that name.
fn group_of(t: &Tdms, record: &str) -> R<String> {
    let want = record.trim();
    groups(t)
        .into_iter()
        .find(|g| g.eq_ignore_ascii_case(want))
        .ok_or_else(|| {
            format!(
                "no group '{}' (FILE#GROUP names one run); the file holds {}",
                excerpt(want),
                list_groups(t)
            )
        })
}

/// The channels of a TDMS file by name (`Group/Channel`, or `Channel` alone),
/// only those of `group` when given.
fn candidates(t: &Tdms, group: Option<&str>) -> (Vec<usize>, Vec<Candidate>) {
    let ids: Vec<usize> = (0..t.objects.len())
        .filter(|&i| t.objects[i].channel.is_some())
        .filter(|&i| group.is_none_or(|g| t.objects[i].group == g))
        .collect();
    let cands = ids
        .iter()
        .map(|&i| {
            let o = &t.objects[i];
            Candidate {
                full: o.label(),
                short: o.channel.clone(),
            }
        })
        .collect();
    (ids, cands)
}

/// Which objects of a file give the record's channels and time, and the
/// timing the file states: what the whole-file reader and the streamed one
/// ([`stream`]) both read the values by.
struct Plan {
    /// Channels and the object each is read from.
    channels: Vec<(Channel, usize)>,
    /// The time channel's object, if one is used.
    time: Option<usize>,
    /// The rate `wf_increment` states, and where.
    stated_rate: Option<(f64, String)>,
    /// `wf_start_offset` of the first channel with waveform timing.
    start_time_s: Option<f64>,
}

/// The [`Plan`] of a file under `opts`.
///
/// # Errors
/// [`Error::Format`] naming the file for a group or channel not found or
/// ambiguous (listing what the file holds), or waveform timing that is
/// not one recording's.
fn plan(path: &Path, t: &Tdms, opts: &LoadOptions) -> Result<Plan> {
    let err = |r: String| format_err(path, r);
    let group = opts
        .record
        .as_deref()
        .map(|r| group_of(t, r))
        .transpose()
        .map_err(err)?;
    let (ids, cands) = candidates(t, group.as_deref());
    let has = || names::list(&cands.iter().map(|c| c.full.clone()).collect::<Vec<_>>());
    let all = groups(t);
    let several = group.is_none() && all.len() > 1;
    let mapped =
        names::map_channels(&cands, opts, ", as Group/Channel or Channel").map_err(|r| {
            if several {
                // One run per group, as LabVIEW writes them: say how to pick one.
                let file = path
                    .file_name()
                    .map_or(String::new(), |f| f.to_string_lossy().into_owned());
                err(format!(
                    "{r}; the file holds several groups (runs?): {}; name one as FILE#GROUP \
                     (e.g. '{}#{}')",
                    list_groups(t),
                    excerpt(&file),
                    excerpt(&all[0])
                ))
            } else {
                err(r)
            }
        })?;
    let channels: Vec<(Channel, usize)> = mapped.into_iter().map(|(c, k)| (c, ids[k])).collect();
    let time_name = opts
        .time
        .clone()
        .unwrap_or_else(|| super::csv::TIME_COLUMN.into());
    let time = if opts.ignore_time {
        None
    } else {
        match names::find(&cands, &time_name).map_err(err)? {
            Some(k) => Some(ids[k]),
            None if opts.time.is_some() => {
                return Err(err(format!(
                    "no channel '{}' for time; the file has: {}",
                    excerpt(&time_name),
                    has()
                )))
            }
            None => None,
        }
    };
    // The waveform timing of the channels used.
    let mut stated_rate = None;
    let mut start_time_s = None;
    let mut first_start: Option<(String, (i64, u64), f64)> = None;
    for &(_, i) in &channels {
        let o = &t.objects[i];
        let Some(inc) = o.num("wf_increment") else {
            continue;
        };
        if !(inc.is_finite() && inc > 0.0) {
            return Err(err(format!(
                "channel '{}': wf_increment {inc}; expected a positive number of seconds",
                excerpt(&o.label())
            )));
        }
        let fs = rate_of_increment(inc);
        match &stated_rate {
            None => stated_rate = Some((fs, format!("wf_increment of '{}'", excerpt(&o.label())))),
            Some((f0, from)) if (f0 - fs).abs() > 1e-12 * f0 => {
                return Err(err(format!(
                    "channel '{}' is sampled at {fs} Hz (wf_increment), but {from} says {f0} Hz",
                    excerpt(&o.label())
                )))
            }
            Some(_) => {}
        }
        start_time_s.get_or_insert(o.num("wf_start_offset").unwrap_or(0.0));
        if let Some(Prop::Time(s, f)) = o.prop("wf_start_time") {
            match &first_start {
                None => first_start = Some((o.label(), (*s, *f), fs)),
                Some((other, (s0, f0), fs0)) => {
                    let dt =
                        (s - s0) as f64 + (*f as f64 - *f0 as f64) / 18_446_744_073_709_551_616.0;
                    if dt.abs() * fs0 >= 0.5 {
                        return Err(err(format!(
                            "channels '{}' and '{}' start {dt} s apart (wf_start_time); \
                             they are not one recording",
                            excerpt(other),
                            excerpt(&o.label())
                        )));
                    }
                }
            }
        }
    }
    Ok(Plan {
        channels,
        time,
        stated_rate,
        start_time_s,
    })
}

/// Object `o` as a column holding `values`: its name and stated unit.
fn column(o: &Object, values: Vec<f64>) -> RawColumn {
    let unit = match o.prop("unit_string") {
        Some(Prop::Text(u)) if !u.trim().is_empty() => Some((
            u.trim().to_string(),
            format!("unit_string of '{}'", excerpt(&o.label())),
        )),
        _ => None,
    };
    RawColumn {
        name: excerpt(&o.label()),
        values,
        resolution: 0.0,
        unit,
    }
}

/// The error for a channel's values.
fn channel_err(path: &Path, o: &Object, r: &str) -> Error {
    format_err(path, format!("channel '{}': {r}", excerpt(&o.label())))
}

/// Parses a TDMS file held in memory into raw columns.
pub(crate) fn parse(path: &Path, bytes: &[u8], opts: &LoadOptions) -> Result<RawTable> {
    let t = open(path, bytes)?;
    let plan = plan(path, &t, opts)?;
    let read = |i: usize| -> Result<RawColumn> {
        let o = &t.objects[i];
        let v = values::values(bytes, o).map_err(|r| channel_err(path, o, &r))?;
        Ok(column(o, v))
    };
    let mut channels = Vec::with_capacity(plan.channels.len());
    for &(c, i) in &plan.channels {
        channels.push((c, read(i)?));
    }
    let time = plan.time.map(read).transpose()?;
    Ok(RawTable {
        time,
        channels,
        locator: Locator::Samples,
        stated_rate: plan.stated_rate,
        start_time_s: plan.start_time_s,
        notes: t.notes,
        ..RawTable::default()
    })
}

/// `1 / increment`, as the decimal with the fewest digits whose reciprocal
/// is the same double (a `wf_increment` written as `1 / 1000` gives 1000).
fn rate_of_increment(inc: f64) -> f64 {
    let raw = 1.0 / inc;
    for digits in 1..=17 {
        if let Ok(c) = format!("{:.*e}", digits - 1, raw).parse::<f64>() {
            if 1.0 / c == inc {
                return c;
            }
        }
    }
    raw
}

/// What a TDMS file holds, for `inspect`: groups and channels.
pub(crate) fn contents(
    path: &Path,
    bytes: &[u8],
    record: Option<&str>,
    limit: usize,
) -> Result<Vec<(String, String)>> {
    let t = open(path, bytes)?;
    let group = record
        .map(|r| group_of(&t, r))
        .transpose()
        .map_err(|r| format_err(path, r))?;
    let mut out = Vec::new();
    let shown = t
        .objects
        .iter()
        .filter(|o| group.as_ref().is_none_or(|g| &o.group == g));
    for o in shown.take(limit) {
        let desc = match &o.channel {
            None => {
                let n = t
                    .objects
                    .iter()
                    .filter(|c| c.channel.is_some() && c.group == o.group)
                    .count();
                if o.group == "/" {
                    format!("file properties: {}", o.props.len())
                } else {
                    format!("group of {n} channel(s)")
                }
            }
            Some(_) => {
                let mut d = format!(
                    "channel, {}, {} values",
                    o.ty.map_or("no data", type_name),
                    o.values
                );
                if let Some(inc) = o.num("wf_increment") {
                    d.push_str(&format!(
                        ", wf_increment {inc} s ({} Hz)",
                        rate_of_increment(inc)
                    ));
                }
                if let Some(Prop::Text(u)) = o.prop("unit_string") {
                    d.push_str(&format!(", unit {}", excerpt(u)));
                }
                d
            }
        };
        out.push((excerpt(&o.label()), desc));
    }
    for n in &t.notes {
        out.push(("note".into(), n.clone()));
    }
    Ok(out)
}

#[cfg(test)]
mod tests {
    use super::segments::split_path;
    use super::*;

    #[test]
    fn object_paths_split_with_quotes() {
        assert_eq!(split_path("/").unwrap(), Vec::<String>::new());
        assert_eq!(split_path("/'G'").unwrap(), vec!["G"]);
        assert_eq!(
            split_path("/'Group 1'/'it''s/a name'").unwrap(),
            vec!["Group 1", "it's/a name"]
        );
        assert!(split_path("/G").is_err());
        assert!(split_path("/'G").is_err());
    }

    #[test]
    fn rates_snap_to_the_decimal_of_the_increment() {
        assert_eq!(rate_of_increment(1.0 / 1000.0), 1000.0);
        assert_eq!(rate_of_increment(0.001), 1000.0);
        assert_eq!(rate_of_increment(1.0 / 2048.0), 2048.0);
        assert_eq!(rate_of_increment(1.0 / 25600.0), 25600.0);
    }
}
