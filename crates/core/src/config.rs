//! Options of the environment: the v0 rules by default, the tutorial's extensions and the
//! observation settings as opt-ins. A plain struct with `Default`, validated once.

use crate::consts::{BIRD_PROB, FUEL_PROB, HEIGHT, MAX_EPISODE_STEPS, MAX_FUEL, WIDTH};
use crate::error::ConfigError;

/// Every option name [`Config::set`] accepts, as in SPEC.md.
pub const OPTION_NAMES: &[&str] = &[
    "obs_type",
    "obs_size",
    "frame_stack",
    "hud",
    "hud_style",
    "lives",
    "bird_fuel_collision",
    "alien_prob",
    "frame_skip",
    "sticky_prob",
    "bird_prob",
    "fuel_prob",
    "max_fuel",
    "max_episode_steps",
];

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
        ObsType::ALL
            .into_iter()
            .find(|t| t.as_str() == s)
            .ok_or_else(|| out_of_range("obs_type", s, "one of \"rgb\", \"rgb_float\", \"grayscale\", \"features\""))
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
            _ => Err(out_of_range("bird_fuel_collision", s, "\"pass\" or \"destroy\"")),
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
            .ok_or_else(|| out_of_range("hud_style", s, "one of \"auto\", \"text\", \"gauge\""))
    }
}

