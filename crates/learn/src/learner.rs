//! The loop of Python's `train.py`, one update per [`Learner::update`]: a rollout of `num_steps` batch steps on the
//! native vector env (NEXT_STEP autoreset, reset steps masked), GAE, then `update_epochs` passes of
//! `num_minibatches` shuffled minibatches, each a clipped-gradient Adam step.

use std::collections::VecDeque;

use candle_core::{Device, Tensor};
use chopperscape::{Config, N_ACTIONS, Rng};
use chopperscape_vector::{CAUSE_BIRD, CAUSE_FUEL, Observations, VectorEnv};
use serde::{Deserialize, Serialize};

use crate::LearnError;
use crate::adam::{Adam, clip_grad_norm};
use crate::agent::Agent;
use crate::gae::gae;
use crate::loss::{Batch, ppo_loss};
use crate::phases::{Laps, NoLaps, Phase};
use crate::progress::Row;
use crate::recipe::Recipe;
use crate::stats::{ObsNorm, RewardScale};

/// How many finished episodes the returns columns average (Python's `deque(maxlen=100)`).
pub const RECENT_EPISODES: usize = 100;

/// A PPO run in memory: the envs, the agent, its optimiser and every statistic the curve needs.
#[derive(Debug)]
pub struct Learner {
    recipe: Recipe,
    envs: VectorEnv,
    obs_dim: usize,
    agent: Agent,
    adam: Adam,
    obs_norm: ObsNorm,
    reward: RewardScale,
    /// The normalised observation each env acts on next.
    next_obs: Vec<f32>,
    /// The previous step ended env `i`'s episode: its next step is a reset step.
    next_done: Vec<bool>,
    ep_return: Vec<f64>,
    ep_len: Vec<u64>,
    finished: VecDeque<(f64, u64)>,
    episodes: u64,
    env_steps: u64,
    updates: u64,
    rng: Rng,
}

/// Everything [`Learner::from_state`] needs to go on exactly where a run stopped (the `resume.json` of a run).
#[derive(Clone, Debug, Serialize, Deserialize)]
pub struct State {
    /// `chopperscape-learn-resume/1`.
    pub format: String,
    /// The recipe.
    pub recipe: Recipe,
    /// The agent's parameters ([`Agent::vars`]' order, `(inputs, outputs)` weights).
    pub params: Vec<Vec<f32>>,
    /// Adam's state.
    pub adam: Adam,
    /// The observation statistics.
    pub obs_norm: ObsNorm,
    /// The reward scaling's statistics and returns.
    pub reward: RewardScale,
    /// Each env's snapshot (hex), whether its reset is pending, its steps since reset.
    pub envs: Vec<(String, bool, u32)>,
    /// See [`Learner`].
    pub next_obs: Vec<f32>,
    /// See [`Learner`].
    pub ep_return: Vec<f64>,
    /// See [`Learner`].
    pub ep_len: Vec<u64>,
    /// The last finished episodes' returns and lengths.
    pub finished: Vec<(f64, u64)>,
    /// Episodes finished.
    pub episodes: u64,
    /// Decisions taken.
    pub env_steps: u64,
    /// Updates done.
    pub updates: u64,
    /// The learner's generator (actions, minibatches).
    pub rng: [u64; 4],
    /// Wall seconds of the run so far (the caller's clock; 0 where it keeps none).
    #[serde(default)]
    pub wall_s: f64,
}

/// The format name of [`State`].
pub const STATE_FORMAT: &str = "chopperscape-learn-resume/1";

/// The env config of a recipe: features, its `env_options` set by name as the command line's `--option`.
///
/// # Errors
/// An option the core refuses.
pub fn env_config(recipe: &Recipe) -> Result<Config, LearnError> {
    let mut config = Config::features();
    for (name, value) in &recipe.env_options {
        let text = match value {
            serde_json::Value::String(s) => s.clone(),
            serde_json::Value::Null => "none".into(),
            serde_json::Value::Array(items) => items.iter().map(|v| v.to_string()).collect::<Vec<_>>().join("x"),
            other => other.to_string(),
        };
        config.set(name, &text).map_err(|e| LearnError::Recipe(e.to_string()))?;
    }
    Ok(config)
}

fn hex(bytes: &[u8]) -> String {
    bytes.iter().map(|b| format!("{b:02x}")).collect()
}

fn unhex(s: &str) -> Option<Vec<u8>> {
    (0..s.len()).step_by(2).map(|i| u8::from_str_radix(s.get(i..i + 2)?, 16).ok()).collect()
}

