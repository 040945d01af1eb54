//! `chopperscape demo`: watch a built-in or a trained policy play, headless or in a window, and record it.

use std::path::PathBuf;
use std::process::ExitCode;

use anyhow::Result;
use chopperscape::Config;
use clap::{Args, ValueEnum};
use serde_json::json;

use super::{PolicyArg, Tally, policy_and_config, policy_parser, table_header, table_row};
use crate::episode::{EpisodeResult, play_policy, replay_actions};
use crate::media::{Recorder, open_video};
use crate::options::GameOptions;
use crate::progress;
use crate::usage_bail;

/// The file `demo` writes when no `--out` is given (replaced on every run).
pub const DEFAULT_OUT: &str = "chopperscape-demo.gif";

/// How the demo shows its episodes.
#[derive(Clone, Copy, Debug, PartialEq, Eq, ValueEnum)]
pub enum Render {
    /// In a window at 30 fps.
    Human,
    /// Into a video file: --out, or chopperscape-demo.gif (.gif, .png or .mp4 by the file's extension).
    Gif,
    /// Not at all: play headless.
    None,
}

/// Watch a built-in or a trained policy play ChopperScape-v0.
///
/// With no arguments: one episode of the random policy with seed 0, recorded to chopperscape-demo.gif in the
/// current folder (that default file is replaced on every run; a file named with --out is never overwritten
/// without --force). Episodes use seeds S, S+1, …; the random policy's own generator is seeded from the
/// episode's seed too, so every run with the same flags is identical. A trained policy (--policy NAME.onnx,
/// from python -m chopperscape.learn.export) plays greedily under the options it was trained with; a game option
/// given here that changes one of them is used, with a warning.
#[derive(Args, Debug)]
#[command(after_help = "Examples:\n  chopperscape demo\n  \
chopperscape demo --policy heuristic --episodes 10 --seed 0 --json\n  \
chopperscape demo --policy heuristic --out heuristic.mp4\n  chopperscape demo --render human --lives 3\n  \
chopperscape demo --policy models/ppo-features.onnx --episodes 10 --json\n\n\
With --json, each episode prints one line:\n  \
{\"episode\": 0, \"seed\": 0, \"steps\": 312, \"return\": 302, \"cause\": \"bird\"}")]
pub struct DemoArgs {
    /// The policy: random, heuristic, a fixed action (right, left, down, up, noop), or a trained policy
    /// exported by python -m chopperscape.learn.export (NAME.onnx)
    #[arg(long, default_value = "random", value_parser = policy_parser, value_name = "NAME|FILE.onnx")]
    pub policy: PolicyArg,
    /// Number of episodes, at least 1
    #[arg(long, default_value_t = 1, allow_negative_numbers = true, value_parser = clap::value_parser!(u32).range(1..))]
    pub episodes: u32,
    /// Seed of the first episode
    #[arg(long, default_value_t = 0, allow_negative_numbers = true, value_parser = super::seed_parser)]
    pub seed: u64,
    /// Print one JSON object per episode (and nothing else on standard output); implies --render none
    /// unless --out or --render is given
    #[arg(long)]
    pub json: bool,
    /// Record the episodes to this file (.gif, .png as animated PNG, or .mp4 through ffmpeg)
    #[arg(long, value_name = "FILE")]
    pub out: Option<PathBuf>,
    /// Where to show the episodes [default: gif, or none with --json]
    #[arg(long, value_enum)]
    pub render: Option<Render>,
    /// Overwrite the --out file if it exists
    #[arg(long)]
    pub force: bool,
    #[command(flatten)]
    pub options: GameOptions,
}

/// Runs `demo`.
pub fn run(args: DemoArgs) -> Result<ExitCode> {
    let render = match (args.render, &args.out) {
        (Some(Render::None | Render::Human), Some(_)) => {
            usage_bail!("--out records a file; it cannot be combined with --render none or --render human")
        }
        (Some(r), _) => r,
        (None, Some(_)) => Render::Gif,
        (None, None) if args.json => Render::None,
        (None, None) => Render::Gif,
    };
    let (out, force) = match &args.out {
        Some(path) => (path.clone(), args.force),
        None => (PathBuf::from(DEFAULT_OUT), true),
    };
    if render == Render::Gif {
        crate::media::Format::from_path(&out)?;
        crate::output::check_free(&out, force)?;
    }
    let (mut policy, config) = policy_and_config(&args.policy, &args.options)?;

    let bar = progress::bar(u64::from(args.episodes), "playing", args.json);
    // Only a recording or a window replays the episodes; otherwise nothing of them is kept but the tally.
    let keep = render != Render::None;
    let mut results = Vec::new();
    let mut tally = Tally::default();
    if !args.json {
        bar.suspend(|| crate::say!("{}", table_header()))?;
    }
    for i in 0..u64::from(args.episodes) {
        let e = play_policy(&config, &mut policy.as_any(), args.seed.wrapping_add(i), |_| Ok(()))?;
        tally.add(&e);
        let line = if args.json {
            json!({"episode": i, "seed": e.seed, "steps": e.steps, "return": e.ret, "cause": e.cause}).to_string()
        } else {
            table_row(i as usize, &e)
        };
        bar.suspend(|| crate::say!("{line}"))?;
        if keep {
            results.push(e);
        }
        bar.inc(1);
    }
    bar.finish_and_clear();
    if !args.json {
        crate::say!("{tally}")?;
    }

    match render {
        Render::None => {}
        Render::Gif => {
            let frames: u64 = results.iter().map(|e| u64::from(e.steps) + 1).sum();
            let Ok(frames) = u32::try_from(frames) else {
                anyhow::bail!("{frames} frames are more than one recording can hold ({})", u32::MAX)
            };
            record(&config, &results, &out, frames, force, args.json)?;
            let msg = format!("wrote {} ({frames} frames at 30 fps)", out.display());
            if args.json { crate::note!("{msg}") } else { crate::say!("{msg}")? }
        }
        Render::Human => show(&config, &results)?,
    }
    Ok(ExitCode::SUCCESS)
}

/// Re-plays the episodes into one video file.
fn record(
    config: &Config,
    results: &[EpisodeResult],
    out: &std::path::Path,
    frames: u32,
    force: bool,
    json: bool,
) -> Result<()> {
    let mut recorder = Recorder::new(vec![open_video(out, frames, force)?]);
    let bar = progress::bar(u64::from(frames), "recording", json);
    for e in results {
        replay_actions(config, e.seed, &e.actions, |env| {
            bar.inc(1);
            recorder.push(env)
        })?;
    }
    bar.finish_and_clear();
    recorder.finish()
}

/// Shows the episodes in a window at 30 fps; Esc or closing the window stops.
#[cfg(feature = "window")]
fn show(config: &Config, results: &[EpisodeResult]) -> Result<()> {
    let mut window = crate::window::Window::open("ChopperScape demo")?;
    let mut rgb = vec![0; crate::media::FRAME_LEN];
    for e in results {
        let stopped = replay_actions(config, e.seed, &e.actions, |env| {
            if !window.is_open() {
                anyhow::bail!("closed");
            }
            env.render_into(&mut rgb)?;
            window.show(&rgb)
        });
        if stopped.is_err() && !window.is_open() {
            break;
        }
        stopped?;
    }
    Ok(())
}

/// Without the `window` feature there is no window to show.
#[cfg(not(feature = "window"))]
fn show(_config: &Config, _results: &[EpisodeResult]) -> Result<()> {
    usage_bail!("--render human needs a window, and this chopperscape was built without the `window` feature")
}
