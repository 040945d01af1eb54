"""The built-in policies, computed in Rust from the env's own state: `random` (seeded), `heuristic`, and the fixed
actions `right`, `left`, `down`, `up`, `noop`. A policy picks an action from the env's state; the trained ones
(the recipe's models, exported to ONNX) are the other kind (docs/policies.md).

One env (any `gymnasium.make` wrappers around it are looked through):

>>> import gymnasium as gym, chopperscape
>>> from chopperscape import policies
>>> env = gym.make("ChopperScape-v0", obs_type="features")
>>> policy = policies.heuristic()
>>> obs, info = env.reset(seed=0)
>>> obs, reward, terminated, truncated, info = env.step(policy.act(env))

A batch: one call returns the actions of every environment of a native `chopperscape.VectorEnv`, computed in
Rust with the GIL released:

>>> envs = chopperscape.VectorEnv(8, obs_type="features")
>>> batch = policies.VectorPolicy("heuristic", num_envs=8)
>>> obs, info = envs.reset(seed=0)
>>> obs, rewards, terminated, truncated, info = envs.step(batch.act(envs))

Episodes equal the command line's: `chopperscape demo --policy P --episodes N --seed S` plays episode `i` from
`reset(seed=S + i)` with the `random` policy's generator seeded `S + i` too; `episodes(P, N, S)` does the same.
Policy `i` of a `VectorPolicy(P, n, seed=S)` is seeded `S + i`, as environment `i` of a batch reset with `seed=S`.
The heuristic plans for the options of the env it plays (`frame_skip`, `sticky_prob`).
"""

from __future__ import annotations

from collections.abc import Iterator
from typing import Any

import gymnasium as gym
import numpy as np

from . import _core
from ._checks import policy_seed, positive_int
from .env import ChopperScapeEnv, make_env
from .vector import VectorEnv

__all__ = [
    "NAMES",
    "Policy",
    "VectorPolicy",
    "episodes",
    "fixed",
    "heuristic",
    "make",
    "random",
]

#: Every built-in policy's name, as the command line's `--policy` takes it.
NAMES: list[str] = list(_core.POLICY_NAMES)
_FIXED = {0: "right", 1: "left", 2: "down", 3: "up", 4: "noop"}


def _check_name(name: str) -> None:
    if name not in NAMES:
        raise ValueError(f"unknown policy {name!r}: allowed built-in policies are {', '.join(NAMES)}")


def _check_seed(seed: int) -> int:
    return policy_seed(seed)


def _single(env: Any) -> _core.Env:
    base = getattr(env, "unwrapped", env)
    if isinstance(base, ChopperScapeEnv):
        return base._core
    if isinstance(base, _core.Env):
        return base
    if isinstance(base, gym.vector.VectorEnv):
        raise TypeError("Policy.act takes one environment; for a vector env use chopperscape.policies.VectorPolicy")
    raise TypeError(f"Policy.act takes a ChopperScape-v0 environment (from gymnasium.make), got {type(env).__name__}")


class Policy:
    """A built-in policy for one ChopperScape-v0 env. `act(env)` returns the action (an `int` in 0..=4) for the
    env's current state; `reset(seed)` restarts it (the `random` policy's generator) as if new."""

    def __init__(self, name: str, seed: int = 0):
        _check_name(name)
        self._core = _core.Policy(name, _check_seed(seed))

    @property
    def name(self) -> str:
        """The policy's name, as in `NAMES`."""
        return self._core.name

    @property
    def seed(self) -> int:
        """The seed of its generator (only `random` draws from it)."""
        return self._core.seed

    def act(self, env: Any) -> int:
        """The action for `env`'s current state (`env` may be wrapped: `env.unwrapped` is read)."""
        return self._core.act(_single(env))

    def reset(self, seed: int | None = None) -> None:
        """Restarts the policy with `seed` (default: the seed it has), as the CLI does for each episode."""
        self._core.reset(None if seed is None else _check_seed(seed))

    def __repr__(self) -> str:
        return f"Policy({self.name!r}, seed={self.seed})"


