"""No memory growth over a long run: Python objects (tracemalloc) and the process (RSS, Rust included)."""

from __future__ import annotations

import resource
import tracemalloc

import gymnasium as gym
import numpy as np
from conftest import SHORT

from chopperscape import VectorEnv


def rss_kib() -> int:
    with open("/proc/self/statm") as f:
        return int(f.read().split()[1]) * resource.getpagesize() // 1024


def run_single(steps: int, env) -> None:
    for t in range(steps):
        _, _, terminated, truncated, _ = env.step(t % 5)
        if terminated or truncated:
            env.reset()


def run_vector(batches: int, envs) -> None:
    actions = np.arange(envs.num_envs) % 5
    for _ in range(batches):
        envs.step(actions)


def test_200k_single_steps_and_vector_batches_do_not_grow_memory():
    env = gym.make("ChopperScape-v0", **SHORT)
    env.reset(seed=0)
    envs = VectorEnv(64, num_threads=2, **SHORT)
    envs.reset(seed=0)
    run_single(20_000, env)  # warm up: caches, the pool, allocator arenas
    run_vector(500, envs)
    rss_before = rss_kib()
    tracemalloc.start()
    snap_before = tracemalloc.take_snapshot()
    run_single(200_000, env)
    run_vector(3_000, envs)
    snap_after = tracemalloc.take_snapshot()
    tracemalloc.stop()
    growth = sum(s.size_diff for s in snap_after.compare_to(snap_before, "filename"))
    rss_growth = rss_kib() - rss_before
    assert growth < 256 * 1024, f"Python heap grew by {growth} bytes"
    assert rss_growth < 8 * 1024, f"RSS grew by {rss_growth} KiB"
