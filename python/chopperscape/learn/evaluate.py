"""Evaluates a trained policy on held-out seeds and prints one JSON object.

    python -m chopperscape.learn.evaluate MODEL --episodes 100 --seed 1000000

`MODEL` is a file written by ``python -m chopperscape.learn.train`` (``model.pt``), a Stable-Baselines3 ``.zip`` (then
give the env options it was trained with: ``--option obs_type=features``; a ``vecnormalize.json`` beside it, from
``chopperscape.integrations.sb3.save_normalization``, normalises the observations as in training), or the name of a
built-in
built-in policy (``random``, ``heuristic``, ``noop``…, see ``chopperscape.policies``), so that baselines come from
the same seeds; a file named like a built-in policy is given as ``./NAME``.

Loading a model never runs code from it: a recipe model is read with ``torch.load(weights_only=True)`` (tensors
and plain data), and the pickled parts of an SB3 ``.zip`` are replaced by what the env gives. Pickles (SB3's
``vecnormalize.pkl``, an SB3 model whose settings cannot be rebuilt) are refused unless ``--trust-pickle``: give it
only for files whose author you trust.

Episode ``k`` is played on seed ``S + k`` (the seeds of a ``VectorEnv`` reset with ``seed=S``), each to its end or
to the 10,000-step truncation (``--option max_episode_steps=N``, or ``none``; a recipe model trained with
``--option max_episode_steps=N`` plays to its own ``N`` unless ``--option`` gives another; one trained with ``none``
to 10,000), with the greedy action
(``--stochastic`` samples instead, from a generator seeded with ``S``). The output:

    {"model": ..., "episodes": 100, "seed": 1000000, "mean_return": ..., "std_return": ..., "min_return": ...,
     "max_return": ..., "mean_steps": ..., "causes": {"bird": 0.62, "fuel": 0.08, "truncated": 0.30}, ...}

Memory does not grow with ``--episodes`` (at most 1,000,000): episodes are played ``CHUNK`` at a time and summarised
as they end, and the ``--per-episode`` rows wait in a temporary file until the line is written. ``causes`` gives
the share of episodes that ended each way (``--per-episode`` adds each episode's seed,
return, steps and cause: the episodes ``chopperscape demo --policy MODEL.onnx --json`` plays for the same
``--seed``, from the export of the same model).

``--video out.gif`` (or ``out.mp4``, through the ``ffmpeg`` program) also writes the first ``--video-episodes K``
episodes (default 1) one after the other, at 30 frames a second, as the command line's ``record`` draws them
(600 × 800, the text HUD). The episodes are played first and their actions replayed to draw them, so the video
shows exactly the episodes of the result line.
"""

from __future__ import annotations

import argparse
import importlib.util
import itertools
import json
import math
import sys
import tempfile
from collections.abc import Iterable, Iterator
from pathlib import Path
from typing import Any, Callable

import numpy as np

from .._checks import regular_file
from .._cli import env_options, print_chunks, print_line
from ..policies import NAMES, VectorPolicy
from ..vector import VectorEnv
from .recipe import MAX_MODEL_BYTES

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


class _BuiltinPlayer:
    """A built-in policy over each chunk of environments: policy `i` seeded as environment `i` (`S + i`)."""

    def __init__(self, name: str):
        self.name = name
        self.policy: VectorPolicy | None = None

    def start_chunk(self, n: int, seed: int) -> None:

        self.policy = VectorPolicy(self.name, n, seed=seed)

    def __call__(self, obs: np.ndarray, envs: VectorEnv) -> np.ndarray:
        assert self.policy is not None
        return self.policy.act(envs)


#: `--option` names evaluation does not take, and why.
REFUSED_OPTIONS = {
    "num_threads": "evaluation steps its own batch on one thread (results do not depend on threads)",
    "autoreset_mode": "evaluation plays each episode once to its end; it needs no autoreset mode",
    "copy": "evaluation reads each step's arrays itself; it takes no `copy`",
    "render_mode": "evaluation draws nothing itself; give --video FILE (.gif or .mp4) for a video",
}


def observation_shape(options: dict[str, Any]) -> tuple[int, ...]:
    """The observation shape of one env with `options` (a `ValueError` naming a bad option)."""
    options = {"max_episode_steps": None, **options}
    envs = VectorEnv(1, num_threads=1, **options)
    try:
        return tuple(envs.single_observation_space.shape or ())
    finally:
        envs.close()


