//! Options of the environment: the v0 rules by default, the tutorial's extensions and the
//! observation settings as opt-ins. A plain struct with `Default`, validated once.
//!
//! Every option is declared once, in the table of the `options!` invocation below: its field and Rust type, its
//! default (as text), what it allows (a range or a set, from which the words of its errors come), its one-line
//! doc, whether it is a rule or an observation setting, its command-line flag and whether the web page sets it.
//! The macro generates from that table the [`Config`] struct, `Config::default()`, [`OPTIONS`] (what the CLI's
//! flags, the web page, `_core.OPTIONS` and the docs' tests read), [`Config::validate`]'s range checks and
//! [`Config::get`], [`Config::set`] and [`Config::value`]. Adding an option is adding one row.

use crate::error::ConfigError;
use crate::features::FEATURES_LEN;
use crate::limits::{MAX_ENV_BYTES, check_budget};

/// One option of SPEC.md, described once: the command line's flags and help, the web page's options, the Python
/// binding (`_core.OPTIONS`) and the tests of the Python docs read it from here.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub struct OptionInfo {
    /// The name [`Config::set`] takes, as in SPEC.md: the name of its [`Config`] field.
    pub name: &'static str,
    /// The default value, as text [`Config::set`] takes (and [`Config::get`] gives for `Config::default()`).
    pub default: &'static str,
    /// What the option allows, in words: exactly what the errors of [`Config::set`] and [`Config::validate`] say.
    pub allowed: &'static str,
    /// What the option does, in one line.
    pub doc: &'static str,
    /// Whether it is a rules option (what an action log records) rather than an observation setting.
    pub rule: bool,
    /// The kind of value it takes (its Rust type in [`Config`]).
    pub kind: OptionKind,
    /// The flag of the `chopperscape` commands that play, if they take the option as a flag of its own.
    pub flag: Option<CliFlag>,
    /// Whether the web page (`chopperscape-web`'s `Session`) may set it.
    pub page: bool,
}

/// The kind of value an option takes, after its Rust type in [`Config`].
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum OptionKind {
    /// One of a few names (an enum such as [`ObsType`]).
    Choice,
    /// `true` or `false`.
    Bool,
    /// `(height, width)` in pixels, written `HxW`.
    Size,
    /// An integer in a range (`u32`).
    Integer,
    /// An integer in a range, or `none` (`Option<u32>`).
    IntegerOrNone,
    /// A probability in `[0, 1]` (`f64`).
    Probability,
}

impl OptionKind {
    /// Whether values of this kind are numbers, which may be written negative (and are then refused as out of
    /// range, rather than read as a flag).
    pub fn is_numeric(self) -> bool {
        matches!(self, OptionKind::Integer | OptionKind::IntegerOrNone | OptionKind::Probability)
    }
}

/// An option's command-line flag.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub struct CliFlag {
    /// The long flag without its dashes: `lives` for `--lives`.
    pub long: &'static str,
    /// The name of its value in the help: `L`, `P`, `pass|destroy`.
    pub value_name: &'static str,
}

/// One option's value, typed: what [`Config::value`] gives.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum OptionValue {
    /// A [`OptionKind::Choice`]: the name of the choice.
    Choice(&'static str),
    /// A [`OptionKind::Bool`].
    Bool(bool),
    /// A [`OptionKind::Size`]: `(height, width)`.
    Size((u32, u32)),
    /// A [`OptionKind::Integer`].
    Integer(u32),
    /// A [`OptionKind::IntegerOrNone`].
    IntegerOrNone(Option<u32>),
    /// A [`OptionKind::Probability`].
    Probability(f64),
}

/// How the values of one Rust type of [`Config`] are read from and written as text, and typed.
trait OptionText: Sized {
    /// The kind of option of this type.
    const KIND: OptionKind;
    /// `text` (trimmed) read as a value of option `option`; the error names the option and `allowed`.
    fn parse_text(option: &'static str, text: &str, allowed: &'static str) -> Result<Self, ConfigError>;
    /// The value as text [`OptionText::parse_text`] reads back.
    fn write_text(&self) -> String;
    /// The value, typed.
    fn value(&self) -> OptionValue;
}

