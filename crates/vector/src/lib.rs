//! Batched stepping of N ChopperScape environments, written into preallocated buffers, over a private
//! pool of worker threads, with Gymnasium's autoreset.
//!
//! # How the types relate
//! - [`VectorEnv`] owns `num_envs` [`chopperscape::ChopperScape`] environments (environment `i` of a
//!   batch reset with seed `s` is seeded `s + i`) and a lazily built pool of `num_threads` workers.
//!   One call steps every environment: the batch is cut into one contiguous chunk per thread.
//! - [`BatchMut`] holds mutable views of the outputs (observations, rewards, flags, fuel, lives, cause),
//!   so a caller can hand in memory it owns (numpy arrays). [`Buffers`] owns such arrays for Rust callers;
//!   [`VectorEnv::reset`] / [`VectorEnv::step`] use buffers the vector env allocates on first use.
//! - [`AutoresetMode`] says what happens after an episode ends, exactly as Gymnasium's modes of that name.
//! - [`BatchError`] is everything a call can refuse; a refused call changes no environment.
//!
//! # Examples
//! ```
//! use chopperscape::Config;
//! use chopperscape_vector::VectorEnv;
//!
//! let mut venv = VectorEnv::new(Config::features(), 8, 2).unwrap();
//! venv.reset(Some(42)).unwrap();
//! for _ in 0..100 {
//!     venv.step(&[4; 8]).unwrap(); // every chopper does nothing
//! }
//! assert_eq!(venv.rewards(), &[1.0; 8]);
//! assert_eq!(venv.fuel(), &[900; 8]);
//! ```

mod buffers;
mod error;
mod pool;

pub use buffers::{BatchMut, Buffers, CAUSE_BIRD, CAUSE_FUEL, CAUSE_NAMES, CAUSE_NONE, Observations, cause_code};
pub use error::BatchError;

use chopperscape::limits::{check_budget, probe};
use chopperscape::{BoxSpace, ChopperScape, Config, ConfigError, Env, N_ACTIONS, ObsBufMut, SnapshotError, Status};

use crate::pool::LazyPool;

/// The most memory one batch may take: 16 GiB for its environments and its output buffers
/// ([`VectorEnv::batch_bytes`]). A batch over it is refused with [`ConfigError::TooLarge`] before anything is
/// allocated.
pub const MAX_BATCH_BYTES: u64 = 16 << 30;

/// The most worker threads a batch may ask for.
pub const MAX_THREADS: usize = 1024;

/// What a vector env does with an environment whose episode ended, as Gymnasium's `AutoresetMode`.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, Default)]
pub enum AutoresetMode {
    /// The step after the one that ended the episode resets that environment (its action is ignored) and
    /// returns the reset observation, reward 0 and both flags false. Gymnasium's default.
    #[default]
    NextStep,
    /// The step that ends the episode resets the environment at once: it returns the reset observation, the
    /// step's own reward and flags, and the last observation in `final_observations`.
    SameStep,
}

/// One environment of the batch and whether it must be reset before its next step (`NextStep`).
#[derive(Clone, Debug)]
struct Slot {
    env: ChopperScape,
    ended: bool,
    /// Steps since the last reset, for [`VectorEnv::set_time_limit`]; saturates at `u32::MAX`.
    elapsed: u32,
}

/// `num_envs` ChopperScape environments stepped together. See the [crate docs](crate).
#[derive(Clone, Debug)]
pub struct VectorEnv {
    slots: Vec<Slot>,
    obs_len: usize,
    mode: AutoresetMode,
    num_threads: usize,
    /// `num_threads − 1` workers: the calling thread is the last.
    pool: LazyPool,
    time_limit: Option<u32>,
    started: bool,
    /// Output buffers of [`VectorEnv::reset`] / [`VectorEnv::step`], allocated on their first call.
    buffers: Option<Buffers>,
    /// Whether `step_into`'s observation buffer persists, unmodified, between calls (see
    /// [`VectorEnv::set_persistent_observations`]).
    persistent: bool,
}

