//! The difficulty modes of ChopperScape-Bench: a small ladder of named, versioned rule sets, declared once here
//! so that Python (`_core.MODES`, `mode=`), the command line and the page give each name the same meaning.
//!
//! A mode fixes **every rules option** (see [`OPTIONS`](crate::OPTIONS)) except `max_episode_steps`, which the
//! evaluation protocol states (10,000 agent steps): the options listed in [`Mode::options`] take those values,
//! every other rules option keeps its v0 default. Observation options (`obs_type`, `obs_size`, `frame_stack`,
//! `hud`, `hud_style`) stay free: they change what an agent sees, never the game.
//!
//! A mode is applied with [`Config::set`], so its values are validated by the same code as any option; a config
//! that contradicts a mode (an option given beside it with another value) is named by [`Mode::contradictions`].
//! A change to a rung's options is a new mode (`sticky-v1`, …); an existing name never changes meaning.
//!
//! Every surface (the command line's `--mode` and flags, Python's `mode=` and keyword options, the page's mode
//! menu and inputs) builds its config with [`configure`]: the mode first, then the options given beside it, then
//! one error if any of them contradicts the mode.
//!
//! ```
//! use chopperscape::{Config, ConfigError, configure, mode};
//!
//! let sticky = mode("sticky-v0").unwrap();
//! let mut config = Config::features();
//! sticky.apply(&mut config).unwrap();
//! assert_eq!(config.frame_skip, 4);
//! assert!(sticky.contradictions(&config).is_empty());
//! config.set("lives", "3").unwrap();
//! assert_eq!(sticky.contradictions(&config), ["lives 3 != 1"]);
//!
//! let set = |options: &'static [(&'static str, &'static str)]| {
//!     move |c: &mut Config| options.iter().try_for_each(|(name, value)| c.set(name, value))
//! };
//! let config = configure::<ConfigError>(Config::features(), Some(sticky), set(&[("hud", "false")])).unwrap();
//! assert_eq!((config.frame_skip, config.hud), (4, false));
//! let err = configure::<ConfigError>(Config::features(), Some(sticky), set(&[("lives", "3")])).unwrap_err();
//! assert_eq!(
//!     err.to_string(),
//!     "options contradict mode \"sticky-v0\", whose rules options are fixed (frame_skip=4, sticky_prob=0.25, \
//!      the others at their defaults): lives 3 != 1; drop them, or give no mode"
//! );
//! ```

use crate::config::{Config, OPTIONS};
use crate::error::ConfigError;

/// One rung of the ladder.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub struct Mode {
    /// The name `mode=` and `--mode` take, with its version (`"sticky-v0"`).
    pub name: &'static str,
    /// Its Gymnasium id (`gymnasium.make(id)` plays this mode).
    pub id: &'static str,
    /// What it is, in one line.
    pub doc: &'static str,
    /// The rules options it sets, as [`Config::set`] takes them; every other rules option keeps its default.
    pub options: &'static [(&'static str, &'static str)],
}

/// The ladder, easiest first. Each rung adds to the one before it.
pub const MODES: &[Mode] = &[
    Mode {
        name: "v0",
        id: "ChopperScape-v0",
        doc: "The tutorial's game exactly as SPEC.md states it: every rules option at its default",
        options: &[],
    },
    Mode {
        name: "sticky-v0",
        id: "ChopperScape-Sticky-v0",
        doc: "v0 with ALE v5's stochasticity: each action repeated for 4 steps, the previous one applied with \
              probability 0.25",
        options: &[("frame_skip", "4"), ("sticky_prob", "0.25")],
    },
    Mode {
        name: "full-v0",
        id: "ChopperScape-Full-v0",
        doc: "sticky-v0 with the tutorial's three extensions: 3 lives, alien birds firing missiles, birds and fuel \
              tanks destroying each other",
        options: &[
            ("frame_skip", "4"),
            ("sticky_prob", "0.25"),
            ("lives", "3"),
            ("alien_prob", "0.005"),
            ("bird_fuel_collision", "destroy"),
        ],
    },
];

