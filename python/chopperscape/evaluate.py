"""Evaluates a trained policy on held-out seeds and prints one JSON object.

    python -m chopperscape.evaluate MODEL --episodes 100 --seed 1000000

`MODEL` is a file written by ``python -m chopperscape.train`` (``model.pt``), a Stable-Baselines3 ``.zip`` (then
give the env options it was trained with: ``--option obs_type='"features"'``; a ``vecnormalize.pkl`` beside it
normalises the observations as in training), or the name of a built-in pilot
(``random``, ``heuristic``, ``noop``…, see ``chopperscape.pilots``), so that baselines come from the same seeds. Episode ``k`` is played on seed
``S + k`` (the seeds of a ``VectorEnv`` reset with ``seed=S``), each to its end or to the 10,000-step truncation,
with the greedy action (``--stochastic`` samples instead, from a generator seeded with ``S``). The output:

    {"model": ..., "episodes": 100, "seed": 1000000, "mean_return": ..., "std_return": ..., "min_return": ...,
     "max_return": ..., "mean_steps": ..., "causes": {"bird": 0.62, "fuel": 0.08, "truncated": 0.30}, ...}

where ``causes`` gives the share of episodes that ended each way.
"""

from __future__ import annotations

import argparse
import json
import sys
from pathlib import Path
from typing import Any, Callable

import numpy as np

from ._cli import env_options
from .vector import VectorEnv

#: Most environments stepped together while evaluating (bounded memory, whatever `--episodes`).
CHUNK = 128


def play_episodes(
    act: Callable[[np.ndarray, VectorEnv], np.ndarray], episodes: int, seed: int, env_options: dict[str, Any],
    max_episode_steps: int | None = 10_000,
) -> list[dict[str, Any]]:
    """Plays `episodes` episodes on seeds `seed, seed + 1, …` with `act(obs_batch, envs) -> actions` (`envs`, the
    `VectorEnv` being played, is for pilots that read the game); one dict each (`seed`, `return`, `steps`,
    `cause`)."""
    if isinstance(episodes, bool) or not isinstance(episodes, int) or episodes < 1:
        raise ValueError(f"invalid value {episodes!r} for `episodes`: allowed an integer >= 1")
    results: list[dict[str, Any]] = []
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
            while live.any():
                obs, reward, term, trunc, info = envs.step(np.asarray(act(obs, envs), dtype=np.int64))
                ret += np.where(live, reward, 0).astype(np.int64)
                steps += live
                ended = live & (term | trunc)
                for i in np.flatnonzero(ended):
                    causes[i] = str(info["cause"][i]) if term[i] else "truncated"
                live &= ~ended
        finally:
            envs.close()
        results += [
            {"seed": seed + first + i, "return": int(ret[i]), "steps": int(steps[i]), "cause": causes[i]}
            for i in range(n)
        ]
    return results


def summary(results: list[dict[str, Any]]) -> dict[str, Any]:
    """Mean, spread and end causes of a list of `play_episodes` results."""
    rets = np.array([r["return"] for r in results], dtype=np.float64)
    causes: dict[str, float] = {}
    for r in results:
        causes[r["cause"]] = causes.get(r["cause"], 0) + 1 / len(results)
    return {
        "episodes": len(results),
        "mean_return": round(float(rets.mean()), 1),
        "std_return": round(float(rets.std()), 1),
        "min_return": int(rets.min()),
        "max_return": int(rets.max()),
        "mean_steps": round(float(np.mean([r["steps"] for r in results])), 1),
        "causes": {k: round(v, 3) for k, v in sorted(causes.items())},
    }


class _PilotPlayer:
    """A built-in pilot over each chunk of environments: pilot `i` seeded as environment `i` (`S + i`)."""

    def __init__(self, name: str):
        self.name = name
        self.pilot = None

    def start_chunk(self, n: int, seed: int) -> None:
        from .pilots import VectorPilot

        self.pilot = VectorPilot(self.name, n, seed=seed)

    def __call__(self, obs: np.ndarray, envs: VectorEnv) -> np.ndarray:
        return self.pilot.act(envs)


