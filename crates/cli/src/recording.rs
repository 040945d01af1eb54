//! Where a recording goes and how an episode is drawn into it: shared by `record` (which plays, then draws) and
//! `replay` (which re-runs a log, then draws), below both commands.

use std::path::{Path, PathBuf};

use anyhow::Result;
use chopperscape::Config;
use clap::Args;

use crate::episode::{EpisodeResult, replay_actions};
use crate::media::{Recorder, open_frames, open_video};
use crate::output::{PendingDir, check_free};
use crate::progress;

/// Where a recording goes (the flags `record` and `replay` share).
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
    /// Checks every destination before anything is played, so a refusal costs nothing: each is free (or
    /// `--force` is given), its folder exists, and no two of them (nor `input`, the file read) are one file.
    ///
    /// # Errors
    /// A [`crate::UsageError`] for two outputs on one file or a bad extension; another error for an output
    /// that exists or cannot be written.
    pub fn check(&self, input: Option<(&str, &Path)>) -> Result<()> {
        let mut paths: Vec<(&str, &Path, bool)> = Vec::new();
        paths.extend(input.map(|(what, p)| (what, p, false)));
        paths.extend(self.out.as_deref().map(|p| ("--out", p, false)));
        paths.extend(self.frames.as_deref().map(|p| ("--frames", p, true)));
        paths.extend(self.save_actions.as_deref().map(|p| ("--save-actions", p, false)));
        crate::distinct::check(&paths)?;
        if let Some(out) = &self.out {
            crate::media::Format::from_path(out)?;
            check_free(out, self.force)?;
        }
        if let Some(dir) = &self.frames {
            PendingDir::check(dir, self.force)?;
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

/// The sinks `outputs` asks for (none for an action log alone).
pub fn recorder(outputs: &RecordOutputs, frames: u32) -> Result<Recorder> {
    let mut sinks = Vec::new();
    if let Some(out) = &outputs.out {
        sinks.push(open_video(out, frames, outputs.force)?);
    }
    if let Some(dir) = &outputs.frames {
        sinks.push(open_frames(dir, outputs.force)?);
    }
    Ok(Recorder::new(sinks))
}

/// Draws `episode` into the video and frame outputs of `outputs` (for `record`: the episode it just played).
pub fn render(config: &Config, episode: &EpisodeResult, outputs: &RecordOutputs) -> Result<()> {
    let mut recorder = recorder(outputs, episode.steps + 1)?;
    if recorder.is_empty() {
        return Ok(());
    }
    let bar = progress::bar(u64::from(episode.steps) + 1, "recording", false);
    replay_actions(config, episode.seed, &episode.actions, |env| {
        bar.inc(1);
        recorder.push(env)
    })?;
    bar.finish_and_clear();
    recorder.finish()
}
