//! Playing one episode headless: with a built-in policy, a trained policy, or from a list of actions.
//!
//! The env observes the cheap `features` vector (nothing is drawn), or for a trained policy what the policy
//! takes; a caller that records asks the env for the full frame through the `frame` callback, which runs after
//! `reset` and after every step.

use anyhow::{Context, Result, bail};
use chopperscape::{ChopperScape, Config, Env, ObsType, Observation, Status, policy};
use chopperscape_policy::Policy;
use serde::Serialize;

/// What one episode came to.
#[derive(Clone, Debug, PartialEq, Eq, Serialize)]
pub struct EpisodeResult {
    /// The seed of `reset`.
    pub seed: u64,
    /// Agent steps taken.
    pub steps: u32,
    /// The episode return (sum of rewards).
    #[serde(rename = "return")]
    pub ret: i64,
    /// `"bird"`, `"fuel"`, `"truncated"`, or `None` while the episode still runs.
    pub cause: Option<&'static str>,
    /// Every action taken, in order.
    #[serde(skip)]
    pub actions: Vec<u8>,
    /// Chopper top-left corner `[x, y]` after reset.
    pub start: (i32, i32),
    /// Chopper top-left corner `[x, y]` now (at the end of the episode).
    pub chopper: (i32, i32),
}

impl EpisodeResult {
    /// The episode as an action log writes it.
    pub fn played(&self) -> crate::actionlog::Played<'_> {
        crate::actionlog::Played {
            seed: self.seed,
            steps: self.steps,
            ret: self.ret,
            cause: self.cause,
            actions: &self.actions,
        }
    }
}

/// One environment plus its observation buffer.
pub struct Runner {
    env: ChopperScape,
    obs: Observation,
    seed: u64,
    actions: Vec<u8>,
    start: (i32, i32),
}

impl Runner {
    /// An environment with `config`'s rules; its observation is switched to `features` (nothing is drawn).
    pub fn new(config: &Config) -> Result<Runner> {
        Runner::observing(&Config { obs_type: ObsType::Features, frame_stack: 1, ..config.clone() })
    }

    /// An environment with `config`'s rules and observation.
    pub fn observing(config: &Config) -> Result<Runner> {
        let env = ChopperScape::new(config.clone()).context("invalid game options")?;
        let space = env.observation_space();
        let obs = Observation::zeros(space.shape.clone(), space.dtype);
        Ok(Runner { env, obs, seed: 0, actions: Vec::new(), start: (0, 0) })
    }

    /// Starts an episode with `seed`.
    pub fn reset(&mut self, seed: u64) {
        self.env.reset_into(Some(seed), self.obs.as_buf_mut()).expect("the buffer has the env's own length");
        self.seed = seed;
        self.actions.clear();
        let c = self.env.world().chopper;
        self.start = (c.x, c.y);
    }

    /// Takes one action (0..=4).
    ///
    /// # Errors
    /// An invalid action, or a step after the episode ended.
    pub fn step(&mut self, action: u8) -> Result<()> {
        self.env.step_into(i64::from(action), self.obs.as_buf_mut())?;
        self.actions.push(action);
        Ok(())
    }

    /// Whether the episode has ended.
    pub fn is_over(&self) -> bool {
        self.env.world().status.is_over()
    }

    /// The environment (to read the world or render a frame).
    pub fn env(&self) -> &ChopperScape {
        &self.env
    }

    /// The episode so far.
    pub fn result(&self) -> EpisodeResult {
        let w = self.env.world();
        EpisodeResult {
            seed: self.seed,
            steps: w.steps,
            ret: w.episode_return,
            cause: cause_of(w.status),
            actions: self.actions.clone(),
            start: self.start,
            chopper: (w.chopper.x, w.chopper.y),
        }
    }
}

/// The JSON name of how an episode ended, if it has.
pub fn cause_of(status: Status) -> Option<&'static str> {
    match status {
        Status::Terminated(c) => Some(c.as_str()),
        Status::Truncated => Some("truncated"),
        Status::NotStarted | Status::Running => None,
    }
}

/// The most agent steps the command line plays in one episode when `max_episode_steps` is `none`: a policy
/// that never crashes (`noop` with `--bird-prob 0 --fuel-prob 1`) would otherwise play, and hold its actions,
/// forever. A thousand times the default limit; the actions of such an episode take 10 MB.
pub const STEP_CAP: u32 = 10_000_000;