/// The options of one environment. `Config::default()` is ChopperScape-v0 with an `rgb` 600 × 800 observation.
#[derive(Clone, Debug, PartialEq)]
pub struct Config {
    /// What the agent sees. Default: `Rgb`.
    pub obs_type: ObsType,
    /// Observation size `(height, width)` in pixels, drawn natively. Default: `(600, 800)`. Range: 8..=4096 each.
    pub obs_size: (u32, u32),
    /// Number of last observations stacked on the last axis. Default: 1. Range: 1..=64.
    pub frame_stack: u32,
    /// Whether pixel observations carry the HUD. Default: `true`.
    pub hud: bool,
    /// How the HUD is drawn: text, gauges, or text only where it is legible. Default: `Auto`.
    pub hud_style: HudStyle,
    /// Lives per episode. Default: 1. Range: 1..=1000.
    pub lives: u32,
    /// Bird–fuel tank collisions. Default: `Pass`.
    pub bird_fuel_collision: BirdFuelCollision,
    /// Probability per step that an alien bird appears. Default: 0. Range: [0, 1].
    pub alien_prob: f64,
    /// Steps each action is repeated for. Default: 1. Range: 1..=1000.
    pub frame_skip: u32,
    /// Probability per step that the previous action is applied instead of the new one. Default: 0. Range: [0, 1].
    pub sticky_prob: f64,
    /// Probability per step that a bird appears. Default: 0.01. Range: [0, 1].
    pub bird_prob: f64,
    /// Probability per step that a fuel tank appears. Default: 0.01. Range: [0, 1].
    pub fuel_prob: f64,
    /// Fuel at reset and after a refill, in steps. Default: 1000. Range: 1..=1,000,000.
    pub max_fuel: u32,
    /// Agent steps after which the episode is truncated; `None` never truncates. Default: `Some(10_000)`.
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

/// What `max_episode_steps` allows, in words.
const MAX_EPISODE_STEPS_ALLOWED: &str = "an integer in 1..=4294967295, or none to never truncate";

fn out_of_range(option: &'static str, value: impl ToString, allowed: &'static str) -> ConfigError {
    ConfigError::OutOfRange { option, value: value.to_string(), allowed }
}

fn check_prob(option: &'static str, p: f64) -> Result<(), ConfigError> {
    if (0.0..=1.0).contains(&p) { Ok(()) } else { Err(out_of_range(option, p, "a probability in [0, 1]")) }
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
                return Err(out_of_range("obs_size", format!("({h}, {w})"), "(height, width) with each in 8..=4096"));
            }
        }
        check_range("frame_stack", self.frame_stack, 1, 64, "an integer in 1..=64")?;
        check_range("lives", self.lives, 1, 1000, "an integer in 1..=1000")?;
        check_prob("alien_prob", self.alien_prob)?;
        check_range("frame_skip", self.frame_skip, 1, 1000, "an integer in 1..=1000")?;
        check_prob("sticky_prob", self.sticky_prob)?;
        check_prob("bird_prob", self.bird_prob)?;
        check_prob("fuel_prob", self.fuel_prob)?;
        check_range("max_fuel", self.max_fuel, 1, 1_000_000, "an integer in 1..=1000000")?;
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

    /// The options that differ between `self` and `other`, each as `name self_value != other_value`, in
    /// [`OPTION_NAMES`] order: what a refused restore names.
    pub fn differences(&self, other: &Config) -> Vec<String> {
        let mut out = Vec::new();
        let mut cmp = |name: &str, a: String, b: String| {
            if a != b {
                out.push(format!("{name} {a} != {b}"));
            }
        };
        let steps = |m: Option<u32>| m.map_or_else(|| "none".to_string(), |m| m.to_string());
        cmp("obs_type", self.obs_type.as_str().into(), other.obs_type.as_str().into());
        cmp("obs_size", format!("{:?}", self.obs_size), format!("{:?}", other.obs_size));
        cmp("frame_stack", self.frame_stack.to_string(), other.frame_stack.to_string());
        cmp("hud", self.hud.to_string(), other.hud.to_string());
        cmp("hud_style", self.hud_style.as_str().into(), other.hud_style.as_str().into());
        cmp("lives", self.lives.to_string(), other.lives.to_string());
        cmp("bird_fuel_collision", self.bird_fuel_collision.as_str().into(), other.bird_fuel_collision.as_str().into());
        cmp("alien_prob", self.alien_prob.to_string(), other.alien_prob.to_string());
        cmp("frame_skip", self.frame_skip.to_string(), other.frame_skip.to_string());
        cmp("sticky_prob", self.sticky_prob.to_string(), other.sticky_prob.to_string());
        cmp("bird_prob", self.bird_prob.to_string(), other.bird_prob.to_string());
        cmp("fuel_prob", self.fuel_prob.to_string(), other.fuel_prob.to_string());
        cmp("max_fuel", self.max_fuel.to_string(), other.max_fuel.to_string());
        cmp("max_episode_steps", steps(self.max_episode_steps), steps(other.max_episode_steps));
        out
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
                let allowed = "HxW or H,W with each in 8..=4096, for example 84x84";
                let (h, w) = v.split_once(['x', ',']).ok_or_else(|| out_of_range("obs_size", v, allowed))?;
                next.obs_size = (parse("obs_size", h, allowed)?, parse("obs_size", w, allowed)?);
            }
            "frame_stack" => next.frame_stack = parse("frame_stack", v, "an integer in 1..=64")?,
            "hud" => next.hud = parse("hud", v, "true or false")?,
            "hud_style" => next.hud_style = v.parse()?,
            "lives" => next.lives = parse("lives", v, "an integer in 1..=1000")?,
            "bird_fuel_collision" => next.bird_fuel_collision = v.parse()?,
            "alien_prob" => next.alien_prob = parse("alien_prob", v, "a probability in [0, 1]")?,
            "frame_skip" => next.frame_skip = parse("frame_skip", v, "an integer in 1..=1000")?,
            "sticky_prob" => next.sticky_prob = parse("sticky_prob", v, "a probability in [0, 1]")?,
            "bird_prob" => next.bird_prob = parse("bird_prob", v, "a probability in [0, 1]")?,
            "fuel_prob" => next.fuel_prob = parse("fuel_prob", v, "a probability in [0, 1]")?,
            "max_fuel" => next.max_fuel = parse("max_fuel", v, "an integer in 1..=1000000")?,
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
