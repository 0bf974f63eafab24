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

pub mod stream;

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

/// The error for a file that does not start as an MDF file does; `head`
/// is its first bytes.
fn check_magic(path: &Path, head: &[u8]) -> Result<()> {
    if head.starts_with(b"MDF     ") {
        return Ok(());
    }
    Err(format_err(
        path,
        if head.is_empty() {
            "file is empty; expected an MDF 4 file".to_string()
        } else {
            "not an MDF file (it does not start with 'MDF')".to_string()
        },
    ))
}

/// How a file of `len` bytes is opened: the reader's allocations bounded
/// by what the file can hold.
fn open_options(len: usize) -> OpenOptions {
    OpenOptions {
        build_channels_db: true,
        parallel_parsing: false,
        parallel_threshold: usize::MAX,
        // A buffer sized from a number in the file never exceeds the file.
        max_alloc: len.clamp(1 << 16, 64 << 20),
        // Nothing decompresses past 1032:1 (deflate's limit).
        max_decompressed: (len as u64).saturating_mul(1032).saturating_add(1 << 20),
    }
}

fn open(path: &Path, bytes: &[u8]) -> Result<Mf4File> {
    check_magic(path, bytes)?;
    let options = open_options(bytes.len());
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

/// The channels of a file and which of them feed which channel of the
/// recording: what the whole-file and the streamed reader both start from.
struct Mapping {
    items: Vec<Item>,
    cands: Vec<Candidate>,
    /// Each channel of the recording and the item it is read from.
    used: Vec<(Channel, usize)>,
}

impl Mapping {
    /// Maps the channels `opts` asks for onto the items of `file`.
    fn new(path: &Path, file: &Mf4File, opts: &LoadOptions) -> Result<Self> {
        let (items, cands) = items(file);
        let used = names::map_channels(&cands, opts, "").map_err(|r| format_err(path, r))?;
        Ok(Mapping { items, cands, used })
    }

    fn label(&self, k: usize) -> String {
        excerpt(&self.cands[k].full)
    }

    fn channel<'f>(&self, file: &'f Mf4File, k: usize) -> &'f falcon_mdf::Channel {
        let it = &self.items[k];
        &file.data_groups()[it.dg].channel_groups[it.cg].channels[it.ch]
    }

    /// The item of the first channel used: its group is the record's.
    fn first(&self) -> &Item {
        &self.items[self.used[0].1]
    }

    /// The items used from another group than the first one's.
    fn other_groups(&self) -> impl Iterator<Item = usize> + '_ {
        let first = self.first();
        self.used
            .iter()
            .map(|&(_, k)| k)
            .filter(move |&k| (self.items[k].dg, self.items[k].cg) != (first.dg, first.cg))
    }

    /// The item read as time: the one `opts` names, else the master
    /// channel of the first channel's group (which must be time); none
    /// when the time is ignored or the group has no master.
    fn time_item(&self, path: &Path, file: &Mf4File, opts: &LoadOptions) -> Result<Option<usize>> {
        let err = |r: String| format_err(path, r);
        let first = self.first();
        if opts.ignore_time {
            return Ok(None);
        }
        if let Some(name) = &opts.time {
            let has = || {
                names::list(
                    &self
                        .cands
                        .iter()
                        .map(|c| c.full.clone())
                        .collect::<Vec<_>>(),
                )
            };
            return Ok(Some(
                names::find(&self.cands, name)
                    .map_err(err)?
                    .ok_or_else(|| {
                        err(format!(
                            "no channel '{}' for time; the file has: {}",
                            excerpt(name),
                            has()
                        ))
                    })?,
            ));
        }
        let Some(m) = file.master_channel(first.dg, first.cg) else {
            return Ok(None);
        };
        if m.sync_type != SyncType::Time {
            return Err(err(format!(
                "the master channel '{}' is not time ({:?}); give the sampling rate and \
                 ignore the time column",
                excerpt(&m.name),
                m.sync_type
            )));
        }
        self.items
            .iter()
            .position(|it| {
                (it.dg, it.cg) == (first.dg, first.cg)
                    && file.data_groups()[it.dg].channel_groups[it.cg].channels[it.ch].id == m.id
            })
            .map(Some)
            .ok_or_else(|| err("the master channel is not in its group".into()))
    }

    /// Item `k` as a raw column holding `values`, named and with its unit.
    fn column(&self, file: &Mf4File, k: usize, values: Vec<f64>) -> RawColumn {
        let c = self.channel(file, k);
        RawColumn {
            name: self.label(k),
            values,
            resolution: 0.0,
            unit: (!c.unit.trim().is_empty()).then(|| {
                (
                    c.unit.trim().to_string(),
                    format!("unit of '{}'", self.label(k)),
                )
            }),
        }
    }
}