impl Learner {
    /// A fresh run of `recipe`: envs reset with seeds `seed + i`, the agent initialised from `seed`.
    ///
    /// # Errors
    /// A recipe out of range or one this learner cannot train ([`Recipe::check`]), an env option refused.
    pub fn new(recipe: Recipe) -> Result<Learner, LearnError> {
        recipe.check().map_err(LearnError::Recipe)?;
        let config = env_config(&recipe)?;
        let mut envs = VectorEnv::new(config, recipe.num_envs, recipe.env_threads).map_err(LearnError::env)?;
        let obs_dim = envs.obs_len();
        let mut rng = Rng::seed_from_u64(recipe.seed);
        let agent = Agent::new(obs_dim, N_ACTIONS, recipe.hidden, &mut rng)?;
        let sizes: Vec<usize> = agent.vars().iter().map(|v| v.elem_count()).collect();
        let n = recipe.num_envs;
        let mut learner = Learner {
            adam: Adam::new(&sizes),
            obs_norm: ObsNorm::new(obs_dim, recipe.norm_obs),
            reward: RewardScale::new(n, recipe.norm_reward),
            next_obs: vec![0.0; n * obs_dim],
            next_done: vec![false; n],
            ep_return: vec![0.0; n],
            ep_len: vec![0; n],
            finished: VecDeque::with_capacity(RECENT_EPISODES),
            episodes: 0,
            env_steps: 0,
            updates: 0,
            rng,
            agent,
            obs_dim,
            envs: {
                envs.reset(Some(recipe.seed)).map_err(LearnError::env)?;
                envs
            },
            recipe,
        };
        learner.observe();
        Ok(learner)
    }

    /// Normalises the batch's current observations into `next_obs` (updating the statistics).
    fn observe(&mut self) {
        let Observations::F32(raw) = self.envs.observations() else { unreachable!("features are f32") };
        let rows = self.recipe.num_envs;
        self.obs_norm.apply(raw, rows, true, &mut self.next_obs);
    }

    /// The recipe.
    pub fn recipe(&self) -> &Recipe {
        &self.recipe
    }

    /// Decisions taken so far (reset steps not counted).
    pub fn env_steps(&self) -> u64 {
        self.env_steps
    }

    /// Updates done so far.
    pub fn updates(&self) -> u64 {
        self.updates
    }

    /// Whether the step budget is spent.
    pub fn finished(&self) -> bool {
        self.env_steps >= self.recipe.total_steps
    }

    /// The agent.
    pub fn agent(&self) -> &Agent {
        &self.agent
    }

    /// The observation normaliser.
    pub fn obs_norm(&self) -> &ObsNorm {
        &self.obs_norm
    }

    /// One observation's size.
    pub fn obs_dim(&self) -> usize {
        self.obs_dim
    }

    /// The greedy action of the current policy for one raw observation (the statistics frozen).
    ///
    /// # Errors
    /// An observation of the wrong size.
    pub fn greedy(&self, raw: &[f32]) -> Result<usize, LearnError> {
        let mut norm = self.obs_norm.clone();
        let mut x = vec![0.0; raw.len()];
        norm.apply(raw, 1, false, &mut x);
        let logits: Vec<f32> = self
            .agent
            .actor
            .forward(&Tensor::from_vec(x, (1, raw.len()), &Device::Cpu)?, true)?
            .flatten_all()?
            .to_vec1()?;
        Ok(logits.iter().enumerate().fold(0, |best, (i, &l)| if l > logits[best] { i } else { best }))
    }

    /// One update: a rollout, then the optimisation. `wall_s`: the run's wall seconds, for the row
    /// (measured by the caller; the browser has no clock here).
    ///
    /// # Errors
    /// A loss that is not finite (nothing is changed by that minibatch), an env error.
    pub fn update(&mut self, wall_s: f64) -> Result<Row, LearnError> {
        self.update_laps(wall_s, &mut NoLaps)
    }

