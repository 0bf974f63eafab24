//! Matching the channel names a user gives against what a binary file holds
//! (MAT variables and signals, TDMS channels, MDF channels).
//!
//! A name matches a candidate's full name ignoring case (`Model Root/Load
//! cell/Force`, `Measurements/Force`), else its short name (`Force`) when
//! exactly one candidate has it; two candidates with that short name are an
//! error listing both, never a guess.

use crate::error::excerpt;

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
}
