#!/usr/bin/env python3
"""Can the pixel recipe's CNN express a policy that depends on the frames? Behaviour cloning of the heuristic from
84×84×4 grayscale frames (frame skip 4, the pixel preset's observation), then greedy play on held-out seeds.

    python python/examples/bc_pixels.py --samples 40000 --epochs 4 --eval-episodes 50

A perception check for docs/learning.md ("the budget is not what is missing"): PPO on frames settles on a constant
action; if the same `CnnAgent` cloned from the heuristic flies better than any constant action (at most 703 on the
held-out seeds), the network can read what the policy needs from the frames and the fault is in PPO's signal.
The last line printed is a JSON summary.
"""

from __future__ import annotations

import argparse
import json
import time

import numpy as np


def collect(samples: int, num_envs: int, seed: int, options: dict) -> tuple[np.ndarray, np.ndarray]:
    from chopperscape import VectorEnv
    from chopperscape.policies import VectorPolicy

    envs = VectorEnv(num_envs, num_threads=1, max_episode_steps=10_000, **options)
    policy = VectorPolicy("heuristic", num_envs, seed=seed)
    obs, _ = envs.reset(seed=seed)
    xs, ys = [], []
    total = 0
    while total < samples:
        actions = np.asarray(policy.act(envs), dtype=np.int64)
        xs.append(obs.copy())
        ys.append(actions)
        total += len(actions)
        obs, *_ = envs.step(actions)
    envs.close()
    return np.concatenate(xs)[:samples], np.concatenate(ys)[:samples]


def main() -> None:
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("--samples", type=int, default=40_000, help="heuristic decisions to clone (default 40000)")
    p.add_argument("--epochs", type=int, default=4)
    p.add_argument("--eval-episodes", type=int, default=50)
    p.add_argument("--eval-seed", type=int, default=1_000_000)
    p.add_argument("--seed", type=int, default=0)
    a = p.parse_args()
    import torch

    from chopperscape.learn import evaluate, model
    from chopperscape.learn.recipe import PRESETS, Recipe

    torch.manual_seed(a.seed)
    torch.set_num_threads(1)
    pixels = PRESETS["pixels"]  # the observation the pixel recipe learns from
    options = {"obs_type": pixels["obs_type"], **pixels["env_options"]}
    t0 = time.monotonic()
    x, y = collect(a.samples, 32, a.seed, options)
    agent = model.build_agent(pixels["network"], tuple(x.shape[1:]), invert_frames=Recipe().invert_frames)
    opt = torch.optim.Adam(agent.parameters(), lr=3e-4)
    xt, yt = torch.from_numpy(x), torch.from_numpy(y)
    split = int(0.9 * len(x))  # the last 10 % (the latest decisions of each env) held out for accuracy
    losses = []
    for _ in range(a.epochs):
        for idx in torch.randperm(split).split(256):
            loss = torch.nn.functional.cross_entropy(agent.actor(xt[idx]), yt[idx])
            opt.zero_grad()
            loss.backward()
            opt.step()
            losses.append(loss.item())
    with torch.no_grad():
        pred = torch.cat([agent.actor(xt[i : i + 1024]).argmax(-1) for i in range(split, len(x), 1024)])
    accuracy = float((pred == yt[split:]).float().mean())
    majority = float(np.bincount(y[split:], minlength=5).max() / len(y[split:]))

    def act(obs: np.ndarray, _envs) -> np.ndarray:
        with torch.no_grad():
            return agent.actor(torch.from_numpy(obs)).argmax(-1).numpy()

    results = evaluate.play_episodes(act, a.eval_episodes, a.eval_seed, options)
    out = {
        "samples": a.samples,
        "epochs": a.epochs,
        "final_loss": round(float(np.mean(losses[-20:])), 4),
        "held_out_accuracy": round(accuracy, 3),
        "majority_action_share": round(majority, 3),
        "wall_s": round(time.monotonic() - t0, 1),
        **evaluate.summary(results),
    }
    print(json.dumps(out))


if __name__ == "__main__":
    main()