/// The mode named `name` (as in [`MODES`]), if there is one.
pub fn mode(name: &str) -> Option<&'static Mode> {
    MODES.iter().find(|m| m.name == name)
}

/// Every mode's name, comma-separated: what an error about an unknown mode lists.
pub fn mode_names() -> String {
    MODES.iter().map(|m| m.name).collect::<Vec<_>>().join(", ")
}

/// A config built as every surface builds one: `mode` (if any) applied to `base` first, whatever the order the
/// options were given in; then `set` sets the options given beside it, in whatever form the surface reads them
/// (text flags, Python values, the page's inputs); then, with a mode, a rules option that contradicts it is
/// refused with one error naming the mode, what it fixes and every such option.
///
/// # Errors
/// What `set` returns, or [`ConfigError::ModeContradiction`] (through `E::from`).
pub fn configure<E: From<ConfigError>>(
    mut base: Config,
    mode: Option<&Mode>,
    set: impl FnOnce(&mut Config) -> Result<(), E>,
) -> Result<Config, E> {
    if let Some(mode) = mode {
        mode.apply(&mut base)?;
    }
    set(&mut base)?;
    if let Some(mode) = mode {
        mode.check(&base)?;
    }
    Ok(base)
}

/// The rules options a mode fixes: every rules option but `max_episode_steps` (the protocol's step limit).
fn fixed_names() -> impl Iterator<Item = &'static str> {
    OPTIONS.iter().filter(|o| o.rule && o.name != "max_episode_steps").map(|o| o.name)
}

impl Mode {
    /// Sets every rules option this mode fixes on `config` (its [`Mode::options`], the others to their
    /// defaults), through [`Config::set`]; observation options and `max_episode_steps` are left as they are.
    ///
    /// # Errors
    /// What [`Config::set`] says (never, for the modes of [`MODES`]: a test applies each).
    pub fn apply(&self, config: &mut Config) -> Result<(), ConfigError> {
        let mut next = config.clone();
        for name in fixed_names() {
            let default = OPTIONS.iter().find(|o| o.name == name).map_or("", |o| o.default);
            next.set(name, self.value(name).unwrap_or(default))?;
        }
        *config = next;
        Ok(())
    }