def load_policy(
    model: str | Path, stochastic: bool, seed: int, env_options: dict[str, Any], trust_pickle: bool = False
):
    """`(act, env_options)` for a model file (a recipe `model.pt`, a Stable-Baselines3 `.zip`) or a built-in
    policy's name.

    A bare built-in name (`"random"`, a `str`) is always that policy; a file of that name is read as `./random` (or a
    `Path`). Loading never runs code from the file (see `load_recipe`, `load_sb3`) unless `trust_pickle`."""
    if isinstance(model, str) and model in NAMES:
        return _BuiltinPlayer(model), {"obs_type": "features", **env_options}
    path = Path(model)
    if not path.exists() and not path.is_symlink():
        raise ValueError(
            f"model file {str(path)!r} does not exist (give a model.pt from chopperscape.learn.train, an SB3 .zip, "
            f"or a built-in policy: {', '.join(NAMES)})"
        )
    regular_file(path, f"model file {str(path)!r}", MAX_MODEL_BYTES)
    needs = ("torch", "stable_baselines3") if path.suffix == ".zip" else ("torch",)
    missing = [m for m in needs if importlib.util.find_spec(m) is None]
    if missing:
        raise ValueError(
            f"reading model file {str(path)!r} needs {' and '.join(missing)}, which is not installed: "
            "pip install 'chopperscape[train]'"
        )
    if path.suffix == ".zip":
        return load_sb3(path, stochastic, env_options, trust_pickle)
    return load_recipe(path, stochastic, seed, env_options)


def load_recipe(path: Path, stochastic: bool, seed: int, env_options: dict[str, Any]):
    """`(act, env_options)` for a `chopperscape.learn.train` model. Read with `torch.load(weights_only=True)`: tensors
    and plain data only, so a crafted file cannot run code; its fields are then checked one by one."""
    import torch

    # One thread: a small MLP gains nothing from more, and OpenMP spinning under load can slow it by 100x.
    torch.set_num_threads(1)
    what = f"model file {str(path)!r}"
    from .model import load

    agent, model_shape, norm, recipe = load(path, what)
    options = {"obs_type": recipe["obs_type"], **recipe["env_options"], **env_options}
    shape = observation_shape(options)
    if shape != model_shape:
        raise ValueError(
            f"{what} takes observations of shape {model_shape}, but these env options give observations of shape "
            f"{shape} ({_describe(options)}): evaluate it with the options it was trained with"
        )
    gen = torch.Generator().manual_seed(seed)

    def act(obs: np.ndarray, envs: VectorEnv) -> np.ndarray:
        with torch.no_grad():
            logits = agent.actor(torch.from_numpy(norm(obs)))
            if stochastic:
                return torch.multinomial(logits.softmax(-1), 1, generator=gen).squeeze(-1).numpy()
            return logits.argmax(-1).numpy()

    return act, options


def _describe(options: dict[str, Any]) -> str:
    return ", ".join(f"{k}={v!r}" for k, v in options.items()) or "the defaults"


def load_sb3(path: Path, stochastic: bool, env_options: dict[str, Any], trust_pickle: bool = False):
    """`(act, env_options)` for a Stable-Baselines3 PPO `.zip`, with the observation normalisation saved beside it.

    SB3 stores the model's settings as JSON, but some of them (the spaces, the policy class, schedules) as
    cloudpickle, which runs code when loaded; its weights are read with `weights_only=True`. Unless
    `trust_pickle`, no pickle is loaded: every pickled setting is replaced by what this env and SB3's own
    classes give (named by the readable copy SB3 stores beside it), and a setting that cannot be is refused.
    Normalisation: `vecnormalize.json` (`chopperscape.integrations.sb3.save_normalization`) is read as data; SB3's
    `vecnormalize.pkl` is a pickle, read only with `trust_pickle`."""
    from stable_baselines3 import PPO

    from ..integrations import sb3

    what = f"model file {str(path)!r}"
    # As the adapter gives them (`ChopperScapeVecEnv(keep_dim=True)`): grayscale with a channel axis.
    env_options = {"keep_dim": True, **env_options}
    shape = observation_shape(env_options)
    if trust_pickle:
        model = PPO.load(path, device="cpu")
    else:
        custom = sb3.safe_load_objects(path, env_options)
        try:
            model = PPO.load(path, device="cpu", custom_objects=custom)
        except (RuntimeError, KeyError, TypeError, AttributeError) as e:
            raise ValueError(
                f"{what} could not be read without unpickling ({str(e).splitlines()[0]}); pass "
                "--trust-pickle if you trust who made it"
            ) from None
    model_shape = tuple(model.observation_space.shape or ())
    if model_shape != shape:
        raise ValueError(
            f"{what} takes observations of shape {model_shape}, but these env options give {shape} "
            f"({_describe(env_options)}): give the options it was trained with (--option ...)"
        )
    norm = sb3.load_normalization(path.parent, trust_pickle)

    def act(obs: np.ndarray, envs: VectorEnv) -> np.ndarray:
        return model.predict(obs if norm is None else norm(obs), deterministic=not stochastic)[0]

    return act, env_options


