//! Options of the environment: the v0 rules by default, the tutorial's extensions and the
//! observation settings as opt-ins. A plain struct with `Default`, validated once.

use crate::consts::{BIRD_PROB, FUEL_PROB, HEIGHT, MAX_EPISODE_STEPS, MAX_FUEL, WIDTH};
use crate::error::ConfigError;

/// One option of SPEC.md, described once: the command line's help, the Python binding (`_core.OPTIONS`) and the
/// tests of the Python docs read it from here.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub struct OptionInfo {
    /// The name [`Config::set`] takes, as in SPEC.md.
    pub name: &'static str,
    /// The default value, as text [`Config::set`] takes (and [`Config::get`] gives for `Config::default()`).
    pub default: &'static str,
    /// What the option allows, in words: exactly what the errors of [`Config::set`] and [`Config::validate`] say.
    pub allowed: &'static str,
    /// What the option does, in one line.
    pub doc: &'static str,
    /// Whether it is a rules option (what an action log records) rather than an observation setting.
    pub rule: bool,
}

const OBS_TYPE_ALLOWED: &str = "one of \"rgb\", \"rgb_float\", \"grayscale\", \"features\"";
const OBS_SIZE_ALLOWED: &str = "HxW or H,W with each in 8..=4096, for example 84x84";
const FRAME_STACK_ALLOWED: &str = "an integer in 1..=64";
const HUD_ALLOWED: &str = "true or false";
const HUD_STYLE_ALLOWED: &str = "one of \"auto\", \"text\", \"gauge\"";
const LIVES_ALLOWED: &str = "an integer in 1..=1000";
const BIRD_FUEL_COLLISION_ALLOWED: &str = "\"pass\" or \"destroy\"";
const PROBABILITY_ALLOWED: &str = "a probability in [0, 1]";
const FRAME_SKIP_ALLOWED: &str = "an integer in 1..=1000";
const MAX_FUEL_ALLOWED: &str = "an integer in 1..=1000000";
const MAX_EPISODE_STEPS_ALLOWED: &str = "an integer in 1..=4294967295, or none to never truncate";

/// Every option, in SPEC order ([`OPTION_NAMES`] is its names); the defaults are `Config::default()`, the v0 rules
/// with an `rgb` 600 × 800 observation.
pub const OPTIONS: &[OptionInfo] = &[
    OptionInfo { name: "obs_type", default: "rgb", allowed: OBS_TYPE_ALLOWED, doc: "What the agent sees", rule: false },
    OptionInfo {
        name: "obs_size",
        default: "600x800",
        allowed: OBS_SIZE_ALLOWED,
        doc: "Pixel observation size, height x width, drawn at that size",
        rule: false,
    },
    OptionInfo {
        name: "frame_stack",
        default: "1",
        allowed: FRAME_STACK_ALLOWED,
        doc: "Number of last observations stacked on the last axis",
        rule: false,
    },
    OptionInfo {
        name: "hud",
        default: "true",
        allowed: HUD_ALLOWED,
        doc: "Whether pixel observations carry the HUD (fuel and lives)",
        rule: false,
    },
    OptionInfo {
        name: "hud_style",
        default: "auto",
        allowed: HUD_STYLE_ALLOWED,
        doc: "How drawn frames show fuel and lives (auto: the text line in frames of at least 300x400, gauge bars \
              in smaller ones)",
        rule: false,
    },
    OptionInfo { name: "lives", default: "1", allowed: LIVES_ALLOWED, doc: "Lives per episode", rule: true },
    OptionInfo {
        name: "bird_fuel_collision",
        default: "pass",
        allowed: BIRD_FUEL_COLLISION_ALLOWED,
        doc: "What a bird and a fuel tank that collide do",
        rule: true,
    },
    OptionInfo {
        name: "alien_prob",
        default: "0",
        allowed: PROBABILITY_ALLOWED,
        doc: "Probability per step that an alien bird appears",
        rule: true,
    },
    OptionInfo {
        name: "frame_skip",
        default: "1",
        allowed: FRAME_SKIP_ALLOWED,
        doc: "Steps each action is repeated for",
        rule: true,
    },
    OptionInfo {
        name: "sticky_prob",
        default: "0",
        allowed: PROBABILITY_ALLOWED,
        doc: "Probability per step that the previous action is applied instead of the new one",
        rule: true,
    },
    OptionInfo {
        name: "bird_prob",
        default: "0.01",
        allowed: PROBABILITY_ALLOWED,
        doc: "Probability per step that a bird appears",
        rule: true,
    },
    OptionInfo {
        name: "fuel_prob",
        default: "0.01",
        allowed: PROBABILITY_ALLOWED,
        doc: "Probability per step that a fuel tank appears",
        rule: true,
    },
    OptionInfo {
        name: "max_fuel",
        default: "1000",
        allowed: MAX_FUEL_ALLOWED,
        doc: "Fuel at reset and after a refill, in steps",
        rule: true,
    },
    OptionInfo {
        name: "max_episode_steps",
        default: "10000",
        allowed: MAX_EPISODE_STEPS_ALLOWED,
        doc: "Agent steps after which an episode is truncated",
        rule: true,
    },
];

