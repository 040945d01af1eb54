//! Writing to standard output and standard error without panicking.
//!
//! `println!` panics when standard output is closed (`| head -1`) or full (`> /dev/full`), which ends the
//! program with exit code 101. Every line of the command line's output goes through [`line`] instead, whose
//! failure is a [`StdoutError`]: `main` ends quietly with 141 (128 + SIGPIPE, what a shell shows for a
//! program stopped by a closed pipe) for a closed pipe, and with a one-line error and 1 for anything else.
//! Messages on standard error go through [`error_line`], which ignores a closed or full standard error.

use std::io::Write;

/// Standard output could not be written.
#[derive(Debug)]
pub struct StdoutError(pub std::io::Error);

impl std::fmt::Display for StdoutError {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(f, "cannot write to standard output: {}", self.0)
    }
}

impl std::error::Error for StdoutError {}

/// Writes `text` and a newline to standard output, flushed at once (so a reader sees each line as it comes).
///
/// # Errors
/// A [`StdoutError`] when standard output is closed or cannot be written.
pub fn line(text: &str) -> anyhow::Result<()> {
    let mut out = std::io::stdout().lock();
    writeln!(out, "{text}").and_then(|()| out.flush()).map_err(|e| StdoutError(e).into())
}

/// Writes `text` and a newline to standard error; a closed or full standard error is ignored.
pub fn error_line(text: &str) {
    let _ = writeln!(std::io::stderr().lock(), "{text}");
}

/// Prints to standard output through [`line`]: `say!("{x}")?`.
#[macro_export]
macro_rules! say {
    ($($arg:tt)*) => {
        $crate::report::line(&format!($($arg)*))
    };
}

/// Prints to standard error through [`error_line`].
#[macro_export]
macro_rules! note {
    ($($arg:tt)*) => {
        $crate::report::error_line(&format!($($arg)*))
    };
}