fn parse<T: std::str::FromStr>(option: &'static str, value: &str, allowed: &'static str) -> Result<T, ConfigError> {
    value.trim().parse().map_err(|_| out_of_range(option, value, allowed))
}

impl OptionText for u32 {
    const KIND: OptionKind = OptionKind::Integer;
    fn parse_text(option: &'static str, text: &str, allowed: &'static str) -> Result<Self, ConfigError> {
        parse(option, text, allowed)
    }
    fn write_text(&self) -> String {
        self.to_string()
    }
    fn value(&self) -> OptionValue {
        OptionValue::Integer(*self)
    }
}

impl OptionText for f64 {
    const KIND: OptionKind = OptionKind::Probability;
    fn parse_text(option: &'static str, text: &str, allowed: &'static str) -> Result<Self, ConfigError> {
        parse(option, text, allowed)
    }
    fn write_text(&self) -> String {
        self.to_string()
    }
    fn value(&self) -> OptionValue {
        OptionValue::Probability(*self)
    }
}

impl OptionText for bool {
    const KIND: OptionKind = OptionKind::Bool;
    fn parse_text(option: &'static str, text: &str, allowed: &'static str) -> Result<Self, ConfigError> {
        parse(option, text, allowed)
    }
    fn write_text(&self) -> String {
        self.to_string()
    }
    fn value(&self) -> OptionValue {
        OptionValue::Bool(*self)
    }
}

impl OptionText for (u32, u32) {
    const KIND: OptionKind = OptionKind::Size;
    fn parse_text(option: &'static str, text: &str, allowed: &'static str) -> Result<Self, ConfigError> {
        let (h, w) = text.split_once(['x', ',']).ok_or_else(|| out_of_range(option, text, allowed))?;
        Ok((parse(option, h, allowed)?, parse(option, w, allowed)?))
    }
    fn write_text(&self) -> String {
        format!("{}x{}", self.0, self.1)
    }
    fn value(&self) -> OptionValue {
        OptionValue::Size(*self)
    }
}

impl OptionText for Option<u32> {
    const KIND: OptionKind = OptionKind::IntegerOrNone;
    fn parse_text(option: &'static str, text: &str, allowed: &'static str) -> Result<Self, ConfigError> {
        if text.eq_ignore_ascii_case("none") { Ok(None) } else { Ok(Some(parse(option, text, allowed)?)) }
    }
    fn write_text(&self) -> String {
        self.map_or_else(|| "none".to_string(), |n| n.to_string())
    }
    fn value(&self) -> OptionValue {
        OptionValue::IntegerOrNone(*self)
    }
}

/// [`OptionText`] for an enum with `ALL` and `as_str`, and its `FromStr` for the option `$option`.
macro_rules! choice {
    ($ty:ty, $option:literal) => {
        impl OptionText for $ty {
            const KIND: OptionKind = OptionKind::Choice;
            fn parse_text(option: &'static str, text: &str, allowed: &'static str) -> Result<Self, ConfigError> {
                <$ty>::ALL.into_iter().find(|t| t.as_str() == text).ok_or_else(|| out_of_range(option, text, allowed))
            }
            fn write_text(&self) -> String {
                self.as_str().to_string()
            }
            fn value(&self) -> OptionValue {
                OptionValue::Choice(self.as_str())
            }
        }

        impl std::str::FromStr for $ty {
            type Err = ConfigError;
            fn from_str(s: &str) -> Result<Self, ConfigError> {
                <$ty as OptionText>::parse_text($option, s, allowed_of($option))
            }
        }
    };
}