def load_policy(path: Path, stochastic: bool, seed: int, env_options: dict[str, Any]):
    """`(act, env_options)` for a model file (a recipe `model.pt`, a Stable-Baselines3 `.zip`) or a pilot name."""
    from .pilots import NAMES

    if not path.exists() and str(path) in NAMES:
        return _PilotPlayer(str(path)), {"obs_type": "features", **env_options}
    if not path.is_file():
        raise ValueError(
            f"model file {str(path)!r} does not exist (give a model.pt from chopperscape.train, an SB3 .zip, "
            f"or a pilot name: {', '.join(NAMES)})"
        )
    if path.suffix == ".zip":
        from stable_baselines3 import PPO

        model = PPO.load(path, device="cpu")
        # A VecNormalize saved beside the model (as `python/examples/sb3_ppo.py --tuned` does) normalises its inputs.
        stats = path.with_name("vecnormalize.pkl")
        if stats.is_file():
            import pickle

            with open(stats, "rb") as f:
                norm = pickle.load(f)
            norm.training = False
            return (lambda obs, envs: model.predict(norm.normalize_obs(obs), deterministic=not stochastic)[0]), env_options
        return (lambda obs, envs: model.predict(obs, deterministic=not stochastic)[0]), env_options
    import torch

    from .train import Agent, ObsNormalizer, RunningMeanStd

    # One thread: a small MLP gains nothing from more, and OpenMP spinning under load can slow it by 100x.
    torch.set_num_threads(1)

    try:
        payload = torch.load(path, map_location="cpu", weights_only=False)
    except Exception as err:
        raise ValueError(f"model file {str(path)!r} is not a chopperscape.train model: {err}") from None
    if not isinstance(payload, dict) or payload.get("format") != "chopperscape-ppo/1":
        raise ValueError(f"model file {str(path)!r} is not a chopperscape.train model (format chopperscape-ppo/1)")
    recipe = payload["recipe"]
    agent = Agent(payload["obs_dim"], payload["num_actions"], recipe["hidden"])
    agent.actor.load_state_dict(payload["actor"])
    agent.critic.load_state_dict(payload["critic"])
    agent.eval()
    norm = ObsNormalizer((payload["obs_dim"],), payload["obs_rms"] is not None)
    if payload["obs_rms"] is not None:
        norm.rms = RunningMeanStd.from_state(payload["obs_rms"])
    gen = torch.Generator().manual_seed(seed)

    def act(obs: np.ndarray, envs: VectorEnv) -> np.ndarray:
        with torch.no_grad():
            logits = agent.actor(torch.from_numpy(norm(obs)))
            if stochastic:
                return torch.multinomial(logits.softmax(-1), 1, generator=gen).squeeze(-1).numpy()
            return logits.argmax(-1).numpy()

    options = {"obs_type": recipe["obs_type"], **recipe["env_options"], **env_options}
    return act, options


def main(argv: list[str] | None = None) -> int:
    p = argparse.ArgumentParser(prog="python -m chopperscape.evaluate", description=__doc__.splitlines()[0])
    p.add_argument("model", type=Path, help="model.pt from chopperscape.train, an SB3 .zip, or a pilot name")
    p.add_argument("--episodes", type=int, default=100, help="episodes to play (default 100)")
    p.add_argument("--seed", type=int, default=1_000_000, help="first seed (default 1000000, held out from training)")
    p.add_argument("--stochastic", action="store_true", help="sample actions instead of taking the greedy one")
    p.add_argument("--option", action="append", default=[], metavar="NAME=VALUE", help="env option (JSON value)")
    p.add_argument("--per-episode", action="store_true", help="also list every episode")
    a = p.parse_args(argv)
    if a.episodes < 1:
        p.error(f"--episodes {a.episodes}: allowed an integer >= 1")
    if not 0 <= a.seed < 2**63:
        p.error(f"--seed {a.seed}: allowed 0 <= seed < 2**63")
    options = env_options(p, a.option)
    try:
        act, play_options = load_policy(a.model, a.stochastic, a.seed, options)
        results = play_episodes(act, a.episodes, a.seed, play_options)
    except ValueError as err:
        print(f"error: {err}", file=sys.stderr)
        return 2
    out: dict[str, Any] = {"model": str(a.model), "seed": a.seed}
    if not isinstance(act, _PilotPlayer):
        out["greedy"] = not a.stochastic
    out.update(summary(results))
    if a.per_episode:
        out["per_episode"] = results
    print(json.dumps(out))
    return 0


if __name__ == "__main__":
    sys.exit(main())
