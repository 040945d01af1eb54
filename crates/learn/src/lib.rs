//! PPO in pure Rust: the `fast` features recipe of Python's `chopperscape.learn.train`, on candle's CPU tensors
//! and autodiff, stepping the native vector env in place. No threads or OS randomness of its own, so it builds
//! for `wasm32-unknown-unknown` unchanged (the page's Train control runs it in a Web Worker).
//!
//! - [`Recipe`]: Python's `Recipe` and the presets it trains (`fast`, `features`);
//! - [`Learner`]: one update per call ([`Learner::update`], a [`progress::Row`] of the curve), its
//!   [`State`] for `--resume`;
//! - [`evaluate`]: greedy play on held-out seeds ([`Learner::evaluate`]) and the heuristic on the same episodes;
//! - [`phases`]: where an update's time goes ([`Learner::update_laps`]), in Python's phases;
//! - [`export::to_onnx`]: the policy as the ONNX file `chopperscape-policy` plays;
//! - the parts, each tested against hand-computed values and Python's on the same batch (`tests/golden.rs`):
//!   [`gae::gae`], [`loss::ppo_loss`], [`stats`] (normalisers), [`adam`], [`agent`] (the MLP).

pub mod adam;
pub mod agent;
pub mod evaluate;
pub mod export;
pub mod gae;
mod learner;
pub mod loss;
pub mod phases;
pub mod progress;
pub mod recipe;
pub mod stats;

pub use learner::{Learner, RECENT_EPISODES, STATE_FORMAT, State, env_config, explained_variance, permutation, sample};
pub use recipe::{LR_FLOOR, Recipe};

/// What a run can fail with.
#[derive(Debug, thiserror::Error)]
pub enum LearnError {
    /// A recipe setting out of range, or one this learner does not train.
    #[error("{0}")]
    Recipe(String),
    /// The env refused (an option, a batch too large).
    #[error("env: {0}")]
    Env(String),
    /// A tensor operation failed.
    #[error("tensor: {0}")]
    Tensor(#[from] candle_core::Error),
    /// The loss was not finite: the minibatch's step was not taken.
    #[error("the loss became {loss} at update {update}")]
    NotFinite {
        /// The loss.
        loss: f32,
        /// The update it happened in.
        update: u64,
    },
    /// A resume state that does not fit.
    #[error("the resume state does not fit: {0}")]
    State(String),
}

impl LearnError {
    pub(crate) fn env(e: impl std::fmt::Display) -> LearnError {
        LearnError::Env(e.to_string())
    }
}
