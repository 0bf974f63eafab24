//! ASAM MDF 4 files (`.mf4`: Vector, dSPACE, ETAS loggers, asammdf), read
//! with the pure-Rust `falcon_mdf` crate.
//!
//! A channel is named by its name (`Force`) or, when several channel groups
//! hold one of that name, `group/name` with the group's acquisition name
//! (or `group N` for the N-th group without one). The time column is the
//! master channel of the channels' group (a time master, in s, or the unit
//! it states); channels from groups with different master channels are not
//! one recording and are refused. Samples the file marks invalid are gaps.
//!
//! `falcon_mdf` was chosen among the MDF readers checked (`mdf4-rs`,
//! `falcon_mdf`) because it decodes what asammdf writes (DT, DZ and DL data
//! blocks, conversions, invalidation bits) and bounds what it allocates from
//! numbers in the file; its panics are contained all the same, its reads
//! are limited to what the file can hold, and a channel whose decoded
//! length differs from its group's sample count (a read cut at that limit)
//! is refused, not used.

use std::path::Path;

use falcon_mdf::blocks::SyncType;
use falcon_mdf::{Mf4File, OpenOptions, SignalValues};

use super::contain::{contain, detail};
use super::names::{self, Candidate};
use super::{LoadOptions, Locator, RawColumn, RawTable, TimeUnit};
use crate::error::{excerpt, Error, Result};
use crate::recording::Channel;

type R<T> = std::result::Result<T, String>;

fn format_err(path: &Path, reason: impl Into<String>) -> Error {
    Error::Format {
        path: path.to_path_buf(),
        reason: reason.into(),
    }
}

/// Runs a call into the MDF reader with its panics contained.
fn mdf<T>(what: &str, f: impl FnOnce() -> falcon_mdf::Result<T>) -> R<T> {
    match contain(f) {
        Some(Ok(v)) => Ok(v),
        Some(Err(e)) => Err(format!("{what}: {}", detail(&e))),
        None => Err(format!("{what}: the MDF structure could not be decoded")),
    }
}

fn open(path: &Path, bytes: &[u8]) -> Result<Mf4File> {
    if !bytes.starts_with(b"MDF     ") {
        return Err(format_err(
            path,
            if bytes.is_empty() {
                "file is empty; expected an MDF 4 file".to_string()
            } else {
                "not an MDF file (it does not start with 'MDF')".to_string()
            },
        ));
    }
    let len = bytes.len();
    let options = OpenOptions {
        build_channels_db: true,
        parallel_parsing: false,
        parallel_threshold: usize::MAX,
        // A buffer sized from a number in the file never exceeds the file.
        max_alloc: len.clamp(1 << 16, 64 << 20),
        // Nothing decompresses past 1032:1 (deflate's limit).
        max_decompressed: (len as u64).saturating_mul(1032).saturating_add(1 << 20),
    };
    mdf("damaged MDF file", || {
        Mf4File::from_bytes_with_options(bytes.to_vec(), options)
    })
    .map_err(|r| format_err(path, r))
}

/// A channel of the file: where it is and what it is called.
struct Item {
    dg: usize,
    cg: usize,
    ch: usize,
}

fn group_name(file: &Mf4File, dg: usize, cg: usize) -> String {
    let g = &file.data_groups()[dg].channel_groups[cg];
    if !g.acquisition_name.trim().is_empty() {
        g.acquisition_name.trim().to_string()
    } else if file.data_groups()[dg].channel_groups.len() > 1 {
        format!("group {}.{}", dg + 1, cg + 1)
    } else {
        format!("group {}", dg + 1)
    }
}

fn items(file: &Mf4File) -> (Vec<Item>, Vec<Candidate>) {
    let mut items = Vec::new();
    let mut cands = Vec::new();
    for (dg, d) in file.data_groups().iter().enumerate() {
        for (cg, g) in d.channel_groups.iter().enumerate() {
            for (ch, c) in g.channels.iter().enumerate() {
                items.push(Item { dg, cg, ch });
                cands.push(Candidate {
                    full: format!("{}/{}", group_name(file, dg, cg), c.name),
                    short: Some(c.name.clone()),
                });
            }
        }
    }
    (items, cands)
}

/// The values of a decoded channel, invalid samples as NaN; `want` is the
/// sample count its group declares.
fn values(signal: &falcon_mdf::Signal, want: u64) -> R<Vec<f64>> {
    let vals = mdf("decoding", || signal.values())?;
    let mut v = match vals {
        SignalValues::U8(_)
        | SignalValues::U16(_)
        | SignalValues::U32(_)
        | SignalValues::U64(_)
        | SignalValues::I8(_)
        | SignalValues::I16(_)
        | SignalValues::I32(_)
        | SignalValues::I64(_)
        | SignalValues::F32(_) => vals.to_f64(),
        // Already f64: moved, not copied.
        SignalValues::F64(v) => v,
        other => {
            return Err(format!(
                "holds {} values; expected numbers",
                other.kind().name()
            ))
        }
    };
    if v.len() as u64 != want {
        return Err(format!(
            "{} values decoded of the {want} its group declares (truncated or damaged data)",
            v.len()
        ));
    }
    if let Some(valid) = contain(|| signal.validity()).flatten() {
        for (x, ok) in v.iter_mut().zip(valid) {
            if !ok {
                *x = f64::NAN;
            }
        }
    }
    Ok(v)
}

