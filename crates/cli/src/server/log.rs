//! Warnings about refused connections and failed accepts, at most one line a second per kind, so a flood
//! of connections cannot flood the terminal too.

use std::time::{Duration, Instant};

/// Counts events of one kind and prints a line for them at most once per [`Throttled::EVERY`].
pub struct Throttled {
    last: Option<Instant>,
    unreported: u64,
}

impl Throttled {
    /// The shortest time between two lines.
    pub const EVERY: Duration = Duration::from_secs(1);

    /// Nothing counted yet.
    pub fn new() -> Throttled {
        Throttled { last: None, unreported: 0 }
    }

    /// Counts one event; prints `line(n)` (n: events since the last line, this one included) unless a line
    /// was printed less than [`Throttled::EVERY`] ago.
    pub fn note(&mut self, line: impl FnOnce(u64) -> String) {
        self.unreported += 1;
        let now = Instant::now();
        if self.last.is_none_or(|t| now.duration_since(t) >= Self::EVERY) {
            crate::note!("{}", line(self.unreported));
            self.unreported = 0;
            self.last = Some(now);
        }
    }
}