/// The unit a master channel read as time states (taken out of `col`),
/// when no time channel is named.
fn time_unit(
    path: &Path,
    col: &mut RawColumn,
    opts: &LoadOptions,
) -> Result<Option<(TimeUnit, String)>> {
    if opts.time.is_some() {
        return Ok(None);
    }
    let Some((u, from)) = col.unit.take() else {
        return Ok(None);
    };
    let unit = TimeUnit::parse(&u).ok_or_else(|| {
        format_err(
            path,
            format!(
                "the master channel is in '{}' ({from}); expected s, ms or us",
                excerpt(&u)
            ),
        )
    })?;
    Ok(Some((unit, from)))
}

/// Parses an MDF 4 file held in memory into raw columns.
pub(crate) fn parse(path: &Path, bytes: &[u8], opts: &LoadOptions) -> Result<RawTable> {
    let file = open(path, bytes)?;
    let map = Mapping::new(path, &file, opts)?;
    let err = |r: String| format_err(path, r);
    // Channels of different groups must share their time axis.
    let first = map.first();
    let master = |it: &Item| {
        file.master_channel(it.dg, it.cg).map(|m| {
            mdf("master", || file.signal(m)).and_then(|s| mdf("master", || s.values_f64()))
        })
    };
    for k in map.other_groups() {
        let same = match (master(first), master(&map.items[k])) {
            (Some(Ok(a)), Some(Ok(b))) => {
                a.len() == b.len() && a.iter().zip(&b).all(|(x, y)| x.to_bits() == y.to_bits())
            }
            _ => false,
        };
        if !same {
            return Err(err(format!(
                "channels '{}' and '{}' are in groups with different time axes; \
                 they are not one recording",
                map.label(map.used[0].1),
                map.label(k)
            )));
        }
    }
    let time_k = map.time_item(path, &file, opts)?;
    let used = &map.used;
    // Everything needed, decoded in one batch (each group's records are
    // assembled once).
    let mut needed: Vec<usize> = used.iter().map(|&(_, k)| k).chain(time_k).collect();
    needed.sort_unstable();
    needed.dedup();
    let chans: Vec<&falcon_mdf::Channel> = needed.iter().map(|&k| map.channel(&file, k)).collect();
    let signals = mdf("reading", || file.signals(&chans)).map_err(err)?;
    let mut decoded: Vec<(usize, Vec<f64>)> = Vec::with_capacity(needed.len());
    for (&k, sig) in needed.iter().zip(&signals) {
        let it = &map.items[k];
        let want = file.data_groups()[it.dg].channel_groups[it.cg].sample_count;
        let v = values(sig, want).map_err(|r| err(format!("channel '{}': {r}", map.label(k))))?;
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
        map.column(&file, k, values)
    };
    let channels: Vec<(Channel, RawColumn)> = used.iter().map(|&(c, k)| (c, take(k))).collect();
    let mut time_unit_found = None;
    let time = match time_k {
        None => None,
        Some(k) => {
            let mut col = take(k);
            time_unit_found = time_unit(path, &mut col, opts)?;
            Some(col)
        }
    };
    Ok(RawTable {
        time,
        time_unit: time_unit_found,
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