/// Parses an MDF 4 file held in memory into raw columns.
pub(crate) fn parse(path: &Path, bytes: &[u8], opts: &LoadOptions) -> Result<RawTable> {
    let file = open(path, bytes)?;
    let (items, cands) = items(&file);
    let err = |r: String| format_err(path, r);
    let has = || names::list(&cands.iter().map(|c| c.full.clone()).collect::<Vec<_>>());
    let label = |k: usize| excerpt(&cands[k].full);
    let channel_of = |k: usize| {
        let it = &items[k];
        &file.data_groups()[it.dg].channel_groups[it.cg].channels[it.ch]
    };
    // Which items feed which channel.
    let used = names::map_channels(&cands, opts, "").map_err(err)?;
    let groups: Vec<usize> = used.iter().map(|&(_, k)| k).collect();
    // Channels of different groups must share their time axis.
    let first = &items[groups[0]];
    for &k in &groups[1..] {
        let it = &items[k];
        if (it.dg, it.cg) != (first.dg, first.cg) {
            let master = |it: &Item| {
                file.master_channel(it.dg, it.cg).map(|m| {
                    mdf("master", || file.signal(m)).and_then(|s| mdf("master", || s.values_f64()))
                })
            };
            let same = match (master(first), master(it)) {
                (Some(Ok(a)), Some(Ok(b))) => {
                    a.len() == b.len() && a.iter().zip(&b).all(|(x, y)| x.to_bits() == y.to_bits())
                }
                _ => false,
            };
            if !same {
                return Err(err(format!(
                    "channels '{}' and '{}' are in groups with different time axes; \
                     they are not one recording",
                    label(groups[0]),
                    label(k)
                )));
            }
        }
    }
    let time_k = if opts.ignore_time {
        None
    } else if let Some(name) = &opts.time {
        Some(names::find(&cands, name).map_err(err)?.ok_or_else(|| {
            err(format!(
                "no channel '{}' for time; the file has: {}",
                excerpt(name),
                has()
            ))
        })?)
    } else {
        match file.master_channel(first.dg, first.cg) {
            None => None,
            Some(m) => {
                if m.sync_type != SyncType::Time {
                    return Err(err(format!(
                        "the master channel '{}' is not time ({:?}); give the sampling rate and \
                         ignore the time column",
                        excerpt(&m.name),
                        m.sync_type
                    )));
                }
                Some(
                    items
                        .iter()
                        .position(|it| {
                            (it.dg, it.cg) == (first.dg, first.cg)
                                && file.data_groups()[it.dg].channel_groups[it.cg].channels[it.ch]
                                    .id
                                    == m.id
                        })
                        .ok_or_else(|| err("the master channel is not in its group".into()))?,
                )
            }
        }
    };
    // Everything needed, decoded in one batch (each group's records are
    // assembled once).
    let mut needed: Vec<usize> = used.iter().map(|&(_, k)| k).chain(time_k).collect();
    needed.sort_unstable();
    needed.dedup();
    let chans: Vec<&falcon_mdf::Channel> = needed.iter().map(|&k| channel_of(k)).collect();
    let signals = mdf("reading", || file.signals(&chans)).map_err(err)?;
    let mut decoded: Vec<(usize, Vec<f64>)> = Vec::with_capacity(needed.len());
    for (&k, sig) in needed.iter().zip(&signals) {
        let it = &items[k];
        let want = file.data_groups()[it.dg].channel_groups[it.cg].sample_count;
        let v = values(sig, want).map_err(|r| err(format!("channel '{}': {r}", label(k))))?;
        decoded.push((k, v));
    }
    let uses =
        |k: usize| used.iter().filter(|&&(_, j)| j == k).count() + usize::from(time_k == Some(k));
    let mut take = |k: usize| -> RawColumn {
        // Moved out unless another channel reads the same item too.
        let shared = uses(k) > 1;
        let values = decoded
            .iter_mut()
            .find(|(j, _)| *j == k)
            .map(|(_, v)| if shared { v.clone() } else { std::mem::take(v) })
            .unwrap_or_default();
        let c = channel_of(k);
        RawColumn {
            name: label(k),
            values,
            resolution: 0.0,
            unit: (!c.unit.trim().is_empty())
                .then(|| (c.unit.trim().to_string(), format!("unit of '{}'", label(k)))),
        }
    };
    let channels: Vec<(Channel, RawColumn)> = used.iter().map(|&(c, k)| (c, take(k))).collect();
    let mut time_unit = None;
    let time = match time_k {
        None => None,
        Some(k) => {
            let mut col = take(k);
            if opts.time.is_none() {
                if let Some((u, from)) = col.unit.take() {
                    let unit = TimeUnit::parse(&u).ok_or_else(|| {
                        err(format!(
                            "the master channel is in '{}' ({from}); expected s, ms or us",
                            excerpt(&u)
                        ))
                    })?;
                    time_unit = Some((unit, from));
                }
            }
            Some(col)
        }
    };
    Ok(RawTable {
        time,
        time_unit,
        channels,
        locator: Locator::Samples,
        ..RawTable::default()
    })
}

/// What an MDF file holds, for `inspect`: groups and channels.
pub(crate) fn contents(path: &Path, bytes: &[u8], limit: usize) -> Result<Vec<(String, String)>> {
    let file = open(path, bytes)?;
    let (items, cands) = items(&file);
    let mut out = Vec::new();
    for (it, cand) in items.iter().zip(&cands).take(limit) {
        let g = &file.data_groups()[it.dg].channel_groups[it.cg];
        let c = &g.channels[it.ch];
        let master = if c.is_master() { ", master" } else { "" };
        let unit = if c.unit.trim().is_empty() {
            String::new()
        } else {
            format!(", unit {}", excerpt(&c.unit))
        };
        out.push((
            excerpt(&cand.full),
            format!(
                "channel, {:?}, {} samples{master}{unit}",
                c.data_type, g.sample_count
            ),
        ));
    }
    Ok(out)
}
