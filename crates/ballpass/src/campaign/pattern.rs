//! File-name patterns of folder mode: `*` matches any run of characters,
//! `{velocity}`, `{repeat}` and `{bearing}` match a non-empty run that is
//! captured as that field (`v{velocity}_r{repeat}.csv`).
//!
//! Matching is the two-pointer wildcard algorithm, O(name × pattern) in the
//! worst case and never exponential: a field is "one character, then `*`",
//! and on a mismatch only the most recent `*` takes one more character.
//! Earlier stars never need to grow: the literal run between two stars is
//! matched at its earliest place, which leaves the longest rest for the
//! later stars (the classic argument for glob matching). The captures are
//! those of the leftmost, shortest reading: each field as short as the rest
//! of the pattern allows, earlier fields first.

use crate::error::{Error, Result};

/// A captured field.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Field {
    /// `{velocity}`, mm/s (`p` reads as a decimal point: `12p5`).
    Velocity,
    /// `{repeat}`, a whole number.
    Repeat,
    /// `{bearing}`, a name.
    Bearing,
}

#[derive(Debug, Clone, Copy, PartialEq)]
enum Atom {
    /// One given character.
    Char(char),
    /// Any one character: the first of a field.
    AnyOne,
    /// Any run of characters; closes field `Some(i)` (index into the
    /// pattern's fields) when it follows that field's first character.
    Star(Option<usize>),
}

/// A parsed pattern.
#[derive(Debug, Clone, PartialEq)]
pub struct Pattern {
    text: String,
    atoms: Vec<Atom>,
    fields: Vec<Field>,
}

impl Pattern {
    /// Parses `p`.
    ///
    /// # Errors
    /// [`Error::InvalidSetting`] (`pattern`) for an unclosed `{` or an
    /// unknown field.
    pub fn parse(p: &str) -> Result<Self> {
        let mut atoms = Vec::new();
        let mut fields = Vec::new();
        let mut rest = p;
        while let Some(c) = rest.chars().next() {
            if c == '*' {
                atoms.push(Atom::Star(None));
                rest = &rest[1..];
            } else if c == '{' {
                let end = rest
                    .find('}')
                    .ok_or_else(|| Error::setting("pattern", format!("'{p}': unclosed '{{'")))?;
                let field = match &rest[1..end] {
                    "velocity" => Field::Velocity,
                    "repeat" => Field::Repeat,
                    "bearing" => Field::Bearing,
                    other => {
                        return Err(Error::setting(
                            "pattern",
                            format!("'{p}': unknown field {{{other}}} (expected {{velocity}}, {{repeat}} or {{bearing}})"),
                        ))
                    }
                };
                atoms.push(Atom::AnyOne);
                atoms.push(Atom::Star(Some(fields.len())));
                fields.push(field);
                rest = &rest[end + 1..];
            } else {
                atoms.push(Atom::Char(c));
                rest = &rest[c.len_utf8()..];
            }
        }
        Ok(Self {
            text: p.to_string(),
            atoms,
            fields,
        })
    }

    /// The pattern as written.
    pub fn as_str(&self) -> &str {
        &self.text
    }

    /// Whether the pattern captures `f`.
    pub fn has(&self, f: Field) -> bool {
        self.fields.contains(&f)
    }

