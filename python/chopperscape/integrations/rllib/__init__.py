"""ChopperScape-v0 for Ray RLlib's new API stack: the env by name, every option through `env_config`,
one native `VectorEnv` per env runner, and seeds that differ across runners and sub-envs.

Importing this module registers `"ChopperScape-v0"` with RLlib (`ray.tune.registry.register_env`);
`import chopperscape` alone never imports Ray.

>>> import chopperscape.integrations.rllib
>>> from ray.rllib.algorithms.ppo import PPOConfig
>>> config = (
...     PPOConfig()
...     .environment("ChopperScape-v0", env_config={"obs_type": "features"})
...     .env_runners(num_env_runners=2, num_envs_per_env_runner=16,
...                  gym_env_vectorize_mode="vector_entry_point")  # the native batch; "sync" for Python sub-envs
... )

How RLlib builds the env of each runner (`SingleAgentEnvRunner.make_env`), and what this module does there:

- `gym_env_vectorize_mode="vector_entry_point"`: RLlib calls `env_creator(env_config | {"num_envs": n})` once
  per runner; we return one `chopperscape.VectorEnv` of `n` envs, stepped by one Rust call a batch with the GIL
  released. Its threads default to the CPUs Ray gave the runner (`OMP_NUM_THREADS`, which Ray sets to
  `num_cpus_per_env_runner`), at most one per 64 envs; `env_config["num_threads"]` overrides.
- `"sync"` (RLlib's default) or `"async"`: RLlib calls `env_creator(EnvContext)` once per sub-env and batches the
  `n` Python envs in Gymnasium's `SyncVectorEnv` / `AsyncVectorEnv`; we return `gym.make("ChopperScape-v0")`.

Seeds. RLlib resets runner `w` once with `seed = config.seed + w` (+10**6 on evaluation runners), and Gymnasium's
vectors give sub-env `i` the seed `seed + i`, so runner 1's env 1 and runner 2's env 0 would play the same game.
This module remaps, so that no two sub-envs anywhere share a seed (for seeds below 2**43 and fewer than 2**20
runners and envs per runner):

- native batch: sub-env `i` of the runner reset with `s` gets `s * SEED_STRIDE + i`;
- Python sub-envs: the sub-env reset with `x` (= `s + i`) by its runner `w` gets `x * SEED_STRIDE + w`.

(The vector creator is not told its runner's index by RLlib, the single-env creator not its place in the vector,
hence two formulas; each is one-to-one.) With `config.seed` unset every env draws its seed from OS entropy.
`runner_seeds(env_runner)` returns the seeds a runner's envs were last reset with.

Connectors (:mod:`.connectors`) and the ONNX export (:mod:`.export`) are re-exported here; the PPO trainer of the
bench's RLlib row is :mod:`.ppo` (`python -m chopperscape.integrations.rllib.ppo`).
"""

from __future__ import annotations

import os
from collections.abc import Mapping
from typing import Any

import gymnasium as gym
import numpy as np
from gymnasium.vector import AutoresetMode

from ...policyfile import seed_ranges
from ...vector import VectorEnv

try:
    from ray.tune.registry import register_env
except ImportError as e:  # pragma: no cover - depends on the installation
    raise ImportError(
        "chopperscape.integrations.rllib needs Ray RLlib, which is not installed: pip install 'ray[rllib]' torch"
    ) from e

__all__ = [
    "ENV_NAME",
    "SEED_STRIDE",
    "FloatPixels",
    "ReturnScaledPPOLearner",
    "ReturnScaling",
    "check_env_config",
    "discounted_returns",
    "env_creator",
    "episode_id",
    "export_onnx",
    "float_pixels",
    "observation_filter",
    "observation_filter_state",
    "register",
    "runner_seeds",
    "seed_ranges",
]

#: The name this module registers with RLlib (the same as Gymnasium's id).
ENV_NAME = "ChopperScape-v0"
#: The seed of a sub-env is its runner's (or its own) RLlib seed times this, plus its index (or its runner's).
SEED_STRIDE = 2**20

#: `env_config` keys that only the native batch uses; the Python sub-envs ignore them.
VECTOR_ONLY = ("num_threads",)


def env_creator(config: Mapping[str, Any]) -> gym.Env | gym.vector.VectorEnv:
    """Builds what RLlib asks for: a native `VectorEnv` when `config` holds `num_envs` (RLlib's
    `vector_entry_point` mode), else one `ChopperScape-v0` (a sub-env of RLlib's Python vector).

    `config` is the `env_config` of the algorithm (RLlib's `EnvContext`): every option of `ChopperScapeEnv`,
    plus `max_episode_steps` (default 10000, as `gymnasium.make`) and, for the native batch, `num_threads`.
    An unknown option or a bad value raises `ValueError` naming it. Lists (what JSON and YAML configs hold) are
    taken as tuples: `"obs_size": [84, 84]` is `(84, 84)`.
    """
    options: dict[str, Any] = {k: tuple(v) if isinstance(v, list) else v for k, v in dict(config).items()}
    num_envs: Any = options.pop("num_envs", None)
    for key in ("autoreset_mode", "copy"):
        if key in options:
            raise ValueError(
                f"option `{key}` cannot be set through RLlib's env_config: RLlib needs autoreset_mode=NEXT_STEP and "
                "copy=True (it keeps the observation arrays it is given)"
            )
    if num_envs is None:
        worker_index = int(getattr(config, "worker_index", 0) or 0)
        for key in VECTOR_ONLY:
            options.pop(key, None)
        return RunnerSeededEnv(gym.make(ENV_NAME, **options), worker_index)
    if "num_threads" not in options:
        options["num_threads"] = _runner_threads(int(num_envs))
    env = VectorEnv(num_envs, autoreset_mode=AutoresetMode.NEXT_STEP, copy=True, **options)
    if env.num_envs >= SEED_STRIDE:
        raise ValueError(f"invalid value {num_envs} for `num_envs_per_env_runner`: allowed 1..{SEED_STRIDE - 1}")
    return RunnerSeededVectorEnv(env)


