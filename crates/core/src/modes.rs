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
//! ```
//! use chopperscape::{Config, mode};
//!
//! let sticky = mode("sticky-v0").unwrap();
//! let mut config = Config::features();
//! sticky.apply(&mut config).unwrap();
//! assert_eq!(config.frame_skip, 4);
//! assert!(sticky.contradictions(&config).is_empty());
//! config.set("lives", "3").unwrap();
//! assert_eq!(sticky.contradictions(&config), ["lives 3 != 1"]);
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
    fn contradictions_name_each_option() {
        let sticky = mode("sticky-v0").unwrap();
        let mut c = sticky.config().unwrap();
        c.set("frame_skip", "2").unwrap();
        c.set("bird_prob", "0.02").unwrap();
        c.set("obs_type", "features").unwrap();
        assert_eq!(sticky.contradictions(&c), ["frame_skip 2 != 4", "bird_prob 0.02 != 0.01"]);
    }
}
