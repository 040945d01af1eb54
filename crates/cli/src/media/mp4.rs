//! MP4 through the `ffmpeg` program, fed raw rgb24 frames on its standard input.
//!
//! ffmpeg's standard error is read all along by a thread (so it can never fill its pipe and stall ffmpeg) and
//! its last lines go into any error, so "ffmpeg stopped reading frames" says why.

use std::io::{Read, Write};
use std::path::Path;
use std::process::{Child, ChildStdin, Command, Stdio};
use std::thread::JoinHandle;

use anyhow::{Context, Result, anyhow, bail};

use super::{FPS, FrameSink, H, W};
use crate::interrupt::{self, Cleanup, Registered};
use crate::output::PendingFile;

/// The most of ffmpeg's standard error kept for a message, in bytes (its end is kept).
const STDERR_KEPT: usize = 4096;

/// Pipes frames into `ffmpeg`, which writes an H.264 (or its default MP4 codec) file.
pub struct Mp4Sink {
    child: Option<(Child, Registered)>,
    stdin: Option<ChildStdin>,
    stderr: Option<JoinHandle<String>>,
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
        let registered = interrupt::register(Cleanup::Kill(child.id()));
        let stdin = child.stdin.take();
        let stderr = child.stderr.take().map(|mut pipe| {
            std::thread::spawn(move || {
                let mut kept = Vec::new();
                let mut chunk = [0u8; 1024];
                while let Ok(n @ 1..) = pipe.read(&mut chunk) {
                    kept.extend_from_slice(&chunk[..n]);
                    if kept.len() > STDERR_KEPT {
                        kept.drain(..kept.len() - STDERR_KEPT);
                    }
                }
                String::from_utf8_lossy(&kept).trim().to_string()
            })
        });
        Ok(Mp4Sink { child: Some((child, registered)), stdin, stderr, pending: Some(pending) })
    }

    /// Closes ffmpeg's input, waits for it, and returns how it ended and what it said.
    fn wait(&mut self) -> Result<(std::process::ExitStatus, String)> {
        drop(self.stdin.take());
        let (mut child, registered) = self.child.take().ok_or_else(|| anyhow!("ffmpeg was already waited for"))?;
        let status = child.wait().context("ffmpeg did not finish")?;
        drop(registered);
        let said = self.stderr.take().and_then(|t| t.join().ok()).unwrap_or_default();
        Ok((status, said))
    }
}

impl FrameSink for Mp4Sink {
    fn push(&mut self, rgb: &[u8]) -> Result<()> {
        let Some(stdin) = self.stdin.as_mut() else { bail!("ffmpeg's input is already closed") };
        let Err(e) = stdin.write_all(rgb) else { return Ok(()) };
        let (status, said) = self.wait()?;
        if said.is_empty() {
            bail!("ffmpeg stopped reading frames ({e}); it exited with {status} and said nothing");
        }
        bail!("ffmpeg stopped reading frames ({e}); it exited with {status} and said: {said}")
    }

    fn finish(mut self: Box<Self>) -> Result<()> {
        let (status, said) = self.wait()?;
        if !status.success() {
            bail!("ffmpeg failed ({status}): {said}");
        }
        self.pending.take().ok_or_else(|| anyhow!("the file was already written"))?.commit()
    }

    fn dest(&self) -> &Path {
        self.pending.as_ref().map_or(Path::new("the .mp4 file"), |p| p.dest())
    }
}

impl Drop for Mp4Sink {
    /// An abandoned recording stops `ffmpeg`; the temporary file goes with the `PendingFile`.
    fn drop(&mut self) {
        drop(self.stdin.take());
        if let Some((mut child, _registered)) = self.child.take() {
            let _ = child.kill();
            let _ = child.wait();
        }
    }
}
