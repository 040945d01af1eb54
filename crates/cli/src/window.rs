//! A window that shows 600 × 800 RGB frames at 30 fps and reads the keyboard (minifb, X11).

use anyhow::{Result, bail};
use minifb::{Key, KeyRepeat, WindowOptions};

use crate::media::{FPS, H, W};

/// An open game window.
pub struct Window {
    window: minifb::Window,
    pixels: Vec<u32>,
}

/// The message for a machine where no window can open.
fn no_display(why: &str) -> String {
    format!(
        "cannot open a window: {why}.\n  Watch the game without a display: chopperscape demo (writes chopperscape-demo.gif)\n  \
         Play it in a browser: chopperscape web (serves the browser version)"
    )
}

impl Window {
    /// Opens a window titled `title`.
    ///
    /// # Errors
    /// No display (`DISPLAY` is not set) or the window could not open; the message names `chopperscape demo`
    /// and `chopperscape web` instead.
    pub fn open(title: &str) -> Result<Window> {
        if std::env::var_os("DISPLAY").is_none_or(|d| d.is_empty()) && std::env::var_os("WAYLAND_DISPLAY").is_none() {
            bail!(no_display("no display (DISPLAY is not set)"));
        }
        let mut window = match minifb::Window::new(title, W as usize, H as usize, WindowOptions::default()) {
            Ok(w) => w,
            Err(e) => bail!(no_display(&e.to_string())),
        };
        window.set_target_fps(FPS as usize);
        Ok(Window { window, pixels: vec![0; (W * H) as usize] })
    }

    /// Whether the window is still open and Esc is not pressed.
    pub fn is_open(&self) -> bool {
        self.window.is_open() && !self.window.is_key_down(Key::Escape)
    }

    /// Shows an RGB frame and waits for the next 1/30 s tick; also polls the keyboard.
    pub fn show(&mut self, rgb: &[u8]) -> Result<()> {
        for (px, c) in self.pixels.iter_mut().zip(rgb.chunks_exact(3)) {
            *px = u32::from(c[0]) << 16 | u32::from(c[1]) << 8 | u32::from(c[2]);
        }
        self.window.update_with_buffer(&self.pixels, W as usize, H as usize)?;
        Ok(())
    }

    /// Whether `key` went down since the last frame.
    pub fn pressed(&self, key: Key) -> bool {
        self.window.is_key_pressed(key, KeyRepeat::No)
    }

    /// The action of the arrow keys or WASD held now: Up, Down, Left, Right in that priority, else Do Nothing.
    pub fn held_action(&self) -> u8 {
        let down = |a: Key, b: Key| self.window.is_key_down(a) || self.window.is_key_down(b);
        if down(Key::Up, Key::W) {
            3
        } else if down(Key::Down, Key::S) {
            2
        } else if down(Key::Left, Key::A) {
            1
        } else if down(Key::Right, Key::D) {
            0
        } else {
            4
        }
    }
}