impl VectorEnv {
    /// `num_envs` environments with these options, stepped over `num_threads` threads, with `NextStep`
    /// autoreset. Call [`VectorEnv::reset`] (or [`VectorEnv::reset_into`]) before stepping.
    ///
    /// # Errors
    /// An option out of range, `num_envs == 0`, `num_threads` outside `1..=`[`MAX_THREADS`], or a batch whose
    /// memory ([`VectorEnv::batch_bytes`]) is over [`MAX_BATCH_BYTES`] or refused by the system (all as
    /// [`chopperscape::Error::Config`]). Nothing is allocated for a refused batch.
    pub fn new(config: Config, num_envs: usize, num_threads: usize) -> Result<VectorEnv, chopperscape::Error> {
        VectorEnv::with_mode(config, num_envs, num_threads, AutoresetMode::NextStep)
    }

    /// As [`VectorEnv::new`], with the autoreset mode of your choice.
    ///
    /// # Errors
    /// As [`VectorEnv::new`].
    pub fn with_mode(
        config: Config,
        num_envs: usize,
        num_threads: usize,
        mode: AutoresetMode,
    ) -> Result<VectorEnv, chopperscape::Error> {
        let in_range = |option, v: usize, max: usize, allowed| {
            if v == 0 || v > max {
                Err(ConfigError::OutOfRange { option, value: v.to_string(), allowed })
            } else {
                Ok(())
            }
        };
        in_range("num_envs", num_envs, usize::MAX, "an integer >= 1")?;
        in_range("num_threads", num_threads, MAX_THREADS, "an integer >= 1 (at most 1024)")?;
        config.validate()?;
        let needed = VectorEnv::batch_bytes(&config, num_envs, mode);
        let what = format!(
            "a batch of num_envs={num_envs} environments (obs_type \"{}\", obs_size ({}, {}), frame_stack {})",
            config.obs_type.as_str(),
            config.obs_size.0,
            config.obs_size.1,
            config.frame_stack
        );
        check_budget(what.clone(), needed, MAX_BATCH_BYTES, "use fewer environments or smaller observations")?;
        probe(needed, &what)?;
        let env = ChopperScape::new(config)?;
        let obs_len = env.obs_len();
        let mut slots = Vec::new();
        slots.try_reserve_exact(num_envs).map_err(|_| ConfigError::OutOfMemory { what, needed })?;
        slots.resize(num_envs, Slot { env, ended: false, elapsed: 0 });
        let num_threads = num_threads.min(num_envs);
        let pool = LazyPool::new(num_threads - 1);
        Ok(VectorEnv {
            slots,
            obs_len,
            mode,
            num_threads,
            pool,
            time_limit: None,
            started: false,
            buffers: None,
            persistent: false,
        })
    }

    /// Bytes a batch of `num_envs` environments with these options takes: each environment (its state and
    /// observation buffers, [`Config::env_bytes`]) and its share of the output buffers (one
    /// observation, two with `SameStep`'s final observations, and the scalars). Saturates instead of overflowing.
    pub fn batch_bytes(config: &Config, num_envs: usize, mode: AutoresetMode) -> u64 {
        let obs = config.observation_bytes();
        let finals = if mode == AutoresetMode::SameStep { obs } else { 0 };
        // Rewards, flags, fuel, lives and cause, and the wider copies Python hands out.
        let scalars = 64;
        let per_env = std::mem::size_of::<Slot>() as u64 + config.env_bytes() + obs + finals + scalars;
        per_env.saturating_mul(num_envs as u64)
    }

    /// Number of environments.
    pub fn num_envs(&self) -> usize {
        self.slots.len()
    }

    /// Worker threads a batch is split over (at most `num_envs`).
    pub fn num_threads(&self) -> usize {
        self.num_threads
    }

    /// Promises that the observation buffer given to [`VectorEnv::step_into`] is the same memory on every call
    /// and that nobody modifies it between calls. Then `rgb` and `grayscale` observations (without frame
    /// stacking) are drawn incrementally straight onto it
    /// ([`ChopperScape::step_into_incremental`](chopperscape::ChopperScape::step_into_incremental)): only what
    /// changed is written, instead of a whole frame per env and step. A buffer at another address is detected
    /// and redrawn in full; a modified one is not. [`VectorEnv::step`] (the vector env's own buffers) always
    /// works this way. Default: `false`.
    pub fn set_persistent_observations(&mut self, persistent: bool) {
        self.persistent = persistent;
    }