    /// [`Learner::update`], telling `laps` where each stretch of its work ends and which [`Phase`] it was
    /// (the same work, the same result).
    ///
    /// # Errors
    /// As [`Learner::update`].
    pub fn update_laps(&mut self, wall_s: f64, laps: &mut dyn Laps) -> Result<Row, LearnError> {
        let r = self.recipe.clone();
        let (n, steps, dim) = (r.num_envs, r.num_steps, self.obs_dim);
        let lr = r.learning_rate_at(self.env_steps);
        let len = n * steps;
        let mut b_obs = vec![0.0f32; len * dim];
        let mut b_act = vec![0u32; len];
        let (mut b_logp, mut b_val, mut b_rew) = (vec![0.0f32; len], vec![0.0f32; len], vec![0.0f32; len]);
        let (mut b_done, mut b_valid) = (vec![false; len], vec![false; len]);
        let mut ends = [0u64; 3];
        let dev = &Device::Cpu;
        let mut actions = vec![0i64; n];
        laps.lap(Phase::Bookkeeping);
        // --- Rollout
        for t in 0..steps {
            let at = t * n;
            let valid: Vec<bool> = self.next_done.iter().map(|d| !d).collect();
            let x = Tensor::from_slice(&self.next_obs, (n, dim), dev)?;
            let (logits, value) = self.agent.heads(&x, true)?;
            let logits: Vec<f32> = logits.flatten_all()?.to_vec1()?;
            let value: Vec<f32> = value.to_vec1()?;
            for i in 0..n {
                let (a, logp) = sample(&logits[i * N_ACTIONS..(i + 1) * N_ACTIONS], &mut self.rng);
                actions[i] = a as i64;
                b_act[at + i] = a as u32;
                b_logp[at + i] = logp;
            }
            laps.lap(Phase::Forward);
            b_val[at..at + n].copy_from_slice(&value);
            b_obs[at * dim..(at + n) * dim].copy_from_slice(&self.next_obs);
            b_valid[at..at + n].copy_from_slice(&valid);
            laps.lap(Phase::Bookkeeping);
            self.envs.step(&actions).map_err(LearnError::env)?;
            laps.lap(Phase::Env);
            let (term, trunc) = (self.envs.terminated(), self.envs.truncated());
            let done: Vec<bool> = term.iter().zip(trunc).map(|(a, b)| a | b).collect();
            let rewards = self.envs.rewards().to_vec();
            for i in 0..n {
                if valid[i] {
                    self.env_steps += 1;
                    self.ep_return[i] += f64::from(rewards[i]);
                    self.ep_len[i] += 1;
                }
                if done[i] {
                    if self.finished.len() == RECENT_EPISODES {
                        self.finished.pop_front();
                    }
                    self.finished.push_back((self.ep_return[i], self.ep_len[i]));
                    self.episodes += 1;
                    let cause = self.envs.causes()[i];
                    ends[if !term[i] {
                        2
                    } else if cause == CAUSE_BIRD {
                        0
                    } else if cause == CAUSE_FUEL {
                        1
                    } else {
                        2
                    }] += 1;
                    self.ep_return[i] = 0.0;
                    self.ep_len[i] = 0;
                }
            }
            let scaled = self.reward.scale(r.gamma, &rewards, &valid, &done);
            b_rew[at..at + n].copy_from_slice(&scaled);
            b_done[at..at + n].copy_from_slice(&done);
            self.next_done = done;
            laps.lap(Phase::Bookkeeping);
            self.observe();
            laps.lap(Phase::ObsNorm);
        }
        // --- Advantages
        let x = Tensor::from_slice(&self.next_obs, (n, dim), dev)?;
        let next_value: Vec<f32> = self.agent.critic.forward(&x, true)?.flatten_all()?.to_vec1()?;
        let (adv, ret) = gae(n, &b_rew, &b_val, &b_done, &b_valid, &next_value, r.gamma as f32, r.gae_lambda as f32);
        laps.lap(Phase::Gae);
        let keep: Vec<usize> = (0..len).filter(|&k| b_valid[k]).collect();
        let size = keep.len();
        // --- Optimisation
        let mut sums = [0.0f64; 5]; // entropy, approx_kl, clip_frac, value_loss, policy_loss
        let mut minibatches = 0u64;
        let mut params = self.agent.params()?;
        let vars: Vec<_> = self.agent.vars().into_iter().cloned().collect();
        for _ in 0..r.update_epochs {
            let order = permutation(size, &mut self.rng);
            // torch's tensor_split: the first `size % k` minibatches one sample larger.
            let (base, extra) = (size / r.num_minibatches, size % r.num_minibatches);
            let mut start = 0;
            for m in 0..r.num_minibatches {
                let mb = base + usize::from(m < extra);
                let idx: Vec<usize> = order[start..start + mb].iter().map(|&j| keep[j]).collect();
                start += mb;
                if mb == 0 {
                    continue;
                }
                let mut obs = Vec::with_capacity(mb * dim);
                for &k in &idx {
                    obs.extend_from_slice(&b_obs[k * dim..(k + 1) * dim]);
                }
                let pick_f = |v: &[f32]| idx.iter().map(|&k| v[k]).collect::<Vec<f32>>();
                let (acts, old, a, rt) =
                    (idx.iter().map(|&k| b_act[k]).collect::<Vec<u32>>(), pick_f(&b_logp), pick_f(&adv), pick_f(&ret));
                let x = Tensor::from_vec(obs, (mb, dim), dev)?;
                laps.lap(Phase::Bookkeeping);
                let (logits, value) = self.agent.heads(&x, false)?;
                let batch = Batch { actions: &acts, old_logp: &old, advantages: &a, returns: &rt };
                let loss = ppo_loss(&logits, &value, &batch, r.clip_coef, r.ent_coef, r.vf_coef)?;
                let total: f32 = loss.total.to_scalar()?;
                if !total.is_finite() {
                    return Err(LearnError::NotFinite { loss: total, update: self.updates });
                }
                laps.lap(Phase::UpdateForward);
                let grads = loss.total.backward()?;
                laps.lap(Phase::Backward);
                let mut g: Vec<Vec<f32>> = vars
                    .iter()
                    .map(|v| match grads.get(v.as_tensor()) {
                        Some(t) => t.flatten_all()?.to_vec1(),
                        None => Ok(vec![0.0; v.elem_count()]),
                    })
                    .collect::<candle_core::Result<_>>()?;
                clip_grad_norm(&mut g, r.max_grad_norm);
                self.adam.step(&mut params, &g, lr);
                self.agent.set_params(&params)?;
                laps.lap(Phase::Optimizer);
                for (s, x) in
                    sums.iter_mut().zip([loss.entropy, loss.approx_kl, loss.clip_frac, loss.value, loss.policy])
                {
                    *s += f64::from(x);
                }
                minibatches += 1;
            }
        }
        self.updates += 1;
        let explained = explained_variance(&keep.iter().map(|&k| (ret[k], b_val[k])).collect::<Vec<_>>());
        let mean = |k: usize| sums[k] / minibatches.max(1) as f64;
        let returns = (!self.finished.is_empty()).then(|| {
            let c = self.finished.len() as f64;
            let m = self.finished.iter().map(|e| e.0).sum::<f64>() / c;
            let s = (self.finished.iter().map(|e| (e.0 - m).powi(2)).sum::<f64>() / c).sqrt();
            (m, s, self.finished.iter().map(|e| e.1 as f64).sum::<f64>() / c)
        });
        laps.lap(Phase::Bookkeeping);
        Ok(Row {
            env_steps: self.env_steps,
            wall_s,
            episodes: self.episodes,
            returns,
            learning_rate: lr,
            entropy: mean(0),
            approx_kl: mean(1),
            clip_frac: mean(2),
            explained_var: explained,
            value_loss: mean(3),
            policy_loss: mean(4),
            ends,
        })
    }

