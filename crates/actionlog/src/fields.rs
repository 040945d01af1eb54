//! The fields of an action log as read: every one optional and of any scalar type, so that each check can say
//! which field is wrong and what it should be; `actions` is read straight into one byte per action.

use std::collections::BTreeMap;
use std::fmt;

use anyhow::{Result, bail};
use chopperscape::Config;
use serde::Deserialize;
use serde::de::{self, DeserializeSeed, Deserializer, SeqAccess, Visitor};

use super::{ActionLog, ENV_ID, FORMAT, VERSION};

/// A JSON string, number, boolean or null (an array or object is refused where a scalar belongs).
#[derive(Debug, Clone, PartialEq)]
pub enum Scalar {
    /// A string.
    Str(String),
    /// A number.
    Num(serde_json::Number),
    /// `true` or `false`.
    Bool(bool),
    /// `null`.
    Null,
}

impl fmt::Display for Scalar {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            Scalar::Str(s) => write!(f, "{}", serde_json::Value::String(s.clone())),
            Scalar::Num(n) => write!(f, "{n}"),
            Scalar::Bool(b) => write!(f, "{b}"),
            Scalar::Null => f.write_str("null"),
        }
    }
}

impl<'de> Deserialize<'de> for Scalar {
    fn deserialize<D: Deserializer<'de>>(d: D) -> Result<Scalar, D::Error> {
        struct V;
        impl<'de> Visitor<'de> for V {
            type Value = Scalar;
            fn expecting(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
                f.write_str("a string, a number, true, false or null")
            }
            fn visit_str<E: de::Error>(self, v: &str) -> Result<Scalar, E> {
                Ok(Scalar::Str(v.to_string()))
            }
            fn visit_u64<E: de::Error>(self, v: u64) -> Result<Scalar, E> {
                Ok(Scalar::Num(v.into()))
            }
            fn visit_i64<E: de::Error>(self, v: i64) -> Result<Scalar, E> {
                Ok(Scalar::Num(v.into()))
            }
            fn visit_f64<E: de::Error>(self, v: f64) -> Result<Scalar, E> {
                serde_json::Number::from_f64(v).map(Scalar::Num).ok_or_else(|| E::custom("a number that is not finite"))
            }
            fn visit_bool<E: de::Error>(self, v: bool) -> Result<Scalar, E> {
                Ok(Scalar::Bool(v))
            }
            fn visit_unit<E: de::Error>(self) -> Result<Scalar, E> {
                Ok(Scalar::Null)
            }
        }
        d.deserialize_any(V)
    }
}

/// The actions, 0..=4 each, from a string of digits or an array of integers.
#[derive(Debug, Default)]
pub struct Actions(pub Vec<u8>);

impl<'de> Deserialize<'de> for Actions {
    fn deserialize<D: Deserializer<'de>>(d: D) -> Result<Actions, D::Error> {
        struct V;
        impl<'de> Visitor<'de> for V {
            type Value = Actions;
            fn expecting(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
                f.write_str("`actions` as a string of the digits 0..=4 or an array of the integers 0..=4")
            }
            fn visit_str<E: de::Error>(self, s: &str) -> Result<Actions, E> {
                s.bytes()
                    .enumerate()
                    .map(|(i, b)| match b {
                        b'0'..=b'4' => Ok(b - b'0'),
                        _ => Err(E::custom(format_args!(
                            "action {i} is {:?}; actions are the digits 0..=4",
                            s[i..].chars().next().unwrap_or('?')
                        ))),
                    })
                    .collect::<Result<_, E>>()
                    .map(Actions)
            }
            fn visit_seq<A: SeqAccess<'de>>(self, mut seq: A) -> Result<Actions, A::Error> {
                let mut actions = Vec::with_capacity(seq.size_hint().unwrap_or(0).min(1 << 20));
                while let Some(a) = seq.next_element_seed(Action(actions.len()))? {
                    actions.push(a);
                }
                Ok(Actions(actions))
            }
        }
        d.deserialize_any(V)
    }
}

/// One action of an array, knowing its index for the message.
struct Action(usize);

impl<'de> DeserializeSeed<'de> for Action {
    type Value = u8;
    fn deserialize<D: Deserializer<'de>>(self, d: D) -> Result<u8, D::Error> {
        d.deserialize_any(self)
    }
}