    /// The value this mode gives the rules option `name` as text, if it lists it.
    pub fn value(&self, name: &str) -> Option<&'static str> {
        self.options.iter().find(|(n, _)| *n == name).map(|&(_, v)| v)
    }

    /// The v0 config (rgb 600 × 800, 10,000-step limit) with this mode applied.
    ///
    /// # Errors
    /// As [`Mode::apply`].
    pub fn config(&self) -> Result<Config, ConfigError> {
        let mut config = Config::default();
        self.apply(&mut config)?;
        Ok(config)
    }

    /// What this mode fixes, in words: `"frame_skip=4, sticky_prob=0.25, the others at their defaults"`, or
    /// `"every rules option at its default"` for `v0`.
    pub fn fixed(&self) -> String {
        if self.options.is_empty() {
            return "every rules option at its default".into();
        }
        let set: Vec<String> = self.options.iter().map(|(n, v)| format!("{n}={v}")).collect();
        format!("{}, the others at their defaults", set.join(", "))
    }

    /// Checks that `config` plays this mode.
    ///
    /// # Errors
    /// [`ConfigError::ModeContradiction`] naming this mode, what it fixes and each of [`Mode::contradictions`].
    pub fn check(&self, config: &Config) -> Result<(), ConfigError> {
        let options = self.contradictions(config);
        if options.is_empty() {
            return Ok(());
        }
        Err(ConfigError::ModeContradiction { mode: self.name, fixed: self.fixed(), options })
    }

    /// The rules options of `config` that differ from this mode's, each as `name value != fixed` (values as
    /// [`Config::get`] writes them): empty when `config` plays this mode.
    pub fn contradictions(&self, config: &Config) -> Vec<String> {
        let Ok(fixed) = self.config() else { return vec![format!("mode {} does not apply", self.name)] };
        fixed_names()
            .filter_map(|name| {
                let (a, b) = (config.get(name)?, fixed.get(name)?);
                (a != b).then(|| format!("{name} {a} != {b}"))
            })
            .collect()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn every_mode_applies_and_names_are_unique() {
        for (i, m) in MODES.iter().enumerate() {
            let c = m.config().unwrap();
            assert!(m.contradictions(&c).is_empty(), "{}", m.name);
            assert_eq!(mode(m.name), Some(m));
            assert!(MODES[..i].iter().all(|o| o.name != m.name && o.id != m.id));
            for (name, _) in m.options {
                assert!(fixed_names().any(|n| n == *name), "{} sets {name}, not a fixed rules option", m.name);
            }
        }
        assert_eq!(mode("nope"), None);
    }

    #[test]
    fn v0_is_the_default_rules() {
        let v0 = mode("v0").unwrap();
        assert_eq!(v0.config().unwrap(), Config::default());
        assert!(v0.contradictions(&Config::features()).is_empty());
    }

    #[test]
    fn apply_resets_rules_but_keeps_observation_options() {
        let mut c = Config::features();
        c.set("lives", "5").unwrap();
        c.set("frame_stack", "4").unwrap();
        c.set("max_episode_steps", "none").unwrap();
        mode("full-v0").unwrap().apply(&mut c).unwrap();
        assert_eq!((c.lives, c.frame_skip, c.frame_stack, c.max_episode_steps), (3, 4, 4, None));
        mode("v0").unwrap().apply(&mut c).unwrap();
        assert_eq!((c.lives, c.frame_skip, c.alien_prob), (1, 1, 0.0));
    }

    #[test]
    fn configure_applies_the_mode_first_and_refuses_contradictions_in_one_error() {
        let full = mode("full-v0").unwrap();
        let given = |options: Vec<(&'static str, &'static str)>| {
            move |c: &mut Config| options.iter().try_for_each(|(n, v)| c.set(n, v))
        };
        // No mode: the options alone, on the base.
        let plain = configure::<ConfigError>(Config::features(), None, given(vec![("lives", "7")])).unwrap();
        assert_eq!((plain.lives, plain.obs_type), (7, crate::ObsType::Features));
        // The mode's rules, then options that agree with it or that it leaves free.
        let free = given(vec![("lives", "3"), ("max_episode_steps", "50"), ("frame_stack", "2")]);
        let c = configure::<ConfigError>(Config::features(), Some(full), free).unwrap();
        assert_eq!((c.lives, c.frame_skip, c.max_episode_steps, c.frame_stack), (3, 4, Some(50), 2));
        // Every contradiction in one error, naming the mode and what it fixes.
        let clash = given(vec![("lives", "7"), ("frame_skip", "2")]);
        let err = configure::<ConfigError>(Config::features(), Some(full), clash).unwrap_err();
        assert_eq!(
            err,
            ConfigError::ModeContradiction {
                mode: "full-v0",
                fixed: full.fixed(),
                options: vec!["lives 7 != 3".into(), "frame_skip 2 != 4".into()]
            }
        );
        assert!(err.to_string().starts_with("options contradict mode \"full-v0\", whose rules options are fixed"));
        // The setter's own error comes through unchanged.
        let bad = configure::<ConfigError>(Config::features(), Some(full), given(vec![("lives", "0")])).unwrap_err();
        assert!(matches!(bad, ConfigError::OutOfRange { option: "lives", .. }), "{bad}");
        assert_eq!(mode("v0").unwrap().fixed(), "every rules option at its default");
    }

    #[test]
    fn contradictions_name_each_option() {
        let sticky = mode("sticky-v0").unwrap();
        let mut c = sticky.config().unwrap();
        c.set("frame_skip", "2").unwrap();
        c.set("bird_prob", "0.02").unwrap();
        c.set("obs_type", "features").unwrap();
        assert_eq!(sticky.contradictions(&c), ["frame_skip 2 != 4", "bird_prob 0.02 != 0.01"]);
    }
}
