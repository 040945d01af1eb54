"""Playing a policy on seeds and summarising the episodes, in constant memory: what held-out evaluation
(`python -m chopperscape.learn.evaluate`), the seed runner's baselines, ChopperScape-Bench and the RLlib example
measure with.

Episode `k` of `iter_episodes(act, n, S, options)` is played on seed `S + k` (the seeds of a `VectorEnv` reset with
`seed=S`), to its end or to the step limit, at most `CHUNK` episodes at a time; `Summary` adds them up as they end.
"""

from __future__ import annotations

import math
from collections.abc import Iterable, Iterator
from typing import Any, Callable

import numpy as np

from ..vector import VectorEnv

#: Most environments stepped together while evaluating (bounded memory, whatever `--episodes`).
CHUNK = 128
#: The most episodes one evaluation plays (`--episodes`): hours of CPU, constant memory.
MAX_EPISODES = 1_000_000


def iter_episodes(
    act: Callable[[np.ndarray, VectorEnv], np.ndarray],
    episodes: int,
    seed: int,
    env_options: dict[str, Any],
    max_episode_steps: int | None = 10_000,
    keep_actions: int = 0,
) -> Iterator[dict[str, Any]]:
    """Plays `episodes` episodes on seeds `seed, seed + 1, …` with `act(obs_batch, envs) -> actions` (`envs`, the
    `VectorEnv` being played, is for built-in policies that read the game) and yields one dict each, in seed order
    (`seed`, `return`, `steps`, `cause`, and for the first `keep_actions` episodes `actions`, the list of actions
    taken). At most `CHUNK` episodes are played at once and nothing of a chunk is kept once it is yielded, so the
    memory does not grow with `episodes`."""
    if isinstance(episodes, bool) or not isinstance(episodes, int) or episodes < 1:
        raise ValueError(f"invalid value {episodes!r} for `episodes`: allowed an integer >= 1")
    if "max_episode_steps" in env_options:
        env_options = dict(env_options)
        max_episode_steps = env_options.pop("max_episode_steps")
    for first in range(0, episodes, CHUNK):
        n = min(CHUNK, episodes - first)
        envs = VectorEnv(n, num_threads=1, max_episode_steps=max_episode_steps, **env_options)
        try:
            obs, _ = envs.reset(seed=seed + first)
            if hasattr(act, "start_chunk"):
                act.start_chunk(n, seed + first)
            ret, steps = np.zeros(n, np.int64), np.zeros(n, np.int64)
            live = np.ones(n, bool)
            causes: list[str | None] = [None] * n
            kept: list[list[int]] = [[] for _ in range(max(0, min(n, keep_actions - first)))]
            while live.any():
                actions = np.asarray(act(obs, envs), dtype=np.int64)
                for i, taken in enumerate(kept):
                    if live[i]:
                        taken.append(int(actions[i]))
                obs, reward, term, trunc, info = envs.step(actions)
                ret += np.where(live, reward, 0).astype(np.int64)
                steps += live
                ended = live & (term | trunc)
                for j in np.flatnonzero(ended).tolist():
                    causes[j] = str(info["cause"][j]) if term[j] else "truncated"
                live &= ~ended
        finally:
            envs.close()
        for i in range(n):
            row: dict[str, Any] = {"seed": seed + first + i, "return": int(ret[i]), "steps": int(steps[i])}
            row["cause"] = causes[i]
            if i < len(kept):
                row["actions"] = kept[i]
            yield row


def play_episodes(
    act: Callable[[np.ndarray, VectorEnv], np.ndarray],
    episodes: int,
    seed: int,
    env_options: dict[str, Any],
    max_episode_steps: int | None = 10_000,
    keep_actions: int = 0,
) -> list[dict[str, Any]]:
    """:func:`iter_episodes` as a list (one dict per episode: for a few hundred episodes; the command line
    streams them)."""
    return list(iter_episodes(act, episodes, seed, env_options, max_episode_steps, keep_actions))


class Summary:
    """Mean, spread and end causes of episodes added one at a time (:meth:`add`), in constant memory: returns and
    steps are integers, so their sums are exact and the order they come in does not matter."""

    def __init__(self) -> None:
        self.n = 0
        self.sum = self.sum_sq = self.steps = 0
        self.min: int | None = None
        self.max: int | None = None
        self.causes: dict[str, int] = {}

    def add(self, r: dict[str, Any]) -> None:
        ret = int(r["return"])
        self.n += 1
        self.sum += ret
        self.sum_sq += ret * ret
        self.steps += int(r["steps"])
        self.min = ret if self.min is None else min(self.min, ret)
        self.max = ret if self.max is None else max(self.max, ret)
        self.causes[str(r["cause"])] = self.causes.get(str(r["cause"]), 0) + 1

    def result(self) -> dict[str, Any]:
        n = self.n
        if n == 0:
            raise ValueError("no episodes to summarise")
        var = (n * self.sum_sq - self.sum * self.sum) / (n * n)  # exact integers until this division
        return {
            "episodes": n,
            "mean_return": round(self.sum / n, 1),
            "std_return": round(math.sqrt(max(var, 0.0)), 1),
            "min_return": self.min,
            "max_return": self.max,
            "mean_steps": round(self.steps / n, 1),
            "causes": {k: round(v / n, 3) for k, v in sorted(self.causes.items())},
        }


def summary(results: Iterable[dict[str, Any]]) -> dict[str, Any]:
    """Mean, spread and end causes of `play_episodes` results (:class:`Summary`)."""
    acc = Summary()
    for r in results:
        acc.add(r)
    return acc.result()
