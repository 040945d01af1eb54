//! MP4 through the `ffmpeg` program, fed raw rgb24 frames on its standard input.

use std::io::Write;
use std::path::Path;
use std::process::{Child, ChildStdin, Command, Stdio};

use anyhow::{Context, Result, bail};

use super::{FPS, FrameSink, H, W};
use crate::output::PendingFile;

/// Pipes frames into `ffmpeg`, which writes an H.264 (or its default MP4 codec) file.
pub struct Mp4Sink {
    child: Option<Child>,
    stdin: Option<ChildStdin>,
    pending: Option<PendingFile>,
}

impl Mp4Sink {
    /// Starts `ffmpeg` writing to a temporary file beside `path`.
    ///
    /// # Errors
    /// `ffmpeg` is not installed, or `path` exists without `force`.
    pub fn create(path: &Path, force: bool) -> Result<Mp4Sink> {
        let pending = PendingFile::create(path, force)?;
        let size = format!("{W}x{H}");
        let rate = FPS.to_string();
        let spawned = Command::new("ffmpeg")
            .args(["-hide_banner", "-loglevel", "error", "-y", "-f", "rawvideo", "-pix_fmt", "rgb24"])
            .args(["-s", &size, "-r", &rate, "-i", "-", "-pix_fmt", "yuv420p", "-movflags", "+faststart", "-f", "mp4"])
            .arg(pending.temp_path())
            .stdin(Stdio::piped())
            .stdout(Stdio::null())
            .stderr(Stdio::piped())
            .spawn();
        let mut child = match spawned {
            Ok(c) => c,
            Err(e) if e.kind() == std::io::ErrorKind::NotFound => bail!(
                "recording .mp4 needs the `ffmpeg` program, which is not installed \
                 (Debian/Ubuntu: apt install ffmpeg); or record .gif or .png instead"
            ),
            Err(e) => return Err(e).context("cannot start ffmpeg"),
        };
        let stdin = child.stdin.take();
        Ok(Mp4Sink { child: Some(child), stdin, pending: Some(pending) })
    }
}

impl FrameSink for Mp4Sink {
    fn push(&mut self, rgb: &[u8]) -> Result<()> {
        let stdin = self.stdin.as_mut().expect("stdin is open until finish");
        stdin.write_all(rgb).context("ffmpeg stopped reading frames")
    }

    fn finish(mut self: Box<Self>) -> Result<()> {
        drop(self.stdin.take());
        let child = self.child.take().expect("the child runs until finish");
        let out = child.wait_with_output().context("ffmpeg did not finish")?;
        if !out.status.success() {
            bail!("ffmpeg failed ({}): {}", out.status, String::from_utf8_lossy(&out.stderr).trim());
        }
        self.pending.take().expect("the file is pending until finish").commit()
    }
}

impl Drop for Mp4Sink {
    /// An abandoned recording stops `ffmpeg`; the temporary file goes with the `PendingFile`.
    fn drop(&mut self) {
        drop(self.stdin.take());
        if let Some(mut child) = self.child.take() {
            let _ = child.kill();
            let _ = child.wait();
        }
    }
}
