#!/usr/bin/env python3
"""Where does a trained pixel policy fly? The chopper's place and the fuel tanks in its reach, on held-out seeds.

    python python/examples/flight_probe.py MODEL [MODEL ...] [--decisions 6000] [--envs 16]

Each model plays greedily on `--envs` pixel envs from the held-out seeds (1,000,000..), each beside a features twin
(the trunk probe's `collect`: determinism keeps the two in one state, checked every step); the twin's features say
where the chopper is and which tanks it can still catch. One JSON line per model: the chopper's height (0 the top
of the sky, 1 the bottom; the 10th, 50th and 90th percentiles over decisions) and column (0 left, 1 right), the
share of decisions spent in the upper third, the share with a tank that the chopper can still catch (`reachable`:
flying straight sideways it meets the tank before the tank rises past) and refuels per 1,000 decisions.

Why: tanks rise from the bottom at the chopper's speed, so a chopper high in the sky sees every tank come to it and
one low down catches only those born beside it. Issue 43's stalled seed 102 flies at the bottom, every other seed at
the top (docs/notes/pixels-speed-and-probes.md, fifteenth session). The features are read here only: nothing
privileged reaches the policy. The same arguments give the same numbers.
"""

from __future__ import annotations

import argparse
import importlib.util
import json
import os
import sys
from pathlib import Path
from typing import Any

# This file sits beside the package's sources, which lack the compiled `_core`: import the installed package.
HERE = os.path.dirname(os.path.abspath(__file__))
sys.path = [p for p in sys.path if os.path.abspath(p or ".") != HERE]

import numpy as np  # noqa: E402

#: Feature indices (crates/core/src/features.rs): the chopper's x and y (0..1), the fuel, the nearest tank's slot.
#: An empty slot is all zeros, so `reachable` alone says a tank is there and in reach.
CHOPPER_X, CHOPPER_Y, FUEL, TANK_REACHABLE = 0, 1, 2, 23


def _collect():  # the trunk probe's twin-env player, loaded from its file beside this one
    spec = importlib.util.spec_from_file_location("trunk_probe", os.path.join(HERE, "trunk_probe.py"))
    assert spec is not None and spec.loader is not None
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module.collect, module.HELD_OUT_SEED


def flight(features: np.ndarray, ended: np.ndarray, num_envs: int) -> dict[str, Any]:
    """The summary of `features` and `ended` (rows in step order, `num_envs` a step, env by env)."""
    x, y = features[:, CHOPPER_X], features[:, CHOPPER_Y]
    reachable = features[:, TANK_REACHABLE] > 0.5
    steps = len(features) // num_envs
    fuel = features[: steps * num_envs, FUEL].reshape(steps, num_envs)
    went_on = ~ended[: (steps - 1) * num_envs].reshape(steps - 1, num_envs)  # the next row is the same episode's
    refuels = int(np.sum((np.diff(fuel, axis=0) > 0) & went_on))  # within an episode the fuel rises only at a refuel
    q = [0.1, 0.5, 0.9]
    return {
        "decisions": len(features),
        "height_q10_q50_q90": [round(float(v), 3) for v in np.quantile(y, q)],
        "column_q10_q50_q90": [round(float(v), 3) for v in np.quantile(x, q)],
        "upper_third": round(float(np.mean(y < 1 / 3)), 3),
        "tank_reachable": round(float(np.mean(reachable)), 3),
        "refuels_per_1000": round(1000.0 * refuels / len(features), 2),
    }


def main(argv: list[str] | None = None) -> int:
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("models", type=Path, nargs="+", help="pixel model.pt files from python -m chopperscape.learn.train")
    p.add_argument("--decisions", type=int, default=6_000, help="decisions played per model (default 6,000)")
    p.add_argument("--envs", type=int, default=16, help="envs played at once (default 16)")
    a = p.parse_args(argv)
    import torch

    from chopperscape.learn import modelfile

    torch.set_num_threads(1)
    collect, held_out_seed = _collect()
    for path in a.models:
        model = modelfile.load(path)
        if model.recipe["obs_type"] == "features":
            p.error(f"{path} is a features model: the probe plays a pixel policy beside its features twin")
        played = collect(model, a.decisions, a.envs, held_out_seed, {"trained": model.agent})
        print(json.dumps({"model": str(path), **flight(played["features"], played["ended"], a.envs)}), flush=True)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
