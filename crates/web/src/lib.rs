//! ChopperScape in the browser: a thin `wasm-bindgen` face over the core.
//!
//! [`Game`] owns one environment and two frame buffers in WebAssembly memory; after every `reset` and `step`
//! it has drawn the frame with the core's own renderer, so the page builds an `ImageData` straight from
//! `memory.buffer` at [`Game::frame_ptr`] and a frame in the browser is the native frame, byte for byte.
//! The logic lives in [`session`] (plain Rust, tested natively); this file only maps it to JavaScript.
//!
//! ```js
//! import init, { Game } from "./pkg/chopperscape_web.js";
//! const wasm = await init();
//! const game = new Game(["lives", "alien_prob"], ["3", "0.01"]);
//! game.reset(7n);
//! const step = game.step(3); // Up
//! const pixels = new Uint8ClampedArray(wasm.memory.buffer, game.frame_ptr(), game.frame_len());
//! ctx.putImageData(new ImageData(pixels, 800, 600), 0, 0);
//! ```

pub mod session;
pub mod train;

use session::Session;
use wasm_bindgen::prelude::*;

/// One step's result: reward, flags, fuel, lives, and the cause of a termination (`"bird"` / `"fuel"`).
#[wasm_bindgen(getter_with_clone)]
pub struct StepResult {
    /// +1 per step, −10 on a hit.
    pub reward: f32,
    /// The episode ended by the rules.
    pub terminated: bool,
    /// The episode was cut off at `max_episode_steps`.
    pub truncated: bool,
    /// Fuel left.
    pub fuel: u32,
    /// Lives left.
    pub lives: u32,
    /// `"bird"` or `"fuel"` on the step that terminates the episode.
    pub cause: Option<String>,
}

/// The names of the difficulty modes (`chopperscape::MODES`, easiest first): what the page's mode menu lists, with
/// the meaning `--mode` and Python's `mode=` give them.
#[wasm_bindgen]
pub fn mode_names() -> Vec<String> {
    chopperscape::MODES.iter().map(|m| m.name.to_string()).collect()
}

/// The value mode `mode` fixes for rules option `option` as text (`"3"` for `lives` in `full-v0`), or the
/// option's default where the mode keeps it; `undefined` for an unknown mode or option.
#[wasm_bindgen]
pub fn mode_value(mode: &str, option: &str) -> Option<String> {
    let config = chopperscape::mode(mode)?.config().ok()?;
    config.get(option)
}

/// One game of ChopperScape-v0 with the page's options, its frame, and the heuristic policy.
#[wasm_bindgen]
pub struct Game {
    session: Session,
}

#[wasm_bindgen]
impl Game {
    /// A game with the options `names[i] = values[i]` (`lives`, `alien_prob`, …), parsed as the CLI parses them.
    /// Throws an `Error` naming the option and its allowed range.
    #[wasm_bindgen(constructor)]
    pub fn new(names: Vec<String>, values: Vec<String>) -> Result<Game, JsError> {
        if names.len() != values.len() {
            return Err(JsError::new(&format!("{} option names but {} values", names.len(), values.len())));
        }
        let session = Session::new(names.iter().map(String::as_str).zip(values.iter().map(String::as_str)))
            .map_err(|e| JsError::new(&e))?;
        Ok(Game { session })
    }

    /// A game flown by a trained policy: `policy` holds the bytes of an exported `.onnx` (from
    /// `python -m chopperscape.learn.export`), played under the options it was trained with, then `names[i] = values[i]`.
    /// Throws an `Error` saying what is wrong with the file or an option.
    pub fn with_policy(policy: &[u8], names: Vec<String>, values: Vec<String>) -> Result<Game, JsError> {
        if names.len() != values.len() {
            return Err(JsError::new(&format!("{} option names but {} values", names.len(), values.len())));
        }
        let options = names.iter().map(String::as_str).zip(values.iter().map(String::as_str));
        let session = Session::with_policy(policy, options).map_err(|e| JsError::new(&e))?;
        Ok(Game { session })
    }

    /// The action the trained policy picks now (greedy). Throws without a policy.
    pub fn agent_action(&mut self) -> Result<i32, JsError> {
        Ok(self.session.agent_action().map_err(|e| JsError::new(&e))?.index() as i32)
    }

    /// Whether a trained policy flies this game.
    pub fn has_agent(&self) -> bool {
        self.session.has_agent()
    }

    /// Starts an episode from `seed` and draws its first frame.
    pub fn reset(&mut self, seed: u64) {
        self.session.reset(seed);
    }

    /// Advances one step with `action` (0 Right, 1 Left, 2 Down, 3 Up, 4 Do Nothing) and draws the frame.
    /// Throws on an invalid action or a step outside an episode.
    pub fn step(&mut self, action: i32) -> Result<StepResult, JsError> {
        let t = self.session.step(action.into()).map_err(|e| JsError::new(&e))?;
        Ok(StepResult {
            reward: t.reward,
            terminated: t.terminated,
            truncated: t.truncated,
            fuel: t.info.fuel,
            lives: t.info.lives,
            cause: t.info.cause.map(|c| c.as_str().to_owned()),
        })
    }

    /// The action the heuristic policy picks now.
    pub fn heuristic_action(&mut self) -> i32 {
        self.session.heuristic_action().index() as i32
    }

    /// Address in `memory.buffer` of the RGBA frame (600 × 800 × 4, opaque).
    pub fn frame_ptr(&self) -> *const u8 {
        self.session.rgba().as_ptr()
    }

    /// Bytes of the RGBA frame.
    pub fn frame_len(&self) -> usize {
        self.session.rgba().len()
    }

    /// Address in `memory.buffer` of the RGB frame (600 × 800 × 3), exactly as the native renderer draws it.
    pub fn rgb_ptr(&self) -> *const u8 {
        self.session.rgb().as_ptr()
    }

    /// Bytes of the RGB frame.
    pub fn rgb_len(&self) -> usize {
        self.session.rgb().len()
    }

    /// The chopper's left edge, in pixels.
    pub fn chopper_x(&self) -> i32 {
        self.session.world().chopper.x
    }

    /// The chopper's top edge, in pixels.
    pub fn chopper_y(&self) -> i32 {
        self.session.world().chopper.y
    }

    /// Fuel left.
    pub fn fuel(&self) -> u32 {
        self.session.world().fuel_left
    }

    /// Lives left.
    pub fn lives(&self) -> u32 {
        self.session.world().lives
    }

    /// The episode return so far (the HUD's `Rewards`).
    pub fn episode_return(&self) -> i32 {
        self.session.world().episode_return as i32
    }

    /// Steps taken in this episode.
    pub fn steps(&self) -> u32 {
        self.session.world().steps
    }

    /// Whether the episode has ended (or has not started).
    pub fn is_over(&self) -> bool {
        self.session.is_over()
    }
}
