"""One update's experience: the rollout's buffers (:class:`Rollout`), its advantages and returns by GAE
(:func:`advantages`) flattened into the update's :class:`Batch`, and the episodes the run has finished
(:class:`Episodes`).

The envs step in NEXT_STEP autoreset mode: the step after an episode's end is its reset step, which carries no
transition. Such a step is stored with ``valid = 0``: it neither bootstraps nor is learned from, and the batch
leaves it out.
"""

from __future__ import annotations

from collections import deque
from collections.abc import Iterator
from typing import Any, NamedTuple

import numpy as np
import torch


class Rollout:
    """The buffers of `t_len` steps of `num_envs` envs: observations (as the network takes them: uint8 frames or
    float features), actions, their log-probabilities, values, rewards (scaled), ends and validity."""

    def __init__(self, t_len: int, num_envs: int, obs_shape: tuple[int, ...], obs_dtype: torch.dtype, device):
        shape = (t_len, num_envs)
        self.obs = torch.zeros((*shape, *obs_shape), dtype=obs_dtype, device=device)
        self.actions = torch.zeros(shape, dtype=torch.long, device=device)
        self.logp, self.rewards, self.dones, self.values = (torch.zeros(shape, device=device) for _ in range(4))
        self.valid = torch.zeros(shape, device=device)
        self.obs_shape, self.device = obs_shape, device

    def store(self, t: int, obs, action, logp, value, valid: np.ndarray) -> None:
        """Step `t`'s observation and what the policy did there; `valid` is False on reset steps."""
        self.obs[t], self.actions[t], self.logp[t], self.values[t] = obs, action, logp, value
        self.valid[t] = torch.from_numpy(valid.astype(np.float32)).to(self.device)

    def outcome(self, t: int, reward: np.ndarray, done: np.ndarray) -> None:
        """Step `t`'s (scaled) reward and whether it ended its episode (truncation is treated as termination:
        10,000 steps is ten horizons of γ = 0.999)."""
        self.rewards[t] = torch.from_numpy(reward).to(self.device)
        self.dones[t] = torch.from_numpy(done.astype(np.float32)).to(self.device)

    @staticmethod
    def bytes_per_step(obs_shape: tuple[int, ...], pixels: bool, extra_floats: int = 0) -> int:
        """Memory one stored env step takes: its observation twice (the buffer and the update's batch) and seven
        numbers, plus `extra_floats` that a part stores beside it."""
        return 2 * int(np.prod(obs_shape)) * (1 if pixels else 4) + 4 * (extra_floats + 7)


class Batch(NamedTuple):
    """An update's valid steps, flattened: observations, actions, old log-probabilities, advantages, returns and old
    values; `mask` picks them out of the rollout's `t_len × num_envs` steps."""

    obs: torch.Tensor
    actions: torch.Tensor
    logp: torch.Tensor
    advantages: torch.Tensor
    returns: torch.Tensor
    values: torch.Tensor
    mask: torch.Tensor

    def minibatches(self, rng: np.random.Generator, count: int) -> Iterator[torch.Tensor]:
        """One epoch's minibatch indices: a permutation drawn from `rng`, split into `count` even parts (no tiny
        remainder, whose advantage std would be undefined)."""
        size = int(self.obs.shape[0])
        return iter(torch.from_numpy(rng.permutation(size)).to(self.obs.device).tensor_split(count))

    def explained_variance(self) -> float:
        """How much of the returns' variance the old values explain (NaN when the returns do not vary)."""
        var = self.returns.var().item()
        return float("nan") if var == 0 else 1 - (self.returns - self.values).var().item() / var


