"""PPO for ChopperScape: the training recipe, in one file (CleanRL-style, PyTorch on the CPU).

Run it with ``python -m chopperscape.train --minutes 30 --out runs/ppo`` once the package and torch are installed.
It steps the native :class:`chopperscape.VectorEnv` (one Rust call per batch), normalises observations with
running statistics and rewards by the running standard deviation of the discounted return (the two things that made
the difference: see ``docs/learning.md``), and writes as it goes:

- ``OUT/progress.csv``: one row per update, columns ``env_steps,wall_s,episodes,mean_return,std_return,mean_length``
  (the last 100 finished episodes), the format ``python -m chopperscape.plot`` draws;
- ``OUT/model.pt``: the policy, its observation statistics and the options it was trained on, loadable by
  ``python -m chopperscape.evaluate OUT/model.pt``. It is saved at every checkpoint interval and at the end.

Training seeds are ``seed, seed + 1, …`` (one per env); evaluate on other seeds (``evaluate --seed 1000000``).
"""

from __future__ import annotations

import argparse
import csv
import json
import math
import os
import time
from collections import deque
from dataclasses import asdict, dataclass, field
from pathlib import Path
from typing import Any

import numpy as np

try:
    import torch
    from torch import nn
except ImportError as err:  # pragma: no cover - exercised only without torch
    raise ImportError(
        "chopperscape.train needs PyTorch: pip install torch (the CPU build is enough)"
    ) from err

from ._cli import env_options
from .vector import VectorEnv

#: Columns of the progress CSV, shared with the RLlib example and the plot script.
CSV_COLUMNS = ["env_steps", "wall_s", "episodes", "mean_return", "std_return", "mean_length"]


@dataclass
class Recipe:
    """Hyperparameters of the recipe; the defaults are the ones the README's figures come from."""

    obs_type: str = "features"
    env_options: dict[str, Any] = field(default_factory=dict)
    num_envs: int = 64
    num_steps: int = 256
    gamma: float = 0.999
    gae_lambda: float = 0.95
    learning_rate: float = 3e-4
    anneal_lr: bool = True
    update_epochs: int = 4
    num_minibatches: int = 8
    clip_coef: float = 0.2
    ent_coef: float = 0.01
    vf_coef: float = 0.5
    max_grad_norm: float = 0.5
    hidden: int = 128
    norm_obs: bool = True
    norm_reward: bool = True
    seed: int = 0
    torch_threads: int = 1
    env_threads: int = 1


class RunningMeanStd:
    """Running mean and variance (Chan et al.), as Gymnasium's and SB3's normalisers keep them."""

    def __init__(self, shape: tuple[int, ...] = ()):
        self.mean = np.zeros(shape, np.float64)
        self.var = np.ones(shape, np.float64)
        self.count = 1e-4

    def update(self, x: np.ndarray) -> None:
        batch_mean, batch_var, n = x.mean(axis=0), x.var(axis=0), x.shape[0]
        delta, total = batch_mean - self.mean, self.count + n
        self.mean = self.mean + delta * n / total
        m2 = self.var * self.count + batch_var * n + delta**2 * self.count * n / total
        self.var, self.count = m2 / total, total

    def state(self) -> dict[str, Any]:
        return {"mean": self.mean.tolist(), "var": self.var.tolist(), "count": self.count}

    @classmethod
    def from_state(cls, s: dict[str, Any]) -> RunningMeanStd:
        r = cls()
        r.mean, r.var, r.count = np.asarray(s["mean"]), np.asarray(s["var"]), float(s["count"])
        return r


class ObsNormalizer:
    """Standardises observations with running statistics, clipped to ±10 (frozen at evaluation)."""

    def __init__(self, shape: tuple[int, ...], enabled: bool = True):
        self.rms = RunningMeanStd(shape)
        self.enabled = enabled

    def __call__(self, obs: np.ndarray, update: bool = False) -> np.ndarray:
        obs = obs.astype(np.float32, copy=False)
        if not self.enabled:
            return obs
        if update:
            self.rms.update(obs)
        out = (obs - self.rms.mean) / np.sqrt(self.rms.var + 1e-8)
        return np.clip(out, -10.0, 10.0).astype(np.float32)


