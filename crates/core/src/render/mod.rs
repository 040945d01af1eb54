//! The software renderer: draws a [`World`] into a caller-owned frame (RGB or gray), with no allocation per
//! frame once warm.
//!
//! A frame is `height × width` pixels, row-major, white background. Entities are drawn in this order: fuel
//! tanks, birds, aliens, missiles, the chopper last (on top); then the HUD ([`Hud`]) in the strip above the
//! flight band: the tutorial's text line (`hud.rs`) or the fuel and lives gauges (`gauge.rs`). Sprites (`art.rs`)
//! keep their transparency: only their opaque pixels are written.
//!
//! # Scaling
//! A frame of another size than 800 × 600 is drawn natively at that size, never by shrinking a full frame:
//! an entity at `(x, y)` lands at `(⌊x·W/800⌋, ⌊y·H/600⌋)` and every sprite of one kind has the same size,
//! its SPEC size times the scale, rounded (at least one pixel). Sprites are resampled once, in
//! [`Renderer::new`], by box filtering (`sprite.rs`); the HUD is sampled through tables built there too.
//! Every sprite lies at or below row `⌊60·H/600⌋`, so the rows above belong to the HUD alone.
//!
//! # The HUD and the pixel layout version
//! The text line is legible only where each bit of its 8 × 8 font (drawn at twice its size in the full frame)
//! still lands on a pixel of its own: frames at least half the full size in both directions
//! ([`TEXT_MIN_SIZE`], 300 × 400). Below that whole rows and columns of the glyphs are skipped and the line
//! becomes a band of grey blobs (at 84 × 84: two rows). The `hud_style` option chooses ([`Hud::of`]): `text`
//! draws the line at every size, `gauge` the bars at every size, `auto` (the default) the text where it is
//! legible and the gauges elsewhere. The full-size frame of `render()` shows the text unless the style is
//! `gauge`.
//!
//! # The agent view
//! At 84 × 84 the art's sprites shrink to a few box-filtered pixels that blend into the sky (a bird is 3 × 4
//! pixels of mid grey), and at 42 × 42 to two or three. The agent view (`look = "agent"`, and `"auto"` in frames
//! smaller than [`TEXT_MIN_SIZE`]) draws each entity instead as a solid box of its hitbox's size, at least
//! [`AGENT_MIN_SIDE`] pixels a side (grown about its centre), in one grey level per kind ([`AGENT_GREYS`]): the
//! bird black, the alien, missile and chopper in darker to lighter greys, the fuel tank lightest, every one at
//! least 79 levels darker than the white sky and drawn without blending into it. Drawing order, the HUD and
//! incremental drawing are the art's.
//!
//! # Versions
//! What a pixel observation shows under the default options is versioned, like the features layout
//! ([`crate::features::FEATURES_VERSION`]), by [`PIXELS_VERSION`]:
//! - 3: frames smaller than [`TEXT_MIN_SIZE`] show the agent view (`look = "auto"`); frames at least that large
//!   are unchanged. `look = "art"` draws version 2.
//! - 2: frames smaller than [`TEXT_MIN_SIZE`] carry the fuel and lives gauges instead of the text line
//!   (`hud_style = "auto"`); frames at least that large are unchanged. `hud_style = "text"` draws version 1.
//! - 1: the text line `Fuel Left: N | Rewards: N | Lives: N` at every size, sampled at pixel centres (at
//!   84 × 84 a band of one or two rows that a probe could not read the fuel from).
//!
//! # Incremental drawing
//! [`Renderer::draw`] assumes the frame holds what this renderer drew last. It erases the boxes of last frame's
//! sprites to background (which leaves the whole flight band blank, since sprites were drawn nowhere else), draws
//! this frame's sprites in order, and redraws the HUD characters (or gauge columns) that changed. The result
//! equals [`Renderer::draw_full`] bit for bit (tested over long random episodes under every option).

mod art;
mod canvas;
mod gauge;
mod hud;
mod sprite;

pub use canvas::PixelFormat;

use canvas::{Canvas, PixRect};
use gauge::{GaugeInk, GaugeLayout};
use hud::{HudLayout, HudText};
use sprite::ScaledSprite;

use crate::config::{Config, HudStyle, Look};
use crate::consts::{HEIGHT, WIDTH};
use crate::geometry::Rect;
use crate::world::World;

/// The version of what pixel observations show (see the module docs for the history).
pub const PIXELS_VERSION: u32 = 3;

