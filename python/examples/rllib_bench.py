#!/usr/bin/env python3
"""Env steps per second sampled by RLlib's env runners on ChopperScape-v0: 0, 1 and 2 runners, the native batch
versus Python sub-envs, with the policy acting (a torch forward pass a step) and with random actions.

    python python/examples/rllib_bench.py --envs-per-runner 16 --seconds 10

A benchmark, not a test: it prints a Markdown table. Every runner samples at once (`foreach_env_runner`), for
`--seconds` after one warm-up round; 0 runners means the driver's own runner samples.
"""

from __future__ import annotations

import argparse
import os
import sys
import time

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import rllib_ppo


def main() -> int:
    p = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    p.add_argument("--runners", default="0,1,2", help="numbers of env runners to measure")
    p.add_argument("--envs-per-runner", type=int, default=16)
    p.add_argument("--seconds", type=float, default=10.0, help="timed sampling per configuration and action mode")
    p.add_argument("--chunk", type=int, default=1024, help="env steps per sample() call of each runner")
    p.add_argument("--obs-type", default="features")
    p.add_argument("--torch-threads", type=int, default=1, help="torch threads of the driver (as rllib_ppo.py)")
    args = p.parse_args()
    import ray
    import torch

    torch.set_num_threads(args.torch_threads)

    ray.init(logging_level="ERROR")
    print(
        f"| runners | envs/runner | sub-envs | policy steps/s | random steps/s |  (CPUs: {os.cpu_count()}, "
        f"load {os.getloadavg()[0]:.1f})"
    )
    print("|---|---|---|---|---|")
    for runners in [int(r) for r in args.runners.split(",")]:
        for native in (True, False):
            train_args = rllib_ppo.parse_args(
                [
                    "--env-runners",
                    str(runners),
                    "--envs-per-runner",
                    str(args.envs_per_runner),
                    "--obs-type",
                    args.obs_type,
                    "--native" if native else "--python-envs",
                ]
            )
            algo = rllib_ppo.build_config(train_args).build_algo()
            rates = [measure(algo, runners, random, args) for random in (False, True)]
            algo.stop()
            print(
                f"| {runners} | {args.envs_per_runner} | {'native batch' if native else 'Python (sync)'} | "
                f"{rates[0]:,.0f} | {rates[1]:,.0f} |",
                flush=True,
            )
    ray.shutdown()
    return 0


def measure(algo, runners: int, random: bool, args: argparse.Namespace) -> float:
    chunk = args.chunk

    def sample(env_runner, force_reset: bool = False) -> int:
        episodes = env_runner.sample(num_timesteps=chunk, random_actions=random, force_reset=force_reset)
        return sum(e.env_steps() for e in episodes)

    group = algo.env_runner_group
    local = runners == 0
    # Warm-up, and fresh episodes: an episode must not mix policy and random steps.
    group.foreach_env_runner(lambda r: sample(r, force_reset=True), local_env_runner=local)
    steps, start = 0, time.perf_counter()
    while time.perf_counter() - start < args.seconds:
        steps += sum(group.foreach_env_runner(sample, local_env_runner=local))
    return steps / (time.perf_counter() - start)


if __name__ == "__main__":
    sys.exit(main())
