"""Steps per second of ChopperScape from Python (a benchmark, not a test).

    .venv/bin/python python/bench.py [--seconds 1.0]

Prints one line per case: the single env (`features`, and `rgb` 600 × 800) through `gymnasium.make` (with its
wrappers) and through the environment's own `step`; the native vector env (`features`, `grayscale` 84 × 84) at
N = 64 and 1024 with 1 and 2 threads, copy-free (`copy=False`) and with fresh arrays (`copy=True`, the default);
SB3 `VecEnv`s (when stable-baselines3 is installed): the native adapter
`chopperscape.integrations.sb3.ChopperScapeVecEnv`
against SB3's own `make_vec_env` (a `DummyVecEnv` of `Monitor`-wrapped envs), at N = 8 and 64; and Gymnasium's
CartPole-v1 as a yardstick.
"""

from __future__ import annotations

import argparse
import os
import platform
import sys
import time

# This file sits beside the package's sources, which lack the compiled `_core`: import the installed package.
sys.path = [p for p in sys.path if os.path.abspath(p or ".") != os.path.dirname(os.path.abspath(__file__))]

import gymnasium as gym  # noqa: E402
import numpy as np  # noqa: E402

import chopperscape  # noqa: E402


def rate(step, seconds: float) -> tuple[float, float]:
    """Calls `step()` (which returns how many env steps it made) for about `seconds`; returns env steps per
    wall-clock second and per CPU second of this process (all its threads): on a busy machine the second is
    the steadier figure, and for one thread it estimates an idle core."""
    deadline = time.perf_counter() + seconds / 5
    while time.perf_counter() < deadline:  # warm up
        step()
    done, start, cpu = 0, time.perf_counter(), time.process_time()
    end = start + seconds
    while True:
        for _ in range(16):
            done += step()
        now = time.perf_counter()
        if now >= end:
            return done / (now - start), done / max(time.process_time() - cpu, 1e-9)


def single(env, own: bool):
    """A step function for one env: autoresets on episode end, cycles through the actions."""
    target = env.unwrapped if own else env
    env.reset(seed=0)
    actions = [int(a) for a in np.random.default_rng(0).integers(0, 5 if env.action_space.n == 5 else 2, 4096)]
    state = {"t": 0}
    step_fn, reset_fn = target.step, target.reset

    def step() -> int:
        t = state["t"] = (state["t"] + 1) & 4095
        _, _, terminated, truncated, _ = step_fn(actions[t])
        if terminated or truncated:
            reset_fn()
        return 1

    return step


def batch_steps(envs, num_envs: int):
    """A `step()` for `rate` that steps a batch of `num_envs` with random actions, cycling through 64 batches."""
    batches = np.random.default_rng(0).integers(0, 5, (64, num_envs))
    state = {"t": 0}

    def step() -> int:
        state["t"] = (state["t"] + 1) & 63
        envs.step(batches[state["t"]])
        return num_envs

    return step


def vector(num_envs: int, threads: int, copy: bool, **options):
    envs = chopperscape.VectorEnv(num_envs, num_threads=threads, copy=copy, **options)
    envs.reset(seed=0)
    return batch_steps(envs, num_envs)


def sb3_vec(kind: str, num_envs: int):
    if kind == "native":
        from chopperscape.integrations.sb3 import ChopperScapeVecEnv

        envs = ChopperScapeVecEnv(num_envs, seed=0, obs_type="features")
    else:
        from stable_baselines3.common.env_util import make_vec_env

        envs = make_vec_env("ChopperScape-v0", n_envs=num_envs, seed=0, env_kwargs={"obs_type": "features"})
    envs.reset()
    return batch_steps(envs, num_envs)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--seconds", type=float, default=1.0, help="measuring time per case (default 1.0)")
    args = parser.parse_args()
    cpus = len(os.sched_getaffinity(0)) if hasattr(os, "sched_getaffinity") else os.cpu_count()
    print(
        f"# chopperscape {chopperscape.__version__}, Python {platform.python_version()}, "
        f"{platform.machine()}, {cpus} CPUs, gymnasium {gym.__version__}"
    )
    cases = []
    for obs_type in ["features", "rgb"]:
        cases.append(
            (
                f"single {obs_type:<9} gymnasium.make",
                lambda o=obs_type: single(gym.make("ChopperScape-v0", obs_type=o), own=False),
            )
        )
        cases.append(
            (
                f"single {obs_type:<9} env.step",
                lambda o=obs_type: single(gym.make("ChopperScape-v0", obs_type=o), own=True),
            )
        )
    for name, options in [
        ("features", {"obs_type": "features"}),
        ("gray84x84", {"obs_type": "grayscale", "obs_size": (84, 84)}),
    ]:
        for n in [64, 1024]:
            for threads in [1, 2]:
                for copy in [False, True]:
                    label = f"vector {name:<9} N={n:<4} T={threads} copy={copy!s:<5}"
                    cases.append((label, lambda n=n, t=threads, c=copy, o=options: vector(n, t, c, **o)))
    try:
        import stable_baselines3  # noqa: F401

        for n in [8, 64]:
            for kind in ["native", "make_vec_env"]:
                cases.append((f"SB3 VecEnv {kind:<12} N={n}", lambda k=kind, n=n: sb3_vec(k, n)))
    except ImportError:
        print("# stable-baselines3 is not installed: no SB3 VecEnv cases")
    cases.append(("CartPole-v1 gymnasium.make", lambda: single(gym.make("CartPole-v1"), own=False)))
    cases.append(("CartPole-v1 env.step", lambda: single(gym.make("CartPole-v1"), own=True)))
    print(f"{'case':<44} {'steps/s':>14} {'steps/CPU-s':>14}")
    for label, make in cases:
        wall, cpu = rate(make(), args.seconds)
        print(f"{label:<44} {wall:>14,.0f} {cpu:>14,.0f}", flush=True)


if __name__ == "__main__":
    main()
