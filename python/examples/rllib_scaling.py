#!/usr/bin/env python3
"""RLlib's PPO training throughput with the fast preset's settings (the leaderboard's `rllib-ppo` row): one env
runner of 128 games, two runners of 64, and two runners on a two-node Ray cluster (two raylets on this machine,
one CPU each, through Ray's own `ray.cluster_utils.Cluster`, so each runner has a node to itself).

    .venv-rllib/bin/python python/examples/rllib_scaling.py --iterations 4

A benchmark, not a test: each configuration trains `--iterations` iterations of 16,384 decisions in a child
`python -m chopperscape.integrations.rllib.ppo` and is reported as decisions a second of the iterations after the
first (the first carries the runners' start-up), then a Markdown table. docs/rllib.md holds its figures.
"""

from __future__ import annotations

import argparse
import csv
import json
import os
import subprocess
import sys
import tempfile
from pathlib import Path

from chopperscape.bench.rows import ROWS

CONFIGS = [("1 runner × 128 games", 1, 128, False), ("2 runners × 64 games", 2, 64, False)]
CONFIGS += [("2 runners × 64 games, two-node cluster", 2, 64, True)]


def flags(runners: int, games: int) -> list[str]:
    """The `rllib-ppo` row's flags with `runners` runners of `games` games each."""
    s = {**ROWS["rllib-ppo"].settings(), "env-runners": runners, "envs-per-runner": games}
    s["env-config"] = {**s["env-config"], "mode": "sticky-v0"}  # the row's first rung
    return [f"--{k}={json.dumps(v) if k == 'env-config' else v}" for k, v in s.items()]


def rate(path: Path) -> tuple[float, int]:
    """Decisions a second after the first iteration, and the decisions measured, from a progress CSV."""
    with open(path, newline="") as f:
        rows = list(csv.DictReader(f))
    if len(rows) < 2:
        raise SystemExit(f"{path}: {len(rows)} progress rows; give more --iterations")
    first, last = rows[0], rows[-1]
    steps = int(last["env_steps"]) - int(first["env_steps"])
    return steps / (float(last["wall_s"]) - float(first["wall_s"])), steps


def run(name: str, runners: int, games: int, two_nodes: bool, iterations: int, out: Path) -> dict:
    cmd = [sys.executable, "-m", "chopperscape.integrations.rllib.ppo", *flags(runners, games)]
    cmd += [f"--iterations={iterations}", "--seed=0", f"--csv={out / 'progress.csv'}"]
    cluster = None
    if two_nodes:
        from ray.cluster_utils import Cluster

        cluster = Cluster(initialize_head=True, head_node_args={"num_cpus": 1})
        cluster.add_node(num_cpus=1)
        cluster.wait_for_nodes()
        cmd += [f"--address={cluster.address}"]
    try:
        done = subprocess.run(cmd, capture_output=True, text=True)
    finally:
        if cluster is not None:
            cluster.shutdown()
    if done.returncode != 0:
        raise SystemExit(f"{name}: {' '.join(cmd)} failed ({done.returncode}):\n{done.stderr[-2000:]}")
    per_s, steps = rate(out / "progress.csv")
    return {"name": name, "per_s": per_s, "steps": steps}


def main() -> int:
    p = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    p.add_argument("--iterations", type=int, default=4, help="iterations of 16,384 decisions per configuration")
    a = p.parse_args()
    if a.iterations < 2:
        p.error(f"--iterations {a.iterations}: at least 2 (the first is not timed)")
    results = []
    for name, runners, games, two_nodes in CONFIGS:
        with tempfile.TemporaryDirectory() as out:
            results.append(run(name, runners, games, two_nodes, a.iterations, Path(out)))
        print(f"{name}: {results[-1]['per_s']:,.0f} decisions/s", file=sys.stderr)
    print(
        f"| configuration | decisions/s (after the first iteration) |  (CPUs: {os.cpu_count()}, load "
        f"{os.getloadavg()[0]:.1f})"
    )
    print("|---|---|")
    for r in results:
        print(f"| {r['name']} | {r['per_s']:,.0f} ({r['steps']:,} decisions) |")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