/// The words of what an option allows, from its range in the table.
macro_rules! allowed {
    (choice($words:literal)) => {
        $words
    };
    (bool) => {
        "true or false"
    };
    (probability) => {
        "a probability in [0, 1]"
    };
    (int($lo:literal, $hi:literal)) => {
        concat!("an integer in ", $lo, "..=", $hi)
    };
    (int_or_none($lo:literal, $hi:literal, $none:literal)) => {
        concat!("an integer in ", $lo, "..=", $hi, ", or none ", $none)
    };
    (size($lo:literal, $hi:literal, $example:literal)) => {
        concat!("HxW or H,W with each in ", $lo, "..=", $hi, ", for example ", $example)
    };
}

/// Whether `$v` (a reference to the field) is within the option's range from the table.
macro_rules! within {
    (choice($words:literal), $v:expr) => {{
        let _ = $v;
        true
    }};
    (bool, $v:expr) => {{
        let _ = $v;
        true
    }};
    (probability, $v:expr) => {
        (0.0..=1.0).contains($v)
    };
    (int($lo:literal, $hi:literal), $v:expr) => {
        ($lo..=$hi).contains($v)
    };
    (int_or_none($lo:literal, $hi:literal, $none:literal), $v:expr) => {
        $v.is_none_or(|n| ($lo..=$hi).contains(&n))
    };
    (size($lo:literal, $hi:literal, $example:literal), $v:expr) => {{
        let &(h, w) = $v;
        ($lo..=$hi).contains(&h) && ($lo..=$hi).contains(&w)
    }};
}

/// A flag from the table: `none`, or `("long", "VALUE")`.
macro_rules! flag {
    (none) => {
        None
    };
    (($long:literal, $value_name:literal)) => {
        Some(CliFlag { long: $long, value_name: $value_name })
    };
}

/// Whether the role in the table is `rule` (rather than `observation`).
macro_rules! is_rule {
    (rule) => {
        true
    };
    (observation) => {
        false
    };
}

