//! Sprites resampled once to the frame's scale: opaque runs per row, pixel bytes in the frame's format.

use super::art::Art;
use super::canvas::{Canvas, PixRect, PixelFormat};

/// One row segment of opaque pixels.
#[derive(Clone, Copy, Debug)]
struct Run {
    /// Row within the sprite.
    dy: u16,
    /// First column within the sprite.
    dx: u16,
    /// Pixels in the run.
    len: u16,
    /// Offset of its first pixel's bytes in [`ScaledSprite::bytes`].
    offset: u32,
}

/// A sprite at the frame's scale, ready to blit.
#[derive(Clone, Debug)]
pub(crate) struct ScaledSprite {
    /// Size in frame pixels.
    pub w: usize,
    pub h: usize,
    runs: Vec<Run>,
    bytes: Vec<u8>,
}

impl ScaledSprite {
    /// Resamples `art` (native size `sw × sh`) to `w × h` frame pixels by box filtering, in exact integers.
    ///
    /// Each frame pixel covers a footprint of the native sprite; it is opaque when at least half of that
    /// footprint is, and takes the area-weighted mean colour of the opaque part (rounded). At native size this
    /// is the identity; when shrinking it keeps thin shapes from vanishing the way point sampling would. If a
    /// sprite would come out fully transparent (tiny frames), any coverage at all counts as opaque.
    pub fn new(art: &Art, w: usize, h: usize, format: PixelFormat) -> ScaledSprite {
        let (sw, sh) = (art.width(), art.height());
        // In units where a native pixel is `w` (x) or `h` (y) long, a frame pixel is `sw` (x) or `sh` (y) long.
        let overlap = |d: usize, s: usize, dlen: usize, slen: usize| -> u64 {
            let (a0, a1) = (d * slen, (d + 1) * slen);
            let (b0, b1) = (s * dlen, (s + 1) * dlen);
            a1.min(b1).saturating_sub(a0.max(b0)) as u64
        };
        let sample = |dx: usize, dy: usize| -> (u64, [u64; 3]) {
            let (mut cover, mut sum) = (0u64, [0u64; 3]);
            let (x0, x1) = (dx * sw / w, ((dx + 1) * sw).div_ceil(w).min(sw));
            let (y0, y1) = (dy * sh / h, ((dy + 1) * sh).div_ceil(h).min(sh));
            for sy in y0..y1 {
                let oy = overlap(dy, sy, h, sh);
                for sx in x0..x1 {
                    if let Some(c) = art.pixel(sx, sy) {
                        let a = oy * overlap(dx, sx, w, sw);
                        cover += a;
                        for (s, v) in sum.iter_mut().zip(c) {
                            *s += a * v as u64;
                        }
                    }
                }
            }
            (cover, sum)
        };
        let area = (sw * sh) as u64;
        let build = |any: bool| {
            let mut runs = Vec::new();
            let mut bytes = Vec::new();
            let bpp = format.bytes_per_pixel();
            for dy in 0..h {
                let mut open: Option<Run> = None;
                for dx in 0..w {
                    let (cover, sum) = sample(dx, dy);
                    let opaque = if any { cover > 0 } else { 2 * cover >= area };
                    if opaque {
                        let run = open.get_or_insert(Run {
                            dy: dy as u16,
                            dx: dx as u16,
                            len: 0,
                            offset: bytes.len() as u32,
                        });
                        run.len += 1;
                        let c = sum.map(|s| ((s + cover / 2) / cover) as u8);
                        format.push(&mut bytes, c);
                    } else if let Some(run) = open.take() {
                        runs.push(run);
                    }
                }
                runs.extend(open.take());
            }
            debug_assert_eq!(bytes.len(), runs.iter().map(|r| r.len as usize * bpp).sum::<usize>());
            (runs, bytes)
        };
        let (mut runs, mut bytes) = build(false);
        if runs.is_empty() {
            (runs, bytes) = build(true);
        }
        ScaledSprite { w, h, runs, bytes }
    }

    /// A solid `w × h` box of grey level `grey` (the agent view's sprites).
    pub fn solid(w: usize, h: usize, grey: u8, format: PixelFormat) -> ScaledSprite {
        let bpp = format.bytes_per_pixel();
        let runs =
            (0..h).map(|dy| Run { dy: dy as u16, dx: 0, len: w as u16, offset: (dy * w * bpp) as u32 }).collect();
        let mut bytes = Vec::with_capacity(w * h * bpp);
        for _ in 0..w * h {
            format.push(&mut bytes, [grey; 3]);
        }
        ScaledSprite { w, h, runs, bytes }
    }

    /// Draws the sprite with its top-left corner at `(x, y)`, clipped to the canvas. Returns the clipped box.
    #[inline]
    pub fn blit(&self, canvas: &mut Canvas<'_>, x: usize, y: usize) -> PixRect {
        let bpp = canvas.bpp;
        let (cw, ch) = (canvas.width, canvas.height);
        let rect = PixRect { x, y, w: self.w.min(cw.saturating_sub(x)), h: self.h.min(ch.saturating_sub(y)) };
        if rect.w == self.w && rect.h == self.h {
            for r in &self.runs {
                let (len, src) = (r.len as usize * bpp, r.offset as usize);
                let dst = ((y + r.dy as usize) * cw + x + r.dx as usize) * bpp;
                canvas.bytes[dst..dst + len].copy_from_slice(&self.bytes[src..src + len]);
            }
        } else {
            for r in &self.runs {
                let (py, px) = (y + r.dy as usize, x + r.dx as usize);
                if py >= ch || px >= cw {
                    continue;
                }
                let len = (r.len as usize).min(cw - px) * bpp;
                let (src, dst) = (r.offset as usize, (py * cw + px) * bpp);
                canvas.bytes[dst..dst + len].copy_from_slice(&self.bytes[src..src + len]);
            }
        }
        rect
    }
}
