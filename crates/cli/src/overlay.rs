//! Text and banners drawn over a finished RGB frame (the pause and end-of-episode messages of `play`), with the
//! `font8x8` bitmap font scaled up. Drawn in this crate so the core's renderer stays as SPEC.md states it.

use font8x8::legacy::BASIC_LEGACY;

use crate::media::{H, W};

/// Width in pixels of `text` drawn at `scale`.
pub fn text_width(text: &str, scale: usize) -> usize {
    text.chars().count() * 8 * scale
}

/// Draws `text` with its top-left corner at `(x, y)`, each font pixel `scale` × `scale`; clipped to the frame.
pub fn draw_text(rgb: &mut [u8], x: usize, y: usize, scale: usize, text: &str, color: [u8; 3]) {
    let (w, h) = (W as usize, H as usize);
    for (i, ch) in text.chars().enumerate() {
        let glyph = BASIC_LEGACY.get(ch as usize).copied().unwrap_or(BASIC_LEGACY[b'?' as usize]);
        for (gy, bits) in glyph.iter().enumerate() {
            for gx in 0..8 {
                if bits >> gx & 1 == 0 {
                    continue;
                }
                let (px, py) = (x + (i * 8 + gx) * scale, y + gy * scale);
                for yy in py..(py + scale).min(h) {
                    for xx in px..(px + scale).min(w) {
                        rgb[(yy * w + xx) * 3..][..3].copy_from_slice(&color);
                    }
                }
            }
        }
    }
}

/// Darkens a band across the middle of the frame and writes `lines` centred on it: the first large, the rest
/// smaller.
pub fn banner(rgb: &mut [u8], lines: &[&str]) {
    let (w, h) = (W as usize, H as usize);
    let heights: Vec<usize> = (0..lines.len()).map(|i| if i == 0 { 32 } else { 16 }).collect();
    let gap = 12;
    let total: usize = heights.iter().sum::<usize>() + gap * lines.len().saturating_sub(1);
    let top = (h - total) / 2 - 24;
    let bottom = (top + total + 48).min(h);
    for px in rgb[top * w * 3..bottom * w * 3].iter_mut() {
        *px /= 4;
    }
    let mut y = top + 24;
    for (line, lh) in lines.iter().zip(&heights) {
        let scale = lh / 8;
        let x = w.saturating_sub(text_width(line, scale)) / 2;
        draw_text(rgb, x, y, scale, line, [255, 255, 255]);
        y += lh + gap;
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::media::FRAME_LEN;

    #[test]
    fn banner_darkens_the_middle_and_writes_white_text() {
        let mut rgb = vec![200u8; FRAME_LEN];
        banner(&mut rgb, &["PAUSED", "press P to resume"]);
        let at = |x: usize, y: usize| &rgb[(y * W as usize + x) * 3..][..3];
        assert_eq!(at(5, 5), [200, 200, 200], "outside the band is untouched");
        assert_eq!(at(5, H as usize / 2), [50, 50, 50], "the band is darkened");
        assert!(rgb.chunks_exact(3).any(|p| p == [255, 255, 255]), "text is drawn");
    }
}