/// The one table of options: generates [`Config`], its `Default`, [`OPTIONS`], the range checks of
/// [`Config::validate`], and [`Config::get`], [`Config::set`] and [`Config::value`]. Each row:
///
/// ```text
/// /// Extra field docs (optional; the field's doc starts with `doc`).
/// field: RustType {
///     default: "text Config::set reads",
///     allowed: int(lo, hi) | int_or_none(lo, hi, "meaning of none") | probability | size(lo, hi, "example")
///              | choice("words") | bool,
///     doc: "one line, as SPEC.md's table and the CLI's help say it",
///     role: rule | observation,
///     flag: ("long-flag", "VALUE") | none,
///     page: true | false,
/// },
/// ```
macro_rules! options {
    ($(
        $(#[doc = $extra:literal])*
        $field:ident: $ty:ty {
            default: $default:literal,
            allowed: $kind:ident $(($($range:tt)*))?,
            doc: $doc:literal,
            role: $role:ident,
            flag: $flag:tt,
            page: $page:literal $(,)?
        }
    ),* $(,)?) => {
        /// The options of one environment. `Config::default()` is ChopperScape-v0 with an `rgb` 600 × 800
        /// observation. Each option's default and allowed values are in [`OPTIONS`] (what [`Config::validate`]
        /// checks).
        #[derive(Clone, Debug, PartialEq)]
        pub struct Config {
            $(
                #[doc = concat!($doc, ".")]
                $(#[doc = $extra])*
                pub $field: $ty,
            )*
        }

        /// Every option, in SPEC order ([`OPTION_NAMES`] is its names); the defaults are `Config::default()`, the
        /// v0 rules with an `rgb` 600 × 800 observation.
        pub const OPTIONS: &[OptionInfo] = &[$(
            OptionInfo {
                name: stringify!($field),
                default: $default,
                allowed: allowed!($kind $(($($range)*))?),
                doc: $doc,
                rule: is_rule!($role),
                kind: <$ty as OptionText>::KIND,
                flag: flag!($flag),
                page: $page,
            },
        )*];

        impl Default for Config {
            fn default() -> Self {
                Config {
                    $(
                        $field: <$ty as OptionText>::parse_text(
                            stringify!($field),
                            $default,
                            allowed!($kind $(($($range)*))?),
                        )
                        .expect("every default in the table parses"),
                    )*
                }
            }
        }

        impl Config {
            /// The first option outside its range, in table order.
            fn check_ranges(&self) -> Result<(), ConfigError> {
                $(
                    if !within!($kind $(($($range)*))?, &self.$field) {
                        return Err(out_of_range(
                            stringify!($field),
                            self.$field.write_text(),
                            allowed!($kind $(($($range)*))?),
                        ));
                    }
                )*
                Ok(())
            }

            /// The value of option `name` as text [`Config::set`] takes back (`600x800`, `true`, `0.01`, `none`),
            /// or `None` for an unknown name.
            pub fn get(&self, name: &str) -> Option<String> {
                match name {
                    $(stringify!($field) => Some(self.$field.write_text()),)*
                    _ => None,
                }
            }

            /// The value of option `name`, typed (the Python binding's value of the option), or `None` for an
            /// unknown name.
            pub fn value(&self, name: &str) -> Option<OptionValue> {
                match name {
                    $(stringify!($field) => Some(self.$field.value()),)*
                    _ => None,
                }
            }

            /// `text` (trimmed) read into option `name` of `self`, unvalidated.
            fn parse_into(&mut self, name: &str, text: &str) -> Result<(), ConfigError> {
                match name {
                    $(
                        stringify!($field) => {
                            self.$field = <$ty as OptionText>::parse_text(
                                stringify!($field),
                                text,
                                allowed!($kind $(($($range)*))?),
                            )?;
                        }
                    )*
                    _ => return Err(ConfigError::Unknown { name: name.to_string(), allowed: OPTION_NAMES }),
                }
                Ok(())
            }
        }
    };
}

options! {
    obs_type: ObsType {
        default: "rgb",
        allowed: choice("one of \"rgb\", \"rgb_float\", \"grayscale\", \"features\""),
        doc: "What the agent sees",
        role: observation,
        flag: none,
        page: false,
    },
    /// `(height, width)`, drawn natively.
    obs_size: (u32, u32) {
        default: "600x800",
        allowed: size(8, 4096, "84x84"),
        doc: "Pixel observation size, height x width, drawn at that size",
        role: observation,
        flag: none,
        page: false,
    },
    frame_stack: u32 {
        default: "1",
        allowed: int(1, 64),
        doc: "Number of last observations stacked on the last axis",
        role: observation,
        flag: none,
        page: false,
    },
    hud: bool {
        default: "true",
        allowed: bool,
        doc: "Whether pixel observations carry the HUD (fuel and lives)",
        role: observation,
        flag: none,
        page: false,
    },
    hud_style: HudStyle {
        default: "auto",
        allowed: choice("one of \"auto\", \"text\", \"gauge\""),
        doc: "How drawn frames show fuel and lives (auto: the text line in frames of at least 300x400, gauge bars \
              in smaller ones)",
        role: observation,
        flag: ("hud-style", "auto|text|gauge"),
        page: false,
    },
    look: Look {
        default: "auto",
        allowed: choice("one of \"auto\", \"art\", \"agent\""),
        doc: "How drawn frames show the entities (auto: the tutorial's art in frames of at least 300x400, the agent \
              view in smaller ones: solid boxes of at least 3x3 pixels, one grey level per kind)",
        role: observation,
        flag: none,
        page: false,
    },
    lives: u32 {
        default: "1",
        allowed: int(1, 1000),
        doc: "Lives per episode",
        role: rule,
        flag: ("lives", "L"),
        page: true,
    },
    bird_fuel_collision: BirdFuelCollision {
        default: "pass",
        allowed: choice("\"pass\" or \"destroy\""),
        doc: "What a bird and a fuel tank that collide do",
        role: rule,
        flag: ("bird-fuel-collision", "pass|destroy"),
        page: true,
    },
    alien_prob: f64 {
        default: "0",
        allowed: probability,
        doc: "Probability per step that an alien bird appears",
        role: rule,
        flag: ("aliens", "P"),
        page: true,
    },
    frame_skip: u32 {
        default: "1",
        allowed: int(1, 1000),
        doc: "Steps each action is repeated for",
        role: rule,
        flag: ("frame-skip", "K"),
        page: true,
    },
    sticky_prob: f64 {
        default: "0",
        allowed: probability,
        doc: "Probability per step that the previous action is applied instead of the new one",
        role: rule,
        flag: ("sticky", "P"),
        page: true,
    },
    bird_prob: f64 {
        default: "0.01",
        allowed: probability,
        doc: "Probability per step that a bird appears",
        role: rule,
        flag: ("bird-prob", "P"),
        page: true,
    },
    fuel_prob: f64 {
        default: "0.01",
        allowed: probability,
        doc: "Probability per step that a fuel tank appears",
        role: rule,
        flag: ("fuel-prob", "P"),
        page: true,
    },
    max_fuel: u32 {
        default: "1000",
        allowed: int(1, 1000000),
        doc: "Fuel at reset and after a refill, in steps",
        role: rule,
        flag: ("max-fuel", "N"),
        page: true,
    },
    /// `None` never truncates.
    max_episode_steps: Option<u32> {
        default: "10000",
        allowed: int_or_none(1, 4294967295, "to never truncate"),
        doc: "Agent steps after which an episode is truncated",
        role: rule,
        flag: ("max-episode-steps", "N|none"),
        page: false,
    },
}

/// The option named `name` in [`OPTIONS`], if there is one.
pub fn option_info(name: &str) -> Option<&'static OptionInfo> {
    OPTIONS.iter().find(|o| o.name == name)
}

/// What option `name` of the table allows (for the errors of the enums' `FromStr`).
fn allowed_of(name: &str) -> &'static str {
    option_info(name).map_or("", |o| o.allowed)
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

choice!(ObsType, "obs_type");

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
    /// Both behaviours, in SPEC order.
    pub const ALL: [BirdFuelCollision; 2] = [BirdFuelCollision::Pass, BirdFuelCollision::Destroy];

    /// The name used in SPEC.md: `"pass"` or `"destroy"`.
    pub fn as_str(self) -> &'static str {
        match self {
            BirdFuelCollision::Pass => "pass",
            BirdFuelCollision::Destroy => "destroy",
        }
    }
}

