//! The game options of SPEC.md as command-line flags, shared by every command that plays: the rules options,
//! and `--hud-style`, how drawn frames show the fuel and the lives (not a rule: action logs do not record it).
//!
//! Each flag is checked while parsing by `Config::set` on its SPEC name, so a bad value fails with clap's usage
//! error (exit code 2) and the core's message naming the option and its allowed range.

use anyhow::Result;
use chopperscape::{CliFlag, Config, ConfigError, MODES, Mode, OPTIONS, OptionInfo, option_info};
use clap::builder::PossibleValuesParser;
use clap::{Arg, ArgAction, ArgMatches, Command};

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

/// The heading of the game options in the help.
const HEADING: &str = "Game options (SPEC.md; the defaults are the v0 rules)";

/// The options of SPEC.md that have a flag in the core's table ([`chopperscape::OptionInfo::flag`]): the rules
/// options and `--hud-style`; each defaults to the v0 rules. The flags are built from the table at run time
/// ([`GameOptions::augment_args`]), each with [`help`] of its option, so an option added to the table is a flag
/// here with nothing written by hand.
#[derive(Debug, Clone, Default)]
pub struct GameOptions {
    /// The flags given, as `(option, value)`, in table order.
    values: Vec<(&'static OptionInfo, String)>,
    /// The difficulty mode `--mode` names ([`chopperscape::MODES`]): applied before the flags, which may not
    /// contradict the rules it fixes.
    mode: Option<&'static Mode>,
}

/// The `--mode` flag: a name of [`chopperscape::MODES`], as Python's `mode=` and the page's mode take it.
fn mode_arg() -> Arg {
    Arg::new("mode")
        .long("mode")
        .value_name("NAME")
        .help(
            "A difficulty mode of ChopperScape-Bench: it fixes every rules option but --max-episode-steps \
             (docs/SPEC.md, \"Difficulty modes\"); a rules flag given beside it must agree with it",
        )
        .value_parser(PossibleValuesParser::new(MODES.iter().map(|m| m.name)))
        .action(ArgAction::Set)
        .required(false)
}

/// The options of the core's table that have a flag and that `keep` keeps, in table order.
fn flagged(keep: fn(&OptionInfo) -> bool) -> impl Iterator<Item = (&'static OptionInfo, CliFlag)> {
    OPTIONS.iter().filter(move |o| keep(o)).filter_map(|o| o.flag.map(|f| (o, f)))
}

/// Every option with a flag: what the commands that play take.
fn every(_: &OptionInfo) -> bool {
    true
}

/// The observation settings with a flag (`--hud-style`): how frames are drawn, which an action log does not fix.
fn drawing(o: &OptionInfo) -> bool {
    !o.rule
}

/// Reads the flags of the options `keep` keeps from `matches` into `values`, in table order.
fn read(values: &mut Vec<(&'static OptionInfo, String)>, matches: &ArgMatches, keep: fn(&OptionInfo) -> bool) {
    for (o, _) in flagged(keep) {
        if let Some(value) = matches.get_one::<String>(o.name) {
            values.retain(|(given, _)| given.name != o.name);
            values.push((o, value.clone()));
        }
    }
    values.sort_by_key(|(o, _)| OPTIONS.iter().position(|x| x.name == o.name));
}

/// The clap argument of option `o`, whose flag is `flag`: its id is the option's name.
pub fn arg(o: &'static OptionInfo, flag: CliFlag) -> Arg {
    Arg::new(o.name)
        .long(flag.long)
        .help(help(o.name))
        .value_name(flag.value_name)
        .allow_negative_numbers(o.kind.is_numeric())
        .value_parser(option(o.name))
        .action(ArgAction::Set)
        .required(false)
}

impl GameOptions {
    /// The value given for option `name`, if its flag was given.
    pub fn get(&self, name: &str) -> Option<&str> {
        self.values.iter().find(|(o, _)| o.name == name).map(|(_, v)| v.as_str())
    }

    /// The rules options given, as `(Config::set name, value)` (`--hud-style` is not one): those `--mode` fixes
    /// first, then the rules flags.
    pub fn given(&self) -> Vec<(&'static str, &str)> {
        let fixed = self.mode.into_iter().flat_map(|m| m.options.iter().copied());
        fixed.chain(self.values.iter().filter(|(o, _)| o.rule).map(|(o, v)| (o.name, v.as_str()))).collect()
    }

    /// `base` with these options applied, `--hud-style` included: the mode's rules first, then the flags
    /// (the core's [`chopperscape::configure`], as Python and the page build theirs).
    ///
    /// # Errors
    /// A flag that contradicts `--mode` ([`crate::UsageError`], exit code 2); a value `Config::set` refuses
    /// (already checked while parsing, so only in theory).
    pub fn apply(&self, base: Config) -> Result<Config> {
        chopperscape::configure(base, self.mode, |c| self.values.iter().try_for_each(|(o, value)| c.set(o.name, value)))
            .map_err(|e| match e {
                ConfigError::ModeContradiction { .. } => anyhow::Error::new(crate::UsageError(e.to_string())),
                e => anyhow::Error::new(e),
            })
    }
}

impl clap::FromArgMatches for GameOptions {
    fn from_arg_matches(matches: &ArgMatches) -> Result<Self, clap::Error> {
        let mut options = GameOptions::default();
        options.update_from_arg_matches(matches)?;
        Ok(options)
    }

    fn update_from_arg_matches(&mut self, matches: &ArgMatches) -> Result<(), clap::Error> {
        read(&mut self.values, matches, every);
        if let Some(name) = matches.get_one::<String>("mode") {
            self.mode = chopperscape::mode(name);
        }
        Ok(())
    }
}

impl clap::Args for GameOptions {
    fn augment_args(cmd: Command) -> Command {
        let cmd = cmd.next_help_heading(HEADING).arg(mode_arg());
        flagged(every).fold(cmd, |cmd, (o, flag)| cmd.arg(arg(o, flag)))
    }

    fn augment_args_for_update(cmd: Command) -> Command {
        GameOptions::augment_args(cmd)
    }
}

/// The flags of the observation settings that have one (`--hud-style`): what `replay` may change of an action
/// log's config, which fixes the rules. Built from the core's table as [`GameOptions`] is.
#[derive(Debug, Clone, Default)]
pub struct DrawOptions(GameOptions);

impl DrawOptions {
    /// `base` with these options applied.
    ///
    /// # Errors
    /// A value `Config::set` refuses (already checked while parsing, so only in theory).
    pub fn apply(&self, base: Config) -> Result<Config> {
        self.0.apply(base)
    }
}

impl clap::FromArgMatches for DrawOptions {
    fn from_arg_matches(matches: &ArgMatches) -> Result<Self, clap::Error> {
        let mut options = DrawOptions::default();
        options.update_from_arg_matches(matches)?;
        Ok(options)
    }

    fn update_from_arg_matches(&mut self, matches: &ArgMatches) -> Result<(), clap::Error> {
        read(&mut self.0.values, matches, drawing);
        Ok(())
    }
}

impl clap::Args for DrawOptions {
    fn augment_args(cmd: Command) -> Command {
        flagged(drawing).fold(cmd, |cmd, (o, flag)| cmd.arg(arg(o, flag)))
    }

    fn augment_args_for_update(cmd: Command) -> Command {
        DrawOptions::augment_args(cmd)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use clap::{FromArgMatches, Parser};

    #[derive(Parser, Debug)]
    struct Cli {
        #[command(flatten)]
        options: GameOptions,
    }

    fn parse(args: &[&str]) -> Result<GameOptions, clap::Error> {
        Cli::try_parse_from(std::iter::once("t").chain(args.iter().copied())).map(|cli| cli.options)
    }

    #[test]
    fn hud_style_is_applied_but_is_not_a_rule() {
        let options = parse(&["--hud-style", "gauge", "--lives", "2"]).unwrap();
        assert_eq!(options.given(), [("lives", "2")]);
        assert_eq!(options.get("hud_style"), Some("gauge"));
        let c = options.apply(Config::default()).unwrap();
        assert_eq!((c.hud_style, c.lives), (chopperscape::HudStyle::Gauge, 2));
        assert!(!chopperscape_actionlog::rule_values(&c).contains_key("hud_style"));
    }

    /// `--mode` plays each mode of the core's table as its options given one by one, takes only the table's
    /// names, and refuses a rules flag that contradicts it (exit code 2) while one that agrees, the step limit
    /// and the HUD's style stay free.
    #[test]
    fn a_mode_is_its_options_and_refuses_contradictions() {
        for m in chopperscape::MODES {
            let by_mode = parse(&["--mode", m.name]).unwrap().apply(Config::default()).unwrap();
            assert_eq!(by_mode, m.config().unwrap(), "{}", m.name);
            let mut one_by_one = Config::default();
            for (name, value) in m.options {
                one_by_one.set(name, value).unwrap();
            }
            assert_eq!(by_mode, one_by_one, "{}", m.name);
            let free = parse(&["--mode", m.name, "--max-episode-steps", "50", "--hud-style", "gauge"]).unwrap();
            assert_eq!(free.apply(Config::default()).unwrap().max_episode_steps, Some(50));
        }
        let err = parse(&["--mode", "nope"]).unwrap_err().to_string();
        assert!(err.contains("v0") && err.contains("sticky-v0"), "{err}");
        let full = chopperscape::mode("full-v0").unwrap();
        let lives = full.value("lives").unwrap();
        let agree = parse(&["--mode", "full-v0", "--lives", lives]).unwrap();
        assert!(agree.apply(Config::default()).is_ok());
        let clash = parse(&["--mode", "full-v0", "--lives", "7"]).unwrap();
        let err = clash.apply(Config::default()).unwrap_err();
        assert!(err.downcast_ref::<crate::UsageError>().is_some(), "{err}");
        assert!(
            err.to_string().contains("contradict mode \"full-v0\"") && err.to_string().contains("lives 7 != 3"),
            "{err}"
        );
        let v0 = parse(&["--mode", "v0", "--frame-skip", "4"]).unwrap();
        assert!(v0.apply(Config::default()).is_err(), "v0 fixes frame_skip at 1");
        assert!(parse(&["--mode", "sticky-v0"]).unwrap().given().contains(&("sticky_prob", "0.25")));
    }

    /// Walks the core's table: every option with a flag is a flag of the commands that play, with the table's
    /// long name, value name and help, and its value reaches `Config::set` under the option's name; no other
    /// flag is there. Nothing here names an option.
    #[test]
    fn every_flag_is_the_tables() {
        use clap::Args as _;
        let cmd = GameOptions::augment_args(Command::new("t"));
        // `--mode` names a rules set of the modes table, not an option (a_mode_is_its_options_...).
        let args: Vec<&Arg> = cmd.get_arguments().filter(|a| a.get_id() != "mode").collect();
        let table: Vec<(&OptionInfo, CliFlag)> = OPTIONS.iter().filter_map(|o| o.flag.map(|f| (o, f))).collect();
        assert_eq!(args.len(), table.len(), "one flag per option with a flag in the table");
        for (arg, (o, flag)) in args.iter().zip(&table) {
            assert_eq!(arg.get_id().as_str(), o.name);
            assert_eq!(arg.get_long(), Some(flag.long), "{}", o.name);
            assert_eq!(arg.get_value_names().map(|v| v[0].as_str()), Some(flag.value_name), "{}", o.name);
            let help = arg.get_help().map(ToString::to_string).unwrap_or_default();
            assert_eq!(help, format!("{}: {} [default: {}]", o.doc, o.allowed, o.default), "{}", o.name);
            assert_eq!(arg.get_help_heading(), Some(HEADING), "{}", o.name);
            // The default given as a flag sets the option to its default; a value it refuses is a usage error.
            let long = format!("--{}", flag.long);
            let options = parse(&[&long, o.default]).unwrap_or_else(|e| panic!("{long} {}: {e}", o.default));
            assert_eq!(options.get(o.name), Some(o.default));
            assert_eq!(options.given().len(), usize::from(o.rule), "{long} is a rule flag iff a rule");
            let mut c = Config::features();
            c.set(o.name, "1").ok();
            let applied = options.apply(c.clone()).unwrap();
            assert_eq!(applied.get(o.name).as_deref(), Some(o.default), "{long}");
            let err = parse(&[&long, "nonsense"]).unwrap_err();
            assert_eq!(err.kind(), clap::error::ErrorKind::ValueValidation, "{long}");
            assert!(err.to_string().contains(o.allowed), "{long}: {err}");
            if o.kind.is_numeric() {
                assert!(parse(&[&long, "-1"]).unwrap_err().to_string().contains(o.allowed), "{long} -1");
            }
        }
    }

    /// The flags users know, under the names and value names they had before the table made them.
    #[test]
    fn the_flags_keep_their_names() {
        use clap::Args as _;
        let cmd = GameOptions::augment_args(Command::new("t"));
        let mut flags: Vec<(String, String)> = cmd
            .get_arguments()
            .map(|a| (a.get_long().unwrap().to_string(), a.get_value_names().unwrap()[0].to_string()))
            .collect();
        flags.sort();
        let expected = [
            ("aliens", "P"),
            ("bird-fuel-collision", "pass|destroy"),
            ("bird-prob", "P"),
            ("frame-skip", "K"),
            ("fuel-prob", "P"),
            ("hud-style", "auto|text|gauge"),
            ("lives", "L"),
            ("max-episode-steps", "N|none"),
            ("max-fuel", "N"),
            ("mode", "NAME"),
            ("sticky", "P"),
        ];
        assert_eq!(flags, expected.map(|(a, b)| (a.to_string(), b.to_string())));
    }

    #[test]
    fn the_rules_flags_are_the_rules_options() {
        let mut args = Vec::new();
        for o in OPTIONS.iter().filter(|o| o.flag.is_some()) {
            args.push(format!("--{}", o.flag.unwrap().long));
            args.push(o.default.to_string());
        }
        let args: Vec<&str> = args.iter().map(String::as_str).collect();
        let all = parse(&args).unwrap();
        let given: std::collections::BTreeSet<&str> = all.given().into_iter().map(|(name, _)| name).collect();
        let rules: std::collections::BTreeSet<&str> = OPTIONS.iter().filter(|o| o.rule).map(|o| o.name).collect();
        assert_eq!(given, rules, "every rules option has a flag");
    }

    #[test]
    fn replay_takes_the_drawing_flags_only() {
        use clap::Args as _;
        let cmd = DrawOptions::augment_args(Command::new("t"));
        let ids: Vec<&str> = cmd.get_arguments().map(|a| a.get_id().as_str()).collect();
        let drawing: Vec<&str> = OPTIONS.iter().filter(|o| !o.rule && o.flag.is_some()).map(|o| o.name).collect();
        assert_eq!(ids, drawing);
        let matches = cmd.try_get_matches_from(["t", "--hud-style", "text"]).unwrap();
        let draw = DrawOptions::from_arg_matches(&matches).unwrap();
        assert_eq!(draw.apply(Config::default()).unwrap().hud_style, chopperscape::HudStyle::Text);
    }
}
