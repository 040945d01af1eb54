//! Animated PNG through the `png` crate. APNG declares its frame count up front, so the caller knows it
//! (episodes are deterministic: they are played headless first, then replayed to record).

use std::fs::File;
use std::io::BufWriter;
use std::path::Path;

use anyhow::{Result, bail};

use super::{FPS, FrameSink, H, W};
use crate::output::PendingFile;

/// Writes an animated PNG of a known number of frames.
pub struct ApngSink {
    writer: png::Writer<BufWriter<File>>,
    pending: PendingFile,
    left: u32,
}

impl ApngSink {
    /// Starts `path` for exactly `frames` frames.
    pub fn create(path: &Path, frames: u32, force: bool) -> Result<ApngSink> {
        let pending = PendingFile::create(path, force)?;
        let mut enc = png::Encoder::new(BufWriter::new(pending.writer()?), W, H);
        enc.set_color(png::ColorType::Rgb);
        enc.set_depth(png::BitDepth::Eight);
        enc.set_compression(png::Compression::Fast);
        enc.set_animated(frames.max(1), 0)?;
        enc.set_frame_delay(1, FPS as u16)?;
        Ok(ApngSink { writer: enc.write_header()?, pending, left: frames.max(1) })
    }
}

impl FrameSink for ApngSink {
    fn push(&mut self, rgb: &[u8]) -> Result<()> {
        if self.left == 0 {
            bail!("more frames than the animated PNG declared");
        }
        self.writer.write_image_data(rgb)?;
        self.left -= 1;
        Ok(())
    }

    fn finish(self: Box<Self>) -> Result<()> {
        if self.left != 0 {
            bail!("the animated PNG is missing {} frames", self.left);
        }
        self.writer.finish()?;
        self.pending.commit()
    }

    fn dest(&self) -> &Path {
        self.pending.dest()
    }
}
