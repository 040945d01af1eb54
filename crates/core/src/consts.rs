//! The constants of the rules, named as in `SPEC.md`. Units are pixels and steps.

/// Canvas width in pixels.
pub const WIDTH: i32 = 800;
/// Canvas height in pixels.
pub const HEIGHT: i32 = 600;

/// Left edge of the flight band (pixels).
pub const X_MIN: i32 = 0;
/// Right edge of the flight band (pixels, exclusive).
pub const X_MAX: i32 = 800;
/// Top edge of the flight band (pixels): 10 % of the height; the HUD lives above it.
pub const Y_MIN: i32 = 60;
/// Bottom edge of the flight band (pixels, exclusive): 90 % of the height.
pub const Y_MAX: i32 = 540;

/// Chopper width and height (pixels).
pub const CHOPPER_SIZE: (i32, i32) = (64, 64);
/// Bird width and height (pixels).
pub const BIRD_SIZE: (i32, i32) = (32, 32);
/// Fuel tank width and height (pixels).
pub const FUEL_TANK_SIZE: (i32, i32) = (32, 32);
/// Alien bird width and height (pixels).
pub const ALIEN_SIZE: (i32, i32) = (32, 32);
/// Missile width and height (pixels).
pub const MISSILE_SIZE: (i32, i32) = (16, 8);

/// Fuel at reset, in steps of flight (default of the `max_fuel` option).
pub const MAX_FUEL: u32 = 1000;
/// Distance the chopper moves per step for a move action (pixels).
pub const CHOPPER_SPEED: i32 = 5;
/// Distance a bird or alien moves left per step (pixels).
pub const BIRD_SPEED: i32 = 5;
/// Distance a fuel tank rises per step (pixels).
pub const FUEL_TANK_SPEED: i32 = 5;
/// Distance a missile moves left per step (pixels).
pub const MISSILE_SPEED: i32 = 10;

/// Chopper spawn x range at reset, `[lo, hi)` (5–10 % of the width).
pub const CHOPPER_SPAWN_X: (i32, i32) = (40, 80);
/// Chopper spawn y range at reset, `[lo, hi)` (15–20 % of the height).
pub const CHOPPER_SPAWN_Y: (i32, i32) = (90, 120);

/// Default probability per step that a bird appears.
pub const BIRD_PROB: f64 = 0.01;
/// Default probability per step that a fuel tank appears.
pub const FUEL_PROB: f64 = 0.01;

/// Reward of every step.
pub const STEP_REWARD: i32 = 1;
/// Reward of a step in which the chopper is hit.
pub const HIT_REWARD: i32 = -10;

/// Steps after it appears that an alien fires its first missile.
pub const ALIEN_FIRST_SHOT: u32 = 20;
/// Steps between an alien's missiles after the first.
pub const ALIEN_SHOT_PERIOD: u32 = 40;
/// Missile offset from the alien's top-left corner: `(x − 16, y + 12)`.
pub const MISSILE_OFFSET: (i32, i32) = (-16, 12);

/// Steps after which the registered environment truncates an episode.
pub const MAX_EPISODE_STEPS: u32 = 10_000;

/// Frames per second of `render_mode = "human"`.
pub const RENDER_FPS: u32 = 30;

/// HUD text origin: its left end (x) and its baseline (y), in pixels of the 800 × 600 canvas.
pub const HUD_ORIGIN: (i32, i32) = (10, 20);
