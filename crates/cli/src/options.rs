//! The game options of SPEC.md as command-line flags, shared by every command that plays: the rules options,
//! and `--hud-style`, how drawn frames show the fuel and the lives (not a rule: action logs do not record it).
//!
//! Each flag is checked while parsing by `Config::set` on its SPEC name, so a bad value fails with clap's usage
//! error (exit code 2) and the core's message naming the option and its allowed range.

use anyhow::{Context, Result};
use chopperscape::Config;
use clap::Args;

/// A clap value parser that accepts exactly what `Config::set(name, value)` accepts.
fn option(name: &'static str) -> impl Fn(&str) -> Result<String, String> + Clone + Send + Sync + 'static {
    move |value: &str| {
        Config::default().set(name, value).map_err(|e| e.to_string())?;
        Ok(value.to_string())
    }
}

/// The options of SPEC.md ("Options beyond the tutorial"); each defaults to the v0 rules.
#[derive(Args, Debug, Clone, Default)]
#[command(next_help_heading = "Game options (SPEC.md; the defaults are the v0 rules)")]
pub struct GameOptions {
    /// Lives per episode, 1..=1000 [default: 1]
    #[arg(long, value_name = "L", allow_negative_numbers = true, value_parser = option("lives"))]
    pub lives: Option<String>,
    /// Probability per step that an alien bird appears, in [0, 1] [default: 0]
    #[arg(long, value_name = "P", allow_negative_numbers = true, value_parser = option("alien_prob"))]
    pub aliens: Option<String>,
    /// What a bird and a fuel tank that collide do: pass or destroy [default: pass]
    #[arg(long, value_name = "pass|destroy", value_parser = option("bird_fuel_collision"))]
    pub bird_fuel_collision: Option<String>,
    /// Steps each action is repeated for, 1..=1000 [default: 1]
    #[arg(long, value_name = "K", allow_negative_numbers = true, value_parser = option("frame_skip"))]
    pub frame_skip: Option<String>,
    /// Probability that the previous action is applied instead of the new one, in [0, 1] [default: 0]
    #[arg(long, value_name = "P", allow_negative_numbers = true, value_parser = option("sticky_prob"))]
    pub sticky: Option<String>,
    /// Probability per step that a bird appears, in [0, 1] [default: 0.01]
    #[arg(long, value_name = "P", allow_negative_numbers = true, value_parser = option("bird_prob"))]
    pub bird_prob: Option<String>,
    /// Probability per step that a fuel tank appears, in [0, 1] [default: 0.01]
    #[arg(long, value_name = "P", allow_negative_numbers = true, value_parser = option("fuel_prob"))]
    pub fuel_prob: Option<String>,
    /// Fuel at reset and after a refill, 1..=1000000 [default: 1000]
    #[arg(long, value_name = "N", allow_negative_numbers = true, value_parser = option("max_fuel"))]
    pub max_fuel: Option<String>,
    /// Agent steps after which an episode is truncated, or `none` [default: 10000]
    #[arg(long, value_name = "N|none", allow_negative_numbers = true, value_parser = option("max_episode_steps"))]
    pub max_episode_steps: Option<String>,
    /// How drawn frames show fuel and lives: auto (the text line at full size, gauge bars in frames under
    /// 300x400), text, or gauge [default: auto]
    #[arg(long, value_name = "auto|text|gauge", value_parser = option("hud_style"))]
    pub hud_style: Option<String>,
}

impl GameOptions {
    /// The rules flags that were given, as `(Config::set name, value)` (`--hud-style` is not one).
    pub fn given(&self) -> Vec<(&'static str, &str)> {
        [
            ("lives", &self.lives),
            ("alien_prob", &self.aliens),
            ("bird_fuel_collision", &self.bird_fuel_collision),
            ("frame_skip", &self.frame_skip),
            ("sticky_prob", &self.sticky),
            ("bird_prob", &self.bird_prob),
            ("fuel_prob", &self.fuel_prob),
            ("max_fuel", &self.max_fuel),
            ("max_episode_steps", &self.max_episode_steps),
        ]
        .into_iter()
        .filter_map(|(name, v)| v.as_deref().map(|v| (name, v)))
        .collect()
    }

    /// `base` with these options applied, `--hud-style` included.
    ///
    /// # Errors
    /// A value `Config::set` refuses (already checked while parsing, so only in theory).
    pub fn apply(&self, mut base: Config) -> Result<Config> {
        for (name, value) in self.given().into_iter().chain(self.hud_style.as_deref().map(|v| ("hud_style", v))) {
            base.set(name, value).with_context(|| format!("option {name}"))?;
        }
        Ok(base)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn hud_style_is_applied_but_is_not_a_rule() {
        let options =
            GameOptions { hud_style: Some("gauge".into()), lives: Some("2".into()), ..GameOptions::default() };
        assert_eq!(options.given(), [("lives", "2")]);
        let c = options.apply(Config::default()).unwrap();
        assert_eq!((c.hud_style, c.lives), (chopperscape::HudStyle::Gauge, 2));
        assert!(!chopperscape_actionlog::rule_values(&c).contains_key("hud_style"));
    }
}
