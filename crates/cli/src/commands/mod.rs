//! One file per command.

pub mod bench;
pub mod dataset;
pub mod demo;
pub mod play;
pub mod record;
pub mod replay;
pub mod web;

use clap::builder::PossibleValuesParser;

use crate::episode::EpisodeResult;

/// A clap parser for the built-in policy names.
pub fn policy_parser() -> PossibleValuesParser {
    PossibleValuesParser::new(chopperscape::policy::NAMES)
}

/// A clap parser for a seed, whose message gives the range.
pub fn seed_parser(s: &str) -> Result<u64, String> {
    s.trim().parse().map_err(|_| format!("{s} is not a seed: give a whole number in 0..={}", u64::MAX))
}

/// The header of the episode table.
pub fn table_header() -> String {
    format!("{:>7}  {:>6}  {:>6}  {:>7}  {}", "episode", "seed", "steps", "return", "cause")
}

/// One row of the episode table.
pub fn table_row(i: usize, e: &EpisodeResult) -> String {
    format!("{i:>7}  {:>6}  {:>6}  {:>7}  {}", e.seed, e.steps, e.ret, e.cause.unwrap_or("running"))
}

/// The summary under the table: mean steps, mean return and the share of each cause, counted as episodes end
/// (so a long run keeps no per-episode record).
#[derive(Debug, Default)]
pub struct Tally {
    episodes: u64,
    steps: f64,
    returns: f64,
    bird: u64,
    fuel: u64,
    truncated: u64,
}

impl Tally {
    /// Counts one finished episode.
    pub fn add(&mut self, e: &EpisodeResult) {
        self.episodes += 1;
        self.steps += f64::from(e.steps);
        self.returns += e.ret as f64;
        match e.cause {
            Some("bird") => self.bird += 1,
            Some("fuel") => self.fuel += 1,
            Some("truncated") => self.truncated += 1,
            _ => {}
        }
    }
}

impl std::fmt::Display for Tally {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        let n = self.episodes.max(1) as f64;
        let share = |c: u64| 100.0 * c as f64 / n;
        write!(
            f,
            "{} episodes: mean steps {:.1}, mean return {:.1}; causes: bird {:.0}%, fuel {:.0}%, truncated {:.0}%",
            self.episodes,
            self.steps / n,
            self.returns / n,
            share(self.bird),
            share(self.fuel),
            share(self.truncated)
        )
    }
}