/// The option named `name` in [`OPTIONS`], if there is one.
pub fn option_info(name: &str) -> Option<&'static OptionInfo> {
    OPTIONS.iter().find(|o| o.name == name)
}

const fn option_names<const N: usize>() -> [&'static str; N] {
    let mut names = [""; N];
    let mut i = 0;
    while i < N {
        names[i] = OPTIONS[i].name;
        i += 1;
    }
    names
}

/// Every option name [`Config::set`] accepts, as in SPEC.md: the names of [`OPTIONS`].
pub const OPTION_NAMES: &[&str] = &option_names::<{ OPTIONS.len() }>();

/// What the agent sees.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, Default)]
pub enum ObsType {
    /// `u8`, shape `(H, W, 3)`: the rendered frame.
    #[default]
    Rgb,
    /// `f32` in `[0, 1]`, shape `(H, W, 3)`: the rendered frame divided by 255.
    RgbFloat,
    /// `u8`, shape `(H, W)`: the luma of the rendered frame.
    Grayscale,
    /// `f32`, shape `(FEATURES_LEN,)`: a description of the state (see [`crate::features`]).
    Features,
}

impl ObsType {
    /// Every observation type, in SPEC order.
    pub const ALL: [ObsType; 4] = [ObsType::Rgb, ObsType::RgbFloat, ObsType::Grayscale, ObsType::Features];

    /// The name used in SPEC.md and Python: `"rgb"`, `"rgb_float"`, `"grayscale"`, `"features"`.
    pub fn as_str(self) -> &'static str {
        match self {
            ObsType::Rgb => "rgb",
            ObsType::RgbFloat => "rgb_float",
            ObsType::Grayscale => "grayscale",
            ObsType::Features => "features",
        }
    }

    /// Whether the observation is a rendered image.
    pub fn is_pixels(self) -> bool {
        !matches!(self, ObsType::Features)
    }
}

impl std::str::FromStr for ObsType {
    type Err = ConfigError;
    fn from_str(s: &str) -> Result<Self, ConfigError> {
        ObsType::ALL.into_iter().find(|t| t.as_str() == s).ok_or_else(|| out_of_range("obs_type", s, OBS_TYPE_ALLOWED))
    }
}

/// What happens when a bird (or alien) and a fuel tank collide.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, Default)]
pub enum BirdFuelCollision {
    /// They pass through each other (v0).
    #[default]
    Pass,
    /// Both are removed.
    Destroy,
}

impl BirdFuelCollision {
    /// The name used in SPEC.md: `"pass"` or `"destroy"`.
    pub fn as_str(self) -> &'static str {
        match self {
            BirdFuelCollision::Pass => "pass",
            BirdFuelCollision::Destroy => "destroy",
        }
    }
}

impl std::str::FromStr for BirdFuelCollision {
    type Err = ConfigError;
    fn from_str(s: &str) -> Result<Self, ConfigError> {
        match s {
            "pass" => Ok(BirdFuelCollision::Pass),
            "destroy" => Ok(BirdFuelCollision::Destroy),
            _ => Err(out_of_range("bird_fuel_collision", s, BIRD_FUEL_COLLISION_ALLOWED)),
        }
    }
}

/// How the HUD is drawn into a frame (when `hud` is on): the tutorial's text line, or gauges a network can read at
/// any size. See [`crate::render`] for the layout and [`crate::render::PIXELS_VERSION`] for its history.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, Default)]
pub enum HudStyle {
    /// The text where it is legible (frames at least half the full size in each direction,
    /// [`crate::render::TEXT_MIN_SIZE`]), the gauges in smaller frames.
    #[default]
    Auto,
    /// The text line `Fuel Left: N | Rewards: N | Lives: N` at every size (pixel layout version 1).
    Text,
    /// A fuel bar and a lives bar at every size.
    Gauge,
}

