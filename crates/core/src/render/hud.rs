//! The text HUD: `Fuel Left: N | Rewards: N` (plus ` | Lives: N` with more than one life), in black.
//!
//! The font is `font8x8`'s public-domain 8 × 8 bitmap font, drawn at twice its size in the 800 × 600 frame (`|` as a solid bar):
//! each glyph is a 16 × 16 cell, the text's left end at x = 10 and the bottom of its capitals on the baseline
//! y = 20 (glyph rows 0–6 above it, the descender row below), so cells span y = 6..22.
//!
//! At other frame sizes the text is scaled like everything else: each frame pixel samples the 800 × 600 text
//! at its centre (nearest neighbour), through column and row tables built once. From half the full size
//! down (`TEXT_MIN_SIZE`) every font bit still gets a pixel; below it bits are skipped, and at small sizes
//! (84 × 84) the line becomes a band one or two pixels high that is no longer legible but still changes with
//! the numbers (what `hud_style = "text"` draws; `"auto"` draws the gauges there). Text beyond the right edge is
//! cut off.

use std::fmt::Write;

use font8x8::legacy::BASIC_LEGACY;

use super::canvas::Canvas;
use crate::consts::{HEIGHT, HUD_ORIGIN, WIDTH};
use crate::world::World;

/// `|` as a solid bar: `font8x8` draws a broken bar, which reads as a colon at a glance.
const SOLID_BAR: [u8; 8] = [0x18, 0x18, 0x18, 0x18, 0x18, 0x18, 0x18, 0x18];
/// Glyph cell side in 800 × 600 pixels (the 8 × 8 font at twice its size).
const CELL: usize = 16;
/// Font pixels per glyph bit.
const DOT: usize = CELL / 8;
/// Characters that fit between the left end and the frame's right edge.
pub(crate) const MAX_CHARS: usize = (WIDTH as usize - HUD_ORIGIN.0 as usize) / CELL;

/// The HUD text of one frame, formatted without allocating.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(crate) struct HudText {
    bytes: [u8; MAX_CHARS],
    len: usize,
}

impl HudText {
    /// The empty line.
    pub const EMPTY: HudText = HudText { bytes: [b' '; MAX_CHARS], len: 0 };

    /// The line for `world`; `Lives` appears when the `lives` option is more than 1.
    pub fn of(world: &World, max_lives: u32) -> HudText {
        let mut t = HudText::EMPTY;
        let _ = write!(t, "Fuel Left: {} | Rewards: {}", world.fuel_left, world.episode_return);
        if max_lives > 1 {
            let _ = write!(t, " | Lives: {}", world.lives);
        }
        t
    }

    /// The character in slot `i` (a space past the end).
    fn at(&self, i: usize) -> u8 {
        self.bytes[i]
    }
}

impl Write for HudText {
    fn write_str(&mut self, s: &str) -> std::fmt::Result {
        for &b in s.as_bytes() {
            if self.len < MAX_CHARS {
                self.bytes[self.len] = b;
                self.len += 1;
            }
        }
        Ok(())
    }
}

/// Where the text lands in one frame size: built once per renderer.
#[derive(Clone, Debug)]
pub(crate) struct HudLayout {
    /// Frame columns of each character slot, `[start, end)`; empty for slots that sample no column.
    slot_cols: Vec<(usize, usize)>,
    /// For each frame column from the first slot's start: the glyph bit (0 = leftmost) it samples.
    col_bit: Vec<u8>,
    /// First column of `col_bit`.
    col0: usize,
    /// Frame rows of the text and the glyph row each samples.
    rows: Vec<(usize, u8)>,
}

impl HudLayout {
    /// The layout for a `height × width` frame.
    pub fn new(height: usize, width: usize) -> HudLayout {
        let (left, top) = (HUD_ORIGIN.0 as usize, HUD_ORIGIN.1 as usize - 7 * DOT);
        // A frame pixel's centre in 800 × 600 pixels: ((2d + 1) · 800) / (2 · width), rounded down.
        let sample = |d: usize, full: usize, size: usize| ((2 * d + 1) * full) / (2 * size);
        let mut slot_cols = vec![(0, 0); MAX_CHARS];
        let mut col_bit = Vec::new();
        let mut col0 = None;
        for dx in 0..width {
            let sx = sample(dx, WIDTH as usize, width);
            if sx < left || sx >= left + MAX_CHARS * CELL {
                continue;
            }
            let slot = (sx - left) / CELL;
            let c0 = *col0.get_or_insert(dx);
            let cols = &mut slot_cols[slot];
            if cols.1 == 0 {
                cols.0 = dx;
            }
            cols.1 = dx + 1;
            debug_assert_eq!(col_bit.len(), dx - c0);
            col_bit.push((((sx - left) % CELL) / DOT) as u8);
        }
        let rows = (0..height)
            .filter_map(|dy| {
                let sy = sample(dy, HEIGHT as usize, height);
                (top..top + CELL).contains(&sy).then(|| (dy, ((sy - top) / DOT) as u8))
            })
            .collect();
        HudLayout { slot_cols, col_bit, col0: col0.unwrap_or(0), rows }
    }

    /// The last frame row the text touches, plus one (0 when it touches none).
    pub fn bottom(&self) -> usize {
        self.rows.last().map_or(0, |&(y, _)| y + 1)
    }

    /// Draws the whole line onto a canvas whose HUD area is background.
    pub fn draw_full(&self, canvas: &mut Canvas<'_>, text: &HudText) {
        for i in 0..text.len {
            self.draw_slot(canvas, i, text.at(i));
        }
    }

    /// Redraws the slots whose character differs between `old` (on the canvas) and `new`.
    pub fn draw_changes(&self, canvas: &mut Canvas<'_>, old: &HudText, new: &HudText) {
        for i in 0..old.len.max(new.len) {
            if old.at(i) != new.at(i) {
                self.draw_slot(canvas, i, new.at(i));
            }
        }
    }

    /// Writes slot `i`'s whole cell: black where the glyph has ink, background elsewhere.
    fn draw_slot(&self, canvas: &mut Canvas<'_>, i: usize, ch: u8) {
        let (c0, c1) = self.slot_cols[i];
        if c0 >= c1 {
            return;
        }
        let glyph = match ch {
            b'|' => &SOLID_BAR,
            _ => BASIC_LEGACY.get(ch as usize).unwrap_or(&BASIC_LEGACY[b'?' as usize]),
        };
        let bits = &self.col_bit[c0 - self.col0..c1 - self.col0];
        let bpp = canvas.bpp;
        for &(y, gr) in &self.rows {
            let row = glyph[gr as usize];
            let start = (y * canvas.width + c0) * bpp;
            let px = &mut canvas.bytes[start..start + (c1 - c0) * bpp];
            for (p, &b) in px.chunks_exact_mut(bpp).zip(bits) {
                p.fill(if (row >> b) & 1 == 1 { 0 } else { super::canvas::BACKGROUND });
            }
        }
    }
}
