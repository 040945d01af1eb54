//! The observation pipeline: turns a [`World`] into the observation the agent sees (features or pixels, stacked
//! `frame_stack` deep) and writes it into the buffers of `obs_buffer.rs`.
//!
//! Stacking concatenates on the last axis, oldest first: `rgb` `(H, W, 3k)`, `rgb_float` `(H, W, 3k)`,
//! `grayscale` `(H, W, k)` (no extra axis when `k = 1`: `(H, W)`), `features` `(46k,)`. Reset fills the
//! stack with the first observation.
//!
//! Grayscale is the integer BT.601 luma of the rgb frame: `(299·R + 587·G + 114·B + 500) / 1000`. It is drawn
//! directly into a one-byte-per-pixel canvas (every pixel is a palette colour or a precomputed sprite colour, so
//! its luma is precomputed too); tests check it equals the luma of the rgb frame.
//! `rgb_float` is exactly `rgb as f32 / 255.0`.
//!
//! The canvas is drawn incrementally ([`Renderer::draw`]) and copied out; `render()` paints the full 600 × 800
//! frame from a shared renderer, built once. The HUD of an observation follows `hud` and `hud_style` at its
//! `obs_size` ([`Hud::of_observation`]); `render()` always has one ([`Hud::of_render`]).

use crate::config::{Config, ObsType};
use crate::error::{ConfigError, Error};
use crate::features::{self, FEATURES_LEN};
use crate::limits::try_filled;
use crate::obs_buffer::{ObsBufMut, ObsData};
use crate::render::{Hud, HudScale, PixelFormat, Renderer};
use crate::spaces::{BoxSpace, Dtype};
use crate::world::World;
use std::sync::OnceLock;

/// The observation pipeline of one environment. Owns its buffers; allocates nothing per step.
#[derive(Clone, Debug)]
pub(crate) struct Observer {
    obs_type: ObsType,
    k: usize,
    /// Elements per pixel of one unstacked observation: 3 for rgb, 1 for grayscale, 46 (`FEATURES_LEN`) for features
    /// (the features vector stacks as one "pixel").
    channels: usize,
    /// The frame the renderer draws into, incrementally (pixel types only): RGB, or gray for `grayscale`.
    canvas: Vec<u8>,
    /// The renderer of pixel observations; `None` for `features`, which draw nothing.
    renderer: Option<Renderer>,
    /// The stacked observation (`k > 1` only), in output layout.
    stacked: ObsData,
    /// Scratch for the newest unstacked observation (`k > 1` only).
    newest: ObsData,
    space: BoxSpace,
    /// Whether the canvas no longer holds the last drawn frame (after a restore), so the next draw is full.
    stale: bool,
    /// Where the frame that the renderer's incremental state describes lives (see [`Observer::observe_onto`]).
    target: Target,
}

/// The buffer holding the frame the renderer drew last.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum Target {
    /// The observer's own canvas, last copied into the caller's buffer at this address (0: none).
    Canvas { copied_to: usize },
    /// A caller's buffer at this address, drawn onto directly; the canvas is out of date.
    Caller(usize),
}

