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

use anyhow::{Context, Result, bail};
use chopperscape::Config;
use serde::{Deserialize, Serialize};

use crate::episode::EpisodeResult;
use crate::options::rule_values;

/// The `format` field of every action log.
pub const FORMAT: &str = "chopperscape-actions";
/// The version this build reads and writes.
pub const VERSION: u64 = 1;
/// The environment id the rules belong to.
pub const ENV_ID: &str = "ChopperScape-v0";

/// Actions as written (a digit string) or as also accepted (an array of integers).
#[derive(Serialize, Deserialize, Debug, Clone)]
#[serde(untagged)]
enum Actions {
    Digits(String),
    List(Vec<i64>),
}

/// A saved episode.
#[derive(Serialize, Deserialize, Debug, Clone)]
struct Document {
    format: String,
    version: u64,
    env: String,
    seed: u64,
    options: BTreeMap<String, String>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    policy: Option<String>,
    steps: u32,
    #[serde(rename = "return")]
    ret: i64,
    cause: Option<String>,
    actions: Actions,
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
        format: FORMAT.into(),
        version: VERSION,
        env: ENV_ID.into(),
        seed: episode.seed,
        options: rule_values(config),
        policy: Some(policy.into()),
        steps: episode.steps,
        ret: episode.ret,
        cause: episode.cause.map(String::from),
        actions: Actions::Digits(episode.actions.iter().map(|a| char::from(b'0' + a)).collect()),
    };
    let mut text = serde_json::to_string_pretty(&doc).expect("an action log serializes");
    text.push('\n');
    text
}

/// Reads and checks an action log.
///
/// # Errors
/// An unreadable file, text that is not JSON, another format, version or env, an unknown option or a value out
/// of range, an action outside 0..=4, or a `steps` field that disagrees with the actions.
pub fn read(path: &Path) -> Result<ActionLog> {
    let text = std::fs::read_to_string(path).with_context(|| format!("cannot read action log {}", path.display()))?;
    parse(&text).with_context(|| format!("{} is not a usable action log", path.display()))
}

/// Parses and checks the text of an action log (see [`read`]).
pub fn parse(text: &str) -> Result<ActionLog> {
    let value: serde_json::Value = serde_json::from_str(text).context("damaged: not a JSON document")?;
    let field = |name: &str| value.get(name).cloned().unwrap_or(serde_json::Value::Null);
    if field("format") != FORMAT {
        bail!("the `format` field is {}, expected \"{FORMAT}\"", field("format"));
    }
    if field("version") != VERSION {
        bail!("action log version {} is not supported: this build reads version {VERSION}", field("version"));
    }
    if field("env") != ENV_ID {
        bail!("the log is for env {}, this build plays \"{ENV_ID}\"", field("env"));
    }
    let doc: Document = serde_json::from_value(value).context("damaged: a field is missing or has the wrong type")?;
    let mut config = Config::default();
    for (name, v) in &doc.options {
        config.set(name, v).context("damaged: bad option")?;
    }
    let actions: Vec<u8> = match &doc.actions {
        Actions::Digits(s) => s
            .bytes()
            .enumerate()
            .map(|(i, b)| match b {
                b'0'..=b'4' => Ok(b - b'0'),
                _ => bail!("damaged: action {i} is {:?}; actions are the digits 0..=4", char::from(b)),
            })
            .collect::<Result<_>>()?,
        Actions::List(v) => v
            .iter()
            .enumerate()
            .map(|(i, &a)| match a {
                0..=4 => Ok(a as u8),
                _ => bail!("damaged: action {i} is {a}; actions are 0..=4"),
            })
            .collect::<Result<_>>()?,
    };
    if actions.len() != doc.steps as usize {
        bail!("damaged: `steps` is {} but the log holds {} actions", doc.steps, actions.len());
    }
    Ok(ActionLog {
        seed: doc.seed,
        config,
        policy: doc.policy,
        steps: doc.steps,
        ret: doc.ret,
        cause: doc.cause,
        actions,
    })
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
