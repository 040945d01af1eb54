//! One file per command.

pub mod bench;
pub mod dataset;
pub mod demo;
pub mod play;
pub mod record;
pub mod replay;
pub mod train;
pub mod web;

use std::path::PathBuf;

use anyhow::Result;
use chopperscape::Config;
use chopperscape_policy::Policy;
use clap::builder::PossibleValuesParser;

use crate::episode::{AnyPolicy, EpisodeResult};
use crate::options::GameOptions;
use crate::usage_bail;

/// A clap parser for the built-in policy names only (`dataset`).
pub fn policy_name_parser() -> PossibleValuesParser {
    PossibleValuesParser::new(chopperscape::policy::NAMES)
}

/// What `--policy` names: a built-in policy, or a trained policy exported by `python -m chopperscape.learn.export`.
#[derive(Clone, Debug, PartialEq, Eq)]
pub enum PolicyArg {
    /// A built-in policy (`chopperscape::policy::NAMES`).
    BuiltIn(String),
    /// An ONNX policy file.
    Model(PathBuf),
}

/// A clap parser for `--policy`: a built-in policy's name is always that policy (a file of that name is `./NAME`);
/// anything ending in `.onnx` or holding a `/` is a policy file.
pub fn policy_parser(s: &str) -> Result<PolicyArg, String> {
    let names = chopperscape::policy::NAMES;
    if names.contains(&s) {
        Ok(PolicyArg::BuiltIn(s.to_string()))
    } else if s.ends_with(".onnx") || s.contains(std::path::MAIN_SEPARATOR) || s.contains('/') {
        Ok(PolicyArg::Model(PathBuf::from(s)))
    } else {
        Err(format!(
            "{s:?} is not a built-in policy: give one of {}, or an exported policy file (NAME.onnx, from python -m \
             chopperscape.learn.export)",
            names.join(", ")
        ))
    }
}

impl PolicyArg {
    /// The name an action log records.
    pub fn name(&self) -> String {
        match self {
            PolicyArg::BuiltIn(name) => name.clone(),
            PolicyArg::Model(path) => path.display().to_string(),
        }
    }
}

/// A policy ready to play: a built-in one, or a loaded trained one.
pub enum LoadedPolicy {
    /// A built-in policy by name.
    BuiltIn(String),
    /// A trained policy.
    Model(Box<Policy>),
}

impl LoadedPolicy {
    /// The policy as `episode::play_policy` takes it.
    pub fn as_any(&mut self) -> AnyPolicy<'_> {
        match self {
            LoadedPolicy::BuiltIn(name) => AnyPolicy::BuiltIn(name),
            LoadedPolicy::Model(policy) => AnyPolicy::Model(policy),
        }
    }
}

/// The policy `--policy` names and the options to play it under. A built-in policy plays the v0 rules with the
/// flags given; a trained policy plays the options it was trained with (its metadata), each flag that changes
/// one of its rules said on stderr, and is refused (exit 2, naming both) if the env would not give the
/// observation it takes.
///
/// # Errors
/// A policy file that cannot be loaded, or options that do not fit it: [`crate::UsageError`].
pub fn policy_and_config(arg: &PolicyArg, options: &GameOptions) -> Result<(LoadedPolicy, Config)> {
    let path = match arg {
        PolicyArg::BuiltIn(name) => {
            return Ok((LoadedPolicy::BuiltIn(name.clone()), options.apply(Config::default())?));
        }
        PolicyArg::Model(path) => path,
    };
    let policy = match Policy::load(path) {
        Ok(policy) => policy,
        Err(e) => usage_bail!("--policy {}: {e}", path.display()),
    };
    let trained = match policy.config() {
        Ok(config) => config,
        Err(e) => usage_bail!("--policy {}: {e}", path.display()),
    };
    let played = options.apply(trained.clone())?;
    let pixels = trained.obs_type.is_pixels();
    for difference in trained.differences(&played) {
        // The step limit is how long to watch, not what the policy learned; the HUD's style is drawn only.
        let (name, values) = difference.split_once(' ').unwrap_or((&difference, ""));
        let (was, now) = values.split_once(" != ").unwrap_or((values, ""));
        if name != "max_episode_steps" && (pixels || name != "hud_style") {
            crate::note!(
                "warning: {} was trained with {name} {was}; it plays with {name} {now}, as given",
                path.display()
            );
        }
    }
    if let Err(e) = policy.check(&played) {
        usage_bail!("--policy {}: {e}", path.display());
    }
    Ok((LoadedPolicy::Model(Box::new(policy)), played))
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
