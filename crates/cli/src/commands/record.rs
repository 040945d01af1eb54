//! `chopperscape record`: one episode of a built-in or a trained policy to a video, a folder of frames, or
//! an action log.

use std::process::ExitCode;

use anyhow::Result;
use clap::Args;

use super::{PolicyArg, policy_and_config, policy_parser, table_header, table_row};
use crate::episode::play_policy;
use crate::options::GameOptions;
use crate::recording::{RecordOutputs, render};
use crate::{actionlog, output, progress, usage_bail};

/// Record one episode of a built-in or a trained policy.
///
/// The episode is played headless first, then replayed to draw its frames (it is deterministic), so the
/// progress bar knows its length. A trained policy (--policy NAME.onnx, from python -m chopperscape.learn.export)
/// plays greedily under the options it was trained with; a game option given here that changes one of them is
/// used, with a warning. Nothing is overwritten without --force; every file is written under a
/// temporary name beside its destination and renamed when complete.
#[derive(Args, Debug)]
#[command(after_help = "Examples:\n  chopperscape record --policy heuristic --seed 7 --out run.gif\n  \
chopperscape record --policy random --seed 1 --out run.mp4 --save-actions run.json\n  \
chopperscape record --policy heuristic --frames frames/\n  \
chopperscape record --policy models/ppo-features.onnx --seed 3 --out agent.gif")]
pub struct RecordArgs {
    /// The policy: random, heuristic, a fixed action (right, left, down, up, noop), or a trained policy
    /// exported by python -m chopperscape.learn.export (NAME.onnx)
    #[arg(long, default_value = "random", value_parser = policy_parser, value_name = "NAME|FILE.onnx")]
    pub policy: PolicyArg,
    /// Seed of the episode (and of the random policy's own generator)
    #[arg(long, default_value_t = 0, allow_negative_numbers = true, value_parser = super::seed_parser)]
    pub seed: u64,
    #[command(flatten)]
    pub outputs: RecordOutputs,
    #[command(flatten)]
    pub options: GameOptions,
}

/// Runs `record`.
pub fn run(args: RecordArgs) -> Result<ExitCode> {
    let o = &args.outputs;
    if !o.any() {
        usage_bail!("nothing to record: give --out FILE, --frames DIR or --save-actions FILE");
    }
    o.check(None)?;
    let (mut policy, config) = policy_and_config(&args.policy, &args.options)?;
    let counter = progress::counter("playing", false);
    let episode = play_policy(&config, &mut policy.as_any(), args.seed, |env| {
        let steps = env.world().steps;
        if steps % 1024 == 0 {
            counter.set_position(u64::from(steps));
        }
        Ok(())
    });
    counter.finish_and_clear();
    let episode = episode?;
    render(&config, &episode, o)?;
    if let Some(path) = &o.save_actions {
        output::write_atomic(
            path,
            actionlog::to_json(&config, &args.policy.name(), &episode.played()).as_bytes(),
            o.force,
        )?;
    }
    crate::say!("{}\n{}", table_header(), table_row(0, &episode))?;
    for (what, path) in [("video", &o.out), ("frames", &o.frames), ("actions", &o.save_actions)] {
        if let Some(p) = path {
            crate::say!("wrote {what}: {}", p.display())?;
        }
    }
    Ok(ExitCode::SUCCESS)
}
