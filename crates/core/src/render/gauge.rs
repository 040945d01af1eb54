//! The gauge HUD: a fuel bar and a lives bar in the rows above the flight band, readable by a network (and by
//! a fixed decoder) at any frame size, in RGB and gray alike.
//!
//! # Layout (pixel layout version 2)
//! In a `H × W` frame the rows above the flight band are `B = ⌊60·H / 600⌋` (sprites start at row `B` or
//! below). The bars:
//!
//! | `B` | fuel bar | lives bar |
//! |---|---|---|
//! | ≥ 2 | rows `[⌊B/8⌋, ⌊B/2⌋)`, columns `[0, W)` | rows `[⌊B/2⌋ + ⌊B/8⌋, B − ⌊B/8⌋)`, columns `[0, W)` |
//! | 1 | row 0, columns `[0, ⌊W/2⌋)` | row 0, columns `[⌊W/2⌋, W)` |
//! | 0 (`H < 10`) | none | none |
//!
//! At 84 × 84: `B = 8`, fuel in rows 1–3, lives in rows 5–6, both over all 84 columns; rows 0, 4 and 7 stay
//! background. At 600 × 800: `B = 60`, fuel rows 7–29, lives rows 37–52.
//!
//! # Encoding
//! A bar of `n` columns showing `v` out of `m` (fuel of `max_fuel`, lives of the `lives` option) holds
//! `I = round(255·n·v / m)` units of ink (half up: `⌊(2·255·n·v + m) / (2m)⌋`), filled from the left: column
//! `i` has the grey level `255 − clamp(I − 255·i, 0, 255)`: black columns, then at most one grey column,
//! then background. Every row of the bar is the same. A grey level `g` is the pixel `(g, g, g)` in RGB, whose
//! luma is `g`, so gray frames carry the same bytes.
//!
//! **Decoding** one row: `I = Σ (255 − pixel)`, then `v = I · m / (255·n)`. The error is at most
//! `m / (510·n)`: 1/42,840 of `max_fuel` (0.0024 %) for fuel at 84 × 84, and lives round to the exact value because
//! `255·n > m` for every allowed `lives` (`n ≥ 4`, `m ≤ 1000`).

use super::canvas::{BACKGROUND, Canvas};

/// One bar: rows and columns of the frame it occupies.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(crate) struct Bar {
    rows: (usize, usize),
    cols: (usize, usize),
}

impl Bar {
    /// Columns of the bar.
    fn len(&self) -> usize {
        self.cols.1 - self.cols.0
    }

    /// Units of ink that show `v` out of `m` (`m ≥ 1`, `v ≤ m`): `255·n·v / m`, rounded half up.
    fn ink(&self, v: u32, m: u32) -> u64 {
        let (v, m) = (u64::from(v.min(m)), u64::from(m.max(1)));
        (2 * 255 * self.len() as u64 * v + m) / (2 * m)
    }

    /// Draws the bar's columns `[c0, c1)` (relative to the bar) for `ink` units.
    fn paint(&self, canvas: &mut Canvas<'_>, ink: u64, c0: usize, c1: usize) {
        let bpp = canvas.bpp;
        for y in self.rows.0..self.rows.1 {
            let start = (y * canvas.width + self.cols.0 + c0) * bpp;
            let row = &mut canvas.bytes[start..start + (c1 - c0) * bpp];
            for (i, px) in (c0..).zip(row.chunks_exact_mut(bpp)) {
                px.fill(level(ink, i));
            }
        }
    }

    /// Redraws the columns whose level differs between `old` and `new` ink.
    fn repaint(&self, canvas: &mut Canvas<'_>, old: u64, new: u64) {
        if old == new {
            return;
        }
        let (lo, hi) = (old.min(new), old.max(new));
        // Column i changes only if 255·i < hi and 255·(i + 1) > lo.
        let c0 = (lo / 255) as usize;
        let c1 = ((hi / 255) as usize + 1).min(self.len());
        self.paint(canvas, new, c0, c1);
    }
}