impl HudStyle {
    /// Every style, in SPEC order.
    pub const ALL: [HudStyle; 3] = [HudStyle::Auto, HudStyle::Text, HudStyle::Gauge];

    /// The name used in SPEC.md and Python: `"auto"`, `"text"`, `"gauge"`.
    pub fn as_str(self) -> &'static str {
        match self {
            HudStyle::Auto => "auto",
            HudStyle::Text => "text",
            HudStyle::Gauge => "gauge",
        }
    }
}

impl std::str::FromStr for HudStyle {
    type Err = ConfigError;
    fn from_str(s: &str) -> Result<Self, ConfigError> {
        HudStyle::ALL
            .into_iter()
            .find(|t| t.as_str() == s)
            .ok_or_else(|| out_of_range("hud_style", s, HUD_STYLE_ALLOWED))
    }
}

/// The options of one environment. `Config::default()` is ChopperScape-v0 with an `rgb` 600 × 800 observation.
/// Each option's default and allowed values are in [`OPTIONS`] (what [`Config::validate`] checks).
#[derive(Clone, Debug, PartialEq)]
pub struct Config {
    /// What the agent sees.
    pub obs_type: ObsType,
    /// Observation size `(height, width)` in pixels, drawn natively.
    pub obs_size: (u32, u32),
    /// Number of last observations stacked on the last axis.
    pub frame_stack: u32,
    /// Whether pixel observations carry the HUD.
    pub hud: bool,
    /// How the HUD is drawn: text, gauges, or text only where it is legible.
    pub hud_style: HudStyle,
    /// Lives per episode.
    pub lives: u32,
    /// Bird–fuel tank collisions.
    pub bird_fuel_collision: BirdFuelCollision,
    /// Probability per step that an alien bird appears.
    pub alien_prob: f64,
    /// Steps each action is repeated for.
    pub frame_skip: u32,
    /// Probability per step that the previous action is applied instead of the new one.
    pub sticky_prob: f64,
    /// Probability per step that a bird appears.
    pub bird_prob: f64,
    /// Probability per step that a fuel tank appears.
    pub fuel_prob: f64,
    /// Fuel at reset and after a refill, in steps.
    pub max_fuel: u32,
    /// Agent steps after which the episode is truncated; `None` never truncates.
    pub max_episode_steps: Option<u32>,
}

impl Default for Config {
    fn default() -> Self {
        Config {
            obs_type: ObsType::Rgb,
            obs_size: (HEIGHT as u32, WIDTH as u32),
            frame_stack: 1,
            hud: true,
            hud_style: HudStyle::Auto,
            lives: 1,
            bird_fuel_collision: BirdFuelCollision::Pass,
            alien_prob: 0.0,
            frame_skip: 1,
            sticky_prob: 0.0,
            bird_prob: BIRD_PROB,
            fuel_prob: FUEL_PROB,
            max_fuel: MAX_FUEL,
            max_episode_steps: Some(MAX_EPISODE_STEPS),
        }
    }
}

fn out_of_range(option: &'static str, value: impl ToString, allowed: &'static str) -> ConfigError {
    ConfigError::OutOfRange { option, value: value.to_string(), allowed }
}

fn check_prob(option: &'static str, p: f64) -> Result<(), ConfigError> {
    if (0.0..=1.0).contains(&p) { Ok(()) } else { Err(out_of_range(option, p, PROBABILITY_ALLOWED)) }
}

fn check_range(option: &'static str, v: u32, lo: u32, hi: u32, allowed: &'static str) -> Result<(), ConfigError> {
    if (lo..=hi).contains(&v) { Ok(()) } else { Err(out_of_range(option, v, allowed)) }
}

fn parse<T: std::str::FromStr>(option: &'static str, value: &str, allowed: &'static str) -> Result<T, ConfigError> {
    value.trim().parse().map_err(|_| out_of_range(option, value, allowed))
}

impl Config {
    /// A config with `obs_type = Features`, the cheapest observation; otherwise v0.
    pub fn features() -> Config {
        Config { obs_type: ObsType::Features, ..Config::default() }
    }