/// The options under which this renderer draws the frames of pixel layout `version`, for a policy that learned
/// an older layout: the policy's own options are set over them. `None` for a version it cannot draw (a later
/// one, or none that existed).
pub fn layout_options(version: u32) -> Option<&'static [(&'static str, &'static str)]> {
    match version {
        3 => Some(&[]),
        2 => Some(&[("look", "art")]),
        1 => Some(&[("look", "art"), ("hud_style", "text")]),
        _ => None,
    }
}

/// Whether a `height × width` frame is at least [`TEXT_MIN_SIZE`]: where `"auto"` draws what the full frame shows
/// (the text HUD, the art) rather than what agents read (the gauges, the agent view).
fn full_looking(height: u32, width: u32) -> bool {
    height >= TEXT_MIN_SIZE.0 && width >= TEXT_MIN_SIZE.1
}

/// The smallest frame `(height, width)` in which `hud_style = "auto"` draws the text line: half the full size,
/// where every bit of the font still covers a pixel.
pub const TEXT_MIN_SIZE: (u32, u32) = (HEIGHT as u32 / 2, WIDTH as u32 / 2);

/// What a renderer draws above the flight band.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum Hud {
    /// Nothing: the strip stays background.
    Off,
    /// The tutorial's text line (`hud.rs`).
    Text,
    /// The fuel and lives bars (`gauge.rs`).
    Gauge,
}

impl Hud {
    /// The HUD of a `height × width` frame under the options `hud` (on or off) and `hud_style`.
    pub fn of(hud: bool, style: HudStyle, height: u32, width: u32) -> Hud {
        match (hud, style) {
            (false, _) => Hud::Off,
            (true, HudStyle::Text) => Hud::Text,
            (true, HudStyle::Gauge) => Hud::Gauge,
            (true, HudStyle::Auto) if full_looking(height, width) => Hud::Text,
            (true, HudStyle::Auto) => Hud::Gauge,
        }
    }

    /// The HUD of `config`'s pixel observations (at `obs_size`).
    pub fn of_observation(config: &Config) -> Hud {
        Hud::of(config.hud, config.hud_style, config.obs_size.0, config.obs_size.1)
    }

    /// The HUD of `config`'s full-size `render()` frame: always on; the text unless the style is `gauge`.
    pub fn of_render(config: &Config) -> Hud {
        Hud::of(true, config.hud_style, HEIGHT as u32, WIDTH as u32)
    }
}

impl Look {
    /// What `self` draws in a `height × width` frame: [`Look::Art`] or [`Look::Agent`], never `Auto`.
    pub fn at(self, height: u32, width: u32) -> Look {
        match self {
            Look::Auto if full_looking(height, width) => Look::Art,
            Look::Auto => Look::Agent,
            other => other,
        }
    }

    /// The look of `config`'s pixel observations (at `obs_size`).
    pub fn of_observation(config: &Config) -> Look {
        config.look.at(config.obs_size.0, config.obs_size.1)
    }
}

/// The agent view's smallest side of an entity's box, in frame pixels.
pub const AGENT_MIN_SIDE: usize = 3;

/// The agent view's grey level of each kind, in drawing order: fuel tank, bird, alien, missile, chopper.
pub const AGENT_GREYS: [u8; 5] = [176, 0, 32, 64, 112];

/// The values the HUD shows as full: the `max_fuel` and `lives` options.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub struct HudScale {
    /// A full tank (the `max_fuel` option).
    pub max_fuel: u32,
    /// Lives at reset (the `lives` option); the text shows `Lives` only when it is more than 1.
    pub max_lives: u32,
}

impl HudScale {
    /// The scale of `config`.
    pub fn of(config: &Config) -> HudScale {
        HudScale { max_fuel: config.max_fuel, max_lives: config.lives }
    }
}

impl Default for HudScale {
    /// The v0 options: 1000 fuel, one life.
    fn default() -> HudScale {
        HudScale { max_fuel: crate::consts::MAX_FUEL, max_lives: 1 }
    }
}

/// The HUD's layout at one frame size.
#[derive(Clone, Debug)]
enum HudLayer {
    Off,
    Text(HudLayout),
    Gauge(GaugeLayout),
}

/// The HUD as last drawn.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum HudShown {
    Text(HudText),
    Gauge(GaugeInk),
    Nothing,
}

/// Draws frames of one size and pixel format.
#[derive(Clone, Debug)]
pub struct Renderer {
    height: usize,
    width: usize,
    format: PixelFormat,
    /// What is drawn above the flight band, laid out for this size.
    hud: HudLayer,
    /// Sprites at this scale, indexed by [`Kind`].
    sprites: [ScaledSprite; 5],
    /// How far each kind's sprite starts left of and above its entity's scaled corner (the agent view grows
    /// small boxes about their centre), indexed by [`Kind`].
    shift: [(usize, usize); 5],
    /// Boxes of the sprites drawn last, to erase next time.
    drawn: Vec<PixRect>,
    /// The HUD drawn last.
    shown: HudShown,
}