impl Observer {
    /// The observation pipeline of `config` (already validated, so within the memory budget).
    ///
    /// # Errors
    /// [`ConfigError::OutOfMemory`] when the system refuses the buffers' memory.
    pub(crate) fn new(config: &Config) -> Result<Observer, ConfigError> {
        let (h, w) = (config.obs_size.0 as usize, config.obs_size.1 as usize);
        let k = config.frame_stack as usize;
        let format = if config.obs_type == ObsType::Grayscale { PixelFormat::Gray } else { PixelFormat::Rgb };
        let (single_len, channels) = single_len(config);
        let canvas_len = match config.obs_type {
            ObsType::Features => 0,
            ObsType::Rgb | ObsType::RgbFloat => h * w * 3,
            ObsType::Grayscale => h * w,
        };
        let canvas = try_filled(canvas_len, 255, "the observation canvas")?;
        let renderer = config.obs_type.is_pixels().then(|| {
            let (h, w) = config.obs_size;
            Renderer::with_look(h, w, Hud::of_observation(config), config.look, format)
        });
        let space = match config.obs_type {
            ObsType::Features => BoxSpace::repeated(
                vec![FEATURES_LEN * k],
                Dtype::F32,
                features::low().to_vec(),
                features::high().to_vec(),
            ),
            ObsType::Rgb => BoxSpace::uniform(vec![h, w, 3 * k], Dtype::U8, 0.0, 255.0),
            ObsType::RgbFloat => BoxSpace::uniform(vec![h, w, 3 * k], Dtype::F32, 0.0, 1.0),
            ObsType::Grayscale if k == 1 => BoxSpace::uniform(vec![h, w], Dtype::U8, 0.0, 255.0),
            ObsType::Grayscale => BoxSpace::uniform(vec![h, w, k], Dtype::U8, 0.0, 255.0),
        };
        let (n_stacked, n_newest) = if k > 1 { (single_len * k, single_len) } else { (0, 0) };
        let zeros = |n: usize, what: &str| -> Result<ObsData, ConfigError> {
            Ok(match space.dtype {
                Dtype::U8 => ObsData::U8(try_filled(n, 0, what)?),
                Dtype::F32 => ObsData::F32(try_filled(n, 0.0, what)?),
            })
        };
        let (stacked, newest) = (zeros(n_stacked, "the frame stack")?, zeros(n_newest, "the frame stack")?);
        Ok(Observer {
            obs_type: config.obs_type,
            k,
            channels,
            canvas,
            renderer,
            stacked,
            newest,
            space,
            stale: true,
            target: Target::Canvas { copied_to: 0 },
        })
    }

    pub(crate) fn space(&self) -> &BoxSpace {
        &self.space
    }

    /// Checks that `out` fits this observation.
    pub(crate) fn check(&self, out: &ObsBufMut<'_>) -> Result<(), Error> {
        if out.len() != self.space.len() || out.dtype() != self.space.dtype {
            return Err(Error::BufferSize {
                expected: self.space.len(),
                expected_dtype: self.space.dtype.as_str(),
                got: out.len(),
                got_dtype: out.dtype().as_str(),
            });
        }
        Ok(())
    }

    /// Writes the observation of `world` into `out` (already checked). `reset` starts a new stack and a full redraw.
    pub(crate) fn observe(&mut self, world: &World, config: &Config, reset: bool, out: ObsBufMut<'_>) {
        // The hot path of the cheapest observation: straight into the caller's buffer.
        let out = match out {
            ObsBufMut::F32(o) if self.k == 1 && self.obs_type == ObsType::Features => {
                return features::write(world, config.lives, config.max_fuel, o);
            }
            out => out,
        };
        if let Some(renderer) = self.renderer.as_mut() {
            if reset || self.stale || matches!(self.target, Target::Caller(_)) {
                self.stale = false;
                renderer.draw_full(world, HudScale::of(config), &mut self.canvas);
            } else {
                renderer.draw(world, HudScale::of(config), &mut self.canvas);
            }
        }
        if self.k == 1 {
            let copied_to = match &out {
                ObsBufMut::U8(o) if self.obs_type.is_pixels() => o.as_ptr() as usize,
                _ => 0,
            };
            self.target = Target::Canvas { copied_to };
            self.write_single(world, config, out);
            return;
        }
        let (channels, k) = (self.channels, self.k);
        let mut newest = std::mem::replace(&mut self.newest, ObsData::U8(Vec::new()));
        let mut stacked = std::mem::replace(&mut self.stacked, ObsData::U8(Vec::new()));
        match (&mut newest, &mut stacked, out) {
            (ObsData::U8(n), ObsData::U8(s), ObsBufMut::U8(o)) => {
                self.write_single(world, config, ObsBufMut::U8(n));
                match (channels, k) {
                    (1, 2) if !reset => push_gray::<2>(s, n),
                    (1, 4) if !reset => push_gray::<4>(s, n),
                    (1, 8) if !reset => push_gray::<8>(s, n),
                    _ => push_frame(s, n, channels, k, reset),
                }
                o.copy_from_slice(s);
            }
            (ObsData::F32(n), ObsData::F32(s), ObsBufMut::F32(o)) => {
                self.write_single(world, config, ObsBufMut::F32(n));
                push_frame(s, n, channels, k, reset);
                o.copy_from_slice(s);
            }
            _ => unreachable!("buffers of one observer share the observation's dtype"),
        }
        self.newest = newest;
        self.stacked = stacked;
    }

