"""Throughput of the PPO recipe's whole training loop, per network and frame size (a benchmark, not a test).

    .venv/bin/python python/bench_train.py [--steps 8192] [--case small-84 ...] [--device cpu]

For each case it runs ``chopperscape.learn.train`` (the pixel preset's settings: 32 envs × 128 steps, 4 epochs of 4
minibatches, frame skip 4, 4 stacked frames; the features case uses the features recipe) for ``--steps`` env steps
and prints env steps (decisions) per second of wall time and per CPU second of this process, and where the CPU time
goes: the env alone (rendering included), the network's forward passes in the rollout, and one optimisation epoch's
forward + backward + Adam, each timed on its own. On a shared machine the CPU-second figure is the steadier one; with
one torch thread it estimates one idle core.
"""

from __future__ import annotations

import argparse
import os
import platform
import sys
import tempfile
import time
from pathlib import Path

# This file sits beside the package's sources, which lack the compiled `_core`: import the installed package.
sys.path = [p for p in sys.path if os.path.abspath(p or ".") != os.path.dirname(os.path.abspath(__file__))]

import numpy as np  # noqa: E402
import torch  # noqa: E402

from chopperscape import VectorEnv  # noqa: E402
from chopperscape.learn import model, train  # noqa: E402
from chopperscape.learn.recipe import PRESETS, Recipe, network_of  # noqa: E402

PIXELS = PRESETS["pixels"]
CASES = {
    "features-mlp": dict(obs_type="features", network="mlp", env_options={}),
    "nature-84": dict(network="nature", env_options={**PIXELS["env_options"], "obs_size": [84, 84]}),
    "small-84": dict(network="small", env_options={**PIXELS["env_options"], "obs_size": [84, 84]}),
    "small-42": dict(network="small", env_options={**PIXELS["env_options"], "obs_size": [42, 42]}),
}


def recipe_for(case: str, steps: int, device: str) -> Recipe:
    settings = {k: v for k, v in PIXELS.items() if k != "env_options"} if case != "features-mlp" else {}
    return Recipe(**{**settings, **CASES[case]}, total_steps=steps, device=device)


def parts(recipe: Recipe, repeats: int = 3) -> dict[str, float]:
    """CPU seconds per env step of the loop's parts, each measured alone."""
    n = recipe.num_envs
    envs = VectorEnv(n, num_threads=1, obs_type=recipe.obs_type, **recipe.env_options)
    obs, _ = envs.reset(seed=0)
    actions = np.zeros(n, np.int64)
    t = time.process_time()
    for _ in range(repeats * 20):
        obs, *_ = envs.step(actions)
    env = (time.process_time() - t) / (repeats * 20 * n)
    shape = tuple(envs.single_observation_space.shape)
    agent = model.build_agent(network_of(recipe), shape, invert_frames=recipe.invert_frames).to(recipe.device)
    envs.close()
    x = torch.from_numpy(np.ascontiguousarray(obs)).to(recipe.device)
    if recipe.obs_type == "features":
        x = x.float()
    with torch.no_grad():
        agent.act(x)
        t = time.process_time()
        for _ in range(repeats * 10):
            agent.act(x)
        forward = (time.process_time() - t) / (repeats * 10 * n)
    batch = n * recipe.num_steps // recipe.num_minibatches
    xb = x[torch.randint(0, n, (batch,))]
    opt = torch.optim.Adam(agent.parameters(), lr=1e-4)
    t = time.process_time()
    for _ in range(repeats):
        _, logp, ent, value = agent.act(xb, torch.zeros(batch, dtype=torch.long, device=recipe.device))
        loss = -logp.mean() - 0.01 * ent.mean() + value.pow(2).mean()
        opt.zero_grad()
        loss.backward()
        opt.step()
    per_sample = (time.process_time() - t) / (repeats * batch)
    return {"env": env, "forward": forward, "update": per_sample * recipe.update_epochs}


def main() -> None:
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("--steps", type=int, default=8192, help="env steps per case (default 8192)")
    p.add_argument("--case", action="append", choices=sorted(CASES), help="cases to run (default all)")
    p.add_argument("--device", default="cpu", help="cpu or cuda")
    a = p.parse_args()
    torch.set_num_threads(1)
    print(
        f"# {platform.machine()}, {os.cpu_count()} CPUs, torch {torch.__version__}, device {a.device}, "
        f"load average {os.getloadavg()[0]:.1f}"
    )
    print(f"{'case':<14} {'steps/s wall':>12} {'steps/s CPU':>12} {'env µs':>8} {'forward µs':>10} {'update µs':>10}")
    for case in a.case or list(CASES):
        recipe = recipe_for(case, a.steps, a.device)
        with tempfile.TemporaryDirectory() as out:
            wall, cpu = time.perf_counter(), time.process_time()
            train.train(recipe, Path(out))
            wall, cpu = time.perf_counter() - wall, time.process_time() - cpu
            last = (Path(out) / "progress.csv").read_text().splitlines()[-1]
        steps = int(last.split(",")[0])
        split = parts(recipe)
        print(
            f"{case:<14} {steps / wall:>12,.0f} {steps / cpu:>12,.0f} {split['env'] * 1e6:>8.1f} "
            f"{split['forward'] * 1e6:>10.1f} {split['update'] * 1e6:>10.1f}"
        )


if __name__ == "__main__":
    main()
