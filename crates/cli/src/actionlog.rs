//! The action log: one played episode as a JSON document that `chopperscape replay` re-runs.
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
use std::path::Path;

use std::io::Read;

use anyhow::{Context, Result, bail};
use chopperscape::Config;
use serde::Serialize;

mod fields;

use crate::episode::EpisodeResult;
use crate::options::rule_values;

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

/// Writes `episode`, played under `config` by `policy`, as an action log (JSON text).
pub fn to_json(config: &Config, policy: &str, episode: &EpisodeResult) -> String {
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
#[cfg(test)]
pub fn parse(text: &str) -> Result<ActionLog> {
    parse_bytes(text.as_bytes())
}

/// Parses and checks an action log's bytes; a UTF-8 byte order mark before the document is skipped.
///
/// The document is read straight into its fields (no JSON tree is built), so the memory it takes is about one
/// byte per action beside the text itself.
fn parse_bytes(bytes: &[u8]) -> Result<ActionLog> {
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
    use crate::episode::play_policy;

    fn sample() -> String {
        let mut config = Config::default();
        config.set("lives", "2").unwrap();
        let ep = play_policy(&config, "random", 11, |_| Ok(())).unwrap();
        to_json(&config, "random", &ep)
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
