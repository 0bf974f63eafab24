//! Units a file states for its columns (a units row, `Force [kN]`,
//! `time_ms`, a TDMS `unit_string`, an MDF unit), and the factors that take
//! them to the channel's unit.

use crate::recording::Channel;

/// The unit a column name states: the text in brackets or parentheses at
/// its end (`Force [kN]`, `Zeit (ms)`), or after a last `/` (`time/s`),
/// ` in ` (`time in ms`) or `_` (`time_ms`, `friction_N`) when that is a
/// time unit or a unit of one of the channels (so that a block path such
/// as `Model Root/Load cell/Force` states none).
pub(crate) fn unit_of_name(name: &str) -> Option<&str> {
    let n = name.trim();
    for (open, close) in [('[', ']'), ('(', ')')] {
        if let Some(inner) = n.strip_suffix(close) {
            if let Some(p) = inner.rfind(open) {
                let u = inner[p + 1..].trim();
                return (!u.is_empty()).then_some(u);
            }
        }
    }
    let known = |u: &str| {
        super::TimeUnit::parse(u).is_some()
            || Channel::ALL.iter().any(|&c| channel_factor(c, u).is_some())
    };
    let lower = n.to_ascii_lowercase();
    let candidates = [
        n.rfind('/').map(|p| &n[p + 1..]),
        lower.rfind(" in ").map(|p| &n[p + 4..]),
        n.rfind('_').map(|p| &n[p + 1..]),
    ];
    candidates
        .into_iter()
        .flatten()
        .map(str::trim)
        .find(|u| !u.is_empty() && known(u))
}

/// Factor from `unit` to the channel's unit (N, mm, V), `None` when the
/// unit is not one ballpass knows for that channel.
pub(crate) fn channel_factor(c: Channel, unit: &str) -> Option<f64> {
    let u = unit.trim().trim_matches(|ch| ch == '[' || ch == ']');
    let lower = u.to_lowercase();
    let micro = |s: &str| {
        s.strip_prefix('µ')
            .or_else(|| s.strip_prefix('μ'))
            .or_else(|| s.strip_prefix('u'))
            .map(str::to_string)
    };
    match c {
        Channel::Friction => match u {
            "N" => Some(1.0),
            "kN" => Some(1e3),
            "mN" => Some(1e-3),
            _ => match lower.as_str() {
                "newton" | "newtons" => Some(1.0),
                "kilonewton" | "kilonewtons" => Some(1e3),
                _ => None,
            },
        },
        Channel::Position => match lower.as_str() {
            "mm" | "millimeter" | "millimeters" | "millimetre" | "millimetres" => Some(1.0),
            "m" | "meter" | "meters" | "metre" | "metres" => Some(1e3),
            "cm" => Some(10.0),
            "nm" => Some(1e-6),
            other if micro(other).as_deref() == Some("m") => Some(1e-3),
            "micron" | "microns" | "micrometer" | "micrometers" => Some(1e-3),
            _ => None,
        },
        Channel::Optical => match u {
            "V" | "v" => Some(1.0),
            "mV" => Some(1e-3),
            "kV" => Some(1e3),
            other if micro(other).as_deref() == Some("V") => Some(1e-6),
            _ => match lower.as_str() {
                "volt" | "volts" => Some(1.0),
                "millivolt" | "millivolts" => Some(1e-3),
                _ => None,
            },
        },
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn units_are_read_from_names() {
        assert_eq!(unit_of_name("time_ms"), Some("ms"));
        assert_eq!(unit_of_name("time_s"), Some("s"));
        assert_eq!(unit_of_name("Force [kN]"), Some("kN"));
        assert_eq!(unit_of_name("Zeit (µs)"), Some("µs"));
        assert_eq!(unit_of_name("time/s"), Some("s"));
        assert_eq!(unit_of_name("time in ms"), Some("ms"));
        assert_eq!(unit_of_name("friction_N"), Some("N"));
        assert_eq!(unit_of_name("Force_1"), None);
        assert_eq!(unit_of_name("time"), None);
        assert_eq!(unit_of_name("x []"), None);
        assert_eq!(unit_of_name("Model Root/Load cell/Force"), None);
        assert_eq!(unit_of_name("Model Root/Encoder/um"), Some("um"));
    }

    #[test]
    fn channel_units_convert_to_n_mm_v() {
        assert_eq!(channel_factor(Channel::Friction, "kN"), Some(1e3));
        assert_eq!(channel_factor(Channel::Friction, "N"), Some(1.0));
        assert_eq!(channel_factor(Channel::Position, "µm"), Some(1e-3));
        assert_eq!(channel_factor(Channel::Position, "um"), Some(1e-3));
        assert_eq!(channel_factor(Channel::Position, "m"), Some(1e3));
        assert_eq!(channel_factor(Channel::Optical, "mV"), Some(1e-3));
        assert_eq!(channel_factor(Channel::Position, "counts"), None);
        assert_eq!(channel_factor(Channel::Friction, "V"), None);
    }
}