    /// Truncates each episode after `limit` steps exactly as Gymnasium's `TimeLimit` wrapper does: the step
    /// that reaches the limit is truncated even when it also terminates (the core's own `max_episode_steps`
    /// reports only one of the two). Use it with `max_episode_steps: None` in the config, so that truncation
    /// comes from one place; `None` (the default) leaves truncation to the config.
    ///
    /// # Errors
    /// `Some(0)` (as [`chopperscape::Error::Config`]).
    pub fn set_time_limit(&mut self, limit: Option<u32>) -> Result<(), chopperscape::Error> {
        if limit == Some(0) {
            let allowed = chopperscape::option_info("max_episode_steps").map_or("", |o| o.allowed);
            return Err(ConfigError::OutOfRange { option: "max_episode_steps", value: "0".into(), allowed }.into());
        }
        self.time_limit = limit;
        Ok(())
    }

    /// The time limit of [`VectorEnv::set_time_limit`].
    pub fn time_limit(&self) -> Option<u32> {
        self.time_limit
    }

    /// The autoreset mode.
    pub fn autoreset_mode(&self) -> AutoresetMode {
        self.mode
    }

    /// Elements of one environment's observation.
    pub fn obs_len(&self) -> usize {
        self.obs_len
    }

    /// The observation space of one environment.
    pub fn single_observation_space(&self) -> &BoxSpace {
        self.slots[0].env.observation_space()
    }

    /// The options every environment shares.
    pub fn config(&self) -> &Config {
        self.slots[0].env.config()
    }

    /// Environment `i`, read-only (its world, info, frame).
    ///
    /// # Panics
    /// If `i >= num_envs`.
    pub fn env(&self, i: usize) -> &ChopperScape {
        &self.slots[i].env
    }

    /// Whether [`VectorEnv::reset`] (or a `reset_*into`) has been called.
    pub fn is_started(&self) -> bool {
        self.started
    }

    /// Whether environment `i` ended in the last step and will reset in the next (`NextStep` autoreset).
    ///
    /// # Panics
    /// If `i >= num_envs`.
    pub fn pending_reset(&self, i: usize) -> bool {
        self.slots[i].ended
    }

    /// Steps since environment `i`'s last reset (what the time limit counts).
    ///
    /// # Panics
    /// If `i >= num_envs`.
    pub fn elapsed(&self, i: usize) -> u32 {
        self.slots[i].elapsed
    }

    /// Puts environment `i` in the state of `snapshot`, with its pending reset and step count (as
    /// [`VectorEnv::pending_reset`] and [`VectorEnv::elapsed`] reported them): with
    /// [`chopperscape::ChopperScape::snapshot`] of [`VectorEnv::env`], this saves and restores a whole batch.
    /// Marks the batch started.
    ///
    /// The three must be a state the batch could be in, so that the next step can step every environment:
    /// `elapsed` equals the snapshot's step count, and a reset is pending exactly when the episode ended (by
    /// the rules, or by the time limit; `NextStep` mode only).
    ///
    /// # Errors
    /// A snapshot taken with other options, or a state the batch cannot be in
    /// ([`SnapshotError::Inconsistent`]); nothing changes then.
    ///
    /// # Panics
    /// If `i >= num_envs`.
    pub fn restore_env(
        &mut self,
        i: usize,
        snapshot: &chopperscape::Snapshot,
        pending_reset: bool,
        elapsed: u32,
    ) -> Result<(), chopperscape::Error> {
        let world = snapshot.world();
        let inconsistent = |why: String| Err(SnapshotError::Inconsistent(format!("environment {i}: {why}")).into());
        if elapsed != world.steps {
            return inconsistent(format!("elapsed steps {elapsed} differ from the snapshot's {}", world.steps));
        }
        let over_limit = self.time_limit.is_some_and(|limit| elapsed >= limit);
        let ended = world.status.is_over() || over_limit;
        match (world.status, pending_reset) {
            (Status::NotStarted, _) => return inconsistent("its snapshot was taken before any reset".into()),
            (_, true) if self.mode == AutoresetMode::SameStep => {
                return inconsistent("a pending reset in SAME_STEP mode (which resets at once)".into());
            }
            (status, false) if ended => {
                return inconsistent(format!(
                    "its episode is over ({status:?} after {elapsed} steps) but no reset is pending"
                ));
            }
            (_, true) if !ended => return inconsistent("a reset is pending but its episode goes on".into()),
            _ => {}
        }
        let slot = &mut self.slots[i];
        slot.env.restore(snapshot)?;
        slot.ended = pending_reset;
        slot.elapsed = elapsed;
        self.started = true;
        Ok(())
    }