    /// Checks every option against its range.
    ///
    /// # Errors
    /// The first option out of range, named, with its allowed range.
    pub fn validate(&self) -> Result<(), ConfigError> {
        let (h, w) = self.obs_size;
        for v in [h, w] {
            if !(8..=4096).contains(&v) {
                return Err(out_of_range("obs_size", format!("{h}x{w}"), OBS_SIZE_ALLOWED));
            }
        }
        check_range("frame_stack", self.frame_stack, 1, 64, FRAME_STACK_ALLOWED)?;
        check_range("lives", self.lives, 1, 1000, LIVES_ALLOWED)?;
        check_prob("alien_prob", self.alien_prob)?;
        check_range("frame_skip", self.frame_skip, 1, 1000, FRAME_SKIP_ALLOWED)?;
        check_prob("sticky_prob", self.sticky_prob)?;
        check_prob("bird_prob", self.bird_prob)?;
        check_prob("fuel_prob", self.fuel_prob)?;
        check_range("max_fuel", self.max_fuel, 1, 1_000_000, MAX_FUEL_ALLOWED)?;
        if self.max_episode_steps == Some(0) {
            return Err(out_of_range("max_episode_steps", 0, MAX_EPISODE_STEPS_ALLOWED));
        }
        crate::limits::check_budget(
            format!(
                "one environment's observation buffers (obs_type \"{}\", obs_size ({h}, {w}), frame_stack {})",
                self.obs_type.as_str(),
                self.frame_stack
            ),
            crate::limits::env_bytes(self),
            crate::limits::MAX_ENV_BYTES,
            "choose a smaller obs_size or frame_stack, or obs_type \"grayscale\" or \"features\"",
        )
    }

    /// The options that differ between `self` and `other`, each as `name self_value != other_value` (values as
    /// [`Config::get`] writes them), in [`OPTION_NAMES`] order: what a refused restore names.
    pub fn differences(&self, other: &Config) -> Vec<String> {
        OPTION_NAMES
            .iter()
            .filter_map(|&name| {
                let (a, b) = (self.get(name)?, other.get(name)?);
                (a != b).then(|| format!("{name} {a} != {b}"))
            })
            .collect()
    }

    /// The value of option `name` as text [`Config::set`] takes back (`600x800`, `true`, `0.01`, `none`), or
    /// `None` for an unknown name.
    pub fn get(&self, name: &str) -> Option<String> {
        Some(match name {
            "obs_type" => self.obs_type.as_str().to_string(),
            "obs_size" => format!("{}x{}", self.obs_size.0, self.obs_size.1),
            "frame_stack" => self.frame_stack.to_string(),
            "hud" => self.hud.to_string(),
            "hud_style" => self.hud_style.as_str().to_string(),
            "lives" => self.lives.to_string(),
            "bird_fuel_collision" => self.bird_fuel_collision.as_str().to_string(),
            "alien_prob" => self.alien_prob.to_string(),
            "frame_skip" => self.frame_skip.to_string(),
            "sticky_prob" => self.sticky_prob.to_string(),
            "bird_prob" => self.bird_prob.to_string(),
            "fuel_prob" => self.fuel_prob.to_string(),
            "max_fuel" => self.max_fuel.to_string(),
            "max_episode_steps" => self.max_episode_steps.map_or_else(|| "none".to_string(), |n| n.to_string()),
            _ => return None,
        })
    }

