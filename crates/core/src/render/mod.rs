//! The software renderer: draws a [`World`] into a caller-owned RGB buffer.
//!
//! Interim version: flat boxes for each entity, no HUD. (Replaced by the pixel-art renderer of issue 3.)

use crate::consts::{HEIGHT, WIDTH};
use crate::geometry::Rect;
use crate::world::World;

/// Draws frames of one size.
#[derive(Clone, Debug)]
pub struct Renderer {
    height: usize,
    width: usize,
    hud: bool,
}

impl Renderer {
    /// A renderer for frames of `height × width` pixels, with or without the HUD line.
    pub fn new(height: u32, width: u32, hud: bool) -> Renderer {
        Renderer { height: height as usize, width: width as usize, hud }
    }

    /// Bytes of one RGB frame.
    pub fn frame_len(&self) -> usize {
        self.height * self.width * 3
    }

    /// Draws the whole frame into `rgb` (`height × width × 3`, row-major). `max_lives` is the `lives` option.
    pub fn draw_full(&mut self, world: &World, max_lives: u32, rgb: &mut [u8]) {
        let _ = (max_lives, self.hud);
        rgb.fill(255);
        for b in &world.fuel_tanks {
            self.fill(rgb, b, [0, 160, 0]);
        }
        for b in &world.birds {
            self.fill(rgb, b, [200, 0, 0]);
        }
        for a in &world.aliens {
            self.fill(rgb, &a.body, [160, 0, 160]);
        }
        for m in &world.missiles {
            self.fill(rgb, m, [255, 120, 0]);
        }
        self.fill(rgb, &world.chopper, [0, 0, 200]);
    }

    /// Draws the frame into `rgb`, which holds the frame this renderer drew last.
    pub fn draw(&mut self, world: &World, max_lives: u32, rgb: &mut [u8]) {
        self.draw_full(world, max_lives, rgb);
    }

    fn fill(&self, rgb: &mut [u8], r: &Rect, color: [u8; 3]) {
        let sx = |x: i32| (x as usize * self.width).div_ceil(WIDTH as usize);
        let sy = |y: i32| (y as usize * self.height).div_ceil(HEIGHT as usize);
        for y in sy(r.y)..sy(r.y + r.h).min(self.height) {
            for x in sx(r.x)..sx(r.x + r.w).min(self.width) {
                rgb[(y * self.width + x) * 3..][..3].copy_from_slice(&color);
            }
        }
    }
}