impl Visitor<'_> for Action {
    type Value = u8;
    fn expecting(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "action {} as an integer 0..=4", self.0)
    }
    fn visit_u64<E: de::Error>(self, v: u64) -> Result<u8, E> {
        match v {
            0..=4 => Ok(v as u8),
            _ => Err(E::custom(format_args!("action {} is {v}; actions are 0..=4", self.0))),
        }
    }
    fn visit_i64<E: de::Error>(self, v: i64) -> Result<u8, E> {
        Err(E::custom(format_args!("action {} is {v}; actions are 0..=4", self.0)))
    }
}

/// Every field of an action log, unchecked.
#[derive(Deserialize, Debug, Default)]
pub struct Raw {
    format: Option<Scalar>,
    version: Option<Scalar>,
    env: Option<Scalar>,
    seed: Option<Scalar>,
    options: Option<BTreeMap<String, Scalar>>,
    policy: Option<Scalar>,
    steps: Option<Scalar>,
    #[serde(rename = "return")]
    ret: Option<Scalar>,
    cause: Option<Scalar>,
    actions: Option<Actions>,
}

/// `field` as shown in a message: its JSON text, or `missing`.
fn shown(field: &Option<Scalar>) -> String {
    field.as_ref().map_or_else(|| "missing".to_string(), Scalar::to_string)
}

/// A whole number field within `T`'s range.
fn whole<T: TryFrom<u64> + TryFrom<i64>>(name: &str, field: &Option<Scalar>, range: &str) -> Result<T> {
    let n = match field {
        Some(Scalar::Num(n)) => {
            n.as_u64().and_then(|v| T::try_from(v).ok()).or_else(|| n.as_i64().and_then(|v| T::try_from(v).ok()))
        }
        _ => None,
    };
    n.ok_or_else(|| anyhow::anyhow!("damaged: `{name}` is {}; it must be a whole number in {range}", shown(field)))
}

impl Raw {
    /// Checks every field, in the order that gives the most useful message first (what the file is, then
    /// what it holds).
    pub fn check(self) -> Result<ActionLog> {
        if self.format != Some(Scalar::Str(FORMAT.into())) {
            bail!("the `format` field is {}, expected \"{FORMAT}\"", shown(&self.format));
        }
        if self.version != Some(Scalar::Num(VERSION.into())) {
            bail!("action log version {} is not supported: this build reads version {VERSION}", shown(&self.version));
        }
        if self.env != Some(Scalar::Str(ENV_ID.into())) {
            bail!("the log is for env {}, this build plays \"{ENV_ID}\"", shown(&self.env));
        }
        let seed: u64 = whole("seed", &self.seed, "0..=18446744073709551615")?;
        let steps: u32 = whole("steps", &self.steps, "0..=4294967295")?;
        let ret: i64 = whole("return", &self.ret, "-9223372036854775808..=9223372036854775807")?;
        let Some(options) = self.options else { bail!("damaged: the `options` object is missing") };
        let mut config = Config::default();
        for (name, value) in &options {
            let text = match value {
                Scalar::Str(s) => s.clone(),
                other => other.to_string(),
            };
            config.set(name, &text).map_err(|e| anyhow::anyhow!("damaged: bad option: {e}"))?;
        }
        let policy = match self.policy {
            None | Some(Scalar::Null) => None,
            Some(Scalar::Str(s)) => Some(s),
            Some(other) => bail!("damaged: `policy` is {other}; it must be a string or null"),
        };
        let cause = match self.cause {
            None | Some(Scalar::Null) => None,
            Some(Scalar::Str(s)) if ["bird", "fuel", "truncated"].contains(&s.as_str()) => Some(s),
            Some(other) => bail!("damaged: `cause` is {other}; it must be \"bird\", \"fuel\", \"truncated\" or null"),
        };
        let Some(Actions(actions)) = self.actions else { bail!("damaged: the `actions` field is missing") };
        if actions.len() != steps as usize {
            bail!("damaged: `steps` is {steps} but the log holds {} actions", actions.len());
        }
        Ok(ActionLog { seed, config, policy, steps, ret, cause, actions })
    }
}
