//! What an exported policy says about itself: the ONNX `metadata_props` that `python -m chopperscape.learn.export`
//! writes, one key each (the names below are the file format; `python/chopperscape/export.py` writes the same).

use chopperscape::{Config, ObsType};
use serde_json::Value;

use crate::PolicyError;

/// The format this crate reads: `metadata_props["format"]`.
pub const FORMAT: &str = "chopperscape-policy/1";

/// The `metadata_props` keys, as the exporter writes them.
pub mod keys {
    /// The format name and version, [`super::FORMAT`].
    pub const FORMAT: &str = "format";
    /// The observation type the policy takes (`"features"`, `"grayscale"`, `"rgb"`, `"rgb_float"`).
    pub const OBS_TYPE: &str = "obs_type";
    /// One observation's shape, a JSON list (`[46]`, `[84, 84, 4]`).
    pub const OBS_SHAPE: &str = "obs_shape";
    /// The env options the policy was trained with, a JSON object (`{"frame_skip": 4, "obs_size": [84, 84]}`).
    pub const ENV_OPTIONS: &str = "env_options";
    /// The features layout version the policy learned (the core's `FEATURES_VERSION`).
    pub const FEATURES_VERSION: &str = "features_version";
    /// The pixel layout version the policy learned (the core's `PIXELS_VERSION`).
    pub const PIXELS_VERSION: &str = "pixels_version";
    /// The SHA-256 of the model file it was exported from.
    pub const SOURCE_SHA256: &str = "source_sha256";
}

/// The metadata of an exported policy.
#[derive(Clone, Debug, PartialEq)]
pub struct Metadata {
    /// The observation type it takes.
    pub obs_type: ObsType,
    /// One observation's shape.
    pub obs_shape: Vec<usize>,
    /// The env options it was trained with, as `(name, value)` in the exporter's order, each value as
    /// `Config::set` reads it (`obs_size` `84x84`, `max_episode_steps` `none`).
    pub env_options: Vec<(String, String)>,
    /// The features layout version it learned.
    pub features_version: u32,
    /// The pixel layout version it learned.
    pub pixels_version: u32,
    /// The SHA-256 (hex) of the file it was exported from.
    pub source_sha256: String,
}

fn bad(key: &'static str, problem: impl Into<String>) -> PolicyError {
    PolicyError::Metadata { key, problem: crate::one_line(&problem.into()) }
}

impl Metadata {
    /// Reads the metadata from `(key, value)` pairs. Unknown keys are ignored (a later exporter may add some);
    /// a missing or malformed one is an error naming it.
    ///
    /// # Errors
    /// [`PolicyError::Metadata`] naming the first bad key; [`PolicyError::NotPolicy`] when `format` is absent.
    pub fn from_props<'a>(props: impl IntoIterator<Item = (&'a str, &'a str)>) -> Result<Metadata, PolicyError> {
        let props: Vec<(&str, &str)> = props.into_iter().collect();
        let get = |key: &'static str| props.iter().rev().find(|(k, _)| *k == key).map(|(_, v)| *v);
        let need = |key: &'static str| get(key).ok_or_else(|| bad(key, "is missing"));
        match get(keys::FORMAT) {
            None => return Err(PolicyError::NotPolicy("its metadata has no `format` entry".into())),
            Some(FORMAT) => {}
            Some(other) => return Err(bad(keys::FORMAT, format!("is {other:?}; this chopperscape reads {FORMAT:?}"))),
        }
        let obs_type: ObsType = need(keys::OBS_TYPE)?.parse().map_err(|e| bad(keys::OBS_TYPE, format!("{e}")))?;
        let obs_shape = parse_shape(need(keys::OBS_SHAPE)?)?;
        let env_options = parse_options(need(keys::ENV_OPTIONS)?)?;
        let version = |key: &'static str| -> Result<u32, PolicyError> {
            need(key)?.trim().parse().map_err(|_| bad(key, "must be a whole number"))
        };
        let features_version = version(keys::FEATURES_VERSION)?;
        let pixels_version = version(keys::PIXELS_VERSION)?;
        let source_sha256 = need(keys::SOURCE_SHA256)?.to_string();
        Ok(Metadata { obs_type, obs_shape, env_options, features_version, pixels_version, source_sha256 })
    }

    /// The env options the policy was trained with: `Config::default()` with its `obs_type` and `env_options`.
    ///
    /// # Errors
    /// [`PolicyError::Metadata`] naming an option `Config::set` refuses.
    /// A pixel policy that learned an older layout is shown that layout: the options that draw it
    /// (`chopperscape::render::layout_options`) come first, the policy's own over them.
    pub fn config(&self) -> Result<Config, PolicyError> {
        let mut config = Config { obs_type: self.obs_type, ..Config::default() };
        let layout = if self.obs_type.is_pixels() {
            chopperscape::render::layout_options(self.pixels_version).unwrap_or_default()
        } else {
            &[]
        };
        for &(name, value) in layout {
            config.set(name, value).map_err(|e| bad(keys::PIXELS_VERSION, format!("{e}")))?;
        }
        for (name, value) in &self.env_options {
            config.set(name, value).map_err(|e| bad(keys::ENV_OPTIONS, format!("holds {name}={value}: {e}")))?;
        }
        Ok(config)
    }

    /// Checks the layout version the policy learned against the ones this core draws: the features layout it
    /// computes, or a pixel layout it can still draw ([`Metadata::config`] selects it).
    ///
    /// # Errors
    /// [`PolicyError::Metadata`] naming the version that differs.
    pub fn check_versions(&self) -> Result<(), PolicyError> {
        let (key, learned, current) = if self.obs_type.is_pixels() {
            (keys::PIXELS_VERSION, self.pixels_version, chopperscape::render::PIXELS_VERSION)
        } else {
            (keys::FEATURES_VERSION, self.features_version, chopperscape::features::FEATURES_VERSION)
        };
        let drawn = self.obs_type.is_pixels() && chopperscape::render::layout_options(learned).is_some();
        if learned != current && !drawn {
            return Err(bad(
                key,
                format!("is {learned}: the policy learned layout v{learned}, and this chopperscape draws v{current}"),
            ));
        }
        Ok(())
    }
}

