//! The action log: one played episode as a JSON document that `chopperscape replay` re-runs, and that
//! `chopperscape.integrations.datasets.from_action_logs` (Python) replays into a dataset. This crate is the one reader of
//! it, shared by the command line and the Python binding, so both accept and refuse exactly the same files.
//!
//! ```json
//! {"format": "chopperscape-actions", "version": 1, "env": "ChopperScape-v0", "seed": 3,
//!  "options": {"lives": "1", "alien_prob": "0", ...}, "policy": "human",
//!  "steps": 412, "return": 402, "cause": "bird", "actions": "44443333…"}
//! ```
//! `options` holds every rules option as `Config::set` name → value text; `actions` is a string of digits
//! (one per agent step; an array of integers is read too); `cause` is `null` for an episode stopped before
//! its end.

use std::collections::BTreeMap;
use std::io::Read;
use std::path::Path;

use anyhow::{Context, Result, bail};
use chopperscape::Config;
use serde::Serialize;

mod fields;

/// The `format` field of every action log.
pub const FORMAT: &str = "chopperscape-actions";
/// The version this build reads and writes.
pub const VERSION: u64 = 1;
/// The environment id the rules belong to.
pub const ENV_ID: &str = "ChopperScape-v0";

/// The largest action log [`read`] reads, in bytes. A log takes one byte per action (as digits), so this holds
/// an episode of over 60 million steps; a longer file is refused before it is parsed.
pub const MAX_LOG_BYTES: u64 = 64 << 20;

/// The document as written, for [`to_json`].
#[derive(Serialize)]
struct Document {
    format: &'static str,
    version: u64,
    env: &'static str,
    seed: u64,
    options: BTreeMap<String, String>,
    policy: Option<String>,
    steps: u32,
    #[serde(rename = "return")]
    ret: i64,
    cause: Option<&'static str>,
    actions: String,
}

/// A checked action log.
#[derive(Debug, Clone)]
pub struct ActionLog {
    /// The seed of `reset`.
    pub seed: u64,
    /// The rules, from the log's options.
    pub config: Config,
    /// Who played: a policy name, or `human`.
    pub policy: Option<String>,
    /// Agent steps the episode took.
    pub steps: u32,
    /// The episode return it reached.
    pub ret: i64,
    /// How it ended (`None`: stopped before the end).
    pub cause: Option<String>,
    /// Every action, 0..=4.
    pub actions: Vec<u8>,
}

/// One played episode, as [`to_json`] writes it.
#[derive(Debug, Clone, Copy)]
pub struct Played<'a> {
    /// The seed of `reset`.
    pub seed: u64,
    /// Agent steps taken.
    pub steps: u32,
    /// The episode return.
    pub ret: i64,
    /// `"bird"`, `"fuel"`, `"truncated"`, or `None` for an episode stopped before its end.
    pub cause: Option<&'static str>,
    /// Every action, 0..=4.
    pub actions: &'a [u8],
}

/// Every rules option of `config` (those [`chopperscape::OPTIONS`] marks `rule`) as `Config::set` name → value
/// text (what an action log stores).
pub fn rule_values(config: &Config) -> BTreeMap<String, String> {
    chopperscape::OPTIONS
        .iter()
        .filter(|o| o.rule)
        .filter_map(|o| Some((o.name.to_string(), config.get(o.name)?)))
        .collect()
}

/// Writes `episode`, played under `config` by `policy`, as an action log (JSON text).
pub fn to_json(config: &Config, policy: &str, episode: &Played<'_>) -> String {
    let doc = Document {
        format: FORMAT,
        version: VERSION,
        env: ENV_ID,
        seed: episode.seed,
        options: rule_values(config),
        policy: Some(policy.into()),
        steps: episode.steps,
        ret: episode.ret,
        cause: episode.cause,
        actions: episode.actions.iter().map(|a| char::from(b'0' + a)).collect(),
    };
    let mut text = serde_json::to_string_pretty(&doc).expect("an action log serializes");
    text.push('\n');
    text
}

