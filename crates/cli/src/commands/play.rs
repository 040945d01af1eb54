//! `chopperscape play`: a person flies the chopper in a window.

use std::path::PathBuf;
use std::process::ExitCode;

use anyhow::Result;
use chopperscape::Config;
use clap::Args;

use crate::options::GameOptions;

/// Fly the chopper yourself, in a window at 30 fps.
///
/// Arrow keys or WASD move; P pauses; R restarts (with the next seed); Esc or closing the window quits.
/// On quitting, one JSON line describes the last episode (seed, steps, return, cause, the chopper's start
/// and end positions), and --save-actions writes it as an action log for `chopperscape replay`.
/// Without a display, use `chopperscape demo` or the browser version, `chopperscape web`.
#[derive(Args, Debug)]
#[command(after_help = "Examples:\n  chopperscape play\n  chopperscape play --lives 3 --aliens 0.005\n  \
chopperscape play --seed 3 --save-actions my-run.json && chopperscape replay my-run.json")]
pub struct PlayArgs {
    /// Seed of the first episode (R restarts with the next one)
    #[arg(long, default_value_t = 0, allow_negative_numbers = true, value_parser = super::seed_parser)]
    pub seed: u64,
    /// Write the last episode played as an action log (JSON) to this file
    #[arg(long, value_name = "FILE")]
    pub save_actions: Option<PathBuf>,
    /// Overwrite the --save-actions file if it exists
    #[arg(long)]
    pub force: bool,
    #[command(flatten)]
    pub options: GameOptions,
}

/// Runs `play`.
pub fn run(args: PlayArgs) -> Result<ExitCode> {
    if let Some(path) = &args.save_actions {
        crate::output::check_free(path, args.force)?;
    }
    let config = args.options.apply(Config::default())?;
    game::play(&config, &args)
}

#[cfg(feature = "window")]
mod game {
    use std::process::ExitCode;

    use anyhow::Result;
    use chopperscape::Config;
    use minifb::Key;

    use super::PlayArgs;
    use crate::episode::Runner;
    use crate::media::FRAME_LEN;
    use crate::overlay::banner;
    use crate::window::Window;
    use crate::{actionlog, output};

    /// The window loop: one step per frame while running.
    pub fn play(config: &Config, args: &PlayArgs) -> Result<ExitCode> {
        let mut window = Window::open("ChopperScape")?;
        let mut runner = Runner::new(config)?;
        let mut seed = args.seed;
        runner.reset(seed);
        let mut paused = false;
        let mut rgb = vec![0; FRAME_LEN];
        while window.is_open() {
            if window.pressed(Key::R) {
                seed = seed.wrapping_add(1);
                runner.reset(seed);
                paused = false;
            }
            if window.pressed(Key::P) && !runner.is_over() {
                paused = !paused;
            }
            if !paused && !runner.is_over() {
                runner.step(window.held_action())?;
            }
            runner.env().render_into(&mut rgb)?;
            let result = runner.result();
            if paused {
                banner(&mut rgb, &["PAUSED", "press P to resume"]);
            } else if let Some(cause) = result.cause {
                let headline = match cause {
                    "bird" => "CRASHED INTO A BIRD",
                    "fuel" => "OUT OF FUEL",
                    _ => "TIME IS UP",
                };
                let score = format!("score {} in {} steps", result.ret, result.steps);
                banner(&mut rgb, &[headline, &score, "press R to restart, Esc to quit"]);
            }
            window.show(&rgb)?;
        }
        let result = runner.result();
        // The played episode is saved first, so a closed standard output cannot lose it.
        if let Some(path) = &args.save_actions {
            output::write_atomic(path, actionlog::to_json(config, "human", &result.played()).as_bytes(), args.force)?;
            crate::note!("wrote {} ({} actions)", path.display(), result.steps);
        }
        crate::say!("{}", serde_json::to_string(&result)?)?;
        Ok(ExitCode::SUCCESS)
    }
}

#[cfg(not(feature = "window"))]
mod game {
    use std::process::ExitCode;

    use anyhow::{Result, bail};
    use chopperscape::Config;

    use super::PlayArgs;

    /// Without the `window` feature there is nothing to play in.
    pub fn play(_config: &Config, _args: &PlayArgs) -> Result<ExitCode> {
        bail!(
            "this chopperscape was built without the `window` feature, so `play` cannot open a window.\n  \
             Watch the game: chopperscape demo\n  Play it in a browser: chopperscape web"
        )
    }
}
