//! Matching the channel names a user gives against what a binary file holds
//! (MAT variables and signals, TDMS channels, MDF channels).
//!
//! A name matches a candidate's full name ignoring case (`Model Root/Load
//! cell/Force`, `Measurements/Force`), else its short name (`Force`) when
//! exactly one candidate has it; two candidates with that short name are an
//! error listing both, never a guess.

use crate::error::excerpt;
use crate::recording::{Channel, LoadOptions};

/// Something in a file that may feed a channel.
#[derive(Debug, Clone)]
pub(crate) struct Candidate {
    /// Full name (a path with `/` for signals in groups).
    pub full: String,
    /// Last part of the full name, when it differs.
    pub short: Option<String>,
}

impl Candidate {
    /// A candidate named `full`, answering to its last `/`-separated part too.
    pub fn new(full: impl Into<String>) -> Self {
        let full = full.into();
        let short = full
            .rsplit('/')
            .next()
            .map(str::trim)
            .filter(|s| !s.is_empty() && *s != full)
            .map(str::to_string);
        Self { full, short }
    }
}

/// The candidate `want` names: `Ok(None)` when none does.
///
/// # Errors
/// The reason, listing them, when the short name is shared by several.
pub(crate) fn find(cands: &[Candidate], want: &str) -> Result<Option<usize>, String> {
    let want = want.trim();
    if let Some(i) = cands.iter().position(|c| c.full.eq_ignore_ascii_case(want)) {
        return Ok(Some(i));
    }
    let hits: Vec<usize> = cands
        .iter()
        .enumerate()
        .filter(|(_, c)| {
            c.short
                .as_deref()
                .is_some_and(|s| s.eq_ignore_ascii_case(want))
        })
        .map(|(i, _)| i)
        .collect();
    match hits.as_slice() {
        [] => Ok(None),
        [one] => Ok(Some(*one)),
        many => Err(format!(
            "'{}' names {} signals ({}); give the full name",
            excerpt(want),
            many.len(),
            list(
                &many
                    .iter()
                    .map(|&i| cands[i].full.clone())
                    .collect::<Vec<_>>()
            )
        )),
    }
}

/// The candidate feeding each channel: its mapped name (`opts`), else the
/// channel's default column name. A mapped name that matches nothing is an
/// error, and so is a file where no channel is found (`hint` follows the
/// expected names in that message).
///
/// # Errors
/// The reason, listing what the file has.
pub(crate) fn map_channels(
    cands: &[Candidate],
    opts: &LoadOptions,
    hint: &str,
) -> Result<Vec<(Channel, usize)>, String> {
    let has = || list(&cands.iter().map(|c| c.full.clone()).collect::<Vec<_>>());
    let mut used = Vec::new();
    for c in Channel::ALL {
        let mapped = opts.source(c).name.as_deref();
        let want = mapped.unwrap_or(c.column_name());
        match find(cands, want)? {
            Some(k) => used.push((c, k)),
            None if mapped.is_some() => {
                return Err(format!(
                    "no channel '{}' for {}; the file has: {}",
                    excerpt(want),
                    c.column_name(),
                    has()
                ))
            }
            None => {}
        }
    }
    if used.is_empty() {
        return Err(format!(
            "no channel found; expected friction_N, position_mm or optical_V (or mapped \
             names{hint}); the file has: {}",
            has()
        ));
    }
    Ok(used)
}

/// Names for a message: `'a', 'b', 'c'`, at most 20, then how many more.
pub(crate) fn list(names: &[String]) -> String {
    if names.is_empty() {
        return "nothing readable".into();
    }
    let shown: Vec<String> = names
        .iter()
        .take(20)
        .map(|n| format!("'{}'", excerpt(n)))
        .collect();
    match names.len() - shown.len() {
        0 => shown.join(", "),
        more => format!("{}, and {more} more", shown.join(", ")),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn full_then_unique_short_names() {
        let c = vec![
            Candidate::new("Model Root/Load cell/Force"),
            Candidate::new("Model Root/Encoder/Position"),
            Candidate::new("Group A/Voltage"),
            Candidate::new("Group B/Voltage"),
        ];
        assert_eq!(find(&c, "model root/load cell/force"), Ok(Some(0)));
        assert_eq!(find(&c, " Force "), Ok(Some(0)));
        assert_eq!(find(&c, "Position"), Ok(Some(1)));
        assert_eq!(find(&c, "Group B/Voltage"), Ok(Some(3)));
        assert_eq!(find(&c, "nothing"), Ok(None));
        let e = find(&c, "voltage").unwrap_err();
        assert!(e.contains("'Group A/Voltage', 'Group B/Voltage'"), "{e}");
    }

    #[test]
    fn long_lists_are_bounded() {
        let names: Vec<String> = (0..100).map(|i| format!("v{i}")).collect();
        let l = list(&names);
        assert!(l.ends_with("and 80 more"), "{l}");
    }

    /// Default names by their short form, a mapped name, and the two
    /// errors: a mapped name that matches nothing, and no channel at all.
    #[test]
    fn channels_map_by_default_or_given_names() {
        let cands: Vec<Candidate> = ["Bench/friction_N", "Bench/Encoder", "Bench/Other"]
            .into_iter()
            .map(Candidate::new)
            .collect();
        let mut o = LoadOptions::default();
        assert_eq!(
            map_channels(&cands, &o, "").unwrap(),
            vec![(Channel::Friction, 0)]
        );
        o.source_mut(Channel::Position).name = Some("encoder".into());
        assert_eq!(
            map_channels(&cands, &o, "").unwrap(),
            vec![(Channel::Friction, 0), (Channel::Position, 1)]
        );
        o.source_mut(Channel::Optical).name = Some("Light".into());
        let e = map_channels(&cands, &o, "").unwrap_err();
        assert!(
            e.contains("no channel 'Light' for optical_V") && e.contains("'Bench/Other'"),
            "{e}"
        );
        let none = [Candidate::new("G/x")];
        let e = map_channels(&none, &LoadOptions::default(), ", as Group/Channel").unwrap_err();
        assert!(
            e.contains("no channel found") && e.contains("names, as Group/Channel)"),
            "{e}"
        );
    }
}