/// Reads and checks an action log of at most [`MAX_LOG_BYTES`].
///
/// # Errors
/// An unreadable or too large file, text that is not JSON, another format, version or env, an unknown option
/// or a value out of range, an action outside 0..=4, or a `steps` field that disagrees with the actions.
pub fn read(path: &Path) -> Result<ActionLog> {
    let file = std::fs::File::open(path).with_context(|| format!("cannot read action log {}", path.display()))?;
    let mut bytes = Vec::new();
    file.take(MAX_LOG_BYTES + 1)
        .read_to_end(&mut bytes)
        .with_context(|| format!("cannot read action log {}", path.display()))?;
    if bytes.len() as u64 > MAX_LOG_BYTES {
        bail!(
            "{} is larger than {} MiB, the most an action log may be; it is not a log this program wrote",
            path.display(),
            MAX_LOG_BYTES >> 20
        );
    }
    parse_bytes(&bytes).with_context(|| format!("{} is not a usable action log", path.display()))
}

/// Parses and checks the text of an action log (see [`read`]).
///
/// # Errors
/// As [`parse_bytes`].
pub fn parse(text: &str) -> Result<ActionLog> {
    parse_bytes(text.as_bytes())
}

/// Parses and checks an action log's bytes; a UTF-8 byte order mark before the document is skipped.
///
/// The document is read straight into its fields (no JSON tree is built), so the memory it takes is about one
/// byte per action beside the text itself.
///
/// # Errors
/// Text that is not JSON (or nested deeper than serde_json's limit of 128), another format, version or env,
/// a field of the wrong type or out of range, an unknown option, an action outside 0..=4, or a `steps` field
/// that disagrees with the actions.
pub fn parse_bytes(bytes: &[u8]) -> Result<ActionLog> {
    let bytes = bytes.strip_prefix(b"\xEF\xBB\xBF").unwrap_or(bytes);
    let raw: fields::Raw = serde_json::from_slice(bytes).map_err(|e| {
        if e.is_syntax() || e.is_eof() {
            anyhow::Error::new(e).context("damaged: not a JSON document")
        } else {
            anyhow::Error::new(e).context("damaged")
        }
    })?;
    raw.check()
}

#[cfg(test)]
mod tests {
    use super::*;

    fn sample() -> String {
        let mut config = Config::default();
        config.set("lives", "2").unwrap();
        let actions = [3, 3, 4, 0, 1, 2, 4];
        let ep = Played { seed: 11, steps: 7, ret: 7, cause: None, actions: &actions };
        to_json(&config, "random", &ep)
    }

    #[test]
    fn rule_values_round_trip_through_config_set() {
        let mut c = Config::features();
        for (n, v) in [("lives", "3"), ("alien_prob", "0.125"), ("sticky_prob", "0.1"), ("max_episode_steps", "none")] {
            c.set(n, v).unwrap();
        }
        let values = rule_values(&c);
        assert_eq!(values.len(), 9);
        let mut back = Config::features();
        for (n, v) in &values {
            back.set(n, v).unwrap();
        }
        assert_eq!(back, c);
    }

    #[test]
    fn a_written_log_reads_back_with_its_options_and_actions() {
        let text = sample();
        let log = parse(&text).unwrap();
        assert_eq!(log.config.lives, 2);
        assert_eq!(log.seed, 11);
        assert_eq!(log.actions.len(), log.steps as usize);
        assert_eq!(log.policy.as_deref(), Some("random"));
    }

    #[test]
    fn another_version_is_refused_with_both_versions_named() {
        let text = sample().replace("\"version\": 1", "\"version\": 2");
        let err = format!("{:#}", parse(&text).unwrap_err());
        assert!(err.contains("version 2") && err.contains("version 1"), "{err}");
    }

    #[test]
    fn damaged_logs_are_refused() {
        let text = sample();
        for (bad, what) in [
            (text.replacen("\"actions\": \"", "\"actions\": \"7", 1), "digits 0..=4"),
            (text[..text.len() / 2].to_string(), "not a JSON document"),
            (text.replace("\"lives\": \"2\"", "\"lives\": \"0\""), "lives"),
            (text.replace("\"format\": \"chopperscape-actions\"", "\"format\": \"x\""), "format"),
        ] {
            let err = format!("{:#}", parse(&bad).unwrap_err());
            assert!(err.contains(what), "{what}: {err}");
        }
    }

    #[test]
    fn an_array_of_integers_is_accepted_for_actions() {
        let text = r#"{"format": "chopperscape-actions", "version": 1, "env": "ChopperScape-v0", "seed": 0,
            "options": {}, "steps": 3, "return": 3, "cause": null, "actions": [3, 3, 4]}"#;
        assert_eq!(parse(text).unwrap().actions, vec![3, 3, 4]);
    }
}
