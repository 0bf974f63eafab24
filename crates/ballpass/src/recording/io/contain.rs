//! Containment of third-party parsers: a panic becomes an error in our words.
//!
//! The HDF5 and MDF readers are hardened by their authors, but a file is
//! input from anywhere: every call into them runs under
//! [`std::panic::catch_unwind`], and a panic is reported as the file being
//! damaged, without the parser's internal message (which means nothing to
//! a user: "called `Option::unwrap()` on a `None` value").

use std::cell::Cell;
use std::panic::{catch_unwind, AssertUnwindSafe};
use std::sync::Once;

thread_local! {
    static CONTAINED: Cell<bool> = const { Cell::new(false) };
}

/// Runs `f`; `None` when it panicked. While `f` runs on this thread, the
/// panic message is not printed (other threads and other panics keep the
/// previous hook's behaviour).
pub(crate) fn contain<T>(f: impl FnOnce() -> T) -> Option<T> {
    static HOOK: Once = Once::new();
    HOOK.call_once(|| {
        let previous = std::panic::take_hook();
        std::panic::set_hook(Box::new(move |info| {
            if !CONTAINED.with(Cell::get) {
                previous(info);
            }
        }));
    });
    let was = CONTAINED.with(|c| c.replace(true));
    let r = catch_unwind(AssertUnwindSafe(f));
    CONTAINED.with(|c| c.set(was));
    r.ok()
}

/// A third-party error message reduced to one bounded, escaped line.
pub(crate) fn detail(e: &dyn std::fmt::Display) -> String {
    let text = e.to_string();
    let first = text
        .lines()
        .map(str::trim)
        .find(|l| !l.is_empty())
        .unwrap_or("no detail");
    crate::error::excerpt(first)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_panic_becomes_none_and_values_pass_through() {
        assert_eq!(contain(|| 7), Some(7));
        let r: Option<()> = contain(|| panic!("internal detail"));
        assert!(r.is_none());
        assert_eq!(detail(&"\n  first line\r\nsecond"), "first line");
    }
}
