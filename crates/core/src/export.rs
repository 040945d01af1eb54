//! Image export (cargo feature `export`, on by default): a frame to PNG, an episode to an animated GIF or APNG.
//!
//! Everything writes to any [`std::io::Write`]; [`save_atomically`] adds the file handling (a temporary file in
//! the same folder, renamed over the target only once it is complete, so a failure never leaves a half-written
//! or lost file). Frames are row-major, `height × width` pixels, in a [`PixelFormat`]: what the renderer and the
//! observations produce.
//!
//! # Examples
//! ```
//! use chopperscape::{ChopperScape, Config, Env};
//! use chopperscape::export::{self, GifWriter};
//! use chopperscape::render::PixelFormat;
//!
//! let mut env = ChopperScape::new(Config::features()).unwrap();
//! env.reset(Some(3));
//! let mut png = Vec::new();
//! export::write_png(&mut png, &env.render(), 600, 800, PixelFormat::Rgb).unwrap();
//! assert!(png.starts_with(b"\x89PNG"));
//!
//! let mut gif = GifWriter::new(Vec::new(), 600, 800, PixelFormat::Rgb, 30).unwrap();
//! for _ in 0..3 {
//!     env.step(0).unwrap();
//!     gif.push(&env.render()).unwrap();
//! }
//! assert!(gif.finish().unwrap().starts_with(b"GIF89a"));
//! ```

use std::collections::HashMap;
use std::fs;
use std::io::{self, BufWriter, Write};
use std::path::{Path, PathBuf};

use crate::render::PixelFormat;

