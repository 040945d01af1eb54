"""How the fast preset's figures were measured: train one recipe per training seed (``--preset fast`` with optional
overrides), evaluate it greedily on the 100 held-out seeds from 1,000,000, and append a CSV row with the training's
wall and CPU time. The same runs as ``python -m chopperscape.learn.seeds --seeds ... --preset fast`` (the runs are
deterministic: the same seed gives the same model), in one process so that the CPU time is the training's own.

    python docs/curves/fast-probes/measure.py OUT.csv 0,1,2 [--set '{"update_epochs": 4, "learning_rate": 5e-4}']
"""

from __future__ import annotations

import argparse
import csv
import json
import os
import sys
import time
from pathlib import Path

import numpy as np

from chopperscape.learn import train
from chopperscape.learn.episodes import play_episodes
from chopperscape.learn.players import load_recipe
from chopperscape.learn.recipe import PRESETS, Recipe


def main() -> int:
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("csv", type=Path)
    p.add_argument("seeds", help="training seeds, comma-separated")
    p.add_argument("--set", default="{}", help="recipe settings over the fast preset, as JSON")
    a = p.parse_args()
    for seed in [int(s) for s in a.seeds.split(",")]:
        recipe = Recipe(**{**PRESETS["fast"], **json.loads(a.set), "seed": seed})
        out = a.csv.parent / f"seed-{seed}"
        load = os.getloadavg()[0]
        wall, cpu = time.perf_counter(), time.process_time()
        train.train(recipe, out, force=True)
        wall, cpu = time.perf_counter() - wall, time.process_time() - cpu
        act, options = load_recipe(out / "model.pt", False, 0, {})
        episodes = play_episodes(act, 100, 1_000_000, options)
        returns = np.array([e["return"] for e in episodes])
        with open(out / "progress.csv") as f:
            last = list(csv.DictReader(f))[-1]
        row = {
            "seed": seed,
            "env_steps": last["env_steps"],
            "wall_s": f"{wall:.1f}",
            "cpu_s": f"{cpu:.1f}",
            "load": f"{load:.1f}",
            "mean_return": f"{returns.mean():.1f}",
            "std_return": f"{returns.std():.1f}",
            **{c: f"{np.mean([e['cause'] == c for e in episodes]):.2f}" for c in ("bird", "fuel", "truncated")},
        }
        new = not a.csv.exists()
        with open(a.csv, "a") as f:
            writer = csv.DictWriter(f, fieldnames=list(row))
            if new:
                writer.writeheader()
            writer.writerow(row)
        print(row, file=sys.stderr)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