@torch.no_grad()
def advantages(buf: Rollout, agent: Any, next_obs: torch.Tensor, gamma: float, gae_lambda: float) -> Batch:
    """GAE(λ) over the rollout, bootstrapped from `agent`'s value of `next_obs` (the observation after its last
    step); a reset step neither bootstraps nor is learned from. Returns the update's batch of valid steps."""
    next_value = agent.value(next_obs)
    t_len, n = buf.rewards.shape
    adv = torch.zeros((t_len, n), device=buf.device)
    last = torch.zeros(n, device=buf.device)
    for t in reversed(range(t_len)):
        nv = next_value if t == t_len - 1 else buf.values[t + 1]
        nonterminal = 1.0 - buf.dones[t]
        delta = buf.rewards[t] + gamma * nv * nonterminal - buf.values[t]
        last = delta + gamma * gae_lambda * nonterminal * last
        # The row after an episode's end is its reset step: it carries nothing across.
        last = last * buf.valid[t]
        adv[t] = last
    returns = adv + buf.values
    mask = buf.valid.reshape(-1).bool()
    return Batch(
        obs=buf.obs.reshape(-1, *buf.obs_shape)[mask],
        actions=buf.actions.reshape(-1)[mask],
        logp=buf.logp.reshape(-1)[mask],
        advantages=adv.reshape(-1)[mask],
        returns=returns.reshape(-1)[mask],
        values=buf.values.reshape(-1)[mask],
        mask=mask,
    )


#: How an episode can end, as the progress CSV counts them: a bird, the fuel, or the 10,000-step limit.
ENDS = ("bird", "fuel", "limit")


class Episodes:
    """The run's episodes: each env's running return and length, the last 100 finished `(return, length)`, how
    many have finished, and how those of the current update ended (`ends`, reset by :meth:`new_update`)."""

    def __init__(self, num_envs: int):
        self.returns, self.lengths = np.zeros(num_envs), np.zeros(num_envs, np.int64)
        self.finished: deque[tuple[float, int]] = deque(maxlen=100)
        self.count = 0
        self.ends = dict.fromkeys(ENDS, 0)

    def new_update(self) -> None:
        self.ends = dict.fromkeys(ENDS, 0)

    def record(self, reward: np.ndarray, valid: np.ndarray, term: np.ndarray, trunc: np.ndarray, info: dict) -> None:
        """One env step's rewards and ends, counted on real (not reset) steps."""
        done = term | trunc
        self.returns += np.where(valid, reward, 0)
        self.lengths += valid
        for i in np.flatnonzero(done):
            self.finished.append((float(self.returns[i]), int(self.lengths[i])))
            self.count += 1
            self.ends[str(info["cause"][i]) if term[i] else "limit"] += 1
        self.returns[done], self.lengths[done] = 0, 0

    def columns(self) -> dict[str, Any]:
        """The progress row's episode columns: the count, the last 100's return and length (empty until one has
        ended), and the update's ends as shares (empty when none ended)."""
        ended = sum(self.ends.values())
        row: dict[str, Any] = {"episodes": self.count, "ended": ended}
        if self.finished:
            rets = np.array([r for r, _ in self.finished])
            lens = np.array([k for _, k in self.finished])
            row.update(
                mean_return=f"{rets.mean():.1f}", std_return=f"{rets.std():.1f}", mean_length=f"{lens.mean():.1f}"
            )
        if ended:
            row.update({k: f"{self.ends[k] / ended:.3f}" for k in ENDS})
        return row

    def state_dict(self) -> dict[str, Any]:
        return {
            "returns": torch.from_numpy(self.returns.copy()),
            "lengths": torch.from_numpy(self.lengths.copy()),
            "finished": [[r, k] for r, k in self.finished],
            "count": self.count,
        }

    def load_state_dict(self, s: dict[str, Any]) -> None:
        returns, lengths = s["returns"].numpy().copy(), s["lengths"].numpy().astype(np.int64)
        if returns.shape != self.returns.shape or lengths.shape != self.lengths.shape:
            raise ValueError(f"episode counters of {returns.shape} envs, where the run has {self.returns.shape}")
        self.returns, self.lengths = returns, lengths
        self.finished.clear()
        self.finished.extend((float(r), int(k)) for r, k in s["finished"])
        self.count = int(s["count"])