/// The grey level of column `i` of a bar holding `ink` units.
#[inline]
fn level(ink: u64, i: usize) -> u8 {
    let lit = ink.saturating_sub(255 * i as u64).min(255) as u8;
    BACKGROUND - lit
}

/// Ink of both bars, as last drawn.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Default)]
pub(crate) struct GaugeInk {
    fuel: u64,
    lives: u64,
}

/// Where the bars lie in one frame size; `None` bars when the frame has no row above the flight band.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(crate) struct GaugeLayout {
    bars: Option<(Bar, Bar)>,
}

impl GaugeLayout {
    /// The layout for a `height × width` frame (see the module docs).
    pub fn new(height: usize, width: usize) -> GaugeLayout {
        let band = crate::consts::Y_MIN as usize * height / crate::consts::HEIGHT as usize;
        let bars = match band {
            0 => None,
            1 => {
                let half = width / 2;
                Some((Bar { rows: (0, 1), cols: (0, half) }, Bar { rows: (0, 1), cols: (half, width) }))
            }
            b => {
                let (e, h) = (b / 8, b / 2);
                Some((Bar { rows: (e, h), cols: (0, width) }, Bar { rows: (h + e, b - e), cols: (0, width) }))
            }
        };
        GaugeLayout { bars }
    }

    /// The last frame row the bars touch, plus one (0 when there are none).
    pub fn bottom(&self) -> usize {
        self.bars.map_or(0, |(f, l)| f.rows.1.max(l.rows.1))
    }

    /// The ink of both bars for these values.
    pub fn ink(&self, fuel: u32, max_fuel: u32, lives: u32, max_lives: u32) -> GaugeInk {
        match &self.bars {
            Some((f, l)) => GaugeInk { fuel: f.ink(fuel, max_fuel), lives: l.ink(lives, max_lives) },
            None => GaugeInk::default(),
        }
    }

    /// Draws both bars whole onto a canvas.
    pub fn draw_full(&self, canvas: &mut Canvas<'_>, ink: GaugeInk) {
        if let Some((f, l)) = &self.bars {
            f.paint(canvas, ink.fuel, 0, f.len());
            l.paint(canvas, ink.lives, 0, l.len());
        }
    }

    /// Redraws the columns that differ between `old` (on the canvas) and `new`.
    pub fn draw_changes(&self, canvas: &mut Canvas<'_>, old: GaugeInk, new: GaugeInk) {
        if let Some((f, l)) = &self.bars {
            f.repaint(canvas, old.fuel, new.fuel);
            l.repaint(canvas, old.lives, new.lives);
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn layout_at_84x84_and_full_size() {
        let l = GaugeLayout::new(84, 84);
        let (f, v) = l.bars.unwrap();
        assert_eq!((f.rows, f.cols, v.rows, v.cols), ((1, 4), (0, 84), (5, 7), (0, 84)));
        let (f, v) = GaugeLayout::new(600, 800).bars.unwrap();
        assert_eq!((f.rows, v.rows), ((7, 30), (37, 53)));
        let (f, v) = GaugeLayout::new(15, 9).bars.unwrap();
        assert_eq!((f.rows, f.cols, v.rows, v.cols), ((0, 1), (0, 4), (0, 1), (4, 9)));
        assert_eq!(GaugeLayout::new(9, 800).bars, None);
    }

    #[test]
    fn ink_rounds_half_up_and_spans_the_bar() {
        let bar = Bar { rows: (0, 1), cols: (0, 84) };
        assert_eq!(bar.ink(0, 1000), 0);
        assert_eq!(bar.ink(1000, 1000), 84 * 255);
        assert_eq!(bar.ink(1, 1000), 21); // 21.42
        assert_eq!(bar.ink(500, 1000), 42 * 255);
        assert_eq!((level(300, 0), level(300, 1), level(300, 2)), (0, 210, 255));
    }
}