class VectorPolicy:
    """One built-in policy per environment of a native `chopperscape.VectorEnv` (`gymnasium.make_vec(...,
    vectorization_mode="vector_entry_point")`). `act(envs)` returns the `(num_envs,)` int64 actions in one Rust
    call with the GIL released. Policy `i` is seeded `seed + i`; an environment about to autoreset gets 4 (its
    action is ignored) and its policy draws nothing, so each environment's policy continues across episodes
    exactly as a single env's `Policy` that is not reset between them."""

    def __init__(self, name: str, num_envs: int, seed: int = 0):
        _check_name(name)
        # Within `usize`; the batch's memory budget (as `VectorEnv`'s) is checked in Rust before allocating.
        num_envs = positive_int("num_envs", num_envs, maximum=2**64 - 1)
        self._core = _core.VectorPolicy(name, num_envs, _check_seed(seed))

    @property
    def name(self) -> str:
        return self._core.name

    @property
    def num_envs(self) -> int:
        return self._core.num_envs

    @property
    def seed(self) -> int:
        return self._core.seed

    def act(self, envs: Any) -> np.ndarray:
        """The actions of every environment of `envs` (a `chopperscape.VectorEnv`, possibly wrapped)."""
        base = getattr(envs, "unwrapped", envs)
        if not isinstance(base, VectorEnv):
            raise TypeError(
                "VectorPolicy.act takes chopperscape's native VectorEnv (gymnasium.make_vec(..., "
                f'vectorization_mode="vector_entry_point")), got {type(envs).__name__}; for one env use Policy'
            )
        return self._core.act(base._core)

    def reset(self, seed: int | None = None) -> None:
        """Restarts every policy: policy `i` with `seed + i` (default: the seed it has)."""
        self._core.reset(None if seed is None else _check_seed(seed))

    def __repr__(self) -> str:
        return f"VectorPolicy({self.name!r}, num_envs={self.num_envs}, seed={self.seed})"


def make(name: str, seed: int = 0) -> Policy:
    """The built-in policy `name` (one of `NAMES`)."""
    return Policy(name, seed)


def random(seed: int = 0) -> Policy:
    """Uniformly random actions from the policy's own generator, seeded with `seed` (not the env's)."""
    return Policy("random", seed)


def heuristic() -> Policy:
    """The scripted policy of `crates/core/src/policy.rs`: it dodges hazards and refuels, planning in agent steps."""
    return Policy("heuristic")


def fixed(action: int | str) -> Policy:
    """Always the same action: an index 0..=4 or a name (`"right"`, `"left"`, `"down"`, `"up"`, `"noop"`)."""
    name = _FIXED.get(int(action)) if isinstance(action, (int, np.integer)) and not isinstance(action, bool) else action
    if not isinstance(name, str) or name not in _FIXED.values():
        raise ValueError(f"invalid fixed action {action!r}: allowed 0..=4 or {', '.join(_FIXED.values())}")
    return Policy(name)


def episodes(
    name: str, n: int = 1, seed: int = 0, *, max_episode_steps: int | None = 10_000, **options: Any
) -> Iterator[dict[str, Any]]:
    """Plays `n` episodes of the built-in policy `name` exactly as `chopperscape demo --policy NAME --episodes N
    --seed S --json` does (episode `i` from seed `S + i`, the policy restarted with that seed) and yields what it
    prints: `{"episode", "seed", "steps", "return", "cause"}`, plus `"actions"` (the list of actions taken).
    `options` are the env's keyword options (`frame_skip=4`, `lives=3`, ...); `max_episode_steps=None` plays
    without a time limit. The arguments are checked at once (`ValueError`), before the first episode."""
    seed = _check_seed(seed)
    n = positive_int("n", n)
    policy = Policy(name, seed)
    env = make_env(max_episode_steps, **{**options, "obs_type": "features"})
    return _play(policy, env, n, seed)


def _play(policy: Policy, env: gym.Env, n: int, seed: int) -> Iterator[dict[str, Any]]:
    try:
        for i in range(n):
            s = (seed + i) % 2**64
            policy.reset(s)
            env.reset(seed=s)
            total, actions, cause = 0, [], None
            while True:
                action = policy.act(env)
                _, reward, terminated, truncated, info = env.step(action)
                actions.append(action)
                total += int(float(reward))
                if terminated or truncated:
                    cause = info.get("cause", "truncated") if terminated else "truncated"
                    break
            yield {"episode": i, "seed": s, "steps": len(actions), "return": total, "cause": cause, "actions": actions}
    finally:
        env.close()