def check_env_config(env_config: Mapping[str, Any]) -> None:
    """Builds (and drops) one env from `env_config`, so that a bad option raises its `ValueError` here, in the
    driver: raised in a remote env runner, RLlib 2.60 logs it but then fails with an unrelated `IndexError`."""
    env = env_creator({**env_config, "num_envs": 1})
    env.close()


def register(name: str = ENV_NAME) -> str:
    """Registers `env_creator` with RLlib under `name` (done on import for `"ChopperScape-v0"`); returns `name`."""
    register_env(name, env_creator)
    return name


def runner_seeds(env_runner: Any) -> list[int | None]:
    """The core seeds the sub-envs of an RLlib env runner were last reset with (`None` for an env reset without
    a seed, or never reset). For `algo.env_runner_group.foreach_env_runner(runner_seeds)`."""
    env = getattr(env_runner, "env", None)
    if env is None:
        return []
    vector = _find(env, RunnerSeededVectorEnv)
    if vector is not None:
        return list(vector.reset_seeds) if vector.reset_seeds is not None else [None] * vector.num_envs
    singles = getattr(_find(env, gym.vector.SyncVectorEnv) or env, "envs", None)
    if singles is not None:
        return [getattr(_find(e, RunnerSeededEnv), "reset_seed", None) for e in singles]
    # AsyncVectorEnv: the sub-envs live in other processes.
    return list(env.get_attr("reset_seed"))


class RunnerSeededVectorEnv(gym.vector.VectorWrapper):
    """The native batch of one RLlib env runner: `reset(seed=s)` seeds sub-env `i` with `s * SEED_STRIDE + i`."""

    def __init__(self, env: gym.vector.VectorEnv):
        super().__init__(env)
        #: The seeds of the last seeded reset, one per sub-env (`None` before one).
        self.reset_seeds: list[int] | None = None

    def reset(
        self, *, seed: int | list[int | None] | None = None, options: dict[str, Any] | None = None
    ) -> tuple[np.ndarray, dict[str, Any]]:
        if isinstance(seed, (int, np.integer)) and not isinstance(seed, bool):
            seeds = [int(seed) * SEED_STRIDE + i for i in range(self.num_envs)]
            self.reset_seeds = seeds
            return self.env.reset(seed=seeds, options=options)  # type: ignore[arg-type]  # per-env seeds
        return self.env.reset(seed=seed, options=options)  # type: ignore[arg-type]


class RunnerSeededEnv(gym.Wrapper):
    """A Python sub-env of RLlib runner `worker_index`: `reset(seed=x)` seeds the game with
    `x * SEED_STRIDE + worker_index`."""

    def __init__(self, env: gym.Env, worker_index: int):
        if not 0 <= worker_index < SEED_STRIDE:
            raise ValueError(f"invalid env runner index {worker_index}: allowed 0..{SEED_STRIDE - 1}")
        super().__init__(env)
        self.worker_index = worker_index
        #: The seed of the last seeded reset (`None` before one).
        self.reset_seed: int | None = None

    def reset(self, *, seed: int | None = None, options: dict[str, Any] | None = None) -> tuple[Any, dict[str, Any]]:
        if seed is not None:
            seed = int(seed) * SEED_STRIDE + self.worker_index
            self.reset_seed = seed
        return self.env.reset(seed=seed, options=options)


def _runner_threads(num_envs: int) -> int:
    """Threads for a runner's batch: the CPUs Ray gave the runner (`OMP_NUM_THREADS`, set by Ray to the actor's
    `num_cpus`), else the CPUs this process may use, and at most one per 64 envs. Unlike `VectorEnv`'s default
    (one thread, since a learner usually shares the cores), a runner's CPUs are reserved for it by Ray."""
    try:
        cpus = len(os.sched_getaffinity(0))
    except AttributeError:
        cpus = os.cpu_count() or 1
    try:
        cpus = min(cpus, int(os.environ.get("OMP_NUM_THREADS", "")))
    except ValueError:
        pass
    return max(1, min(cpus, num_envs // 64))


def _find(env: Any, kind: type) -> Any:
    """The first wrapper or env of type `kind` down `env`'s `.env` chain, or `None`."""
    while env is not None:
        if isinstance(env, kind):
            return env
        env = getattr(env, "env", None)
    return None


register()
from .connectors import (  # noqa: E402  (after register(): the connectors import more of RLlib)
    FloatPixels,
    ReturnScaledPPOLearner,
    ReturnScaling,
    discounted_returns,
    episode_id,
    float_pixels,
)
from .export import export_onnx, observation_filter, observation_filter_state  # noqa: E402
