//! `chopperscape replay`: re-run a saved action log, check it reproduces, and optionally render it.

use std::path::PathBuf;
use std::process::ExitCode;

use anyhow::{Result, bail};
use clap::Args;

use crate::episode::replay_actions;
use crate::options::DrawOptions;
use crate::recording::{RecordOutputs, recorder};
use crate::{actionlog, progress, usage_bail};

/// Re-run a saved action log and check that it reproduces its recorded length, return and end exactly.
///
/// Exits with 1 and says what differs when it does not. Renders like `record` with --out or --frames.
#[derive(Args, Debug)]
#[command(after_help = "Examples:\n  chopperscape replay my-run.json\n  \
chopperscape replay my-run.json --out my-run.gif\n  chopperscape replay my-run.json --json")]
pub struct ReplayArgs {
    /// The action log (written by play, record or demo --save-actions)
    pub file: PathBuf,
    /// Print the replayed episode as one JSON line
    #[arg(long)]
    pub json: bool,
    // How the frames are drawn (`--hud-style`): the flags of the core's table, as in every command.
    #[command(flatten)]
    pub draw: DrawOptions,
    #[command(flatten)]
    pub outputs: RecordOutputs,
}

/// Runs `replay`.
pub fn run(args: ReplayArgs) -> Result<ExitCode> {
    if args.outputs.save_actions.is_some() {
        usage_bail!("replay reads an action log; --save-actions does not apply (copy the file instead)");
    }
    args.outputs.check(Some(("the action log", &args.file)))?;
    let mut log = actionlog::read(&args.file)?;
    log.config = args.draw.apply(log.config)?;
    let bar = progress::bar(u64::from(log.steps) + 1, "replaying", args.json);
    let mut recorder = recorder(&args.outputs, log.steps + 1)?;
    let got = replay_actions(&log.config, log.seed, &log.actions, |env| {
        bar.inc(1);
        recorder.push(env)
    });
    bar.finish_and_clear();
    let got = got.map_err(|e| e.context(format!("{} does not replay", args.file.display())))?;
    if got.steps != log.steps || got.ret != log.ret || got.cause.map(String::from) != log.cause {
        bail!(
            "{} does not reproduce: the log records {} steps, return {}, end {}; the replay gives {} steps, \
             return {}, end {}",
            args.file.display(),
            log.steps,
            log.ret,
            log.cause.as_deref().unwrap_or("running"),
            got.steps,
            got.ret,
            got.cause.unwrap_or("running")
        );
    }
    recorder.finish()?;
    if args.json {
        crate::say!("{}", serde_json::to_string(&got)?)?;
    } else {
        crate::say!(
            "{} ({} playing) reproduces: {} steps, return {}, end {}",
            args.file.display(),
            log.policy.as_deref().unwrap_or("unknown policy"),
            got.steps,
            got.ret,
            got.cause.unwrap_or("running (stopped before the end)")
        )?;
    }
    for (what, path) in [("video", &args.outputs.out), ("frames", &args.outputs.frames)] {
        if let Some(p) = path {
            let msg = format!("wrote {what}: {}", p.display());
            if args.json { crate::note!("{msg}") } else { crate::say!("{msg}")? }
        }
    }
    Ok(ExitCode::SUCCESS)
}
