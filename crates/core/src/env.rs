//! The Gymnasium-shaped face of the game: [`Env`], and [`ChopperScape`] which implements it.

use crate::action::{ACTION_MEANINGS, Action, N_ACTIONS};
use crate::config::Config;
use crate::consts::{HEIGHT, WIDTH};
use crate::error::{ConfigError, Error};
use crate::obs_buffer::{ObsBufMut, Observation};
use crate::obs_pipeline::Observer;
use crate::rules::Game;
use crate::spaces::{BoxSpace, Discrete};
use crate::world::{Cause, Status, World};

/// What `info` carries on every step.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub struct Info {
    /// Fuel left after the step.
    pub fuel: u32,
    /// Lives left after the step.
    pub lives: u32,
    /// Why the episode terminated, on the step that terminates it; `None` otherwise (truncation included).
    pub cause: Option<Cause>,
}

/// One step's result, observation aside (what [`ChopperScape::step_into`] returns).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Transition {
    /// Reward of the step: +1 or −10 per underlying step, summed under frame skip.
    pub reward: f32,
    /// The episode ended by the rules.
    pub terminated: bool,
    /// The episode was cut off at `max_episode_steps`.
    pub truncated: bool,
    /// Fuel, lives, and the cause of a termination.
    pub info: Info,
}

/// One step's result, as Gymnasium's `step` returns it.
#[derive(Clone, Debug, PartialEq)]
pub struct Step<O> {
    /// The observation after the step.
    pub observation: O,
    /// Reward of the step.
    pub reward: f32,
    /// The episode ended by the rules.
    pub terminated: bool,
    /// The episode was cut off at `max_episode_steps`.
    pub truncated: bool,
    /// Fuel, lives, and the cause of a termination.
    pub info: Info,
}

/// A Gymnasium-shaped environment.
pub trait Env {
    /// What an observation is.
    type Observation;

    /// The action space.
    fn action_space(&self) -> Discrete;
    /// The observation space: exactly what `reset` and `step` produce.
    fn observation_space(&self) -> &BoxSpace;
    /// The name of each action, by index.
    fn action_meanings(&self) -> &'static [&'static str];
    /// Starts an episode. `Some(seed)` reseeds the environment's generator; `None` continues its stream.
    fn reset(&mut self, seed: Option<u64>) -> (Self::Observation, Info);
    /// Advances one step.
    ///
    /// # Errors
    /// An invalid action, a step before `reset`, or a step after the episode ended.
    fn step(&mut self, action: i64) -> Result<Step<Self::Observation>, Error>;
}

/// ChopperScape-v0: the game, its options and its observation pipeline.
///
/// # Examples
/// ```
/// use chopperscape::{ChopperScape, Config, Env};
///
/// let mut env = ChopperScape::new(Config::features()).unwrap();
/// let (_obs, info) = env.reset(Some(42));
/// assert_eq!(info.fuel, 1000);
/// let step = env.step(0).unwrap(); // Right
/// assert_eq!(step.reward, 1.0);
/// assert!(env.step(9).is_err()); // there are five actions
/// ```
#[derive(Clone, Debug)]
pub struct ChopperScape {
    game: Game,
    observer: Observer,
}

impl ChopperScape {
    /// An environment with these options. Call [`Env::reset`] before stepping.
    ///
    /// # Errors
    /// The first option out of range, named, with its allowed range; options whose observation buffers would
    /// take more than [`crate::limits::MAX_ENV_BYTES`] ([`ConfigError::TooLarge`]), or whose memory the system
    /// refuses ([`ConfigError::OutOfMemory`]).
    pub fn new(config: Config) -> Result<ChopperScape, ConfigError> {
        let game = Game::new(config)?;
        // Everything the observation buffers take, asked of the system at once: a refusal is an error here,
        // never an abort in the middle of building them (or of the caller's first observation).
        crate::limits::probe(game.config().env_bytes(), "one environment's observation buffers")?;
        let observer = Observer::new(game.config())?;
        Ok(ChopperScape { game, observer })
    }

    /// The options.
    pub fn config(&self) -> &Config {
        self.game.config()
    }

    /// The current state of the world.
    pub fn world(&self) -> &World {
        self.game.world()
    }

    /// The rules' state (world, generator, sticky action): what a snapshot holds.
    pub fn game(&self) -> &Game {
        &self.game
    }

    /// Elements of one observation.
    pub fn obs_len(&self) -> usize {
        self.observer.space().len()
    }

    /// Starts an episode and writes its first observation into `out`.
    ///
    /// # Errors
    /// [`Error::BufferSize`] if `out` does not fit the observation space; nothing changes then.
    pub fn reset_into(&mut self, seed: Option<u64>, out: ObsBufMut<'_>) -> Result<Info, Error> {
        self.observer.check(&out)?;
        self.game.reset(seed);
        self.observer.observe(self.game.world(), self.game.config(), true, out);
        Ok(self.info())
    }

