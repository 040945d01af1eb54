//! A folder of numbered PNG frames.

use std::io::BufWriter;
use std::path::Path;

use anyhow::{Context, Result};

use super::{FrameSink, write_png};
use crate::output::PendingDir;

/// Writes `frame_00000.png`, `frame_00001.png`, … into a temporary folder renamed into place at the end.
pub struct FramesSink {
    dir: PendingDir,
    next: u32,
}

impl FramesSink {
    /// Starts the folder `dir`.
    pub fn create(dir: &Path, force: bool) -> Result<FramesSink> {
        Ok(FramesSink { dir: PendingDir::create(dir, force)?, next: 0 })
    }
}

impl FrameSink for FramesSink {
    fn push(&mut self, rgb: &[u8]) -> Result<()> {
        let path = self.dir.path().join(format!("frame_{:05}.png", self.next));
        let file = std::fs::File::create(&path).with_context(|| format!("cannot write {}", path.display()))?;
        write_png(BufWriter::new(file), rgb)?;
        self.next += 1;
        Ok(())
    }

    fn finish(self: Box<Self>) -> Result<()> {
        self.dir.commit()
    }

    fn dest(&self) -> &Path {
        self.dir.dest()
    }
}
