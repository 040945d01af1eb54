//! Progress bars: shown only when standard error is a terminal and the output is not JSON.

use std::io::IsTerminal;

use indicatif::{ProgressBar, ProgressStyle};

/// A bar of `len` steps labelled `what`, or a hidden one when nobody is watching.
pub fn bar(len: u64, what: &str, json: bool) -> ProgressBar {
    if json || !std::io::stderr().is_terminal() {
        return ProgressBar::hidden();
    }
    let style = ProgressStyle::with_template("{msg:>10} [{bar:30}] {pos}/{len} {per_sec} eta {eta}")
        .expect("the template is valid")
        .progress_chars("=> ");
    ProgressBar::new(len).with_style(style).with_message(what.to_string())
}

/// A counter of steps labelled `what`, for an episode whose length is not known yet (hidden when nobody is
/// watching).
pub fn counter(what: &str, json: bool) -> ProgressBar {
    if json || !std::io::stderr().is_terminal() {
        return ProgressBar::hidden();
    }
    let style =
        ProgressStyle::with_template("{msg:>10} {spinner} {pos} steps ({per_sec})").expect("the template is valid");
    ProgressBar::new_spinner().with_style(style).with_message(what.to_string())
}