class Agent(nn.Module):
    """Separate actor and critic MLPs (tanh), orthogonal init as in CleanRL's PPO."""

    def __init__(self, obs_dim: int, num_actions: int, hidden: int):
        super().__init__()

        def layer(i: int, o: int, std: float = math.sqrt(2)) -> nn.Linear:
            lin = nn.Linear(i, o)
            nn.init.orthogonal_(lin.weight, std)
            nn.init.constant_(lin.bias, 0.0)
            return lin

        self.critic = nn.Sequential(
            layer(obs_dim, hidden), nn.Tanh(), layer(hidden, hidden), nn.Tanh(), layer(hidden, 1, 1.0)
        )
        self.actor = nn.Sequential(
            layer(obs_dim, hidden), nn.Tanh(), layer(hidden, hidden), nn.Tanh(), layer(hidden, num_actions, 0.01)
        )

    def value(self, x: torch.Tensor) -> torch.Tensor:
        return self.critic(x).squeeze(-1)

    def act(self, x: torch.Tensor, action: torch.Tensor | None = None):
        logits = self.actor(x)
        dist = torch.distributions.Categorical(logits=logits)
        if action is None:
            action = dist.sample()
        return action, dist.log_prob(action), dist.entropy(), self.value(x)


def save(path: Path, agent: Agent, obs_norm: ObsNormalizer, recipe: Recipe, obs_dim: int, env_steps: int) -> None:
    """Writes the policy atomically (temp file + rename): a crash never leaves a half-written model."""
    payload = {
        "format": "chopperscape-ppo/1",
        "recipe": asdict(recipe),
        "obs_dim": obs_dim,
        "num_actions": 5,
        "obs_rms": obs_norm.rms.state() if obs_norm.enabled else None,
        "env_steps": env_steps,
        "actor": {k: v.detach().clone() for k, v in agent.actor.state_dict().items()},
        "critic": {k: v.detach().clone() for k, v in agent.critic.state_dict().items()},
    }
    tmp = path.with_name(f".{path.name}.part")
    torch.save(payload, tmp)
    os.replace(tmp, path)