choice!(BirdFuelCollision, "bird_fuel_collision");

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

choice!(HudStyle, "hud_style");

/// How the entities are drawn into a frame: the tutorial's pixel art, or the agent view that a small CNN reads
/// (solid boxes, one grey level per kind, at least [`crate::render::AGENT_MIN_SIDE`] pixels a side). See
/// [`crate::render`] for the agent view and [`crate::render::PIXELS_VERSION`] for its history.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, Default)]
pub enum Look {
    /// The art where sprites keep their shape (frames at least half the full size in each direction,
    /// [`crate::render::TEXT_MIN_SIZE`]), the agent view in smaller frames.
    #[default]
    Auto,
    /// The tutorial's pixel art at every size (pixel layout version 2).
    Art,
    /// The agent view at every size.
    Agent,
}

impl Look {
    /// Every look, in SPEC order.
    pub const ALL: [Look; 3] = [Look::Auto, Look::Art, Look::Agent];

    /// The name used in SPEC.md and Python: `"auto"`, `"art"`, `"agent"`.
    pub fn as_str(self) -> &'static str {
        match self {
            Look::Auto => "auto",
            Look::Art => "art",
            Look::Agent => "agent",
        }
    }
}

choice!(Look, "look");

fn out_of_range(option: &'static str, value: impl ToString, allowed: &'static str) -> ConfigError {
    ConfigError::OutOfRange { option, value: value.to_string(), allowed }
}

impl Config {
    /// A config with `obs_type = Features`, the cheapest observation; otherwise v0.
    pub fn features() -> Config {
        Config { obs_type: ObsType::Features, ..Config::default() }
    }