/// Why an export failed.
#[derive(Debug, thiserror::Error)]
#[non_exhaustive]
pub enum ExportError {
    /// Writing failed.
    #[error("could not write the image: {0}")]
    Io(#[from] io::Error),
    /// The PNG encoder refused.
    #[error("PNG encoding failed: {0}")]
    Png(#[from] png::EncodingError),
    /// The GIF encoder refused.
    #[error("GIF encoding failed: {0}")]
    Gif(#[from] gif::EncodingError),
    /// A frame's byte count does not match its size and format.
    #[error("frame {index} has {got} bytes; a {height}x{width} {format:?} frame has {expected}")]
    FrameSize {
        /// Index of the frame in the episode (0 for a single image).
        index: usize,
        /// Bytes expected.
        expected: usize,
        /// Bytes given.
        got: usize,
        /// Frame height.
        height: u32,
        /// Frame width.
        width: u32,
        /// Pixel format.
        format: PixelFormat,
    },
    /// The image size cannot be encoded.
    #[error("a {height}x{width} image cannot be written: {why}")]
    Size {
        /// Frame height.
        height: u32,
        /// Frame width.
        width: u32,
        /// What the format allows.
        why: &'static str,
    },
    /// An animation got a different number of frames than announced, or none.
    #[error("the animation was announced with {announced} frames but got {got}")]
    FrameCount {
        /// Frames announced (APNG needs the count up front).
        announced: usize,
        /// Frames given.
        got: usize,
    },
    /// `fps` must be at least 1.
    #[error("fps must be at least 1, got {0}")]
    Fps(u32),
}

fn check_frame(frame: &[u8], index: usize, height: u32, width: u32, format: PixelFormat) -> Result<(), ExportError> {
    let expected = height as usize * width as usize * format.bytes_per_pixel();
    if frame.len() != expected || height == 0 || width == 0 {
        return Err(ExportError::FrameSize { index, expected, got: frame.len(), height, width, format });
    }
    Ok(())
}

fn png_color(format: PixelFormat) -> png::ColorType {
    match format {
        PixelFormat::Rgb => png::ColorType::Rgb,
        PixelFormat::Gray => png::ColorType::Grayscale,
    }
}

/// Writes one frame as a PNG image (8-bit RGB or grayscale, fast compression).
///
/// # Errors
/// A frame whose length does not match `height × width × bytes per pixel`, or a write error.
pub fn write_png<W: Write>(
    out: W,
    frame: &[u8],
    height: u32,
    width: u32,
    format: PixelFormat,
) -> Result<(), ExportError> {
    check_frame(frame, 0, height, width, format)?;
    let mut enc = png::Encoder::new(out, width, height);
    enc.set_color(png_color(format));
    enc.set_depth(png::BitDepth::Eight);
    enc.set_compression(png::Compression::Fast);
    let mut w = enc.write_header()?;
    w.write_image_data(frame)?;
    w.finish()?;
    Ok(())
}

/// Writes an episode as an animated PNG, one frame at a time. APNG announces its frame count first, so the
/// count is given to [`ApngWriter::new`]; [`ApngWriter::finish`] checks it was met. Plays forever.
pub struct ApngWriter<W: Write> {
    writer: png::Writer<W>,
    height: u32,
    width: u32,
    format: PixelFormat,
    announced: usize,
    pushed: usize,
}

impl<W: Write> ApngWriter<W> {
    /// Starts an animation of `frames` frames of `height × width` pixels at `fps` frames per second.
    ///
    /// # Errors
    /// `frames == 0`, `fps == 0`, or a write error.
    pub fn new(
        out: W,
        height: u32,
        width: u32,
        format: PixelFormat,
        fps: u32,
        frames: usize,
    ) -> Result<Self, ExportError> {
        if fps == 0 {
            return Err(ExportError::Fps(fps));
        }
        let count = u32::try_from(frames).ok().filter(|&n| n > 0);
        let count = count.ok_or(ExportError::FrameCount { announced: frames, got: 0 })?;
        if height == 0 || width == 0 {
            return Err(ExportError::Size { height, width, why: "both sides must be at least 1" });
        }
        let mut enc = png::Encoder::new(out, width, height);
        enc.set_color(png_color(format));
        enc.set_depth(png::BitDepth::Eight);
        enc.set_compression(png::Compression::Fast);
        enc.set_animated(count, 0)?;
        enc.set_frame_delay(1, fps.min(u16::MAX as u32) as u16)?;
        let writer = enc.write_header()?;
        Ok(ApngWriter { writer, height, width, format, announced: frames, pushed: 0 })
    }

    /// Appends the next frame.
    ///
    /// # Errors
    /// A frame of the wrong length, more frames than announced, or a write error.
    pub fn push(&mut self, frame: &[u8]) -> Result<(), ExportError> {
        check_frame(frame, self.pushed, self.height, self.width, self.format)?;
        if self.pushed == self.announced {
            return Err(ExportError::FrameCount { announced: self.announced, got: self.pushed + 1 });
        }
        self.writer.write_image_data(frame)?;
        self.pushed += 1;
        Ok(())
    }

    /// Ends the file.
    ///
    /// # Errors
    /// Fewer frames than announced, or a write error.
    pub fn finish(self) -> Result<(), ExportError> {
        if self.pushed != self.announced {
            return Err(ExportError::FrameCount { announced: self.announced, got: self.pushed });
        }
        self.writer.finish()?;
        Ok(())
    }
}

/// Writes an episode as an animated GIF, one frame at a time. Plays forever.
///
/// Each frame gets its own exact palette when it has at most 256 colours (always the case for 800 × 600
/// frames, whose pixels are palette colours); frames with more (small sizes, whose shrunk sprites blend
/// colours) are quantized by the `gif` crate's NeuQuant. GIF delays are in hundredths of a second, so the frame
/// delay is `100 / fps` rounded (30 fps plays at 1/33 s a frame).
pub struct GifWriter<W: Write> {
    encoder: gif::Encoder<W>,
    height: u32,
    width: u32,
    format: PixelFormat,
    delay: u16,
    pushed: usize,
    indices: Vec<u8>,
    palette: Vec<u8>,
    lookup: HashMap<[u8; 3], u8>,
}

impl<W: Write> GifWriter<W> {
    /// Starts an animation of `height × width` frames at `fps` frames per second.
    ///
    /// # Errors
    /// `fps == 0`, a side above 65535 or zero, or a write error.
    pub fn new(out: W, height: u32, width: u32, format: PixelFormat, fps: u32) -> Result<Self, ExportError> {
        if fps == 0 {
            return Err(ExportError::Fps(fps));
        }
        let (Ok(h), Ok(w)) = (u16::try_from(height), u16::try_from(width)) else {
            return Err(ExportError::Size { height, width, why: "GIF sides are at most 65535" });
        };
        if h == 0 || w == 0 {
            return Err(ExportError::Size { height, width, why: "both sides must be at least 1" });
        }
        let mut encoder = gif::Encoder::new(out, w, h, &[])?;
        encoder.set_repeat(gif::Repeat::Infinite)?;
        let delay = ((200 + fps) / (2 * fps)).max(1) as u16;
        Ok(GifWriter {
            encoder,
            height,
            width,
            format,
            delay,
            pushed: 0,
            indices: Vec::new(),
            palette: Vec::new(),
            lookup: HashMap::new(),
        })
    }

    /// Appends the next frame.
    ///
    /// # Errors
    /// A frame of the wrong length, or a write error.
    pub fn push(&mut self, frame: &[u8]) -> Result<(), ExportError> {
        check_frame(frame, self.pushed, self.height, self.width, self.format)?;
        let (w, h) = (self.width as u16, self.height as u16);
        let bpp = self.format.bytes_per_pixel();
        let rgb = |p: &[u8]| if bpp == 3 { [p[0], p[1], p[2]] } else { [p[0]; 3] };
        let mut gif_frame = if self.exact_palette(frame) {
            gif::Frame::from_palette_pixels(w, h, &self.indices[..], &self.palette[..], None)
        } else {
            let expanded: Vec<u8> = frame.chunks_exact(bpp).flat_map(rgb).collect();
            gif::Frame::from_rgb_speed(w, h, &expanded, 10)
        };
        gif_frame.delay = self.delay;
        self.encoder.write_frame(&gif_frame)?;
        self.pushed += 1;
        Ok(())
    }

    /// Indexes `frame` into `self.indices` / `self.palette`; false when it has more than 256 colours.
    fn exact_palette(&mut self, frame: &[u8]) -> bool {
        let bpp = self.format.bytes_per_pixel();
        self.indices.clear();
        self.palette.clear();
        self.lookup.clear();
        let mut last: Option<([u8; 3], u8)> = None;
        for p in frame.chunks_exact(bpp) {
            let c = if bpp == 3 { [p[0], p[1], p[2]] } else { [p[0]; 3] };
            let index = match last {
                Some((lc, li)) if lc == c => li,
                _ => {
                    let next = self.lookup.len();
                    let i = *self.lookup.entry(c).or_insert(next.min(255) as u8);
                    if self.lookup.len() > next {
                        if next == 256 {
                            return false;
                        }
                        self.palette.extend_from_slice(&c);
                    }
                    last = Some((c, i));
                    i
                }
            };
            self.indices.push(index);
        }
        true
    }

    /// Ends the file and gives back the writer.
    ///
    /// # Errors
    /// No frame was pushed, or a write error.
    pub fn finish(self) -> Result<W, ExportError> {
        if self.pushed == 0 {
            return Err(ExportError::FrameCount { announced: 0, got: 0 });
        }
        Ok(self.encoder.into_inner()?)
    }
}

/// Runs `write` on a buffered temporary file beside `path`, then renames it over `path`. On any failure the
/// temporary file is removed and `path` is left as it was.
///
/// # Errors
/// What `write` returns, or the error of creating, flushing or renaming the file.
pub fn save_atomically<T>(
    path: &Path,
    write: impl FnOnce(&mut BufWriter<fs::File>) -> Result<T, ExportError>,
) -> Result<T, ExportError> {
    let name = path.file_name().ok_or_else(|| {
        ExportError::Io(io::Error::new(io::ErrorKind::InvalidInput, format!("{} names no file", path.display())))
    })?;
    let mut tmp_name = std::ffi::OsString::from(".");
    tmp_name.push(name);
    tmp_name.push(format!(".{}.tmp", std::process::id()));
    let tmp: PathBuf = path.with_file_name(tmp_name);
    let result = (|| {
        let mut file = BufWriter::new(fs::File::create(&tmp)?);
        let value = write(&mut file)?;
        let file = file.into_inner().map_err(|e| e.into_error())?;
        file.sync_all()?;
        fs::rename(&tmp, path)?;
        Ok(value)
    })();
    if result.is_err() {
        let _ = fs::remove_file(&tmp);
    }
    result
}