fn parse_shape(text: &str) -> Result<Vec<usize>, PolicyError> {
    let problem = "must be a JSON list of 1 to 3 sizes in 1..=4096";
    let v: Vec<u64> = serde_json::from_str(text).map_err(|_| bad(keys::OBS_SHAPE, problem))?;
    if !(1..=3).contains(&v.len()) || v.iter().any(|&d| !(1..=4096).contains(&d)) {
        return Err(bad(keys::OBS_SHAPE, problem));
    }
    let elements: u64 = v.iter().product();
    if elements > crate::MAX_OBSERVATION_ELEMENTS as u64 {
        return Err(bad(
            keys::OBS_SHAPE,
            format!(
                "is {v:?}: {elements} elements, more than the {} a policy may take",
                crate::MAX_OBSERVATION_ELEMENTS
            ),
        ));
    }
    Ok(v.into_iter().map(|d| d as usize).collect())
}

/// The options object as `(name, text)`: strings as they are, numbers and booleans as written, `null` as
/// `none`, and a list of two sizes as `HxW` (how `obs_size` is saved from Python).
fn parse_options(text: &str) -> Result<Vec<(String, String)>, PolicyError> {
    let Ok(Value::Object(map)) = serde_json::from_str::<Value>(text) else {
        return Err(bad(keys::ENV_OPTIONS, "must be a JSON object of option names and values"));
    };
    map.into_iter()
        .map(|(name, value)| {
            let text = match &value {
                Value::String(s) => s.clone(),
                Value::Number(n) => n.to_string(),
                Value::Bool(b) => b.to_string(),
                Value::Null => "none".to_string(),
                Value::Array(a) if a.len() == 2 && a.iter().all(Value::is_u64) => format!("{}x{}", a[0], a[1]),
                _ => return Err(bad(keys::ENV_OPTIONS, format!("holds {name}={value}, which is no option value"))),
            };
            Ok((name, text))
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    fn props(options: &str) -> Vec<(&'static str, String)> {
        vec![
            ("format", FORMAT.into()),
            ("obs_type", "grayscale".into()),
            ("obs_shape", "[84, 84, 4]".into()),
            ("env_options", options.into()),
            ("features_version", "2".into()),
            ("pixels_version", "2".into()),
            ("source_sha256", "ab".into()),
        ]
    }

    fn read(p: &[(&'static str, String)]) -> Result<Metadata, PolicyError> {
        Metadata::from_props(p.iter().map(|(k, v)| (*k, v.as_str())))
    }

    #[test]
    fn options_of_every_json_kind_become_config_values() {
        let m = read(&props(
            r#"{"obs_size": [84, 84], "frame_stack": 4, "frame_skip": 4, "hud": true, "sticky_prob": 0.25,
                "max_episode_steps": null, "hud_style": "gauge"}"#,
        ))
        .unwrap();
        let c = m.config().unwrap();
        assert_eq!((c.obs_type, c.obs_size, c.frame_stack, c.frame_skip), (ObsType::Grayscale, (84, 84), 4, 4));
        assert_eq!((c.sticky_prob, c.max_episode_steps, c.hud_style), (0.25, None, chopperscape::HudStyle::Gauge));
    }

    #[test]
    fn a_bad_entry_is_named() {
        let err = read(&props(r#"{"frame_skip": 0}"#)).unwrap().config().unwrap_err().to_string();
        assert!(err.contains("`env_options`") && err.contains("frame_skip=0"), "{err}");
        let mut p = props("{}");
        p[2].1 = "[84, -1]".into();
        assert!(read(&p).unwrap_err().to_string().contains("`obs_shape`"));
        p.remove(2);
        assert!(read(&p).unwrap_err().to_string().contains("`obs_shape` is missing"));
        let mut p = props("{}");
        p[0].1 = "chopperscape-policy/9".into();
        assert!(read(&p).unwrap_err().to_string().contains("`format`"));
    }

    /// A pixel policy is shown the layout it learned: version 2 the art, version 1 the art and the text HUD,
    /// this version the defaults; its own options win; a version from the future is refused by name.
    #[test]
    fn a_pixel_policy_sees_the_layout_it_learned() {
        use chopperscape::{HudStyle, Look};
        let with = |version: &str, options: &str| {
            let mut p = props(options);
            p[5].1 = version.into();
            read(&p).and_then(|m| m.check_versions().map(|()| m))
        };
        let look = |version: &str, options: &str| {
            let c = with(version, options).unwrap().config().unwrap();
            (c.look, c.hud_style)
        };
        assert_eq!(look("3", "{}"), (Look::Auto, HudStyle::Auto));
        assert_eq!(look("2", "{}"), (Look::Art, HudStyle::Auto));
        assert_eq!(look("1", "{}"), (Look::Art, HudStyle::Text));
        assert_eq!(look("2", r#"{"hud_style": "gauge"}"#), (Look::Art, HudStyle::Gauge));
        let err = with("4", "{}").unwrap_err().to_string();
        assert!(err.contains("`pixels_version`") && err.contains("v4") && err.contains("v3"), "{err}");
    }
}
