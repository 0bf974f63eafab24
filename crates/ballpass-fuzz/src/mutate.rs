//! Mutations: byte and word changes aimed at length fields, insertions,
//! deletions, duplications, truncation, splicing with another seed, and
//! for text the tokens that change a reader's path (delimiters, quotes,
//! comments, `NaN`, huge numbers, decimal commas, units, escapes).

use crate::rng::Rng;

/// Largest mutated input, bytes.
pub const MAX_LEN: usize = 1 << 20;

const WORDS32: [u32; 12] = [
    0,
    1,
    7,
    8,
    14,
    15,
    0x7F,
    0xFFFF,
    0x7FFF_FFFF,
    0x8000_0000,
    0xFFFF_FFF8,
    0xFFFF_FFFF,
];

const TOKENS: [&str; 34] = [
    ",",
    ";",
    "\t",
    "\n",
    "\r\n",
    "\r",
    "\"",
    "#",
    "# end",
    "NaN",
    "nan",
    "inf",
    "-inf",
    "1e308",
    "1.7e308",
    "-1e307",
    "1e-320",
    "1,5",
    " ",
    "\u{1b}[31m",
    "time_ms",
    "[ms]",
    "µs",
    "\u{feff}",
    "\0",
    "=",
    "[",
    "]",
    "\"a\"",
    "99999999999999999999",
    "0.001",
    "time_s",
    "friction_N",
    "[kN]",
];

/// A mutation of `input` (`other`, another seed, is spliced in sometimes).
pub fn mutate(rng: &mut Rng, input: &[u8], other: &[u8], text: bool) -> Vec<u8> {
    let mut v = input.to_vec();
    let rounds = 1 + rng.below(4);
    for _ in 0..rounds {
        let len = v.len();
        match rng.below(if text { 11 } else { 9 }) {
            0 if len > 0 => {
                let i = rng.below(len);
                v[i] ^= 1 << rng.below(8);
            }
            1 if len > 0 => {
                let i = rng.below(len);
                v[i] = [0, 1, 0x7F, 0x80, 0xFF, b'0', b'9'][rng.below(7)];
            }
            2 if len >= 4 => {
                // A 32-bit field: an interesting value, or one near the size.
                let i = rng.below(len - 3) & !3;
                let w = if rng.one_in(3) {
                    (len as u32)
                        .wrapping_add(rng.below(17) as u32)
                        .wrapping_sub(8)
                } else {
                    WORDS32[rng.below(WORDS32.len())]
                };
                v[i..i + 4].copy_from_slice(&w.to_le_bytes());
            }
            3 if len >= 8 => {
                let i = rng.below(len - 7) & !7;
                let w: u64 = [0, 1, u64::MAX, 1 << 32, 1 << 40, len as u64 * 2][rng.below(6)];
                v[i..i + 8].copy_from_slice(&w.to_le_bytes());
            }
            4 => {
                let i = rng.below(len + 1);
                let n = 1 + rng.below(16);
                let ins: Vec<u8> = (0..n).map(|_| rng.next_u64() as u8).collect();
                v.splice(i..i, ins);
            }
            5 if len > 1 => {
                let i = rng.below(len);
                let n = 1 + rng.below((len - i).min(64));
                v.drain(i..i + n);
            }
            6 if len > 1 => {
                let i = rng.below(len);
                let n = 1 + rng.below((len - i).min(256));
                let chunk = v[i..i + n].to_vec();
                let at = rng.below(len + 1);
                v.splice(at..at, chunk);
            }
            7 if len > 1 => {
                v.truncate(rng.below(len));
            }
            8 if !other.is_empty() => {
                let i = rng.below(len + 1);
                let j = rng.below(other.len());
                v.truncate(i);
                v.extend_from_slice(&other[j..]);
            }
            9 | 10 if text => {
                let i = rng.below(len + 1);
                let t = TOKENS[rng.below(TOKENS.len())].as_bytes();
                if rng.one_in(2) || len == 0 {
                    v.splice(i..i, t.iter().copied());
                } else {
                    let n = (1 + rng.below(8)).min(len - i.min(len));
                    let i = i.min(len);
                    v.splice(i..(i + n).min(len), t.iter().copied());
                }
            }
            _ => {}
        }
        v.truncate(MAX_LEN);
    }
    v
}