    /// Owned buffers the size of this batch (with the final-observation buffer in `SameStep` mode).
    pub fn new_buffers(&self) -> Buffers {
        let space = self.single_observation_space();
        Buffers::new(self.num_envs(), self.obs_len, space.dtype, self.mode == AutoresetMode::SameStep)
    }

    /// Resets every environment: with `Some(s)`, environment `i` is seeded `s + i` (wrapping); with `None`,
    /// each continues its own generator stream, except that a batch never seeded before starts as if
    /// seeded 0. Writes the first observations and infos into `out` (rewards 0, flags false).
    ///
    /// # Errors
    /// A buffer of the wrong size; nothing changes then.
    pub fn reset_into(&mut self, seed: Option<u64>, out: BatchMut<'_>) -> Result<(), BatchError> {
        let seed = seed.or((!self.started).then_some(0));
        self.reset_each(|i| seed.map(|s| s.wrapping_add(i as u64)), out)
    }

    /// Resets every environment, environment `i` with `seeds[i]` (`None` continues its stream).
    ///
    /// # Errors
    /// A seed list or buffer of the wrong size; nothing changes then.
    pub fn reset_seeds_into(&mut self, seeds: &[Option<u64>], out: BatchMut<'_>) -> Result<(), BatchError> {
        if seeds.len() != self.num_envs() {
            return Err(BatchError::SeedCount { expected: self.num_envs(), got: seeds.len() });
        }
        self.reset_each(|i| seeds[i], out)
    }

    fn reset_each(&mut self, seed: impl Fn(usize) -> Option<u64> + Sync, out: BatchMut<'_>) -> Result<(), BatchError> {
        let space = self.single_observation_space();
        out.check(self.num_envs(), self.obs_len, space.dtype)?;
        let obs_len = self.obs_len;
        self.for_each_chunk(out, |first, slots, out| {
            let BatchMut { observations, rewards, terminated, truncated, fuel, lives, cause, .. } = out;
            for_each_obs(observations, obs_len, |j, obs| {
                let slot = &mut slots[j];
                let info = slot.env.reset_into(seed(first + j), obs).expect("buffer sizes were checked");
                slot.ended = false;
                slot.elapsed = 0;
                rewards[j] = 0.0;
                terminated[j] = false;
                truncated[j] = false;
                fuel[j] = info.fuel;
                lives[j] = info.lives;
                cause[j] = CAUSE_NONE;
            });
        })?;
        self.started = true;
        Ok(())
    }