    /// Checks every option against its range (in [`OPTIONS`] order), then the memory its observation buffers take.
    ///
    /// # Errors
    /// The first option out of range, named, with its allowed range.
    pub fn validate(&self) -> Result<(), ConfigError> {
        self.check_ranges()?;
        let (h, w) = self.obs_size;
        check_budget(
            format!(
                "one environment's observation buffers (obs_type \"{}\", obs_size ({h}, {w}), frame_stack {})",
                self.obs_type.as_str(),
                self.frame_stack
            ),
            self.env_bytes(),
            MAX_ENV_BYTES,
            "choose a smaller obs_size or frame_stack, or obs_type \"grayscale\" or \"features\"",
        )
    }

    /// Bytes of one observation (frame stack included): what a caller's buffer for it takes.
    pub fn observation_bytes(&self) -> u64 {
        let (single, elem) = self.single_observation();
        single * u64::from(self.frame_stack) * elem
    }

    /// Bytes one environment's observation buffers take: the canvas it draws into, the frame stack and its
    /// scratch frame (`frame_stack > 1`), and one observation in the caller's buffer. Exact up to the renderer's
    /// sprites and HUD (a few hundred kilobytes at most). Cannot overflow within the options' ranges. What
    /// [`Config::validate`] holds to [`MAX_ENV_BYTES`](crate::limits::MAX_ENV_BYTES).
    pub fn env_bytes(&self) -> u64 {
        let (single, elem) = self.single_observation();
        // The canvas holds one byte per element of an unstacked observation (RGB or gray); features draw nothing.
        let canvas = if self.obs_type.is_pixels() { single } else { 0 };
        let observation = self.observation_bytes();
        let stack = if self.frame_stack > 1 { observation + single * elem } else { 0 };
        canvas + stack + observation
    }

