//! The software renderer: draws a [`World`] into a caller-owned frame (RGB or gray), with no allocation per
//! frame once warm.
//!
//! A frame is `height × width` pixels, row-major, white background. Entities are drawn in this order: fuel
//! tanks, birds, aliens, missiles, the chopper last (on top); then the HUD line ([`hud`]) in the strip above
//! the flight band. Sprites ([`art`]) keep their transparency: only their opaque pixels are written.
//!
//! # Scaling
//! A frame of another size than 800 × 600 is drawn natively at that size, never by shrinking a full frame:
//! an entity at `(x, y)` lands at `(⌊x·W/800⌋, ⌊y·H/600⌋)` and every sprite of one kind has the same size,
//! its SPEC size times the scale, rounded (at least one pixel). Sprites are resampled once, in
//! [`Renderer::new`], by box filtering ([`sprite`]); the HUD is sampled through tables built there too.
//!
//! # Incremental drawing
//! [`Renderer::draw`] assumes the frame holds what this renderer drew last. It erases the boxes of last frame's
//! sprites to background (which leaves the whole flight band blank, since sprites were drawn nowhere else), draws
//! this frame's sprites in order, and redraws the HUD characters that changed. The result equals
//! [`Renderer::draw_full`] bit for bit (tested over long random episodes under every option).

mod art;
mod canvas;
mod hud;
mod sprite;

pub use canvas::PixelFormat;

use canvas::{Canvas, PixRect};
use hud::{HudLayout, HudText};
use sprite::ScaledSprite;

use crate::consts::{HEIGHT, WIDTH};
use crate::geometry::Rect;
use crate::world::World;

/// Draws frames of one size and pixel format.
#[derive(Clone, Debug)]
pub struct Renderer {
    height: usize,
    width: usize,
    format: PixelFormat,
    /// The HUD layout, `None` when the HUD is off.
    hud: Option<HudLayout>,
    /// Sprites at this scale, indexed by [`Kind`].
    sprites: [ScaledSprite; 5],
    /// Boxes of the sprites drawn last, to erase next time.
    drawn: Vec<PixRect>,
    /// The HUD text drawn last.
    text: HudText,
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
    /// A renderer of RGB frames of `height × width` pixels, with or without the HUD line.
    pub fn new(height: u32, width: u32, hud: bool) -> Renderer {
        Renderer::with_format(height, width, hud, PixelFormat::Rgb)
    }

    /// A renderer of frames of `height × width` pixels in `format`, with or without the HUD line.
    ///
    /// A [`PixelFormat::Gray`] frame equals, pixel for pixel, the [`crate::luma`] of the RGB frame.
    pub fn with_format(height: u32, width: u32, hud: bool, format: PixelFormat) -> Renderer {
        let (h, w) = (height as usize, width as usize);
        let size = |len: usize, frame: usize, full: usize| ((2 * len * frame + full) / (2 * full)).max(1);
        let scaled = |a: &art::Art| {
            let sw = size(a.width(), w, WIDTH as usize);
            let sh = size(a.height(), h, HEIGHT as usize);
            ScaledSprite::new(a, sw, sh, format)
        };
        let sprites = [art::FUEL_TANK, art::BIRD, art::ALIEN, art::MISSILE, art::CHOPPER].map(|a| scaled(&a));
        let hud = hud.then(|| HudLayout::new(h, w));
        // The HUD rows lie above the flight band at every size, so erasing sprites never touches the text.
        debug_assert!(hud.as_ref().is_none_or(|l| l.bottom() <= crate::consts::Y_MIN as usize * h / HEIGHT as usize));
        Renderer { height: h, width: w, format, hud, sprites, drawn: Vec::with_capacity(64), text: HudText::EMPTY }
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

    /// Bytes of one frame: `height × width × 3` for RGB, `height × width` for gray.
    pub fn frame_len(&self) -> usize {
        self.height * self.width * self.format.bytes_per_pixel()
    }

    /// Draws the whole frame into `frame` (`frame_len()` bytes, row-major). `max_lives` is the `lives` option.
    ///
    /// # Panics
    /// If `frame.len() != self.frame_len()`.
    pub fn draw_full(&mut self, world: &World, max_lives: u32, frame: &mut [u8]) {
        self.drawn.clear();
        let mut drawn = std::mem::take(&mut self.drawn);
        self.text = self.paint_into(world, max_lives, frame, |r| drawn.push(r));
        self.drawn = drawn;
    }

    /// Draws the whole frame into `frame` without touching this renderer's memory of the last frame: the same
    /// pixels as [`Renderer::draw_full`], from a shared renderer.
    ///
    /// # Panics
    /// If `frame.len() != self.frame_len()`.
    pub fn paint(&self, world: &World, max_lives: u32, frame: &mut [u8]) {
        self.paint_into(world, max_lives, frame, |_| {});
    }

    /// Draws the frame into `frame`, which must hold the frame this renderer drew last (by `draw_full` or
    /// `draw`); only what changed is redrawn.
    ///
    /// # Panics
    /// If `frame.len() != self.frame_len()`.
    pub fn draw(&mut self, world: &World, max_lives: u32, frame: &mut [u8]) {
        let mut canvas = self.canvas(frame);
        for &r in &self.drawn {
            canvas.erase(r);
        }
        let mut drawn = std::mem::take(&mut self.drawn);
        drawn.clear();
        for_each_sprite(world, |kind, r| {
            let (x, y) = self.place(r);
            drawn.push(self.sprites[kind as usize].blit(&mut canvas, x, y));
        });
        self.drawn = drawn;
        if let Some(hud) = &self.hud {
            let text = HudText::of(world, max_lives);
            hud.draw_changes(&mut canvas, &self.text, &text);
            self.text = text;
        }
    }

    fn paint_into(
        &self,
        world: &World,
        max_lives: u32,
        frame: &mut [u8],
        mut on_sprite: impl FnMut(PixRect),
    ) -> HudText {
        let mut canvas = self.canvas(frame);
        canvas.bytes.fill(canvas::BACKGROUND);
        for_each_sprite(world, |kind, r| {
            let (x, y) = self.place(r);
            on_sprite(self.sprites[kind as usize].blit(&mut canvas, x, y));
        });
        match &self.hud {
            Some(hud) => {
                let text = HudText::of(world, max_lives);
                hud.draw_full(&mut canvas, &text);
                text
            }
            None => HudText::EMPTY,
        }
    }

    fn canvas<'a>(&self, frame: &'a mut [u8]) -> Canvas<'a> {
        assert_eq!(frame.len(), self.frame_len(), "a {}x{} {:?} frame", self.height, self.width, self.format);
        Canvas { width: self.width, height: self.height, bpp: self.format.bytes_per_pixel(), bytes: frame }
    }

    /// The frame pixel of an entity's top-left corner.
    #[inline]
    fn place(&self, r: &Rect) -> (usize, usize) {
        let x = r.x.max(0) as usize * self.width / WIDTH as usize;
        let y = r.y.max(0) as usize * self.height / HEIGHT as usize;
        (x, y)
    }
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
