//! The game options of SPEC.md as command-line flags, shared by every command that plays: the rules options,
//! and `--hud-style`, how drawn frames show the fuel and the lives (not a rule: action logs do not record it).
//!
//! Each flag is checked while parsing by `Config::set` on its SPEC name, so a bad value fails with clap's usage
//! error (exit code 2) and the core's message naming the option and its allowed range.

use anyhow::{Context, Result};
use chopperscape::{Config, option_info};
use clap::Args;

/// A clap value parser that accepts exactly what `Config::set(name, value)` accepts.
fn option(name: &'static str) -> impl Fn(&str) -> Result<String, String> + Clone + Send + Sync + 'static {
    move |value: &str| {
        Config::default().set(name, value).map_err(|e| e.to_string())?;
        Ok(value.to_string())
    }
}

/// The help of the flag of option `name`, from the core's description of it ([`chopperscape::OPTIONS`]): what it
/// does, what it allows, and its default, written nowhere else.
fn help(name: &str) -> String {
    let o = option_info(name).unwrap_or_else(|| panic!("`{name}` is not an option of chopperscape::OPTIONS"));
    format!("{}: {} [default: {}]", o.doc, o.allowed, o.default)
}

/// The options of SPEC.md ("Options beyond the tutorial"); each defaults to the v0 rules. Each flag's help is
/// [`help`] of its option.
#[derive(Args, Debug, Clone, Default)]
#[command(next_help_heading = "Game options (SPEC.md; the defaults are the v0 rules)")]
pub struct GameOptions {
    #[arg(long, help = help("lives"), value_name = "L", allow_negative_numbers = true, value_parser = option("lives"))]
    pub lives: Option<String>,
    #[arg(
        long,
        help = help("alien_prob"),
        value_name = "P",
        allow_negative_numbers = true,
        value_parser = option("alien_prob")
    )]
    pub aliens: Option<String>,
    #[arg(
        long,
        help = help("bird_fuel_collision"),
        value_name = "pass|destroy",
        value_parser = option("bird_fuel_collision")
    )]
    pub bird_fuel_collision: Option<String>,
    #[arg(
        long,
        help = help("frame_skip"),
        value_name = "K",
        allow_negative_numbers = true,
        value_parser = option("frame_skip")
    )]
    pub frame_skip: Option<String>,
    #[arg(
        long,
        help = help("sticky_prob"),
        value_name = "P",
        allow_negative_numbers = true,
        value_parser = option("sticky_prob")
    )]
    pub sticky: Option<String>,
    #[arg(
        long,
        help = help("bird_prob"),
        value_name = "P",
        allow_negative_numbers = true,
        value_parser = option("bird_prob")
    )]
    pub bird_prob: Option<String>,
    #[arg(
        long,
        help = help("fuel_prob"),
        value_name = "P",
        allow_negative_numbers = true,
        value_parser = option("fuel_prob")
    )]
    pub fuel_prob: Option<String>,
    #[arg(long, help = help("max_fuel"), value_name = "N", allow_negative_numbers = true, value_parser = option("max_fuel"))]
    pub max_fuel: Option<String>,
    #[arg(
        long,
        help = help("max_episode_steps"),
        value_name = "N|none",
        allow_negative_numbers = true,
        value_parser = option("max_episode_steps")
    )]
    pub max_episode_steps: Option<String>,
    #[arg(long, help = help("hud_style"), value_name = "auto|text|gauge", value_parser = option("hud_style"))]
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

    #[test]
    fn the_rules_flags_are_the_rules_options() {
        let v = Some("1".to_string());
        let all = GameOptions {
            lives: v.clone(),
            aliens: v.clone(),
            bird_fuel_collision: v.clone(),
            frame_skip: v.clone(),
            sticky: v.clone(),
            bird_prob: v.clone(),
            fuel_prob: v.clone(),
            max_fuel: v.clone(),
            max_episode_steps: v.clone(),
            hud_style: v,
        };
        let given: std::collections::BTreeSet<&str> = all.given().into_iter().map(|(name, _)| name).collect();
        let rules: std::collections::BTreeSet<&str> =
            chopperscape::OPTIONS.iter().filter(|o| o.rule).map(|o| o.name).collect();
        assert_eq!(given, rules);
    }

    #[test]
    fn every_flag_help_is_the_core_description() {
        use clap::Args as _;
        let cmd = GameOptions::augment_args(clap::Command::new("t"));
        let mut seen = 0;
        for arg in cmd.get_arguments() {
            let help = arg.get_help().map(ToString::to_string).unwrap_or_default();
            let name = match arg.get_id().as_str() {
                "aliens" => "alien_prob",
                "sticky" => "sticky_prob",
                id => id,
            };
            let o = option_info(name).unwrap_or_else(|| panic!("flag {name} is not a core option"));
            assert_eq!(help, format!("{}: {} [default: {}]", o.doc, o.allowed, o.default));
            seen += 1;
        }
        assert_eq!(seen, 10);
    }
}