    /// Advances one step and writes the observation into `out`: the allocation-free hot path.
    ///
    /// # Errors
    /// An invalid action, a buffer that does not fit, a step before `reset` or after the episode ended;
    /// nothing changes then.
    pub fn step_into(&mut self, action: i64, out: ObsBufMut<'_>) -> Result<Transition, Error> {
        self.advance(action, out, false)
    }

    /// Like [`ChopperScape::step_into`], but for `rgb` and `grayscale` observations with `frame_stack = 1` it
    /// draws only what changed (a few kilobytes) straight onto `out` instead of copying a whole frame: the
    /// fastest way to get full-size pixels.
    ///
    /// Contract: `out` is the buffer the previous `reset_into`, `step_into` or `step_into_incremental` of this env
    /// wrote, and nobody modified it since. A different buffer (another address) is detected and gets a full
    /// redraw; a modified one is not, and keeps the modification outside the redrawn rectangles. Other
    /// observation types behave exactly as `step_into`.
    ///
    /// # Errors
    /// As [`ChopperScape::step_into`]; nothing changes then.
    pub fn step_into_incremental(&mut self, action: i64, out: ObsBufMut<'_>) -> Result<Transition, Error> {
        self.advance(action, out, true)
    }

    /// One step: checks, the rules, then the observation, copied (`step_into`) or drawn onto `out`.
    #[inline]
    fn advance(&mut self, action: i64, out: ObsBufMut<'_>, onto: bool) -> Result<Transition, Error> {
        let action = Action::try_from(action)?;
        self.observer.check(&out)?;
        let outcome = self.game.step(action)?;
        let (world, config) = (self.game.world(), self.game.config());
        if onto {
            self.observer.observe_onto(world, config, out);
        } else {
            self.observer.observe(world, config, false, out);
        }
        Ok(Transition {
            reward: outcome.reward,
            terminated: outcome.terminated,
            truncated: outcome.truncated,
            info: self.info(),
        })
    }

    /// The info of the current state.
    pub fn info(&self) -> Info {
        let w = self.game.world();
        let cause = match w.status {
            Status::Terminated(c) => Some(c),
            _ => None,
        };
        Info { fuel: w.fuel_left, lives: w.lives, cause }
    }

    /// Draws the full 600 × 800 × 3 frame of the current state into `rgb` (`render_mode = "rgb_array"`),
    /// whatever the observation type.
    ///
    /// # Errors
    /// [`Error::BufferSize`] unless `rgb.len() == 600 * 800 * 3`.
    pub fn render_into(&self, rgb: &mut [u8]) -> Result<(), Error> {
        let n = (HEIGHT * WIDTH * 3) as usize;
        if rgb.len() != n {
            return Err(Error::BufferSize { expected: n, expected_dtype: "uint8", got: rgb.len(), got_dtype: "uint8" });
        }
        Observer::render_full(self.game.world(), self.game.config(), rgb);
        Ok(())
    }

    /// The full 600 × 800 × 3 frame of the current state.
    pub fn render(&self) -> Vec<u8> {
        let mut rgb = vec![0; (HEIGHT * WIDTH * 3) as usize];
        Observer::render_full(self.game.world(), self.game.config(), &mut rgb);
        rgb
    }

    pub(crate) fn parts_mut(&mut self) -> (&mut Game, &mut Observer) {
        (&mut self.game, &mut self.observer)
    }

    pub(crate) fn observer(&self) -> &Observer {
        &self.observer
    }

    fn new_observation(&self) -> Observation {
        let space = self.observer.space();
        Observation::zeros(space.shape.clone(), space.dtype)
    }
}

impl Env for ChopperScape {
    type Observation = Observation;

    fn action_space(&self) -> Discrete {
        Discrete { n: N_ACTIONS }
    }

    fn observation_space(&self) -> &BoxSpace {
        self.observer.space()
    }

    fn action_meanings(&self) -> &'static [&'static str] {
        &ACTION_MEANINGS
    }

    fn reset(&mut self, seed: Option<u64>) -> (Observation, Info) {
        let mut obs = self.new_observation();
        let info = self.reset_into(seed, obs.as_buf_mut()).expect("an observation of the space's own shape fits");
        (obs, info)
    }

    fn step(&mut self, action: i64) -> Result<Step<Observation>, Error> {
        let mut obs = self.new_observation();
        let t = self.step_into(action, obs.as_buf_mut())?;
        Ok(Step { observation: obs, reward: t.reward, terminated: t.terminated, truncated: t.truncated, info: t.info })
    }
}