/// What a sprite shows; the index into [`Renderer::sprites`].
#[derive(Clone, Copy)]
enum Kind {
    FuelTank = 0,
    Bird = 1,
    Alien = 2,
    Missile = 3,
    Chopper = 4,
}

impl Renderer {
    /// A renderer of RGB frames of `height × width` pixels with this HUD.
    pub fn new(height: u32, width: u32, hud: Hud) -> Renderer {
        Renderer::with_format(height, width, hud, PixelFormat::Rgb)
    }

    /// A renderer of frames of `height × width` pixels in `format`, with this HUD.
    ///
    /// A [`PixelFormat::Gray`] frame equals, pixel for pixel, the [`crate::luma`] of the RGB frame.
    pub fn with_format(height: u32, width: u32, hud: Hud, format: PixelFormat) -> Renderer {
        Renderer::with_look(height, width, hud, Look::Art, format)
    }

    /// A renderer of frames of `height × width` pixels in `format`, with this HUD, drawing the entities in
    /// `look` (resolved for this size by [`Look::at`]).
    pub fn with_look(height: u32, width: u32, hud: Hud, look: Look, format: PixelFormat) -> Renderer {
        let (h, w) = (height as usize, width as usize);
        let size = |len: usize, frame: usize, full: usize| ((2 * len * frame + full) / (2 * full)).max(1);
        let arts = [art::FUEL_TANK, art::BIRD, art::ALIEN, art::MISSILE, art::CHOPPER];
        let mut shift = [(0, 0); 5];
        let sprites: [ScaledSprite; 5] = std::array::from_fn(|k| {
            let (sw, sh) = (size(arts[k].width(), w, WIDTH as usize), size(arts[k].height(), h, HEIGHT as usize));
            match look.at(height, width) {
                Look::Agent => {
                    let (bw, bh) = (sw.max(AGENT_MIN_SIDE).min(w), sh.max(AGENT_MIN_SIDE).min(h));
                    shift[k] = ((bw - sw.min(bw)) / 2, (bh - sh.min(bh)) / 2);
                    ScaledSprite::solid(bw, bh, AGENT_GREYS[k], format)
                }
                _ => ScaledSprite::new(&arts[k], sw, sh, format),
            }
        });
        let (hud, shown) = match hud {
            Hud::Off => (HudLayer::Off, HudShown::Nothing),
            Hud::Text => (HudLayer::Text(HudLayout::new(h, w)), HudShown::Text(HudText::EMPTY)),
            Hud::Gauge => (HudLayer::Gauge(GaugeLayout::new(h, w)), HudShown::Gauge(GaugeInk::default())),
        };
        // The HUD rows lie above the flight band at every size, so erasing sprites never touches the HUD.
        debug_assert!({
            let bottom = match &hud {
                HudLayer::Off => 0,
                HudLayer::Text(l) => l.bottom(),
                HudLayer::Gauge(l) => l.bottom(),
            };
            bottom <= crate::consts::Y_MIN as usize * h / HEIGHT as usize
        });
        Renderer { height: h, width: w, format, hud, sprites, shift, drawn: Vec::with_capacity(64), shown }
    }

    /// Frame height in pixels.
    pub fn height(&self) -> usize {
        self.height
    }

    /// Frame width in pixels.
    pub fn width(&self) -> usize {
        self.width
    }

    /// The pixel format of the frames.
    pub fn format(&self) -> PixelFormat {
        self.format
    }

    /// What this renderer draws above the flight band.
    pub fn hud(&self) -> Hud {
        match self.hud {
            HudLayer::Off => Hud::Off,
            HudLayer::Text(_) => Hud::Text,
            HudLayer::Gauge(_) => Hud::Gauge,
        }
    }

    /// Bytes of one frame: `height × width × 3` for RGB, `height × width` for gray.
    pub fn frame_len(&self) -> usize {
        self.height * self.width * self.format.bytes_per_pixel()
    }

    /// Draws the whole frame into `frame` (`frame_len()` bytes, row-major); `scale` gives the HUD's full values.
    ///
    /// # Panics
    /// If `frame.len() != self.frame_len()`.
    pub fn draw_full(&mut self, world: &World, scale: HudScale, frame: &mut [u8]) {
        self.drawn.clear();
        let mut drawn = std::mem::take(&mut self.drawn);
        self.shown = self.paint_into(world, scale, frame, |r| drawn.push(r));
        self.drawn = drawn;
    }

