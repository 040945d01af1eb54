//! Writing an episode's frames: animated GIF, animated PNG, MP4 (through `ffmpeg`), or a folder of PNGs.
//!
//! Every sink takes full 600 × 800 RGB frames at 30 frames per second and writes through a temporary file
//! that is renamed into place only by `finish` (see [`crate::output`]).

mod apng;
mod frames;
mod gif;
mod mp4;

use std::path::Path;

use anyhow::{Context, Result};
use chopperscape::ChopperScape;
use chopperscape::consts::{HEIGHT, WIDTH};

use crate::UsageError;

/// Frames per second of every recording (SPEC's `render_fps`).
pub const FPS: u32 = 30;
/// Frame width in pixels.
pub const W: u32 = WIDTH as u32;
/// Frame height in pixels.
pub const H: u32 = HEIGHT as u32;
/// Bytes of one RGB frame.
pub const FRAME_LEN: usize = (W * H * 3) as usize;

/// A video file format, chosen by the file's extension.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Format {
    /// `.gif`
    Gif,
    /// `.png`: animated PNG.
    Apng,
    /// `.mp4`, through the `ffmpeg` program.
    Mp4,
}

impl Format {
    /// The format of `path`, by its extension.
    ///
    /// # Errors
    /// A [`UsageError`] for any other extension.
    pub fn from_path(path: &Path) -> Result<Format> {
        let ext = path.extension().map(|e| e.to_string_lossy().to_ascii_lowercase()).unwrap_or_default();
        Ok(match ext.as_str() {
            "gif" => Format::Gif,
            "png" | "apng" => Format::Apng,
            "mp4" => Format::Mp4,
            _ => {
                return Err(UsageError(format!(
                    "cannot record to {}: the file name must end in .gif, .png (animated PNG) or .mp4",
                    path.display()
                ))
                .into());
            }
        })
    }
}

/// Something that takes frames and, when finished, leaves a complete file behind.
pub trait FrameSink {
    /// Adds one 600 × 800 × 3 RGB frame.
    fn push(&mut self, rgb: &[u8]) -> Result<()>;
    /// Completes the output and renames it into place.
    fn finish(self: Box<Self>) -> Result<()>;
    /// The file or folder it writes (named in errors).
    fn dest(&self) -> &Path;
}

/// Opens a video file sink for `frames` frames.
///
/// # Errors
/// An existing file without `force`, a missing folder, or (for `.mp4`) a missing `ffmpeg`.
pub fn open_video(path: &Path, frames: u32, force: bool) -> Result<Box<dyn FrameSink>> {
    Ok(match Format::from_path(path)? {
        Format::Gif => Box::new(gif::GifSink::create(path, force)?),
        Format::Apng => Box::new(apng::ApngSink::create(path, frames, force)?),
        Format::Mp4 => Box::new(mp4::Mp4Sink::create(path, force)?),
    })
}

/// Opens a folder sink that writes `frame_00000.png`, `frame_00001.png`, ….
pub fn open_frames(dir: &Path, force: bool) -> Result<Box<dyn FrameSink>> {
    Ok(Box::new(frames::FramesSink::create(dir, force)?))
}

/// Renders an env's full frame once and hands it to every sink.
pub struct Recorder {
    sinks: Vec<Box<dyn FrameSink>>,
    rgb: Vec<u8>,
}

impl Recorder {
    /// A recorder that feeds `sinks`.
    pub fn new(sinks: Vec<Box<dyn FrameSink>>) -> Recorder {
        Recorder { sinks, rgb: vec![0; FRAME_LEN] }
    }

    /// Whether there is anything to record to.
    pub fn is_empty(&self) -> bool {
        self.sinks.is_empty()
    }

    /// Renders `env`'s current state and adds it to every sink.
    pub fn push(&mut self, env: &ChopperScape) -> Result<()> {
        if self.sinks.is_empty() {
            return Ok(());
        }
        env.render_into(&mut self.rgb)?;
        for sink in &mut self.sinks {
            sink.push(&self.rgb).with_context(|| format!("cannot write {}", sink.dest().display()))?;
        }
        Ok(())
    }

    /// Finishes every sink.
    pub fn finish(self) -> Result<()> {
        for sink in self.sinks {
            let dest = sink.dest().to_path_buf();
            sink.finish().with_context(|| format!("cannot write {}", dest.display()))?;
        }
        Ok(())
    }
}

/// Encodes one RGB frame as a PNG (fast compression) into `w`.
pub fn write_png(w: impl std::io::Write, rgb: &[u8]) -> Result<()> {
    let mut enc = png::Encoder::new(w, W, H);
    enc.set_color(png::ColorType::Rgb);
    enc.set_depth(png::BitDepth::Eight);
    enc.set_compression(png::Compression::Fast);
    let mut writer = enc.write_header()?;
    writer.write_image_data(rgb)?;
    writer.finish()?;
    Ok(())
}
