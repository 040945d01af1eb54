#!/usr/bin/env python3
"""Does a trained pixel policy's trunk carry the fuel? A linear probe on its activations.

    python python/examples/trunk_probe.py runs/pixels/model.pt [--init] [--samples 20000] [--held-out 10000]

The model plays greedily (its own states, the ones its decisions depend on) on `--envs` pixel envs, each beside a
features twin env reset with the same seed and stepped with the same actions (determinism keeps the two in one
state; their rewards and ends are checked every step). At each decision the trunk's embedding (what the actor and
critic heads read: `agent.heads(frames)[2]`) is kept with the game's features of the same state. A ridge regression
from the embedding to each value is fitted on the training decisions (seeds 0..) and scored by R² on the held-out
ones (seeds 1,000,000..): `fuel`, `chopper_y`, and the soonest bird's and nearest tank's dx and dy (where that slot is
filled). R² near 1: the value is a linear read-out of the trunk; near 0: the trunk does not carry it. `--init` adds
the same probe on the same network at its initialisation (the recipe's seed), on the same states: what the
architecture carries before any learning. Nothing privileged reaches the policy: the features are read here only.

One JSON line per network (`trained`, `init`) with each value's R² and the sample counts; `--out FILE` appends the
rows to a CSV. One torch thread by default (`--threads`); the same arguments give the same numbers.
"""

from __future__ import annotations

import argparse
import csv
import json
import os
import sys
from pathlib import Path
from typing import Any

# This file sits beside the package's sources, which lack the compiled `_core`: import the installed package.
sys.path = [p for p in sys.path if os.path.abspath(p or ".") != os.path.dirname(os.path.abspath(__file__))]

import numpy as np  # noqa: E402

#: The first held-out seed (the evaluation protocol's).
HELD_OUT_SEED = 1_000_000
#: Probed values: (name, feature index, index of the presence flag that must be 1, or None). The features layout:
#: crates/core/src/features.rs (the same table as python/examples/perception.py's).
PROBED = [
    ("fuel", 2, None),
    ("chopper_y", 1, None),
    ("bird0_dx", 5, 4),
    ("bird0_dy", 6, 4),
    ("tank0_dx", 21, 20),
    ("tank0_dy", 22, 20),
]


def collect(model: Any, samples: int, num_envs: int, seed: int, networks: dict[str, Any]) -> dict[str, np.ndarray]:
    """`samples` decisions of `model` playing greedily from seeds `seed + i`: each network's embeddings of the
    frames (by name), the features of the same states and whether each decision ended its episode (`ended`); rows
    in step order, `num_envs` a step."""
    import torch
    from gymnasium.vector import AutoresetMode

    from chopperscape import VectorEnv
    from chopperscape.options import RULE_OPTIONS

    options = dict(model.recipe["env_options"])
    rules = {k: v for k, v in options.items() if k in RULE_OPTIONS}
    kw: dict[str, Any] = dict(num_threads=1, autoreset_mode=AutoresetMode.SAME_STEP)  # every observation a decision
    pixels = VectorEnv(num_envs, **kw, obs_type=model.recipe["obs_type"], **options)
    twin = VectorEnv(num_envs, **kw, **rules, obs_type="features")
    obs, _ = pixels.reset(seed=seed)
    feats, _ = twin.reset(seed=seed)
    kept: dict[str, list[np.ndarray]] = {name: [] for name in networks}
    features: list[np.ndarray] = []
    ended: list[np.ndarray] = []
    try:
        while sum(len(f) for f in features) < samples:
            x = torch.from_numpy(obs.reshape(num_envs, *model.obs_shape))
            with torch.inference_mode():
                for name, agent in networks.items():
                    logits, _, h = agent.heads(x)
                    kept[name].append(h.numpy().copy())
                    if name == "trained":
                        actions = logits.argmax(-1).numpy().astype(np.int64)
            features.append(feats.copy())
            obs, r, term, trunc, _ = pixels.step(actions)
            feats, r2, term2, trunc2, _ = twin.step(actions)
            if not (np.array_equal(r, r2) and np.array_equal(term, term2) and np.array_equal(trunc, trunc2)):
                raise RuntimeError("the pixel env and its features twin parted")
            ended.append(term | trunc)
    finally:
        pixels.close()
        twin.close()
    out = {name: np.concatenate(v)[:samples] for name, v in kept.items()}
    out["features"] = np.concatenate(features)[:samples]
    out["ended"] = np.concatenate(ended)[:samples]  # whether the decision taken in that state ended its episode
    return out


