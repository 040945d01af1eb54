//! `chopperscape record`: one episode of a built-in pilot to a video, a folder of frames, or an action log.

use std::path::PathBuf;
use std::process::ExitCode;

use anyhow::Result;
use chopperscape::Config;
use clap::Args;

use super::{policy_parser, table_header, table_row};
use crate::episode::play_policy;
use crate::options::GameOptions;
use crate::output::check_free;
use crate::{actionlog, output, usage_bail};

/// Record one episode of a built-in pilot.
///
/// The episode is played headless first, then replayed to draw its frames (it is deterministic), so the
/// progress bar knows its length. Nothing is overwritten without --force; every file is written under a
/// temporary name beside its destination and renamed when complete.
#[derive(Args, Debug)]
#[command(after_help = "Examples:\n  chopperscape record --policy heuristic --seed 7 --out run.gif\n  \
chopperscape record --policy random --seed 1 --out run.mp4 --save-actions run.json\n  \
chopperscape record --policy heuristic --frames frames/")]
pub struct RecordArgs {
    /// The pilot: random, heuristic, or a fixed action (right, left, down, up, noop)
    #[arg(long, default_value = "random", value_parser = policy_parser())]
    pub policy: String,
    /// Seed of the episode (and of the random pilot's own generator)
    #[arg(long, default_value_t = 0)]
    pub seed: u64,
    #[command(flatten)]
    pub outputs: RecordOutputs,
    #[command(flatten)]
    pub options: GameOptions,
}

/// Where a recording goes (shared by `record` and `replay`).
#[derive(Args, Debug, Clone)]
pub struct RecordOutputs {
    /// Video file: .gif, .png (animated PNG) or .mp4 (needs the ffmpeg program)
    #[arg(long, value_name = "FILE")]
    pub out: Option<PathBuf>,
    /// Folder to write numbered PNG frames into (frame_00000.png, …)
    #[arg(long, value_name = "DIR")]
    pub frames: Option<PathBuf>,
    /// Write the episode as an action log (JSON) for `chopperscape replay`
    #[arg(long, value_name = "FILE")]
    pub save_actions: Option<PathBuf>,
    /// Overwrite existing outputs
    #[arg(long)]
    pub force: bool,
}

impl RecordOutputs {
    /// Checks every destination before anything is played, so a refusal costs nothing.
    pub fn check(&self) -> Result<()> {
        if let Some(out) = &self.out {
            crate::media::Format::from_path(out)?;
            check_free(out, self.force)?;
        }
        if let Some(path) = &self.save_actions {
            check_free(path, self.force)?;
        }
        Ok(())
    }

    /// Whether any output is asked for.
    pub fn any(&self) -> bool {
        self.out.is_some() || self.frames.is_some() || self.save_actions.is_some()
    }
}

/// Runs `record`.
pub fn run(args: RecordArgs) -> Result<ExitCode> {
    let o = &args.outputs;
    if !o.any() {
        usage_bail!("nothing to record: give --out FILE, --frames DIR or --save-actions FILE");
    }
    o.check()?;
    let config = args.options.apply(Config::default())?;
    let episode = play_policy(&config, &args.policy, args.seed, |_| Ok(()))?;
    super::replay::render(&config, &episode, o)?;
    if let Some(path) = &o.save_actions {
        output::write_atomic(path, actionlog::to_json(&config, &args.policy, &episode).as_bytes(), o.force)?;
    }
    println!("{}\n{}", table_header(), table_row(0, &episode));
    for (what, path) in [("video", &o.out), ("frames", &o.frames), ("actions", &o.save_actions)] {
        if let Some(p) = path {
            println!("wrote {what}: {}", p.display());
        }
    }
    Ok(ExitCode::SUCCESS)
}
