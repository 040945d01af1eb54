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

/// The header of the episode table.
pub fn table_header() -> String {
    format!("{:>7}  {:>6}  {:>6}  {:>7}  {}", "episode", "seed", "steps", "return", "cause")
}

/// One row of the episode table.
pub fn table_row(i: usize, e: &EpisodeResult) -> String {
    format!("{i:>7}  {:>6}  {:>6}  {:>7}  {}", e.seed, e.steps, e.ret, e.cause.unwrap_or("running"))
}

/// The summary under the table: mean steps, mean return and the share of each cause.
pub fn summary(results: &[EpisodeResult]) -> String {
    let n = results.len().max(1) as f64;
    let mean_steps = results.iter().map(|e| f64::from(e.steps)).sum::<f64>() / n;
    let mean_return = results.iter().map(|e| e.ret as f64).sum::<f64>() / n;
    let share = |c: &str| 100.0 * results.iter().filter(|e| e.cause == Some(c)).count() as f64 / n;
    format!(
        "{} episodes: mean steps {mean_steps:.1}, mean return {mean_return:.1}; causes: bird {:.0}%, fuel {:.0}%, truncated {:.0}%",
        results.len(),
        share("bird"),
        share("fuel"),
        share("truncated")
    )
}