    /// Matches a whole name; the captures in pattern order, or `None`.
    pub fn captures(&self, name: &str) -> Option<Vec<(Field, String)>> {
        let s: Vec<char> = name.chars().collect();
        let a = &self.atoms;
        // Where each atom matched: start index in `s` (for the captures).
        let mut at = vec![0usize; a.len() + 1];
        let (mut i, mut j) = (0usize, 0usize);
        // The latest star: its atom index and where its match ends now.
        let mut star: Option<(usize, usize)> = None;
        while i < s.len() {
            match a.get(j) {
                Some(Atom::Star(_)) => {
                    at[j] = i;
                    star = Some((j, i));
                    j += 1;
                }
                Some(Atom::Char(c)) if *c == s[i] => {
                    at[j] = i;
                    i += 1;
                    j += 1;
                }
                Some(Atom::AnyOne) => {
                    at[j] = i;
                    i += 1;
                    j += 1;
                }
                _ => {
                    // Mismatch: the latest star takes one more character.
                    let (sj, end) = star?;
                    star = Some((sj, end + 1));
                    i = end + 1;
                    j = sj + 1;
                }
            }
        }
        while let Some(Atom::Star(_)) = a.get(j) {
            at[j] = i;
            j += 1;
        }
        if j != a.len() {
            return None;
        }
        at[a.len()] = s.len();
        let mut caps = Vec::with_capacity(self.fields.len());
        for (k, atom) in a.iter().enumerate() {
            if let Atom::Star(Some(f)) = atom {
                // The field is its first character (atom k - 1) and this
                // star, which runs to where atom k + 1 starts.
                let from = at[k - 1];
                let to = at[k + 1];
                caps.push((self.fields[*f], s[from..to].iter().collect()));
            }
        }
        Some(caps)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn caps(p: &str, name: &str) -> Option<Vec<(Field, String)>> {
        Pattern::parse(p).unwrap().captures(name)
    }

    /// A slow, obviously correct matcher: every split tried, fields and
    /// stars shortest first (the reading [`Pattern::captures`] promises).
    fn reference(p: &Pattern, name: &str) -> Option<Vec<(Field, String)>> {
        fn go(a: &[Atom], s: &[char], k: usize, out: &mut Vec<(usize, usize)>) -> bool {
            let Some(first) = a.get(k) else {
                return s.is_empty();
            };
            match first {
                Atom::Char(c) => s.first() == Some(c) && go(a, &s[1..], k + 1, out),
                Atom::AnyOne => !s.is_empty() && go(a, &s[1..], k + 1, out),
                Atom::Star(_) => (0..=s.len()).any(|n| {
                    out.push((k, n));
                    let ok = go(a, &s[n..], k + 1, out);
                    if !ok {
                        out.pop();
                    }
                    ok
                }),
            }
        }
        let s: Vec<char> = name.chars().collect();
        let mut lens = Vec::new();
        if !go(&p.atoms, &s, 0, &mut lens) {
            return None;
        }
        // Rebuild the captures from the star lengths.
        let mut pos = 0;
        let mut caps = Vec::new();
        let mut star_len = lens.iter().copied();
        for atom in &p.atoms {
            match atom {
                Atom::Char(_) | Atom::AnyOne => pos += 1,
                Atom::Star(f) => {
                    let (_, n) = star_len.next().unwrap();
                    if let Some(f) = f {
                        caps.push((p.fields[*f], s[pos - 1..pos + n].iter().collect()));
                    }
                    pos += n;
                }
            }
        }
        Some(caps)
    }

    #[test]
    fn fields_capture_the_shortest_reading() {
        assert_eq!(
            caps("v{velocity}_r{repeat}.csv", "v12p5_r3.csv"),
            Some(vec![
                (Field::Velocity, "12p5".into()),
                (Field::Repeat, "3".into())
            ])
        );
        assert_eq!(
            caps("{velocity}_{repeat}.csv", "9_1_2.csv"),
            Some(vec![
                (Field::Velocity, "9".into()),
                (Field::Repeat, "1_2".into())
            ])
        );
        assert_eq!(caps("*.csv", "a.csv"), Some(vec![]));
        assert_eq!(caps("*.csv", "a.csv.bak"), None);
        assert_eq!(caps("{bearing}.csv", ".csv"), None);
        assert_eq!(caps("a*", "a"), Some(vec![]));
        assert_eq!(caps("", ""), Some(vec![]));
        assert_eq!(caps("", "x"), None);
    }

    /// Against the exhaustive matcher on many random short patterns and
    /// names over a two-letter alphabet (where backtracking matters most).
    #[test]
    fn agrees_with_the_exhaustive_matcher() {
        let mut state = 0x9e37_79b9_7f4a_7c15u64;
        let mut next = |n: u64| {
            state = state
                .wrapping_mul(6364136223846793005)
                .wrapping_add(1442695040888963407);
            (state >> 33) % n
        };
        for _ in 0..20_000 {
            let plen = next(7) as usize;
            let mut p = String::new();
            for _ in 0..plen {
                p.push_str(match next(5) {
                    0 => "*",
                    1 => "{repeat}",
                    2 => "{bearing}",
                    3 => "a",
                    _ => "b",
                });
            }
            let nlen = next(9) as usize;
            let name: String = (0..nlen)
                .map(|_| if next(2) == 0 { 'a' } else { 'b' })
                .collect();
            let pat = Pattern::parse(&p).unwrap();
            assert_eq!(pat.captures(&name), reference(&pat, &name), "{p} on {name}");
        }
    }

    /// Issue 18 item 7: `*a*a*a*a*a*b.csv` against a 200-character name
    /// took 11 s with 4 stars and over 120 s with 5 (backtracking). Now a
    /// few hundred thousand steps at most: this loop of 1000 matches would
    /// take hours with the old matcher.
    #[test]
    fn item7_pattern_matching_is_not_exponential() {
        let name = "a".repeat(200);
        let p = Pattern::parse("*a*a*a*a*a*a*a*a*a*a*b.csv").unwrap();
        for _ in 0..1000 {
            assert_eq!(p.captures(&name), None);
        }
        let p = Pattern::parse("{bearing}a{repeat}a{velocity}b.csv").unwrap();
        assert_eq!(p.captures(&name), None);
    }

    #[test]
    fn bad_patterns_are_errors() {
        assert!(Pattern::parse("v{velocity.csv").is_err());
        assert!(Pattern::parse("{speed}.csv").is_err());
    }
}