    /// Steps every environment with its action (`actions[i]` for environment `i`) and writes the results
    /// into `out`, with autoreset as [`VectorEnv::autoreset_mode`] says.
    ///
    /// # Errors
    /// A wrong number of actions, an action outside `0..=4`, a buffer of the wrong size, or a step before
    /// any reset. Everything is checked before any environment moves, so nothing changes then.
    pub fn step_into(&mut self, actions: &[i64], out: BatchMut<'_>) -> Result<(), BatchError> {
        if actions.len() != self.num_envs() {
            return Err(BatchError::ActionCount { expected: self.num_envs(), got: actions.len() });
        }
        if let Some(index) = actions.iter().position(|&a| !(0..N_ACTIONS as i64).contains(&a)) {
            return Err(BatchError::InvalidAction { index, action: actions[index] });
        }
        if !self.started {
            return Err(BatchError::NotReset);
        }
        let space = self.single_observation_space();
        out.check(self.num_envs(), self.obs_len, space.dtype)?;
        let (obs_len, mode, limit) = (self.obs_len, self.mode, self.time_limit);
        let persistent = self.persistent;
        if mode == AutoresetMode::SameStep && out.final_observations.is_none() {
            return Err(BatchError::MissingFinalObservations);
        }
        // All or nothing: every environment must be able to step (or reset) before any of them moves.
        if let Some(index) = self.slots.iter().position(|s| !s.ended && s.env.world().status != Status::Running) {
            return Err(BatchError::EnvState { index, status: format!("{:?}", self.slots[index].env.world().status) });
        }
        self.for_each_chunk(out, |first, slots, out| {
            let BatchMut { observations, rewards, terminated, truncated, fuel, lives, cause, final_observations } = out;
            let mut finals = final_observations;
            for_each_obs(observations, obs_len, |j, mut obs| {
                let slot = &mut slots[j];
                if slot.ended {
                    // NextStep: this step is the reset; the action is ignored.
                    let info = slot.env.reset_into(None, obs).expect("buffer sizes were checked");
                    slot.ended = false;
                    slot.elapsed = 0;
                    rewards[j] = 0.0;
                    terminated[j] = false;
                    truncated[j] = false;
                    fuel[j] = info.fuel;
                    lives[j] = info.lives;
                    cause[j] = CAUSE_NONE;
                    return;
                }
                let action = actions[first + j];
                let t = if persistent {
                    slot.env.step_into_incremental(action, reborrow(&mut obs))
                } else {
                    slot.env.step_into(action, reborrow(&mut obs))
                }
                .expect("actions, buffers and episode states were checked");
                slot.elapsed = slot.elapsed.saturating_add(1);
                let truncated_now = t.truncated || limit.is_some_and(|limit| slot.elapsed >= limit);
                rewards[j] = t.reward;
                terminated[j] = t.terminated;
                truncated[j] = truncated_now;
                fuel[j] = t.info.fuel;
                lives[j] = t.info.lives;
                cause[j] = cause_code(t.info.cause);
                if t.terminated || truncated_now {
                    match finals.as_mut() {
                        None => slot.ended = true,
                        Some(finals) => {
                            copy_obs(&obs, finals, j * obs_len);
                            slot.env.reset_into(None, obs).expect("buffer sizes were checked");
                            slot.elapsed = 0;
                        }
                    }
                }
            });
        })
    }

    /// Runs `f(first_env_index, slots, outputs)` on one contiguous chunk of environments per thread: the
    /// calling thread takes the first chunk and the pool's `num_threads − 1` workers the others, so a batch
    /// wakes one thread fewer and the caller never sits idle.
    fn for_each_chunk(
        &mut self,
        out: BatchMut<'_>,
        f: impl Fn(usize, &mut [Slot], BatchMut<'_>) + Sync,
    ) -> Result<(), BatchError> {
        let n = self.slots.len();
        let threads = self.num_threads;
        if threads <= 1 {
            f(0, &mut self.slots, out);
            return Ok(());
        }
        let chunk = n.div_ceil(threads);
        let obs_len = self.obs_len;
        let slots = &mut self.slots;
        let f = &f;
        self.pool.get()?.in_place_scope(|scope| {
            let (own_slots, mut rest_slots) = slots.split_at_mut(chunk.min(n));
            let (own_out, mut rest_out) = out.split_at(own_slots.len(), obs_len);
            let mut first = own_slots.len();
            while !rest_slots.is_empty() {
                let take = chunk.min(rest_slots.len());
                let (s, s_rest) = rest_slots.split_at_mut(take);
                let (o, o_rest) = rest_out.split_at(take, obs_len);
                scope.spawn(move |_| f(first, s, o));
                (rest_slots, rest_out, first) = (s_rest, o_rest, first + take);
            }
            f(0, own_slots, own_out);
        });
        Ok(())
    }

    /// Resets every environment into the vector env's own buffers (see [`VectorEnv::reset_into`]).
    ///
    /// # Errors
    /// Never in practice: the own buffers always fit.
    pub fn reset(&mut self, seed: Option<u64>) -> Result<(), BatchError> {
        let mut buffers = self.buffers.take().unwrap_or_else(|| self.new_buffers());
        let result = self.reset_into(seed, buffers.as_mut());
        self.buffers = Some(buffers);
        result
    }

    /// Steps every environment into the vector env's own buffers (see [`VectorEnv::step_into`]).
    ///
    /// # Errors
    /// As [`VectorEnv::step_into`]; nothing changes then.
    pub fn step(&mut self, actions: &[i64]) -> Result<(), BatchError> {
        let mut buffers = self.buffers.take().unwrap_or_else(|| self.new_buffers());
        // The own buffers are only ever lent out read-only, so they hold the last frames unmodified.
        let persistent = std::mem::replace(&mut self.persistent, true);
        let result = self.step_into(actions, buffers.as_mut());
        self.persistent = persistent;
        self.buffers = Some(buffers);
        result
    }

    /// The buffers [`VectorEnv::reset`] and [`VectorEnv::step`] write into; `None` before the first of them.
    pub fn buffers(&self) -> Option<&Buffers> {
        self.buffers.as_ref()
    }

    /// Observations of the last [`VectorEnv::reset`] / [`VectorEnv::step`], environment after environment
    /// (empty before the first).
    pub fn observations(&self) -> Observations<'_> {
        self.buffers.as_ref().map_or(Observations::U8(&[]), Buffers::observations)
    }