    /// Elements of one unstacked observation and bytes per element.
    fn single_observation(&self) -> (u64, u64) {
        let (h, w) = (u64::from(self.obs_size.0), u64::from(self.obs_size.1));
        match self.obs_type {
            ObsType::Rgb => (h * w * 3, 1),
            ObsType::RgbFloat => (h * w * 3, 4),
            ObsType::Grayscale => (h * w, 1),
            ObsType::Features => (FEATURES_LEN as u64, 4),
        }
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
        next.parse_into(name, value.trim())?;
        next.validate()?;
        *self = next;
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_default_env_takes_two_rgb_frames() {
        assert_eq!(Config::default().env_bytes(), 2 * 600 * 800 * 3);
        assert_eq!(Config::features().env_bytes(), FEATURES_LEN as u64 * 4);
        assert_eq!(Config::features().observation_bytes(), FEATURES_LEN as u64 * 4);
    }

    #[test]
    fn the_largest_options_are_over_the_budget() {
        let c = Config { obs_size: (4096, 4096), frame_stack: 64, obs_type: ObsType::RgbFloat, ..Config::default() };
        assert_eq!(c.env_bytes(), 4096 * 4096 * 3 * (2 * 64 * 4 + 4 + 1));
        assert!(c.env_bytes() > MAX_ENV_BYTES);
        let err = c.validate().unwrap_err().to_string();
        assert!(err.contains("over the budget of 4.0 GiB") && err.contains("obs_size (4096, 4096)"), "{err}");
    }

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
        assert_eq!(OPTION_NAMES.len(), 15);
        assert_eq!(option_info("lives").map(|o| o.allowed), Some("an integer in 1..=1000"));
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

    /// The words the table generates are those of the hand-written table they replaced, byte for byte: every
    /// error message, CLI help line and `_core.OPTIONS` row stays as it was.
    #[test]
    fn the_generated_words_are_the_words_users_saw() {
        let words: Vec<(&str, &str)> = OPTIONS.iter().map(|o| (o.name, o.allowed)).collect();
        assert_eq!(
            words,
            [
                ("obs_type", "one of \"rgb\", \"rgb_float\", \"grayscale\", \"features\""),
                ("obs_size", "HxW or H,W with each in 8..=4096, for example 84x84"),
                ("frame_stack", "an integer in 1..=64"),
                ("hud", "true or false"),
                ("hud_style", "one of \"auto\", \"text\", \"gauge\""),
                ("look", "one of \"auto\", \"art\", \"agent\""),
                ("lives", "an integer in 1..=1000"),
                ("bird_fuel_collision", "\"pass\" or \"destroy\""),
                ("alien_prob", "a probability in [0, 1]"),
                ("frame_skip", "an integer in 1..=1000"),
                ("sticky_prob", "a probability in [0, 1]"),
                ("bird_prob", "a probability in [0, 1]"),
                ("fuel_prob", "a probability in [0, 1]"),
                ("max_fuel", "an integer in 1..=1000000"),
                ("max_episode_steps", "an integer in 1..=4294967295, or none to never truncate"),
            ]
        );
        let err = Config::default().set("max_fuel", " 0 ").unwrap_err().to_string();
        assert_eq!(err, "invalid value 0 for option `max_fuel`: allowed an integer in 1..=1000000");
        let err = Config::default().set("obs_size", "84xabc").unwrap_err().to_string();
        assert_eq!(
            err,
            "invalid value abc for option `obs_size`: allowed HxW or H,W with each in 8..=4096, for example 84x84"
        );
        let err = "rgba".parse::<ObsType>().unwrap_err().to_string();
        assert_eq!(
            err,
            "invalid value rgba for option `obs_type`: allowed one of \"rgb\", \"rgb_float\", \"grayscale\", \"features\""
        );
    }

    /// The defaults in the table are the constants of the v0 game (`consts`), and each option's kind is its type.
    #[test]
    fn the_table_defaults_are_the_v0_constants() {
        use crate::consts::{BIRD_PROB, FUEL_PROB, HEIGHT, MAX_EPISODE_STEPS, MAX_FUEL, WIDTH};
        let c = Config::default();
        assert_eq!(c.obs_size, (HEIGHT as u32, WIDTH as u32));
        assert_eq!((c.bird_prob, c.fuel_prob, c.max_fuel), (BIRD_PROB, FUEL_PROB, MAX_FUEL));
        assert_eq!(c.max_episode_steps, Some(MAX_EPISODE_STEPS));
        for o in OPTIONS {
            let value = c.value(o.name).unwrap();
            let kind = match value {
                OptionValue::Choice(_) => OptionKind::Choice,
                OptionValue::Bool(_) => OptionKind::Bool,
                OptionValue::Size(_) => OptionKind::Size,
                OptionValue::Integer(_) => OptionKind::Integer,
                OptionValue::IntegerOrNone(_) => OptionKind::IntegerOrNone,
                OptionValue::Probability(_) => OptionKind::Probability,
            };
            assert_eq!(kind, o.kind, "{}", o.name);
        }
        assert_eq!(c.value("gravity"), None);
        for t in BirdFuelCollision::ALL {
            assert_eq!(t.as_str().parse::<BirdFuelCollision>(), Ok(t));
        }
    }

    #[test]
    fn rules_are_the_options_an_action_log_records() {
        let observation: Vec<&str> = OPTIONS.iter().filter(|o| !o.rule).map(|o| o.name).collect();
        assert_eq!(observation, ["obs_type", "obs_size", "frame_stack", "hud", "hud_style", "look"]);
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
            } else if o.kind == OptionKind::Probability {
                for ok in ["0", "1", "0.5"] {
                    Config::features().set(o.name, ok).unwrap();
                }
                for bad in ["-0.01", "1.01", "nan", "inf"] {
                    refused(o.name, bad);
                }
            }
        }
        assert_eq!(integers, 5, "frame_stack, lives, frame_skip, max_fuel, max_episode_steps");
        assert!(option_info("obs_size").unwrap().allowed.contains("8..=4096"));
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