def train(recipe: Recipe, out: Path, minutes: float | None, total_steps: int | None) -> Path:
    """Runs PPO until `minutes` of wall time or `total_steps` env steps (whichever first); returns the model path."""
    if minutes is None and total_steps is None:
        raise ValueError("give a time budget (minutes) or a step budget (total_steps)")
    out.mkdir(parents=True, exist_ok=True)
    torch.manual_seed(recipe.seed)
    torch.set_num_threads(recipe.torch_threads)
    rng = np.random.default_rng(recipe.seed)

    envs = VectorEnv(
        recipe.num_envs, num_threads=recipe.env_threads, obs_type=recipe.obs_type, **recipe.env_options
    )
    obs_shape = envs.single_observation_space.shape
    if len(obs_shape) != 1:
        raise ValueError(f"this recipe trains an MLP on vector observations; obs_type={recipe.obs_type!r} has shape {obs_shape}")
    obs_dim = int(obs_shape[0])
    agent = Agent(obs_dim, 5, recipe.hidden)
    optimizer = torch.optim.Adam(agent.parameters(), lr=recipe.learning_rate, eps=1e-5)
    obs_norm = ObsNormalizer(obs_shape, recipe.norm_obs)
    ret_rms = RunningMeanStd(())
    disc_return = np.zeros(recipe.num_envs)

    n, t_len = recipe.num_envs, recipe.num_steps
    buf_obs = torch.zeros((t_len, n, obs_dim))
    buf_act = torch.zeros((t_len, n), dtype=torch.long)
    buf_logp = torch.zeros((t_len, n))
    buf_rew = torch.zeros((t_len, n))
    buf_done = torch.zeros((t_len, n))
    buf_val = torch.zeros((t_len, n))
    # With NEXT_STEP autoreset, the step after an episode's end is the reset step: no transition to learn from.
    buf_valid = torch.zeros((t_len, n))

    raw, _ = envs.reset(seed=recipe.seed)
    next_obs = torch.from_numpy(obs_norm(raw, update=True))
    next_done = np.zeros(n, bool)  # the previous step ended an episode: this step is a reset step
    ep_return, ep_len = np.zeros(n), np.zeros(n, np.int64)
    finished: deque[tuple[float, int]] = deque(maxlen=100)
    episodes = 0
    env_steps = 0
    start = time.monotonic()
    model_path = out / "model.pt"
    csv_path = out / "progress.csv"
    with open(out / "recipe.json", "w") as f:
        json.dump(asdict(recipe), f, indent=2)
    csv_file = open(csv_path, "w", newline="")
    writer = csv.writer(csv_file)
    writer.writerow(CSV_COLUMNS)
    update = 0
    try:
        while True:
            elapsed = time.monotonic() - start
            if minutes is not None and elapsed >= minutes * 60:
                break
            if total_steps is not None and env_steps >= total_steps:
                break
            if recipe.anneal_lr:
                frac = max(
                    0.0,
                    1.0
                    - max(
                        elapsed / (minutes * 60) if minutes is not None else 0.0,
                        env_steps / total_steps if total_steps is not None else 0.0,
                    ),
                )
                optimizer.param_groups[0]["lr"] = recipe.learning_rate * max(frac, 0.05)
            for t in range(t_len):
                valid = ~next_done
                with torch.no_grad():
                    action, logp, _, value = agent.act(next_obs)
                buf_obs[t], buf_act[t], buf_logp[t], buf_val[t] = next_obs, action, logp, value
                buf_valid[t] = torch.from_numpy(valid.astype(np.float32))
                raw, reward, term, trunc, _ = envs.step(action.numpy())
                env_steps += int(valid.sum())
                done = term | trunc
                # Episode statistics, on real (not reset) steps.
                ep_return += np.where(valid, reward, 0)
                ep_len += valid
                for i in np.flatnonzero(done):
                    finished.append((float(ep_return[i]), int(ep_len[i])))
                    episodes += 1
                ep_return[done], ep_len[done] = 0, 0
                # Reward scaling by the std of the discounted return (Gymnasium's NormalizeReward).
                r = reward.astype(np.float64)
                if recipe.norm_reward:
                    disc_return = np.where(valid, disc_return * recipe.gamma + r, 0.0)
                    if valid.any():
                        ret_rms.update(disc_return[valid])
                    r = r / math.sqrt(ret_rms.var + 1e-8)
                    disc_return[done] = 0.0
                buf_rew[t] = torch.from_numpy(np.where(valid, r, 0.0).astype(np.float32))
                # Truncation is treated as termination (10,000 steps is ten horizons of γ = 0.999).
                buf_done[t] = torch.from_numpy(done.astype(np.float32))
                next_done = done
                next_obs = torch.from_numpy(obs_norm(raw, update=True))
            # GAE over valid steps; a reset step neither bootstraps nor is learned from.
            with torch.no_grad():
                next_value = agent.value(next_obs)
                adv = torch.zeros((t_len, n))
                last = torch.zeros(n)
                for t in reversed(range(t_len)):
                    nv = next_value if t == t_len - 1 else buf_val[t + 1]
                    nonterminal = 1.0 - buf_done[t]
                    delta = buf_rew[t] + recipe.gamma * nv * nonterminal - buf_val[t]
                    last = delta + recipe.gamma * recipe.gae_lambda * nonterminal * last
                    # The row after an episode's end is its reset step: it carries nothing across.
                    last = last * buf_valid[t]
                    adv[t] = last
                returns = adv + buf_val
            mask = buf_valid.reshape(-1).bool()
            b_obs = buf_obs.reshape(-1, obs_dim)[mask]
            b_act, b_logp = buf_act.reshape(-1)[mask], buf_logp.reshape(-1)[mask]
            b_adv, b_ret = adv.reshape(-1)[mask], returns.reshape(-1)[mask]
            size = b_obs.shape[0]
            for _ in range(recipe.update_epochs):
                # Even minibatches (no tiny remainder, whose advantage std would be undefined).
                for idx in torch.from_numpy(rng.permutation(size)).tensor_split(recipe.num_minibatches):
                    _, logp, entropy, value = agent.act(b_obs[idx], b_act[idx])
                    ratio = (logp - b_logp[idx]).exp()
                    a = b_adv[idx]
                    a = (a - a.mean()) / (a.std() + 1e-8)
                    pg = torch.max(-a * ratio, -a * ratio.clamp(1 - recipe.clip_coef, 1 + recipe.clip_coef)).mean()
                    v_loss = 0.5 * ((value - b_ret[idx]) ** 2).mean()
                    loss = pg - recipe.ent_coef * entropy.mean() + recipe.vf_coef * v_loss
                    optimizer.zero_grad()
                    loss.backward()
                    nn.utils.clip_grad_norm_(agent.parameters(), recipe.max_grad_norm)
                    optimizer.step()
                    if not torch.isfinite(loss):
                        raise FloatingPointError(f"loss became {loss.item()} at update {update}")
            update += 1
            if finished:
                rets = np.array([r for r, _ in finished])
                lens = np.array([l for _, l in finished])
                writer.writerow(
                    [env_steps, f"{time.monotonic() - start:.1f}", episodes, f"{rets.mean():.1f}", f"{rets.std():.1f}",
                     f"{lens.mean():.1f}"]
                )
                csv_file.flush()
            if update % 50 == 0:
                save(model_path, agent, obs_norm, recipe, obs_dim, env_steps)
    finally:
        csv_file.close()
        envs.close()
    save(model_path, agent, obs_norm, recipe, obs_dim, env_steps)
    return model_path