    /// Like [`Observer::observe`] after a step, but for `rgb` and `grayscale` with `frame_stack = 1` it draws only
    /// what changed straight onto `out`, which must hold the last observation this observer wrote there (by
    /// `observe` or `observe_onto`) unmodified. A different buffer (another address) gets a full redraw, so the
    /// only way to get a wrong frame is to modify the buffer between calls. Other observation types fall back to
    /// `observe`.
    pub(crate) fn observe_onto(&mut self, world: &World, config: &Config, out: ObsBufMut<'_>) {
        let o = match out {
            ObsBufMut::U8(o) if self.k == 1 && matches!(self.obs_type, ObsType::Rgb | ObsType::Grayscale) => o,
            out => return self.observe(world, config, false, out),
        };
        let addr = o.as_ptr() as usize;
        let holds_last_frame = !self.stale
            && match self.target {
                Target::Canvas { copied_to } => copied_to == addr,
                Target::Caller(at) => at == addr,
            };
        let renderer = self.renderer.as_mut().expect("pixel observations have a renderer");
        if holds_last_frame {
            renderer.draw(world, HudScale::of(config), o);
        } else {
            self.stale = false;
            renderer.draw_full(world, HudScale::of(config), o);
        }
        self.target = Target::Caller(addr);
    }

    /// The stacked observation (empty when `frame_stack = 1`): part of a snapshot.
    pub(crate) fn stacked(&self) -> &ObsData {
        &self.stacked
    }

    /// Replaces the stacked observation (from a snapshot) and forces a full redraw next time.
    pub(crate) fn set_stacked(&mut self, stacked: ObsData) {
        self.stacked = stacked;
        self.stale = true;
    }

    /// Draws the full 600 × 800 frame of `world`, HUD included (the text, or the gauges when `hud_style` is
    /// `gauge`), into `rgb` (for `render()`), with a renderer per HUD shared by every environment and built on
    /// first use.
    pub(crate) fn render_full(world: &World, config: &Config, rgb: &mut [u8]) {
        static TEXT: OnceLock<Renderer> = OnceLock::new();
        static GAUGE: OnceLock<Renderer> = OnceLock::new();
        let hud = Hud::of_render(config);
        let shared = if hud == Hud::Gauge { &GAUGE } else { &TEXT };
        let full = shared.get_or_init(|| Renderer::new(crate::consts::HEIGHT as u32, crate::consts::WIDTH as u32, hud));
        full.paint(world, HudScale::of(config), rgb);
    }

    /// Writes one unstacked observation of the current world (the canvas is already drawn).
    fn write_single(&self, world: &World, config: &Config, out: ObsBufMut<'_>) {
        match (self.obs_type, out) {
            (ObsType::Features, ObsBufMut::F32(o)) => features::write(world, config.lives, config.max_fuel, o),
            (ObsType::Rgb | ObsType::Grayscale, ObsBufMut::U8(o)) => o.copy_from_slice(&self.canvas),
            (ObsType::RgbFloat, ObsBufMut::F32(o)) => {
                for (d, &s) in o.iter_mut().zip(&self.canvas) {
                    *d = s as f32 / 255.0;
                }
            }
            (t, o) => unreachable!("observation type {t:?} with a {:?} buffer passed check()", o.dtype()),
        }
    }
}

