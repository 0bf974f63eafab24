//! A recording as a TDMS file, as LabVIEW's waveform logging writes one:
//! group `ballpass`, one float64 channel per channel present (named by its
//! column name, `unit_string` its unit), `wf_increment` and
//! `wf_start_offset` its timing, the data in segments of a chosen number of
//! samples (later segments carry the object list over, as NI writers do),
//! contiguous or interleaved. What the tests and the long-record bench
//! stream; [`super::parse`] reads it back to the bit.

use std::io::Write;
use std::path::Path;

use crate::error::Result;
use crate::recording::Recording;

use super::segments::{TOC_INTERLEAVED, TOC_META, TOC_NEW_OBJ_LIST, TOC_RAW, TY_STRING};

const VERSION: u32 = 4713;
const TY_DOUBLE: u32 = 10;
const GROUP: &str = "ballpass";

fn string(out: &mut Vec<u8>, s: &str) {
    out.extend_from_slice(&(s.len() as u32).to_le_bytes());
    out.extend_from_slice(s.as_bytes());
}

/// The metadata of a segment of `n` samples per channel (with the
/// properties in the first).
fn metadata(rec: &Recording, n: usize, first: bool) -> Vec<u8> {
    let mut m = Vec::new();
    let chans = rec.channels();
    let objects = if first { chans.len() + 2 } else { chans.len() };
    m.extend_from_slice(&(objects as u32).to_le_bytes());
    if first {
        for path in ["/".to_string(), format!("/'{GROUP}'")] {
            string(&mut m, &path);
            m.extend_from_slice(&u32::MAX.to_le_bytes());
            m.extend_from_slice(&0u32.to_le_bytes());
        }
    }
    for c in chans {
        string(&mut m, &format!("/'{GROUP}'/'{}'", c.column_name()));
        m.extend_from_slice(&20u32.to_le_bytes());
        m.extend_from_slice(&TY_DOUBLE.to_le_bytes());
        m.extend_from_slice(&1u32.to_le_bytes());
        m.extend_from_slice(&(n as u64).to_le_bytes());
        if !first {
            m.extend_from_slice(&0u32.to_le_bytes());
            continue;
        }
        m.extend_from_slice(&3u32.to_le_bytes());
        string(&mut m, "wf_increment");
        m.extend_from_slice(&TY_DOUBLE.to_le_bytes());
        m.extend_from_slice(&(1.0 / rec.fs_hz()).to_le_bytes());
        string(&mut m, "wf_start_offset");
        m.extend_from_slice(&TY_DOUBLE.to_le_bytes());
        m.extend_from_slice(&rec.meta.start_time_s.to_le_bytes());
        string(&mut m, "unit_string");
        m.extend_from_slice(&TY_STRING.to_le_bytes());
        string(&mut m, c.unit());
    }
    m
}

/// Writes `rec` to `path` as TDMS (module docs), `segment` samples per
/// segment (at least 1), interleaved or not. Written atomically.
///
/// # Errors
/// [`crate::Error::Io`] naming the file when it cannot be written.
pub fn write_tdms(rec: &Recording, path: &Path, segment: usize, interleaved: bool) -> Result<()> {
    crate::fsutil::write_atomic_with(path, |w| {
        let chans: Vec<&[f64]> = rec
            .channels()
            .into_iter()
            .filter_map(|c| rec.channel(c))
            .collect();
        let segment = segment.max(1);
        let mut at = 0;
        let mut last_n = None;
        let mut raw = Vec::new();
        while at < rec.len() {
            let n = segment.min(rec.len() - at);
            let mut toc = TOC_RAW;
            if interleaved {
                toc |= TOC_INTERLEAVED;
            }
            let meta = match last_n {
                None => metadata(rec, n, true),
                Some(m) if m != n => metadata(rec, n, false),
                Some(_) => Vec::new(),
            };
            if !meta.is_empty() {
                toc |= TOC_META;
            }
            if last_n.is_none() {
                toc |= TOC_NEW_OBJ_LIST;
            }
            raw.clear();
            if interleaved {
                for i in at..at + n {
                    for ch in &chans {
                        raw.extend_from_slice(&ch[i].to_le_bytes());
                    }
                }
            } else {
                for ch in &chans {
                    for x in &ch[at..at + n] {
                        raw.extend_from_slice(&x.to_le_bytes());
                    }
                }
            }
            w.write_all(b"TDSm")?;
            w.write_all(&toc.to_le_bytes())?;
            w.write_all(&VERSION.to_le_bytes())?;
            w.write_all(&((meta.len() + raw.len()) as u64).to_le_bytes())?;
            w.write_all(&(meta.len() as u64).to_le_bytes())?;
            w.write_all(&meta)?;
            w.write_all(&raw)?;
            last_n = Some(n);
            at += n;
        }
        Ok(())
    })
}
