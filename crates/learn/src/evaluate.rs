//! Greedy play on held-out seeds, as Python's `evaluate` plays a model: episode `i` on seed `first_seed + i`,
//! each to its end or the env's step limit. The page shows it beside the training curve, whose return is the
//! stochastic policy's (with the recipe's entropy it stays well below the greedy policy's), and compares it with
//! the heuristic on the same episodes.

use chopperscape::policy::{Heuristic, Policy};
use chopperscape::{ChopperScape, Config, Env, ObsData};

use crate::{LearnError, Learner, env_config};

/// One episode played.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Episode {
    /// Its reset seed.
    pub seed: u64,
    /// Its return.
    pub ret: f64,
    /// Its decisions.
    pub steps: u64,
}

/// `act` (from the env and its raw features) played on `episodes` episodes of `config` from `first_seed`.
///
/// # Errors
/// The env's, or `act`'s.
pub fn play(
    config: &Config,
    episodes: u64,
    first_seed: u64,
    mut act: impl FnMut(&ChopperScape, &[f32]) -> Result<usize, LearnError>,
) -> Result<Vec<Episode>, LearnError> {
    let mut env = ChopperScape::new(config.clone()).map_err(LearnError::env)?;
    let mut out = Vec::with_capacity(episodes as usize);
    for i in 0..episodes {
        let seed = first_seed + i;
        let mut obs = env.reset(Some(seed)).0;
        let (mut ret, mut steps) = (0.0, 0);
        loop {
            let ObsData::F32(raw) = &obs.data else { return Err(LearnError::Env("features expected".into())) };
            let action = act(&env, raw)?;
            let step = env.step(action as i64).map_err(LearnError::env)?;
            ret += f64::from(step.reward);
            steps += 1;
            if step.terminated || step.truncated {
                break;
            }
            obs = step.observation;
        }
        out.push(Episode { seed, ret, steps });
    }
    Ok(out)
}

impl Learner {
    /// The current policy's greedy actions on `episodes` episodes from `first_seed`, under the recipe's rules.
    ///
    /// # Errors
    /// The env's.
    pub fn evaluate(&self, episodes: u64, first_seed: u64) -> Result<Vec<Episode>, LearnError> {
        play(&env_config(self.recipe())?, episodes, first_seed, |_, raw| self.greedy(raw))
    }
}

/// The heuristic policy on the same episodes, under `config`'s rules (it plans with their frame skip).
///
/// # Errors
/// The env's.
pub fn heuristic(config: &Config, episodes: u64, first_seed: u64) -> Result<Vec<Episode>, LearnError> {
    let mut policy = Heuristic::for_config(config);
    play(config, episodes, first_seed, |env, _| Ok(policy.act(env.world()).index()))
}

/// The mean return of `episodes` (0 for none).
pub fn mean(episodes: &[Episode]) -> f64 {
    episodes.iter().map(|e| e.ret).sum::<f64>() / episodes.len().max(1) as f64
}
