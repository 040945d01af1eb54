//! Animated GIF through the `gif` crate.
//!
//! The game's frames use few colours, so each frame is indexed exactly against its own palette (no
//! quantization, no dithering; the `gif` crate's NeuQuant is the fallback for a frame with more than 256
//! colours). Only the rectangle that changed since the previous frame is stored, which keeps files small.
//! GIF delays are in hundredths of a second, so they alternate 3 and 4 to average exactly 30 fps.

use std::collections::HashMap;
use std::fs::File;
use std::io::BufWriter;
use std::path::Path;

use anyhow::Result;

use super::{FPS, FrameSink, H, W};
use crate::output::PendingFile;

/// Writes an animated GIF that loops forever.
pub struct GifSink {
    encoder: gif::Encoder<BufWriter<File>>,
    pending: PendingFile,
    previous: Option<Vec<u8>>,
    frames: u64,
}

impl GifSink {
    /// Starts `path`.
    pub fn create(path: &Path, force: bool) -> Result<GifSink> {
        let pending = PendingFile::create(path, force)?;
        let mut encoder = gif::Encoder::new(BufWriter::new(pending.writer()?), W as u16, H as u16, &[])?;
        encoder.set_repeat(gif::Repeat::Infinite)?;
        Ok(GifSink { encoder, pending, previous: None, frames: 0 })
    }

    /// Delay of frame `i` in hundredths of a second, so that frame `i` starts at `round(i * 100 / FPS)`.
    fn delay(i: u64) -> u16 {
        let at = |i: u64| (i * 100 + u64::from(FPS) / 2) / u64::from(FPS);
        (at(i + 1) - at(i)) as u16
    }
}

/// The smallest rectangle `(left, top, width, height)` holding every pixel that differs, if any does.
fn changed_rect(a: &[u8], b: &[u8]) -> Option<(usize, usize, usize, usize)> {
    let (w, h) = (W as usize, H as usize);
    let row = |y: usize| a[y * w * 3..(y + 1) * w * 3] != b[y * w * 3..(y + 1) * w * 3];
    let top = (0..h).find(|&y| row(y))?;
    let bottom = (0..h).rev().find(|&y| row(y))?;
    let (mut left, mut right) = (w, 0);
    for y in top..=bottom {
        let (ra, rb) = (&a[y * w * 3..(y + 1) * w * 3], &b[y * w * 3..(y + 1) * w * 3]);
        if let Some(x) = (0..left).find(|&x| ra[x * 3..x * 3 + 3] != rb[x * 3..x * 3 + 3]) {
            left = x;
        }
        if let Some(x) = (right..w).rev().find(|&x| ra[x * 3..x * 3 + 3] != rb[x * 3..x * 3 + 3]) {
            right = x;
        }
    }
    let right = right.max(left);
    Some((left, top, right - left + 1, bottom - top + 1))
}

/// The pixels of a rectangle of `rgb` as a GIF frame: exactly indexed when it has at most 256 colours.
fn frame_of(rgb: &[u8], (left, top, width, height): (usize, usize, usize, usize)) -> gif::Frame<'static> {
    let mut pixels = Vec::with_capacity(width * height * 3);
    for y in top..top + height {
        let start = (y * W as usize + left) * 3;
        pixels.extend_from_slice(&rgb[start..start + width * 3]);
    }
    let mut index: HashMap<[u8; 3], u8> = HashMap::new();
    let mut palette = Vec::new();
    let mut indexed = Vec::with_capacity(width * height);
    let mut last: Option<([u8; 3], u8)> = None;
    for p in pixels.chunks_exact(3) {
        let c = [p[0], p[1], p[2]];
        let i = match last {
            Some((lc, li)) if lc == c => li,
            _ => {
                let next = index.len();
                let i = match index.get(&c) {
                    Some(&i) => i,
                    None if next < 256 => {
                        index.insert(c, next as u8);
                        palette.extend_from_slice(&c);
                        next as u8
                    }
                    None => return gif::Frame::from_rgb_speed(width as u16, height as u16, &pixels, 10),
                };
                last = Some((c, i));
                i
            }
        };
        indexed.push(i);
    }
    gif::Frame::from_palette_pixels(width as u16, height as u16, indexed, palette, None)
}

impl FrameSink for GifSink {
    fn push(&mut self, rgb: &[u8]) -> Result<()> {
        let full = (0, 0, W as usize, H as usize);
        let rect = match &self.previous {
            None => full,
            // Nothing changed: a one-pixel frame keeps the timing.
            Some(prev) => changed_rect(prev, rgb).unwrap_or((0, 0, 1, 1)),
        };
        let mut frame = frame_of(rgb, rect);
        frame.left = rect.0 as u16;
        frame.top = rect.1 as u16;
        frame.delay = Self::delay(self.frames);
        frame.dispose = gif::DisposalMethod::Keep;
        self.encoder.write_frame(&frame)?;
        self.frames += 1;
        match &mut self.previous {
            Some(prev) => prev.copy_from_slice(rgb),
            None => self.previous = Some(rgb.to_vec()),
        }
        Ok(())
    }

    fn finish(self: Box<Self>) -> Result<()> {
        let GifSink { encoder, pending, .. } = *self;
        drop(encoder.into_inner()?);
        pending.commit()
    }

    fn dest(&self) -> &Path {
        self.pending.dest()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn delays_average_thirty_frames_per_second() {
        let total: u64 = (0..30).map(|i| u64::from(GifSink::delay(i))).sum();
        assert_eq!(total, 100);
        assert!((0..30).all(|i| matches!(GifSink::delay(i), 3 | 4)));
    }

    #[test]
    fn changed_rect_bounds_exactly_the_changed_pixels() {
        let a = vec![255u8; (W * H * 3) as usize];
        let mut b = a.clone();
        assert_eq!(changed_rect(&a, &b), None);
        for (x, y) in [(10usize, 20usize), (30, 5), (12, 40)] {
            b[(y * W as usize + x) * 3 + 1] = 0;
        }
        assert_eq!(changed_rect(&a, &b), Some((10, 5, 21, 36)));
    }
}