    /// The run's state, for [`Learner::from_state`].
    ///
    /// # Errors
    /// Candle's, never in practice.
    pub fn state(&self) -> Result<State, LearnError> {
        let envs = (0..self.recipe.num_envs)
            .map(|i| (hex(&self.envs.env(i).snapshot().to_bytes()), self.envs.pending_reset(i), self.envs.elapsed(i)))
            .collect();
        Ok(State {
            format: STATE_FORMAT.into(),
            recipe: self.recipe.clone(),
            params: self.agent.params()?,
            adam: self.adam.clone(),
            obs_norm: self.obs_norm.clone(),
            reward: self.reward.clone(),
            envs,
            next_obs: self.next_obs.clone(),
            ep_return: self.ep_return.clone(),
            ep_len: self.ep_len.clone(),
            finished: self.finished.iter().copied().collect(),
            episodes: self.episodes,
            env_steps: self.env_steps,
            updates: self.updates,
            rng: self.rng.state(),
            wall_s: 0.0,
        })
    }

    /// The run `state` was taken from, going on exactly as it would have; `total_steps` (when given) replaces
    /// the recipe's step budget (`--steps` on resume).
    ///
    /// # Errors
    /// A state of another format, or one that does not fit its recipe (sizes, snapshots).
    pub fn from_state(state: State) -> Result<Learner, LearnError> {
        let bad = |why: &str| LearnError::State(why.to_string());
        if state.format != STATE_FORMAT {
            return Err(bad(&format!("its format is {:?}, not {STATE_FORMAT:?}", state.format)));
        }
        let mut learner = Learner::new(state.recipe.clone())?;
        let n = learner.recipe.num_envs;
        learner.agent.set_params(&state.params).map_err(|e| bad(&e.to_string()))?;
        let sizes: Vec<usize> = state.params.iter().map(Vec::len).collect();
        let fits = |v: &Vec<Vec<f32>>| v.iter().map(Vec::len).eq(sizes.iter().copied());
        if !fits(&state.adam.m) || !fits(&state.adam.v) {
            return Err(bad("the optimiser's state does not fit the agent"));
        }
        let dim = learner.obs_dim;
        let sizes_ok = state.envs.len() == n
            && state.next_obs.len() == n * dim
            && state.ep_return.len() == n
            && state.ep_len.len() == n
            && state.reward.returns.len() == n
            && state.obs_norm.rms.mean.len() == dim
            && state.obs_norm.rms.var.len() == dim
            && state.reward.rms.mean.len() == 1
            && state.reward.rms.var.len() == 1;
        if !sizes_ok {
            return Err(bad("its sizes do not fit its recipe"));
        }
        for (i, (snap, pending, elapsed)) in state.envs.iter().enumerate() {
            let bytes = unhex(snap).ok_or_else(|| bad("an env snapshot is not hex"))?;
            let snapshot = chopperscape::Snapshot::from_bytes(&bytes).map_err(|e| bad(&e.to_string()))?;
            learner.envs.restore_env(i, &snapshot, *pending, *elapsed).map_err(|e| bad(&e.to_string()))?;
        }
        learner.next_done = state.envs.iter().map(|e| e.1).collect();
        learner.rng = Rng::from_state(state.rng).ok_or_else(|| bad("its generator state is all zeros"))?;
        learner.adam = state.adam;
        learner.obs_norm = state.obs_norm;
        learner.reward = state.reward;
        learner.next_obs = state.next_obs;
        learner.ep_return = state.ep_return;
        learner.ep_len = state.ep_len;
        learner.finished = state.finished.into_iter().rev().take(RECENT_EPISODES).rev().collect();
        learner.episodes = state.episodes;
        learner.env_steps = state.env_steps;
        learner.updates = state.updates;
        Ok(learner)
    }

