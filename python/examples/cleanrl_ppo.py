"""A CleanRL-style PPO in one file, standing for an agent trained outside this package: plain Gymnasium, plain torch,
and its policy saved as plain weights (a `state_dict` of tensors) that `cleanrl_policy:policy` plays in the
bench. The walk from this script to a leaderboard row: docs/site/bench.md, "Adding a row".

    python python/examples/cleanrl_ppo.py --mode sticky-v0 --seed 0 --steps 500000 --out runs/cleanrl/seed-0

It trains on the mode's rules (`gym.make(ID)` of the mode's Gymnasium id, features), resets its `--envs` games on
`seed … seed + envs − 1` (below the evaluation seeds, 1,000,000 on), and writes `OUT/weights.pt` (the actor's
weights, read with `torch.load(weights_only=True)`) and `OUT/train.json` (its settings and training seeds, which
`bench evaluate --train-seeds` declares). It prints one JSON line. Not tuned: an example of joining, not a recipe.
"""

from __future__ import annotations

import argparse
import json
import time
from pathlib import Path

import gymnasium as gym
import numpy as np
import torch
from torch import nn

import chopperscape  # registers the ChopperScape ids


def actor(obs_dim: int, n_actions: int, hidden: int = 64) -> nn.Sequential:
    """The policy network (the layout `cleanrl_policy.py` rebuilds from the saved weights)."""
    return nn.Sequential(
        nn.Linear(obs_dim, hidden), nn.Tanh(), nn.Linear(hidden, hidden), nn.Tanh(), nn.Linear(hidden, n_actions)
    )


def main(argv: list[str] | None = None) -> dict:
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("--mode", default="sticky-v0")
    p.add_argument("--seed", type=int, default=0)
    p.add_argument("--steps", type=int, default=500_000, help="decisions, all games together")
    p.add_argument("--envs", type=int, default=8)
    p.add_argument("--num-steps", type=int, default=128)
    p.add_argument("--hidden", type=int, default=64)
    p.add_argument("--lr", type=float, default=2.5e-4)
    p.add_argument("--gamma", type=float, default=0.99)
    p.add_argument("--out", required=True)
    a = p.parse_args(argv)
    if not 0 <= a.seed and a.seed + a.envs <= 1_000_000:
        p.error("--seed: train below the evaluation seeds (seed + envs <= 1,000,000)")
    torch.manual_seed(a.seed)
    torch.set_num_threads(1)  # a tiny network: one thread is the fastest
    env_id = next(m["id"] for m in chopperscape.MODES if m["name"] == a.mode)
    envs = gym.vector.SyncVectorEnv(
        [lambda: gym.make(env_id, obs_type="features") for _ in range(a.envs)],
        autoreset_mode=gym.vector.AutoresetMode.SAME_STEP,
    )
    obs_dim, n_actions = int(np.prod(envs.single_observation_space.shape)), int(envs.single_action_space.n)
    pi, value = actor(obs_dim, n_actions, a.hidden), actor(obs_dim, 1, a.hidden)
    opt = torch.optim.Adam([*pi.parameters(), *value.parameters()], lr=a.lr, eps=1e-5)
    obs, _ = envs.reset(seed=a.seed)
    done_returns, running = [], np.zeros(a.envs)
    steps, start = 0, time.time()
    while steps < a.steps:
        buf: dict[str, list] = {k: [] for k in ("obs", "act", "logp", "rew", "done", "val")}
        for _ in range(a.num_steps):
            o = torch.as_tensor(obs, dtype=torch.float32).reshape(a.envs, -1)
            with torch.no_grad():
                dist = torch.distributions.Categorical(logits=pi(o))
                act = dist.sample()
                buf["val"].append(value(o).squeeze(-1))
            obs, rew, term, trunc, _ = envs.step(act.numpy())
            running += rew
            for i in np.flatnonzero(term | trunc):
                done_returns.append(float(running[i]))
                running[i] = 0
            for k, v in (("obs", o), ("act", act), ("logp", dist.log_prob(act)), ("rew", rew), ("done", term)):
                buf[k].append(torch.as_tensor(v, dtype=torch.float32) if k in ("rew", "done") else v)
            steps += a.envs
        with torch.no_grad():
            nxt = value(torch.as_tensor(obs, dtype=torch.float32).reshape(a.envs, -1)).squeeze(-1)
        ret, returns = nxt, []
        for r, d in zip(reversed(buf["rew"]), reversed(buf["done"])):
            ret = r / 100 + a.gamma * ret * (1 - d)  # rewards scaled: +1 a step adds up
            returns.append(ret)
        returns = torch.stack(returns[::-1]).flatten()
        o, act, logp = torch.cat(buf["obs"]), torch.cat(buf["act"]), torch.cat(buf["logp"])
        adv = returns - torch.stack(buf["val"]).flatten()
        adv = (adv - adv.mean()) / (adv.std() + 1e-8)
        for _ in range(4):
            dist = torch.distributions.Categorical(logits=pi(o))
            ratio = (dist.log_prob(act) - logp).exp()
            loss_pi = -torch.min(ratio * adv, ratio.clamp(0.8, 1.2) * adv).mean() - 0.01 * dist.entropy().mean()
            loss_v = (value(o).squeeze(-1) - returns).pow(2).mean()
            opt.zero_grad()
            (loss_pi + 0.5 * loss_v).backward()
            nn.utils.clip_grad_norm_([*pi.parameters(), *value.parameters()], 0.5)
            opt.step()
    out = Path(a.out)
    out.mkdir(parents=True, exist_ok=True)
    torch.save(pi.state_dict(), out / "weights.pt")
    summary = {
        "mode": a.mode,
        "steps": steps,
        "train_seeds": [a.seed, a.envs],
        "settings": {k: v for k, v in vars(a).items() if k != "out"},
        "mean_return_last_20": float(np.mean(done_returns[-20:])) if done_returns else None,
        "seconds": round(time.time() - start, 1),
    }
    (out / "train.json").write_text(json.dumps(summary, indent=2) + "\n")
    print(json.dumps(summary))
    return summary


if __name__ == "__main__":
    main()