    /// Sets one option from its SPEC name and a textual value (as the command line and the web page give them),
    /// then validates that option. Leaves `self` unchanged on error.
    ///
    /// Values: `obs_size` as `HxW` or `H,W`; `hud` as `true`/`false`; `hud_style` as `auto`/`text`/`gauge`;
    /// `max_episode_steps` as an integer or `none`.
    ///
    /// # Errors
    /// An unknown name, or a value that does not parse or is out of range.
    pub fn set(&mut self, name: &str, value: &str) -> Result<(), ConfigError> {
        let mut next = self.clone();
        let v = value.trim();
        match name {
            "obs_type" => next.obs_type = v.parse()?,
            "obs_size" => {
                let (h, w) = v.split_once(['x', ',']).ok_or_else(|| out_of_range("obs_size", v, OBS_SIZE_ALLOWED))?;
                next.obs_size = (parse("obs_size", h, OBS_SIZE_ALLOWED)?, parse("obs_size", w, OBS_SIZE_ALLOWED)?);
            }
            "frame_stack" => next.frame_stack = parse("frame_stack", v, FRAME_STACK_ALLOWED)?,
            "hud" => next.hud = parse("hud", v, HUD_ALLOWED)?,
            "hud_style" => next.hud_style = v.parse()?,
            "lives" => next.lives = parse("lives", v, LIVES_ALLOWED)?,
            "bird_fuel_collision" => next.bird_fuel_collision = v.parse()?,
            "alien_prob" => next.alien_prob = parse("alien_prob", v, PROBABILITY_ALLOWED)?,
            "frame_skip" => next.frame_skip = parse("frame_skip", v, FRAME_SKIP_ALLOWED)?,
            "sticky_prob" => next.sticky_prob = parse("sticky_prob", v, PROBABILITY_ALLOWED)?,
            "bird_prob" => next.bird_prob = parse("bird_prob", v, PROBABILITY_ALLOWED)?,
            "fuel_prob" => next.fuel_prob = parse("fuel_prob", v, PROBABILITY_ALLOWED)?,
            "max_fuel" => next.max_fuel = parse("max_fuel", v, MAX_FUEL_ALLOWED)?,
            "max_episode_steps" => {
                next.max_episode_steps = if v.eq_ignore_ascii_case("none") {
                    None
                } else {
                    Some(parse("max_episode_steps", v, MAX_EPISODE_STEPS_ALLOWED)?)
                }
            }
            _ => return Err(ConfigError::Unknown { name: name.to_string() }),
        }
        next.validate()?;
        *self = next;
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn default_is_valid_v0() {
        let c = Config::default();
        c.validate().unwrap();
        assert_eq!(c.lives, 1);
        assert_eq!(c.max_fuel, 1000);
        assert_eq!(c.obs_size, (600, 800));
    }

    #[test]
    fn options_are_the_option_names_in_order() {
        let names: Vec<&str> = OPTIONS.iter().map(|o| o.name).collect();
        assert_eq!(names, OPTION_NAMES);
        assert_eq!(OPTION_NAMES.len(), 14);
        assert_eq!(option_info("lives").map(|o| o.allowed), Some(LIVES_ALLOWED));
        assert_eq!(option_info("gravity"), None);
    }

    #[test]
    fn every_default_is_what_config_default_has_and_round_trips() {
        let v0 = Config::default();
        for o in OPTIONS {
            assert_eq!(v0.get(o.name).as_deref(), Some(o.default), "{}", o.name);
            let mut c = Config::features();
            c.set("obs_type", "grayscale").unwrap();
            c.set(o.name, o.default).unwrap_or_else(|e| panic!("{}: {e}", o.name));
            assert_eq!(c.get(o.name).as_deref(), Some(o.default), "{}", o.name);
            assert!(!o.doc.is_empty() && !o.allowed.is_empty(), "{}", o.name);
        }
        let mut c = Config { obs_type: ObsType::Features, lives: 7, max_episode_steps: None, ..Config::default() };
        for o in OPTIONS {
            c.set(o.name, o.default).unwrap();
        }
        assert_eq!(c, v0, "setting every default gives Config::default()");
        assert_eq!(v0.get("gravity"), None);
    }

    #[test]
    fn rules_are_the_options_an_action_log_records() {
        let observation: Vec<&str> = OPTIONS.iter().filter(|o| !o.rule).map(|o| o.name).collect();
        assert_eq!(observation, ["obs_type", "obs_size", "frame_stack", "hud", "hud_style"]);
    }

    #[test]
    fn every_refused_value_names_the_option_and_its_allowed_words() {
        for o in OPTIONS {
            for bad in ["-1", "nonsense", "1e999x"] {
                let err = Config::features().set(o.name, bad).unwrap_err().to_string();
                assert!(err.contains(o.name) && err.contains(o.allowed), "{} = {bad}: {err}", o.name);
            }
        }
    }

    /// The bounds written in an option's `allowed` words are the bounds enforced, at both ends.
    #[test]
    fn the_ranges_in_the_allowed_words_are_the_ranges_enforced() {
        let refused = |name: &str, value: &str| {
            let err = Config::features().set(name, value).expect_err(value).to_string();
            let allowed = option_info(name).unwrap().allowed;
            assert!(err.contains(name) && err.contains(allowed), "{name} = {value}: {err}");
        };
        let mut integers = 0;
        for o in OPTIONS {
            if let Some(range) = o.allowed.strip_prefix("an integer in ") {
                let range = range.split(',').next().unwrap();
                let (lo, hi) = range.split_once("..=").unwrap();
                let (lo, hi): (u64, u64) = (lo.parse().unwrap(), hi.parse().unwrap());
                for ok in [lo, hi] {
                    Config::features().set(o.name, &ok.to_string()).unwrap_or_else(|e| panic!("{}: {e}", o.name));
                }
                refused(o.name, &(lo - 1).to_string());
                refused(o.name, &(hi + 1).to_string());
                integers += 1;
            } else if o.allowed == PROBABILITY_ALLOWED {
                for ok in ["0", "1", "0.5"] {
                    Config::features().set(o.name, ok).unwrap();
                }
                for bad in ["-0.01", "1.01", "nan", "inf"] {
                    refused(o.name, bad);
                }
            }
        }
        assert_eq!(integers, 5, "frame_stack, lives, frame_skip, max_fuel, max_episode_steps");
        assert!(OBS_SIZE_ALLOWED.contains("8..=4096"));
        for ok in ["8x8", "4096,8", "8x4096"] {
            Config::features().set("obs_size", ok).unwrap();
        }
        for bad in ["7x8", "8x7", "4097x8", "8x4097"] {
            refused("obs_size", bad);
        }
    }

    #[test]
    fn out_of_range_options_name_the_option_and_range() {
        let cases: &[(&str, &str, &str)] = &[
            ("alien_prob", "1.5", "[0, 1]"),
            ("sticky_prob", "-0.1", "[0, 1]"),
            ("bird_prob", "nan", "[0, 1]"),
            ("fuel_prob", "2", "[0, 1]"),
            ("lives", "0", "1..=1000"),
            ("frame_skip", "0", "1..=1000"),
            ("max_fuel", "0", "1..=1000000"),
            ("frame_stack", "0", "1..=64"),
            ("obs_size", "4x4", "8..=4096"),
            ("obs_type", "rgba", "grayscale"),
            ("bird_fuel_collision", "explode", "destroy"),
            ("hud", "maybe", "true or false"),
            ("hud_style", "bars", "\"auto\", \"text\", \"gauge\""),
            ("max_episode_steps", "0", "1..=4294967295"),
        ];
        for (name, value, allowed) in cases {
            let mut c = Config::default();
            let err = c.set(name, value).unwrap_err().to_string();
            assert!(err.contains(name), "{err}");
            assert!(err.contains(allowed), "{err}");
            assert_eq!(c, Config::default(), "a rejected option changed the config");
        }
    }

    #[test]
    fn options_over_the_memory_budget_are_refused_with_the_size() {
        let mut c = Config::default();
        c.set("obs_size", "4096x4096").unwrap();
        let err = c.set("frame_stack", "64").unwrap_err().to_string();
        assert!(err.contains("frame_stack 64") && err.contains("GiB") && err.contains("budget of 4.0 GiB"), "{err}");
        assert_eq!(c.frame_stack, 1, "a refused option changes nothing");
        c.set("frame_stack", "8").unwrap();
    }

    #[test]
    fn max_episode_steps_beyond_u32_names_the_range() {
        let err = Config::default().set("max_episode_steps", "4294967296").unwrap_err().to_string();
        assert!(err.contains("max_episode_steps") && err.contains("1..=4294967295"), "{err}");
    }

    #[test]
    fn differences_name_only_the_options_that_differ() {
        let a = Config::default();
        let b = Config { lives: 3, max_episode_steps: None, ..Config::default() };
        assert_eq!(a.differences(&b), ["lives 1 != 3", "max_episode_steps 10000 != none"]);
        assert!(a.differences(&a).is_empty());
    }

    #[test]
    fn unknown_option_lists_the_known_ones() {
        let err = Config::default().set("gravity", "9.8").unwrap_err().to_string();
        assert!(err.contains("gravity") && err.contains("alien_prob"), "{err}");
    }

    #[test]
    fn set_parses_every_option() {
        let mut c = Config::default();
        for (n, v) in [
            ("obs_type", "grayscale"),
            ("obs_size", "84x84"),
            ("frame_stack", "4"),
            ("hud", "false"),
            ("hud_style", "gauge"),
            ("lives", "3"),
            ("bird_fuel_collision", "destroy"),
            ("alien_prob", "0.02"),
            ("frame_skip", "2"),
            ("sticky_prob", "0.25"),
            ("bird_prob", "0.05"),
            ("fuel_prob", "0.02"),
            ("max_fuel", "500"),
            ("max_episode_steps", "none"),
        ] {
            c.set(n, v).unwrap();
        }
        assert_eq!(c.obs_type, ObsType::Grayscale);
        assert_eq!(c.obs_size, (84, 84));
        assert_eq!((c.frame_stack, c.hud, c.lives, c.frame_skip, c.max_fuel), (4, false, 3, 2, 500));
        assert_eq!(c.bird_fuel_collision, BirdFuelCollision::Destroy);
        assert_eq!(c.hud_style, HudStyle::Gauge);
        assert_eq!(c.max_episode_steps, None);
    }
}