def main(argv: list[str] | None = None) -> None:
    p = argparse.ArgumentParser(prog="python -m chopperscape.train", description=__doc__.splitlines()[0])
    p.add_argument("--out", type=Path, required=True, help="folder for progress.csv, model.pt, recipe.json")
    p.add_argument("--minutes", type=float, default=None, help="wall-clock budget (default 30 if no --steps)")
    p.add_argument("--steps", type=int, default=None, help="env-step budget")
    p.add_argument("--option", action="append", default=[], metavar="NAME=VALUE",
                   help="an env option, e.g. --option frame_skip=4 (JSON values)")
    defaults = Recipe()
    for f in ("obs_type", "num_envs", "num_steps", "gamma", "gae_lambda", "learning_rate", "update_epochs",
              "num_minibatches", "clip_coef", "ent_coef", "vf_coef", "max_grad_norm", "hidden", "seed",
              "torch_threads", "env_threads"):
        p.add_argument(f"--{f.replace('_', '-')}", type=type(getattr(defaults, f)), default=getattr(defaults, f))
    p.add_argument("--no-norm-obs", action="store_true")
    p.add_argument("--no-norm-reward", action="store_true")
    a = p.parse_args(argv)
    options = env_options(p, a.option)
    recipe = Recipe(
        **{k: getattr(a, k) for k in ("obs_type", "num_envs", "num_steps", "gamma", "gae_lambda", "learning_rate",
                                      "update_epochs", "num_minibatches", "clip_coef", "ent_coef", "vf_coef",
                                      "max_grad_norm", "hidden", "seed", "torch_threads", "env_threads")},
        env_options=options, norm_obs=not a.no_norm_obs, norm_reward=not a.no_norm_reward,
    )
    minutes = a.minutes if (a.minutes is not None or a.steps is not None) else 30.0
    path = train(recipe, a.out, minutes, a.steps)
    print(json.dumps({"model": str(path), "progress": str(a.out / "progress.csv")}))


if __name__ == "__main__":
    main()