    /// Changes the step budget (the learning-rate schedule follows it).
    pub fn set_total_steps(&mut self, total_steps: u64) {
        self.recipe.total_steps = total_steps;
    }
}

/// A draw from the softmax of `logits`, and its log-probability.
pub fn sample(logits: &[f32], rng: &mut Rng) -> (usize, f32) {
    let max = logits.iter().fold(f32::NEG_INFINITY, |m, &l| m.max(l));
    let exps: Vec<f64> = logits.iter().map(|&l| f64::from(l - max).exp()).collect();
    let sum: f64 = exps.iter().sum();
    let u = rng.unit() * sum;
    let mut acc = 0.0;
    let mut action = logits.len() - 1;
    for (i, e) in exps.iter().enumerate() {
        acc += e;
        if u < acc {
            action = i;
            break;
        }
    }
    (action, (f64::from(logits[action] - max) - sum.ln()) as f32)
}

/// A uniformly random permutation of `0..n` (Fisher–Yates).
pub fn permutation(n: usize, rng: &mut Rng) -> Vec<usize> {
    let mut v: Vec<usize> = (0..n).collect();
    for i in (1..n).rev() {
        let j = (rng.unit() * (i + 1) as f64) as usize;
        v.swap(i, j.min(i));
    }
    v
}

/// `1 − Var(returns − values) / Var(returns)` (unbiased variances, as torch's); NaN when the returns do not vary.
pub fn explained_variance(pairs: &[(f32, f32)]) -> f64 {
    let var = |x: &[f64]| {
        let n = x.len() as f64;
        let m = x.iter().sum::<f64>() / n;
        x.iter().map(|a| (a - m).powi(2)).sum::<f64>() / (n - 1.0)
    };
    let ret: Vec<f64> = pairs.iter().map(|p| f64::from(p.0)).collect();
    let diff: Vec<f64> = pairs.iter().map(|p| f64::from(p.0 - p.1)).collect();
    let v = var(&ret);
    if v == 0.0 || v.is_nan() { f64::NAN } else { 1.0 - var(&diff) / v }
}