    /// Draws the whole frame into `frame` without touching this renderer's memory of the last frame: the same
    /// pixels as [`Renderer::draw_full`], from a shared renderer.
    ///
    /// # Panics
    /// If `frame.len() != self.frame_len()`.
    pub fn paint(&self, world: &World, scale: HudScale, frame: &mut [u8]) {
        self.paint_into(world, scale, frame, |_| {});
    }

    /// Draws the frame into `frame`, which must hold the frame this renderer drew last (by `draw_full` or
    /// `draw`); only what changed is redrawn.
    ///
    /// # Panics
    /// If `frame.len() != self.frame_len()`.
    pub fn draw(&mut self, world: &World, scale: HudScale, frame: &mut [u8]) {
        let mut canvas = self.canvas(frame);
        for &r in &self.drawn {
            canvas.erase(r);
        }
        let mut drawn = std::mem::take(&mut self.drawn);
        drawn.clear();
        for_each_sprite(world, |kind, r| {
            let (x, y) = self.place(kind, r);
            drawn.push(self.sprites[kind as usize].blit(&mut canvas, x, y));
        });
        self.drawn = drawn;
        match (&self.hud, &mut self.shown) {
            (HudLayer::Text(layout), HudShown::Text(old)) => {
                let text = HudText::of(world, scale.max_lives);
                layout.draw_changes(&mut canvas, old, &text);
                *old = text;
            }
            (HudLayer::Gauge(layout), HudShown::Gauge(old)) => {
                let ink = gauge_ink(layout, world, scale);
                layout.draw_changes(&mut canvas, *old, ink);
                *old = ink;
            }
            _ => {}
        }
    }

    fn paint_into(
        &self,
        world: &World,
        scale: HudScale,
        frame: &mut [u8],
        mut on_sprite: impl FnMut(PixRect),
    ) -> HudShown {
        let mut canvas = self.canvas(frame);
        canvas.bytes.fill(canvas::BACKGROUND);
        for_each_sprite(world, |kind, r| {
            let (x, y) = self.place(kind, r);
            on_sprite(self.sprites[kind as usize].blit(&mut canvas, x, y));
        });
        match &self.hud {
            HudLayer::Text(layout) => {
                let text = HudText::of(world, scale.max_lives);
                layout.draw_full(&mut canvas, &text);
                HudShown::Text(text)
            }
            HudLayer::Gauge(layout) => {
                let ink = gauge_ink(layout, world, scale);
                layout.draw_full(&mut canvas, ink);
                HudShown::Gauge(ink)
            }
            HudLayer::Off => HudShown::Nothing,
        }
    }

    fn canvas<'a>(&self, frame: &'a mut [u8]) -> Canvas<'a> {
        assert_eq!(frame.len(), self.frame_len(), "a {}x{} {:?} frame", self.height, self.width, self.format);
        Canvas { width: self.width, height: self.height, bpp: self.format.bytes_per_pixel(), bytes: frame }
    }

    /// The frame pixel of the top-left corner of a `kind` entity's sprite.
    #[inline]
    fn place(&self, kind: Kind, r: &Rect) -> (usize, usize) {
        let x = r.x.max(0) as usize * self.width / WIDTH as usize;
        let y = r.y.max(0) as usize * self.height / HEIGHT as usize;
        let (sx, sy) = self.shift[kind as usize];
        // Grown boxes stay in the flight band: the rows above it are the HUD's alone.
        let top = crate::consts::Y_MIN as usize * self.height / HEIGHT as usize;
        (x.saturating_sub(sx), y.saturating_sub(sy).max(top.min(y)))
    }
}

/// The gauges' ink for `world`.
#[inline]
fn gauge_ink(layout: &GaugeLayout, world: &World, scale: HudScale) -> GaugeInk {
    layout.ink(world.fuel_left, scale.max_fuel, world.lives, scale.max_lives)
}

/// Calls `f` for every entity in drawing order: tanks, birds, aliens, missiles, the chopper.
#[inline]
fn for_each_sprite(world: &World, mut f: impl FnMut(Kind, &Rect)) {
    world.fuel_tanks.iter().for_each(|r| f(Kind::FuelTank, r));
    world.birds.iter().for_each(|r| f(Kind::Bird, r));
    world.aliens.iter().for_each(|a| f(Kind::Alien, &a.body));
    world.missiles.iter().for_each(|r| f(Kind::Missile, r));
    f(Kind::Chopper, &world.chopper);
}