/// Elements of one unstacked observation of `config`, and elements per pixel (46 for features, whose vector
/// stacks as one "pixel").
fn single_len(config: &Config) -> (usize, usize) {
    let (h, w) = (config.obs_size.0 as usize, config.obs_size.1 as usize);
    match config.obs_type {
        ObsType::Features => (FEATURES_LEN, FEATURES_LEN),
        ObsType::Rgb | ObsType::RgbFloat => (h * w * 3, 3),
        ObsType::Grayscale => (h * w, 1),
    }
}

/// Elements of the frame stack an observer of `config` keeps (0 when `frame_stack = 1`): what a snapshot holds.
pub(crate) fn stacked_len(config: &Config) -> usize {
    if config.frame_stack > 1 { single_len(config).0 * config.frame_stack as usize } else { 0 }
}

/// BT.601 luma, in integers: `(299·R + 587·G + 114·B + 500) / 1000`.
#[inline]
pub fn luma(r: u8, g: u8, b: u8) -> u8 {
    ((299 * r as u32 + 587 * g as u32 + 114 * b as u32 + 500) / 1000) as u8
}

/// Shifts each pixel's group of `k` frames one older and appends the newest frame's channels.
/// `stack` holds pixels of `channels · k` elements; `newest` holds the same pixels of `channels` elements.
/// On `reset` every slot takes the newest frame.
///
/// Shifting the whole buffer left by `channels` elements (one `memmove`) moves every group's frames one
/// older at once; it also drags the next pixel's oldest frame into each group's newest slot, which the newest
/// frame then overwrites.
fn push_frame<T: Copy>(stack: &mut [T], newest: &[T], channels: usize, k: usize, reset: bool) {
    let group = channels * k;
    if reset {
        for (px, new) in stack.chunks_exact_mut(group).zip(newest.chunks_exact(channels)) {
            for slot in px.chunks_exact_mut(channels) {
                slot.copy_from_slice(new);
            }
        }
        return;
    }
    stack.copy_within(channels.., 0);
    match channels {
        1 => put_newest::<T, 1>(stack, newest, group),
        3 => put_newest::<T, 3>(stack, newest, group),
        _ => {
            for (px, new) in stack.chunks_exact_mut(group).zip(newest.chunks_exact(channels)) {
                px[group - channels..].copy_from_slice(new);
            }
        }
    }
}

/// Writes each pixel's `C` newest channels into the last slot of its group (`C` known at compile time).
fn put_newest<T: Copy, const C: usize>(stack: &mut [T], newest: &[T], group: usize) {
    for (px, new) in stack.chunks_exact_mut(group).zip(newest.chunks_exact(C)) {
        let slot: &mut [T; C] = (&mut px[group - C..]).try_into().expect("C elements");
        *slot = new.try_into().expect("C elements");
    }
}

/// [`push_frame`] for one-channel `u8` frames stacked `K` deep (2, 4 or 8): each pixel's group is one
/// little-endian word, shifted down by a byte with the newest frame in the top byte.
fn push_gray<const K: usize>(stack: &mut [u8], newest: &[u8]) {
    macro_rules! words {
        ($word:ty) => {
            for (px, &n) in stack.chunks_exact_mut(K).zip(newest) {
                let v = <$word>::from_le_bytes(px.try_into().expect("K bytes"));
                let v = (v >> 8) | ((n as $word) << (8 * (K - 1)));
                px.copy_from_slice(&v.to_le_bytes());
            }
        };
    }
    match K {
        2 => words!(u16),
        4 => words!(u32),
        8 => words!(u64),
        _ => unreachable!("push_gray handles 2, 4 or 8 frames"),
    }
}