    /// Rewards of the last step (empty before the first reset).
    pub fn rewards(&self) -> &[f32] {
        self.buffers.as_ref().map_or(&[], |b| &b.rewards)
    }

    /// Termination flags of the last step (empty before the first reset).
    pub fn terminated(&self) -> &[bool] {
        self.buffers.as_ref().map_or(&[], |b| &b.terminated)
    }

    /// Truncation flags of the last step (empty before the first reset).
    pub fn truncated(&self) -> &[bool] {
        self.buffers.as_ref().map_or(&[], |b| &b.truncated)
    }

    /// Fuel left after the last step (empty before the first reset).
    pub fn fuel(&self) -> &[u32] {
        self.buffers.as_ref().map_or(&[], |b| &b.fuel)
    }

    /// Lives left after the last step (empty before the first reset).
    pub fn lives(&self) -> &[u32] {
        self.buffers.as_ref().map_or(&[], |b| &b.lives)
    }

    /// Termination cause codes of the last step ([`CAUSE_NAMES`]; empty before the first reset).
    pub fn causes(&self) -> &[u8] {
        self.buffers.as_ref().map_or(&[], |b| &b.cause)
    }
}

/// Calls `f(j, observation j)` for each `obs_len`-element observation of `buf`.
fn for_each_obs(buf: ObsBufMut<'_>, obs_len: usize, mut f: impl FnMut(usize, ObsBufMut<'_>)) {
    match buf {
        ObsBufMut::U8(b) => b.chunks_exact_mut(obs_len).enumerate().for_each(|(j, o)| f(j, ObsBufMut::U8(o))),
        ObsBufMut::F32(b) => b.chunks_exact_mut(obs_len).enumerate().for_each(|(j, o)| f(j, ObsBufMut::F32(o))),
    }
}

fn reborrow<'a>(b: &'a mut ObsBufMut<'_>) -> ObsBufMut<'a> {
    match b {
        ObsBufMut::U8(s) => ObsBufMut::U8(s),
        ObsBufMut::F32(s) => ObsBufMut::F32(s),
    }
}

/// Copies one observation into `to` at element `at`.
fn copy_obs(from: &ObsBufMut<'_>, to: &mut ObsBufMut<'_>, at: usize) {
    match (from, to) {
        (ObsBufMut::U8(f), ObsBufMut::U8(t)) => t[at..at + f.len()].copy_from_slice(f),
        (ObsBufMut::F32(f), ObsBufMut::F32(t)) => t[at..at + f.len()].copy_from_slice(f),
        _ => unreachable!("both buffers were checked against the observation's dtype"),
    }
}
