//! Pixel writes into a caller-owned frame: rectangle fills and sprite blits, in either pixel format.

/// How the pixels of a frame are stored.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, Default)]
pub enum PixelFormat {
    /// Three bytes per pixel: R, G, B.
    #[default]
    Rgb,
    /// One byte per pixel: the integer BT.601 luma of the RGB pixel ([`crate::luma`]).
    Gray,
}

impl PixelFormat {
    /// Bytes per pixel.
    pub fn bytes_per_pixel(self) -> usize {
        match self {
            PixelFormat::Rgb => 3,
            PixelFormat::Gray => 1,
        }
    }

    /// Appends the bytes of one colour in this format.
    pub(crate) fn push(self, out: &mut Vec<u8>, [r, g, b]: [u8; 3]) {
        match self {
            PixelFormat::Rgb => out.extend_from_slice(&[r, g, b]),
            PixelFormat::Gray => out.push(crate::luma(r, g, b)),
        }
    }
}

/// The background byte: white is 255 in every channel and in luma alike.
pub(crate) const BACKGROUND: u8 = 255;

/// A box in frame pixels, already clipped to the frame.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Default)]
pub(crate) struct PixRect {
    pub x: usize,
    pub y: usize,
    pub w: usize,
    pub h: usize,
}

/// A frame being drawn: its size, its format and its bytes.
pub(crate) struct Canvas<'a> {
    pub width: usize,
    pub height: usize,
    pub bpp: usize,
    pub bytes: &'a mut [u8],
}

impl Canvas<'_> {
    /// Fills `r` with the background.
    pub fn erase(&mut self, r: PixRect) {
        let stride = self.width * self.bpp;
        for y in r.y..r.y + r.h {
            let start = y * stride + r.x * self.bpp;
            self.bytes[start..start + r.w * self.bpp].fill(BACKGROUND);
        }
    }
}