def main(argv: list[str] | None = None) -> int:
    p = argparse.ArgumentParser(prog="python -m chopperscape.learn.evaluate", description=__doc__.splitlines()[0])
    p.add_argument(
        "model",
        help="model.pt from chopperscape.learn.train, an SB3 .zip, or a built-in policy's name (a file "
        "named like one: ./NAME)",
    )
    p.add_argument("--episodes", type=int, default=100, help="episodes to play (default 100)")
    p.add_argument("--seed", type=int, default=1_000_000, help="first seed (default 1000000, held out from training)")
    p.add_argument("--stochastic", action="store_true", help="sample actions instead of taking the greedy one")
    p.add_argument(
        "--option",
        action="append",
        default=[],
        metavar="NAME=VALUE",
        help="env option, as the command line's flags take it (obs_size=84x84, hud=false, max_episode_steps=none)",
    )
    p.add_argument("--per-episode", action="store_true", help="also list every episode")
    p.add_argument(
        "--video",
        metavar="FILE",
        help="also write the first episodes as a video: .gif (Pillow) or .mp4 "
        "(needs the ffmpeg program); an existing file is replaced",
    )
    p.add_argument(
        "--video-episodes", type=int, default=1, metavar="K", help="episodes in the --video, from the first (default 1)"
    )
    p.add_argument(
        "--trust-pickle",
        action="store_true",
        help="allow pickled parts of an SB3 .zip and a vecnormalize.pkl beside it: pickles run code when "
        "loaded, so only for files whose author you trust",
    )
    a = p.parse_args(argv)
    if not 1 <= a.episodes <= MAX_EPISODES:
        p.error(f"--episodes {a.episodes}: allowed an integer in 1..={MAX_EPISODES}")
    if not 0 <= a.seed < 2**63:
        p.error(f"--seed {a.seed}: allowed 0 <= seed < 2**63")
    if not 1 <= a.video_episodes <= a.episodes:
        p.error(f"--video-episodes {a.video_episodes}: allowed 1..=--episodes ({a.episodes})")
    options = env_options(p, a.option, refused=REFUSED_OPTIONS)
    given = "max_episode_steps" in options
    limit = options.pop("max_episode_steps", 10_000)
    keep = a.video_episodes if a.video is not None else 0
    acc = Summary()
    kept: list[dict[str, Any]] = []
    # The per-episode rows wait in a temporary file, not in memory, until the result line is written.
    rows = tempfile.TemporaryFile("w+", encoding="utf-8") if a.per_episode else None
    try:
        if a.video is not None:
            from . import video

            video.check_destination(Path(a.video))
        act, play_options = load_policy(a.model, a.stochastic, a.seed, options, trust_pickle=a.trust_pickle)
        # The model's own truncation (a recipe model trained with max_episode_steps=N) unless --option gives one;
        # a model trained without one (`none`) is still evaluated to 10,000 steps, so that evaluation ends.
        if given or play_options.get("max_episode_steps") is None:
            play_options["max_episode_steps"] = limit
        limit = play_options["max_episode_steps"]
        for i, r in enumerate(iter_episodes(act, a.episodes, a.seed, play_options, keep_actions=keep)):
            acc.add(r)
            if i < keep:
                kept.append(r)
            if rows is not None:
                rows.write(("" if i == 0 else ", ") + json.dumps({k: v for k, v in r.items() if k != "actions"}))
        if a.video is not None:
            try:
                video.write(Path(a.video), play_options, kept)
            except OSError as err:
                print(f"error: cannot write {a.video}: {err.strerror or err}", file=sys.stderr)
                return 1
        out: dict[str, Any] = {"model": str(a.model), "seed": a.seed}
        if not isinstance(act, _BuiltinPlayer):
            out["greedy"] = not a.stochastic
        if limit != 10_000:
            out["max_episode_steps"] = limit
        out.update(acc.result())
        tail = {"video": a.video} if a.video is not None else {}
        if rows is None:
            return print_line(json.dumps({**out, **tail}))
        rows.seek(0)
        head = json.dumps(out)[:-1] + ', "per_episode": ['
        end = "]" + (", " + json.dumps(tail)[1:] if tail else "}")
        return print_chunks(itertools.chain([head], iter(lambda: rows.read(1 << 16), ""), [end]))
    except ValueError as err:
        print(f"error: {err}", file=sys.stderr)
        return 2
    except OSError as err:  # the temporary file of the per-episode rows
        print(f"error: cannot hold the per-episode rows in a temporary file: {err.strerror or err}", file=sys.stderr)
        return 1
    finally:
        if rows is not None:
            rows.close()


if __name__ == "__main__":
    sys.exit(main())
