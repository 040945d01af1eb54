//! ChopperScape-v0: a helicopter flies through the sky; birds come from the right and end the episode on
//! contact; fuel tanks rise from the bottom and refill the tank; every step is worth +1; fuel runs out after
//! 1000 steps. This crate is the game itself, exactly as `SPEC.md` states it, and nothing else: no threads,
//! I/O, windows or Python, so it builds for `wasm32-unknown-unknown` unchanged.
//!
//! # How the types relate
//! - [`Config`] holds every option (the v0 rules by default); it is validated once. Each option is declared once,
//!   in the table of `config.rs`, from which [`Config`] and [`OPTIONS`] are generated: its default, what it
//!   allows, whether it is a rule, its command-line flag and whether the web page sets it.
//! - [`Game`] is the rules: a [`World`] (every entity, fuel, score, lives), the env's own generator
//!   ([`Rng`]), and `reset` / `step` that change the world. Pure and allocation-free per step.
//! - [`ChopperScape`] is the Gymnasium-shaped environment ([`Env`]): a game plus the observation pipeline
//!   (features, or pixels from the [`render::Renderer`], stacked `frame_stack` deep). Its hot path
//!   [`ChopperScape::step_into`] writes into a buffer the caller owns.
//! - [`Snapshot`] clones and restores a whole environment, and encodes it to versioned bytes.
//! - [`MODES`] is the ladder of difficulty modes (ChopperScape-Bench): named, versioned rule sets, each
//!   applied to a [`Config`] with [`Mode::apply`]; [`configure`] builds a config from a mode and the options given
//!   beside it, as every surface does.
//! - [`policy`] holds the built-in policies: `random`, fixed actions, and the scripted `heuristic`.
//!
//! # Examples
//! ```
//! use chopperscape::{ChopperScape, Config, Env};
//!
//! let mut env = ChopperScape::new(Config::features()).unwrap();
//! let (_obs, _info) = env.reset(Some(7));
//! let mut total = 0.0;
//! loop {
//!     let step = env.step(4).unwrap(); // Do Nothing
//!     total += step.reward;
//!     if step.terminated || step.truncated {
//!         println!("return {total}, cause {:?}", step.info.cause);
//!         break;
//!     }
//! }
//! ```

mod action;
mod config;
pub mod consts;
mod env;
mod error;
pub mod features;
mod geometry;
pub mod limits;
mod modes;
mod obs_buffer;
mod obs_pipeline;
pub mod policy;
mod reachable;
pub mod render;
mod rng;
mod rules;
mod snapshot;
mod spaces;
mod world;

pub use action::{ACTION_MEANINGS, Action, N_ACTIONS};
pub use config::{
    BirdFuelCollision, CliFlag, Config, HudStyle, Look, OPTION_NAMES, OPTIONS, ObsType, OptionInfo, OptionKind,
    OptionValue, option_info,
};
pub use env::{ChopperScape, Env, Info, Step, Transition};
pub use error::{ConfigError, Error, SnapshotError};
pub use geometry::Rect;
pub use modes::{MODES, Mode, configure, mode, mode_names};
pub use obs_buffer::{ObsBufMut, ObsData, Observation};
pub use obs_pipeline::luma;
pub use rng::Rng;
pub use rules::{Game, Outcome};
pub use snapshot::{SNAPSHOT_VERSION, Snapshot};
pub use spaces::{Bounds, BoxSpace, Discrete, Dtype};
pub use world::{Alien, Cause, Status, World};