/// [`STEP_CAP`], or the `CHOPPERSCAPE_STEP_CAP` environment variable (for tests, which cannot wait for ten
/// million steps).
pub fn step_cap() -> u32 {
    std::env::var("CHOPPERSCAPE_STEP_CAP").ok().and_then(|v| v.parse().ok()).unwrap_or(STEP_CAP)
}

/// Who plays: a built-in policy by name, or a trained policy.
pub enum AnyPolicy<'a> {
    /// A built-in policy (`chopperscape::policy::NAMES`).
    BuiltIn(&'a str),
    /// A trained policy; the env observes what it takes (its options were checked by [`Policy::check`]).
    Model(&'a mut Policy),
}

/// A policy ready to act in one episode.
enum Acting<'p> {
    BuiltIn(Box<dyn policy::Policy + Send + Sync>),
    Model(&'p mut Policy),
}

/// Plays one whole episode with `policy`; a built-in one's own generator (for `random`) is seeded with `seed`
/// too. `frame` sees the env after reset and after every step.
///
/// # Errors
/// An unknown built-in policy, a trained policy that fails, an error from `frame`, or an episode without a step
/// limit that is still running after [`step_cap`] steps.
pub fn play_policy(
    config: &Config,
    policy: &mut AnyPolicy<'_>,
    seed: u64,
    mut frame: impl FnMut(&ChopperScape) -> Result<()>,
) -> Result<EpisodeResult> {
    let (mut runner, mut acting) = match policy {
        AnyPolicy::BuiltIn(name) => {
            (Runner::new(config)?, Acting::BuiltIn(policy::by_name(name, seed, config).map_err(anyhow::Error::msg)?))
        }
        AnyPolicy::Model(model) => (Runner::observing(config)?, Acting::Model(model)),
    };
    runner.reset(seed);
    frame(runner.env())?;
    let cap = if config.max_episode_steps.is_none() { step_cap() } else { u32::MAX };
    while !runner.is_over() {
        if runner.env().world().steps >= cap {
            bail!(
                "the episode did not end within {cap} steps; with --max-episode-steps none the command line stops \
                 there (memory and time stay bounded); give --max-episode-steps N to truncate episodes at N steps"
            );
        }
        let action = match &mut acting {
            Acting::BuiltIn(p) => p.act(runner.env().world()),
            Acting::Model(model) => model.act(&runner.obs)?,
        };
        runner.step(action as u8)?;
        frame(runner.env())?;
    }
    Ok(runner.result())
}

/// Re-plays `actions` from `reset(seed)`.
///
/// # Errors
/// An action outside 0..=4, actions left after the episode ended, or an error from `frame`.
pub fn replay_actions(
    config: &Config,
    seed: u64,
    actions: &[u8],
    mut frame: impl FnMut(&ChopperScape) -> Result<()>,
) -> Result<EpisodeResult> {
    let mut runner = Runner::new(config)?;
    runner.reset(seed);
    frame(runner.env())?;
    for (i, &a) in actions.iter().enumerate() {
        if runner.is_over() {
            bail!("the episode ended after {i} steps but the log has {} actions", actions.len());
        }
        runner.step(a).with_context(|| format!("action {i}"))?;
        frame(runner.env())?;
    }
    Ok(runner.result())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn replaying_a_policy_episode_reproduces_it() {
        let config = Config::default();
        let played = play_policy(&config, &mut AnyPolicy::BuiltIn("random"), 5, |_| Ok(())).unwrap();
        assert!(played.cause.is_some());
        assert_eq!(played.actions.len(), played.steps as usize);
        let replayed = replay_actions(&config, 5, &played.actions, |_| Ok(())).unwrap();
        assert_eq!(replayed, played);
    }

    #[test]
    fn actions_past_the_end_are_refused() {
        let config = Config::default();
        let mut actions = play_policy(&config, &mut AnyPolicy::BuiltIn("noop"), 1, |_| Ok(())).unwrap().actions;
        actions.push(4);
        let err = replay_actions(&config, 1, &actions, |_| Ok(())).unwrap_err().to_string();
        assert!(err.contains("episode ended"), "{err}");
    }
}