#: The ridge penalties tried; the one that scores best on the last quarter of the training decisions is kept.
ALPHAS = (0.1, 1.0, 10.0, 100.0, 1000.0, 10000.0)


def _ridge(h: np.ndarray, y: np.ndarray, h_test: np.ndarray, y_test: np.ndarray, alpha: float) -> float:
    """R² on the test set of a ridge regression (standardised inputs, penalty `alpha`) fitted on the training set."""
    mean, std = h.mean(0), h.std(0) + 1e-6
    a = np.hstack([(h - mean) / std, np.ones((len(h), 1))])
    b = np.hstack([(h_test - mean) / std, np.ones((len(h_test), 1))])
    penalty = alpha * np.eye(a.shape[1])
    penalty[-1, -1] = 0.0
    w = np.linalg.solve(a.T @ a + penalty, a.T @ (y - y.mean()))
    var = float(np.var(y_test))
    return float("nan") if var == 0 else 1.0 - float(np.mean((b @ w + y.mean() - y_test) ** 2)) / var


def ridge_r2(h: np.ndarray, y: np.ndarray, h_test: np.ndarray, y_test: np.ndarray) -> float:
    """The held-out R² of a ridge regression from `h` to `y`, its penalty chosen on the training decisions alone
    (fitted on their first three quarters, scored on the last)."""
    cut = len(h) * 3 // 4
    alpha = max(ALPHAS, key=lambda al: np.nan_to_num(_ridge(h[:cut], y[:cut], h[cut:], y[cut:], al), nan=-np.inf))
    return _ridge(h, y, h_test, y_test, alpha)


def main(argv: list[str] | None = None) -> int:
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("model", type=Path, help="a pixel model.pt from python -m chopperscape.learn.train")
    p.add_argument("--samples", type=int, default=20_000, help="training decisions (default 20,000)")
    p.add_argument("--held-out", type=int, default=10_000, help="held-out decisions (default 10,000)")
    p.add_argument("--envs", type=int, default=32, help="envs played at once (default 32)")
    p.add_argument("--init", action="store_true", help="also probe the same network at its initialisation")
    p.add_argument("--threads", type=int, default=1, help="torch threads (default 1)")
    p.add_argument("--out", type=Path, help="append the rows to this CSV")
    a = p.parse_args(argv)
    import torch

    from chopperscape import NUM_ACTIONS
    from chopperscape.learn import modelfile, networks
    from chopperscape.learn.recipe import network_of

    torch.set_num_threads(a.threads)
    model = modelfile.load(a.model)
    if model.recipe["obs_type"] == "features":
        p.error(f"{a.model} is a features model: the probe reads a CNN's trunk")
    nets: dict[str, Any] = {"trained": model.agent}
    if a.init:
        torch.manual_seed(int(model.recipe.get("seed", 0)))
        invert = model.recipe.get("invert_frames", False) is True
        nets["init"] = networks.build_agent(network_of(model.recipe), model.obs_shape, NUM_ACTIONS, 128, invert).eval()
    train = collect(model, a.samples, a.envs, 0, nets)
    held = collect(model, a.held_out, a.envs, HELD_OUT_SEED, nets)
    rows = []
    for name in nets:
        row: dict[str, Any] = {"model": str(a.model), "network": name, "samples": a.samples, "held_out": a.held_out}
        for value, index, present in PROBED:
            keep = np.ones(len(train["features"]), bool) if present is None else train["features"][:, present] > 0.5
            keep_t = np.ones(len(held["features"]), bool) if present is None else held["features"][:, present] > 0.5
            y, y_t = train["features"][keep, index], held["features"][keep_t, index]
            row[value] = round(ridge_r2(train[name][keep], y, held[name][keep_t], y_t), 4)
        print(json.dumps(row), flush=True)
        rows.append(row)
    if a.out is not None:
        new = not a.out.exists()
        with open(a.out, "a", newline="") as f:
            w = csv.DictWriter(f, fieldnames=list(rows[0]))
            if new:
                w.writeheader()
            w.writerows(rows)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
