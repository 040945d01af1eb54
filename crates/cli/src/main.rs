//! The `chopperscape` command line: watch, play, record, replay, benchmark and train ChopperScape-v0.
//!
//! Every command is one file under `commands/`; the game options of SPEC.md are one shared struct
//! ([`options::GameOptions`]) mapped onto [`chopperscape::Config`] through `Config::set`, so every error names
//! the option and its range. Usage errors (bad flags, bad values) exit with code 2, other failures with 1.

mod commands;
mod distinct;
mod episode;
mod interrupt;
mod media;
mod options;
mod output;
#[cfg(feature = "window")]
mod overlay;
mod progress;
mod recording;
mod report;
mod server;
#[cfg(feature = "window")]
mod window;

use std::process::ExitCode;

use chopperscape_actionlog as actionlog;

use clap::{Parser, Subcommand};

/// ChopperScape-v0 from the command line.
#[derive(Parser, Debug)]
#[command(name = "chopperscape", version, about, long_about = None)]
#[command(after_help = "Examples:\n  chopperscape demo\n  chopperscape play --lives 3\n  \
chopperscape record --policy heuristic --seed 7 --out run.gif\n  chopperscape bench --json")]
struct Cli {
    #[command(subcommand)]
    command: Command,
}

#[derive(Subcommand, Debug)]
enum Command {
    Demo(commands::demo::DemoArgs),
    Play(commands::play::PlayArgs),
    Record(commands::record::RecordArgs),
    Replay(commands::replay::ReplayArgs),
    Bench(commands::bench::BenchArgs),
    Web(commands::web::WebArgs),
    Dataset(commands::dataset::DatasetArgs),
    Train(commands::train::TrainArgs),
}

/// An error in how the command was called (exit code 2), as opposed to a failure while running it (exit code 1).
#[derive(Debug)]
pub struct UsageError(pub String);

impl std::fmt::Display for UsageError {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(&self.0)
    }
}

impl std::error::Error for UsageError {}

/// Returns early with a [`UsageError`].
#[macro_export]
macro_rules! usage_bail {
    ($($arg:tt)*) => {
        return Err(anyhow::Error::new($crate::UsageError(format!($($arg)*))))
    };
}

/// The exit code of a program stopped by a closed pipe (128 + SIGPIPE), as a shell shows it.
const CLOSED_PIPE: u8 = 141;

fn main() -> ExitCode {
    let cli = match Cli::try_parse() {
        Ok(cli) => cli,
        Err(e) => {
            // Help and usage errors; a closed output is no reason to panic.
            let _ = e.print();
            return ExitCode::from(u8::try_from(e.exit_code()).unwrap_or(2));
        }
    };
    if let Command::Train(a) = &cli.command {
        commands::train::set_threads(a);
    }
    if !matches!(cli.command, Command::Web(_))
        && let Err(e) = interrupt::install()
    {
        note!("warning: Ctrl-C will not clean up unfinished files: {e}");
    }
    let result = match cli.command {
        Command::Demo(a) => commands::demo::run(a),
        Command::Play(a) => commands::play::run(a),
        Command::Record(a) => commands::record::run(a),
        Command::Replay(a) => commands::replay::run(a),
        Command::Bench(a) => commands::bench::run(a),
        Command::Web(a) => commands::web::run(a),
        Command::Dataset(a) => commands::dataset::run(a),
        Command::Train(a) => commands::train::run(a),
    };
    match result {
        Ok(code) => code,
        Err(err) => {
            if let Some(out) = err.downcast_ref::<report::StdoutError>()
                && out.0.kind() == std::io::ErrorKind::BrokenPipe
            {
                return ExitCode::from(CLOSED_PIPE);
            }
            note!("error: {err:#}");
            if err.downcast_ref::<UsageError>().is_some() { ExitCode::from(2) } else { ExitCode::FAILURE }
        }
    }
}
