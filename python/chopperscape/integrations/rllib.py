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
"""

from __future__ import annotations

import os
from collections.abc import Mapping
from pathlib import Path
from typing import Any

import gymnasium as gym
import numpy as np
from gymnasium.vector import AutoresetMode
from gymnasium.wrappers.utils import RunningMeanStd

from ..vector import VectorEnv

try:
    from ray.rllib.algorithms.ppo.torch.ppo_torch_learner import PPOTorchLearner
    from ray.rllib.connectors.connector_v2 import ConnectorV2
    from ray.rllib.connectors.env_to_module.observation_preprocessor import SingleAgentObservationPreprocessor
    from ray.rllib.connectors.learner import GeneralAdvantageEstimation
    from ray.rllib.core.columns import Columns
    from ray.rllib.utils.filter import SMALL_NUMBER
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
    "env_creator",
    "export_onnx",
    "float_pixels",
    "observation_filter",
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


class FloatPixels(SingleAgentObservationPreprocessor):
    """Pixel observations (`rgb`, `grayscale`, stacked or not: `uint8`) as `float32` in [0, 1], with a channel axis
    for plain grayscale: what RLlib's default CNN takes (it neither casts `uint8` nor reads 2-D boxes). Use it as
    `config.env_runners(env_to_module_connector=lambda env, spaces, device: FloatPixels())`."""

    def recompute_output_observation_space(self, input_observation_space, input_action_space):
        shape = tuple(input_observation_space.shape)
        return gym.spaces.Box(0.0, 1.0, shape + (1,) if len(shape) == 2 else shape, np.float32)

    def preprocess(self, observation, episode):
        return float_pixels(observation, np.ndim(observation))


def float_pixels(obs: Any, frame_ndim: int) -> np.ndarray:
    """What :class:`FloatPixels` makes of pixel observations, for one observation or a batch of them: `float32` in
    [0, 1] (from `uint8`), with a channel axis when one observation is a plain grayscale frame (`frame_ndim` 2)."""
    obs = np.asarray(obs)
    obs = obs.astype(np.float32) / 255.0 if obs.dtype == np.uint8 else obs.astype(np.float32, copy=False)
    return obs[..., None] if frame_ndim == 2 else obs


class ReturnScaling(ConnectorV2):
    """A learner connector that divides rewards by the running standard deviation of the discounted return, before
    GAE: what the single-machine recipe (:mod:`chopperscape.learn.train`), Gymnasium's `NormalizeReward` and SB3's
    `VecNormalize` do, and what RLlib's new API stack lacks. The statistics are Gymnasium's `RunningMeanStd`,
    updated from each batch's moments, and travel with the learner's state (checkpoints). The episode returns the
    env runners report stay the game's own: only what the learner sees is scaled.

    As in `NormalizeReward`, the discounted return runs over the whole episode, not over the chunk of it that one
    batch holds: a chunk that does not end its episode leaves its return to the episode's next chunk (`carry`, by
    episode id). With batches of 128 steps and γ 0.998 a chunk is a quarter of the return's horizon, so returns
    restarted at each chunk would spread less and scale the rewards up more. RLlib's bootstrap
    step (`Columns.LOSS_MASK` false) neither adds to the return nor to the statistics.

    A batch whose rows are not one per episode step (padded for a recurrent module) is left as it is."""

    def __init__(
        self, input_observation_space: Any = None, input_action_space: Any = None, *, gamma: float = 0.99, **kwargs: Any
    ) -> None:
        super().__init__(input_observation_space, input_action_space, **kwargs)
        self.gamma = float(gamma)
        self.rms = RunningMeanStd(shape=())
        #: The discounted return so far of each episode a batch left unfinished, by episode id.
        self.carry: dict[str, float] = {}

    def __call__(self, *, rl_module: Any, batch: dict[str, Any], episodes: Any, **kwargs: Any) -> Any:
        chunks = list(self.single_agent_episode_iterator(episodes, agents_that_stepped_only=False))
        lens = [len(e) for e in chunks]
        ids = [episode_id(e.id_) for e in chunks]
        for module_batch in batch.values():
            rewards = module_batch[Columns.REWARDS]
            r = _numpy(rewards).astype(np.float64)
            if r.shape[0] != sum(lens):
                continue
            mask = module_batch.get(Columns.LOSS_MASK)
            real = np.ones(r.shape[0], bool) if mask is None else _numpy(mask).astype(bool).reshape(-1)
            returns = discounted_returns(r, lens, self.gamma, [self.carry.get(i, 0.0) for i in ids], real)
            if real.any():
                self.rms.update(returns[real])
            carry, end = {}, 0
            for chunk, i, n in zip(chunks, ids, lens):
                end += n
                steps = np.flatnonzero(real[end - n : end])
                if not chunk.is_terminated and steps.size:
                    carry[i] = float(returns[end - n + steps[-1]])
            self.carry = carry
            module_batch[Columns.REWARDS] = rewards * (1.0 / np.sqrt(self.rms.var + 1e-8))
        return batch

    def get_state(self, components: Any = None, *, not_components: Any = None, **kwargs: Any) -> dict[str, Any]:
        return {
            "mean": float(self.rms.mean),
            "var": float(self.rms.var),
            "count": float(self.rms.count),
            "carry": dict(self.carry),
        }

    def set_state(self, state: dict[str, Any]) -> None:
        self.rms.mean = np.asarray(state["mean"], np.float64)
        self.rms.var = np.asarray(state["var"], np.float64)
        self.rms.count = float(state["count"])
        self.carry = {str(k): float(v) for k, v in state.get("carry", {}).items()}


def _numpy(x: Any) -> np.ndarray:
    return x.detach().cpu().numpy() if hasattr(x, "detach") else np.asarray(x)


def episode_id(chunk_id: str) -> str:
    """The id of the episode an episode chunk of a learner's batch belongs to: RLlib's learner pipeline
    (`AddOneTsToEpisodesAndTruncate`) appends `_<index in the batch>` to each chunk's id, which is otherwise the
    episode's (a hex uuid, the same for all its chunks).

    >>> episode_id("0f3a9c_12")
    '0f3a9c'
    """
    return chunk_id.rsplit("_", 1)[0]


def discounted_returns(
    rewards: np.ndarray,
    lengths: list[int],
    gamma: float,
    starts: list[float] | None = None,
    real: np.ndarray | None = None,
) -> np.ndarray:
    """The discounted return accumulated forward within each episode chunk: `rewards` holds the chunks one after
    another, `lengths` their lengths, `starts` the return each chunk's episode had before it (0 by default), and
    `real` which rows are steps (a row that is not, RLlib's bootstrap step, repeats the return before it).

    >>> discounted_returns(np.array([1.0, 1.0, 1.0, 2.0]), [3, 1], 0.5).tolist()
    [1.0, 1.5, 1.75, 2.0]
    >>> real = np.array([True, True, False, True])  # the third row is a bootstrap step
    >>> discounted_returns(np.array([1.0, 1.0, 0.0, 2.0]), [3, 1], 0.5, [2.0, 0.0], real).tolist()
    [2.0, 2.0, 2.0, 2.0]
    """
    out, start = np.empty_like(rewards, dtype=np.float64), 0
    for k, n in enumerate(lengths):
        acc = 0.0 if starts is None else float(starts[k])
        for t in range(start, start + n):
            if real is None or real[t]:
                acc = acc * gamma + rewards[t]
            out[t] = acc
        start += n
    return out


class ReturnScaledPPOLearner(PPOTorchLearner):
    """RLlib's PPO learner with :class:`ReturnScaling` before GAE, at the config's `gamma`:
    `PPOConfig().learners(learner_class=ReturnScaledPPOLearner)`."""

    def build(self) -> None:
        super().build()
        if self._learner_connector is not None:
            self._learner_connector.insert_before(GeneralAdvantageEstimation, ReturnScaling(gamma=self.config.gamma))


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


def observation_filter_state(env_runner: Any) -> dict:
    """The MeanStdFilter connector's state on a runner (runs in the runner); {} without one."""
    for connector in env_runner._env_to_module.connectors:
        if type(connector).__name__ == "MeanStdFilter":
            return connector.get_state()
    return {}


def observation_filter(algo: Any, space: gym.spaces.Space) -> Any:
    """The observation filter of `algo`'s runners (RLlib's `MeanStdFilter` connector, synced across them) as a
    `ray.rllib.utils.filter.MeanStdFilter` over `space`, to apply with `update=False`; `None` when the runners
    have none (pixels). `ValueError` when the runners cannot be reached."""
    from ray.rllib.connectors.env_to_module.mean_std_filter import MeanStdFilter

    states = algo.env_runner_group.foreach_env_runner(observation_filter_state, local_env_runner=True)
    states = [s for s in states if s]
    if not states:
        return None
    connector = MeanStdFilter()  # (given the space in its constructor, it reads its clip before setting it)
    connector.input_observation_space = space
    connector.set_state(states[0])
    return connector._filters[None]


def export_onnx(
    algo: Any,
    env_config: Mapping[str, Any],
    out: str | os.PathLike[str],
    *,
    train_seeds: list[tuple[int, int]],
    source_sha256: str,
    force: bool = False,
) -> dict[str, Any]:
    """Writes the greedy policy of a trained PPO `algo` to `out` as a ChopperScape policy file, the format of
    `python -m chopperscape.learn.export` (read by `python -m chopperscape.bench evaluate`, the command line, the
    Rust crate and the page): the env's raw observation batch to the logits of the five actions, with what the
    runners apply first in the graph (the observation filter's frozen mean and std for features; the [0, 1]
    scaling for pixels). `train_seeds`: the reset-seed ranges `(first, count)` the runners trained on (written to
    the file, checked by the bench); `source_sha256`: the digest of the weights. The export's logits are compared
    with the module's on 1,000 observations recorded by playing it (`RuntimeError` beyond the tolerance); the file
    is written whole or not at all. Returns what was written and checked. `ValueError` for a bad `out`."""
    import torch

    from .. import FEATURES_VERSION, PIXELS_VERSION, policyfile
    from ..modes import with_mode
    from ..policyfile import observation_shape

    out = Path(out)
    policyfile.check_out(out, force)
    config = dict(env_config)
    obs_type = config.pop("obs_type", "features")
    name = config.pop("mode", None)
    options = {k: v for k, v in config.items() if k not in ("max_episode_steps", *VECTOR_ONLY)}
    if name is not None:
        options = with_mode(name, options)
    shape = observation_shape({"obs_type": obs_type, **options})
    space = gym.spaces.Box(-np.inf, np.inf, shape, np.float32)
    norm = observation_filter(algo, space) if obs_type == "features" else None
    if obs_type == "features" and norm is None:
        raise ValueError("no runner has the observation filter's statistics to export with")
    module = algo.get_module()

    class Policy(torch.nn.Module):
        def __init__(self) -> None:
            super().__init__()
            self.module = module
            if norm is not None:
                stats = norm.running_stats
                mean = np.asarray(stats.mean) if norm.demean else np.zeros(shape)
                scale = 1.0 / (np.asarray(stats.std) + SMALL_NUMBER) if norm.destd else np.ones(shape)
                self.register_buffer("mean", torch.as_tensor(mean, dtype=torch.float32))
                self.register_buffer("scale", torch.as_tensor(scale, dtype=torch.float32))
                self.clip = float(norm.clip) if norm.clip else None

        def forward(self, obs: torch.Tensor) -> torch.Tensor:
            if norm is not None:
                x = (obs - self.get_buffer("mean")) * self.get_buffer("scale")
                x = torch.clamp(x, -self.clip, self.clip) if self.clip is not None else x
            else:  # as FloatPixels: [0, 1], a channel axis for a plain grayscale frame
                x = obs.float() / 255.0 if obs.dtype == torch.uint8 else obs.float()
                x = x.unsqueeze(-1) if len(shape) == 2 else x
            return self.module.forward_inference({"obs": x})["action_dist_inputs"]

    policy = Policy().eval()
    dtype = torch.uint8 if obs_type in ("rgb", "grayscale") else torch.float32
    props = policyfile.metadata(
        obs_type,
        shape,
        options,
        source_sha256=source_sha256,
        features_version=FEATURES_VERSION,
        pixels_version=PIXELS_VERSION,
        train_seeds=train_seeds,
    )

    def logits(obs: np.ndarray) -> np.ndarray:
        with torch.no_grad():
            return policy(torch.from_numpy(obs)).numpy()

    data = policyfile.to_onnx(policy, torch.zeros((2, *shape), dtype=dtype), props)
    result: dict[str, Any] = {"out": str(out), "obs_type": obs_type, "obs_shape": list(shape), "bytes": len(data)}
    result.update(policyfile.check_logits(data, logits, obs_type, options))
    policyfile.write(out, data)
    return result


def seed_ranges(seeds: list[int | None]) -> list[tuple[int, int]]:
    """The seeds of `runner_seeds` (over all runners) as sorted ranges `(first, count)` of consecutive seeds;
    `ValueError` if an env was reset without a seed (its games are then unknown)."""
    if any(s is None for s in seeds):
        raise ValueError("an env was reset without a seed: its training seeds are unknown (give the run a --seed)")
    ranges: list[list[int]] = []
    for s in sorted({int(s) for s in seeds if s is not None}):
        if ranges and ranges[-1][0] + ranges[-1][1] == s:
            ranges[-1][1] += 1
        else:
            ranges.append([s, 1])
    return [(first, count) for first, count in ranges]


register()
