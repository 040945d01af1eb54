"""Datasets in Farama's Minari format: episodes of a built-in pilot, or human play replayed from action logs.

>>> from chopperscape import datasets
>>> ds = datasets.collect("chopperscape/heuristic-features-v0", pilot="heuristic", episodes=100,
...                       obs_type="features")
>>> import minari; minari.load_dataset("chopperscape/heuristic-features-v0")  # the same dataset

Datasets are written under `MINARI_DATASETS_PATH` (default `~/.minari/datasets`), where `minari.load_dataset`
finds them, in Minari's HDF5 layout through Minari's own storage classes, with images stored raw (lossless,
`jpeg_encoding=False`), so a dataset equals a replay of its seeds exactly. Needs `pip install "minari[hdf5]"`.

- Episode `i` of `collect(..., seed=S)` is played from `reset(seed=S + i)` with the pilot restarted with that seed:
  exactly the episodes of `chopperscape demo --policy P --episodes N --seed S`.
- Each episode's seed is stored (Minari's episode metadata `seed`); the dataset metadata holds the env spec (with
  every option), `chopperscape_version`, `pilot`, `seeds`, `env_options` and `max_episode_steps`.
- Steps stream to disk every `chunk_steps` steps, so memory stays bounded however long the collection; the
  dataset is written in a temporary folder next to its place and moved there at the end, so an interrupted
  collection leaves nothing behind and an existing dataset is never overwritten.
- `from_action_logs` replays `chopperscape play --save-actions` logs (human play) into a dataset and checks that
  each replay reaches the steps and return its log recorded.
"""

from __future__ import annotations

import json
import os
import pathlib
import shutil
import sys
import tempfile
import time
from typing import Any, Callable, Iterable, Iterator

import gymnasium as gym
import numpy as np

from . import _core, pilots

__all__ = ["collect", "from_action_logs", "read_action_log"]

ENV_ID = "ChopperScape-v0"
#: The rules options of an action log, at their v0 values (a log may leave any of them out).
_RULES = {"lives": "1", "bird_fuel_collision": "pass", "alien_prob": "0", "frame_skip": "1", "sticky_prob": "0",
          "bird_prob": "0.01", "fuel_prob": "0.01", "max_fuel": "1000"}


def _same_rules(a: dict, b: dict) -> bool:
    def norm(o: dict) -> dict:
        out = {}
        for k, v in {**_RULES, **o}.items():
            try:
                out[k] = float(v)
            except ValueError:
                out[k] = str(v).lower()
        return out

    return norm(a) == norm(b)
LOG_FORMAT, LOG_VERSION = "chopperscape-actions", 1


def _minari():
    try:
        import h5py  # noqa: F401
        import PIL  # noqa: F401  (Minari's HDF5 storage imports it)
        import minari
        from minari.data_collector import EpisodeBuffer
        from minari.dataset.minari_storage import MinariStorage
    except ImportError as e:
        raise ImportError(
            f'chopperscape.datasets needs Minari with HDF5 support: pip install "minari[hdf5]" pillow ({e})'
        ) from None
    return minari, EpisodeBuffer, MinariStorage


class _Progress:
    """A one-line progress report on standard error: episodes, steps, steps per second."""

    def __init__(self, total: int, enabled: bool):
        self.total, self.enabled, self.start, self.last = total, enabled, time.monotonic(), 0.0

    def update(self, episodes: int, steps: int, force: bool = False) -> None:
        now = time.monotonic()
        if not self.enabled or (not force and now - self.last < 0.5):
            return
        self.last = now
        rate = steps / max(now - self.start, 1e-9)
        sys.stderr.write(f"\rcollecting: {episodes}/{self.total} episodes, {steps} steps, {rate:,.0f} steps/s ")
        sys.stderr.flush()

    def close(self) -> None:
        if self.enabled:
            sys.stderr.write("\n")


def _dataset_dir(dataset_id: str) -> pathlib.Path:
    minari, _, _ = _minari()
    from minari.dataset.minari_dataset import parse_dataset_id
    from minari.storage.datasets_root_dir import get_dataset_path

    namespace = parse_dataset_id(dataset_id)[0]  # ValueError for a malformed id, naming the expected form
    path = pathlib.Path(get_dataset_path(dataset_id))
    if path.exists():
        raise ValueError(
            f"a Minari dataset {dataset_id!r} already exists at {path}: choose another name or version, or delete "
            f"it with minari.delete_dataset({dataset_id!r})"
        )
    if namespace is not None:
        from minari.namespace import create_namespace, list_local_namespaces

        if namespace not in list_local_namespaces():
            create_namespace(namespace)
    return path


def _write(
    dataset_id: str,
    env: gym.Env,
    episodes: Iterable[tuple[int, Callable[[], int | None]]],
    total: int,
    metadata: dict[str, Any],
    chunk_steps: int,
    progress: bool | None,
):
    """Plays each `(seed, next_action)` episode in `env` (`next_action()` returns None to stop the episode
    early: its last step is then marked truncated, as Minari's DataCollector does) into a new dataset."""
    minari, EpisodeBuffer, MinariStorage = _minari()
    if isinstance(chunk_steps, bool) or not isinstance(chunk_steps, int) or chunk_steps < 1:
        raise ValueError(f"invalid value {chunk_steps!r} for option `chunk_steps`: allowed an integer >= 1")
    final = _dataset_dir(dataset_id)
    final.parent.mkdir(parents=True, exist_ok=True)
    tmp = pathlib.Path(tempfile.mkdtemp(prefix=f".{final.name}.", dir=final.parent))
    bar = _Progress(total, sys.stderr.isatty() if progress is None else bool(progress))
    try:
        storage = MinariStorage.new(
            tmp / "data",
            observation_space=env.observation_space,
            action_space=env.action_space,
            env_spec=env.spec,
            data_format="hdf5",
            jpeg_encoding=False,
        )
        all_steps, seeds = 0, []
        for ep, (seed, next_action) in enumerate(episodes):
            obs, _ = env.reset(seed=seed)
            seeds.append(seed)
            o, a, r, te, tr = [obs], [], [], [], []
            first, steps, ret = True, 0, 0.0

            def flush() -> None:
                nonlocal first, o, a, r, te, tr
                if not a:
                    return
                storage.update_episodes(
                    [
                        EpisodeBuffer(
                            id=ep,
                            seed=seed if first else None,
                            observations=np.stack(o),
                            actions=np.asarray(a, dtype=np.int64),
                            rewards=np.asarray(r, dtype=np.float64),
                            terminations=np.asarray(te, dtype=np.bool_),
                            truncations=np.asarray(tr, dtype=np.bool_),
                        )
                    ]
                )
                first, o, a, r, te, tr = False, [], [], [], [], []

            while True:
                action = next_action()
                if action is None:
                    if not a:
                        raise ValueError(f"episode {ep} (seed {seed}) has no steps: a dataset episode needs one")
                    tr[-1] = tr[-1] or not te[-1]
                    break
                obs, reward, terminated, truncated, _ = env.step(action)
                o.append(obs)
                a.append(action)
                r.append(float(reward))
                te.append(bool(terminated))
                tr.append(bool(truncated))
                steps += 1
                ret += float(reward)
                if terminated or truncated:
                    break
                if len(a) >= chunk_steps:
                    flush()
                    bar.update(ep, all_steps + steps)
            flush()
            all_steps += steps
            storage.update_episode_metadata([{"total_steps": steps, "rewards_sum": ret}], [ep])
            bar.update(ep + 1, all_steps)
        bar.update(len(seeds), all_steps, force=True)
        storage.update_metadata({**metadata, "seeds": seeds})
        umask = os.umask(0)
        os.umask(umask)
        os.chmod(tmp, 0o777 & ~umask)  # mkdtemp made it private
        os.replace(tmp, final)
    except BaseException:
        shutil.rmtree(tmp, ignore_errors=True)
        raise
    finally:
        bar.close()
    return minari.load_dataset(dataset_id)


def _metadata(dataset_id: str, algorithm: str, options: dict, max_episode_steps: int | None, **extra: Any) -> dict:
    minari, _, _ = _minari()
    meta = {
        "dataset_id": dataset_id,
        "minari_version": minari.__version__,
        "algorithm_name": algorithm,
        "code_permalink": "https://github.com/chopperscape/chopperscape",
        "requirements": [f"chopperscape=={_core.__version__}"],
        "chopperscape_version": _core.__version__,
        "env_options": {k: (list(v) if isinstance(v, tuple) else v) for k, v in options.items()},
        "max_episode_steps": max_episode_steps,
    }
    meta.update({k: v for k, v in extra.items() if v is not None})
    return meta


def collect(
    dataset_id: str,
    pilot: str = "heuristic",
    episodes: int = 1,
    seed: int = 0,
    *,
    max_episode_steps: int | None = 10_000,
    chunk_steps: int = 1000,
    progress: bool | None = None,
    author: str | None = None,
    description: str | None = None,
    **options: Any,
):
    """Plays `episodes` episodes of the built-in `pilot` (see `chopperscape.pilots.NAMES`) into a new Minari
    dataset `dataset_id` (`"namespace/name-vN"`) and returns it (`minari.MinariDataset`). `options` are the env's
    keyword options (`obs_type="grayscale"`, `obs_size=(84, 84)`, `frame_skip=4`, ...). Episode `i` starts from
    `reset(seed=seed + i)` with the pilot restarted with that seed, as `chopperscape demo` plays them."""
    pilots._check_name(pilot)
    seed = pilots._check_seed(seed)
    if isinstance(episodes, bool) or not isinstance(episodes, (int, np.integer)) or episodes < 1:
        raise ValueError(f"invalid value {episodes!r} for option `episodes`: allowed an integer >= 1")
    env = gym.make(ENV_ID, max_episode_steps=max_episode_steps, **options)
    player = pilots.Pilot(pilot, seed)

    def plays() -> Iterator[tuple[int, Callable[[], int]]]:
        for i in range(int(episodes)):
            s = (seed + i) % 2**64
            player.reset(s)
            yield s, lambda: player.act(env)

    meta = _metadata(
        dataset_id,
        f"chopperscape.pilots:{pilot}",
        options,
        max_episode_steps,
        pilot=pilot,
        author={author} if author else None,
        description=description
        or f"{episodes} episodes of the {pilot} pilot on {ENV_ID} (seeds {seed}..{seed + int(episodes) - 1})",
    )
    try:
        return _write(dataset_id, env, plays(), int(episodes), meta, chunk_steps, progress)
    finally:
        env.close()


def read_action_log(path: str | os.PathLike) -> dict[str, Any]:
    """Reads a `chopperscape play --save-actions` (or `record`) log: `{"seed", "options", "actions", "steps",
    "return", "cause", "policy"}`, with `options` as the env's keyword options (text values) and
    `max_episode_steps` apart. `ValueError` naming the file and what is wrong for anything else."""
    path = pathlib.Path(path)
    try:
        doc = json.loads(path.read_text())
    except (OSError, UnicodeDecodeError, json.JSONDecodeError) as e:
        raise ValueError(f"{path} is not a usable action log: {e}") from None
    if not isinstance(doc, dict) or doc.get("format") != LOG_FORMAT:
        raise ValueError(f"{path} is not a usable action log: its `format` is not {LOG_FORMAT!r}")
    if doc.get("version") != LOG_VERSION:
        raise ValueError(f"{path}: action log version {doc.get('version')!r} is not supported (reads {LOG_VERSION})")
    if doc.get("env") != ENV_ID:
        raise ValueError(f"{path}: the log is for env {doc.get('env')!r}, this package plays {ENV_ID!r}")
    actions = doc.get("actions")
    if isinstance(actions, str) and all(c in "01234" for c in actions):
        actions = [int(c) for c in actions]
    elif not (isinstance(actions, list) and all(isinstance(x, int) and 0 <= x <= 4 for x in actions)):
        raise ValueError(f"{path}: `actions` must be a string of digits 0..=4 or a list of integers 0..=4")
    if doc.get("steps") != len(actions):
        raise ValueError(f"{path}: `steps` is {doc.get('steps')!r} but the log holds {len(actions)} actions")
    options = dict(doc.get("options") or {})
    limit = options.pop("max_episode_steps", "10000")
    return {
        "seed": int(doc["seed"]),
        "options": options,
        "max_episode_steps": None if str(limit).lower() == "none" else int(limit),
        "actions": actions,
        "steps": doc["steps"],
        "return": doc.get("return"),
        "cause": doc.get("cause"),
        "policy": doc.get("policy"),
    }


def from_action_logs(
    dataset_id: str,
    logs: Iterable[str | os.PathLike],
    *,
    chunk_steps: int = 1000,
    progress: bool | None = None,
    author: str | None = None,
    description: str | None = None,
    **obs_options: Any,
):
    """Replays action logs (`chopperscape play --save-actions FILE`) into a new Minari dataset: one episode per
    log, from the log's seed with its rules options. `obs_options` choose the observation (`obs_type`,
    `obs_size`, `frame_stack`, `hud`); every log must have the same rules options. A log that stopped before its
    episode ended gives an episode whose last step is truncated. `ValueError` when a replay does not reach the
    steps or return its log recorded (a log from other rules)."""
    paths = [pathlib.Path(p) for p in logs]
    if not paths:
        raise ValueError("no action logs given: from_action_logs needs at least one")
    read = [read_action_log(p) for p in paths]
    rules, limit = read[0]["options"], read[0]["max_episode_steps"]
    for p, log in zip(paths, read):
        if not _same_rules(log["options"], rules) or log["max_episode_steps"] != limit:
            raise ValueError(
                f"{p} was played with other options than {paths[0]} ({log['options']} vs {rules}): "
                "one dataset holds one env spec"
            )
    bad = sorted(set(obs_options) - {"obs_type", "obs_size", "frame_stack", "hud"})
    if bad:
        raise ValueError(f"options {bad} change the rules, which come from the logs: allowed obs_type, obs_size, "
                         "frame_stack, hud")
    options = {**rules, **obs_options}
    env = gym.make(ENV_ID, max_episode_steps=limit, **options)

    def plays() -> Iterator[tuple[int, Callable[[], int | None]]]:
        for p, log in zip(paths, read):
            it = iter(log["actions"])
            yield log["seed"], (lambda it=it: next(it, None))

    meta = _metadata(
        dataset_id,
        "human" if all(log["policy"] in (None, "human") for log in read) else "action-logs",
        options,
        limit,
        pilot="action logs",
        action_logs=[p.name for p in paths],
        author={author} if author else None,
        description=description or f"{len(paths)} episodes replayed from chopperscape action logs",
    )
    try:
        ds = _write(dataset_id, env, plays(), len(paths), meta, chunk_steps, progress)
    finally:
        env.close()
    for i, (p, log) in enumerate(zip(paths, read)):
        meta_i = next(iter(ds.storage.get_episode_metadata([i])))
        if meta_i["total_steps"] != log["steps"] or (log["return"] is not None and meta_i["rewards_sum"] != log["return"]):
            minari = _minari()[0]
            minari.delete_dataset(dataset_id)
            raise ValueError(
                f"{p}: the replay took {meta_i['total_steps']} steps for a return of {meta_i['rewards_sum']:g}, but "
                f"the log recorded {log['steps']} steps and a return of {log['return']}: it was not played under "
                "these rules; nothing was written"
            )
    return ds


def main(argv: list[str] | None = None) -> int:
    """`python -m chopperscape.datasets`: what `chopperscape dataset` runs (see `--help`)."""
    import argparse

    parser = argparse.ArgumentParser(
        prog="python -m chopperscape.datasets",
        description="Write a Minari dataset of ChopperScape-v0 episodes (under MINARI_DATASETS_PATH).",
    )
    parser.add_argument("--out", required=True, help='the dataset id, e.g. "chopperscape/heuristic-v0"')
    parser.add_argument("--policy", default="heuristic", choices=pilots.NAMES)
    parser.add_argument("--episodes", type=int, default=1)
    parser.add_argument("--seed", type=int, default=0)
    parser.add_argument("--from-logs", nargs="+", metavar="LOG", help="replay these action logs instead of a pilot")
    parser.add_argument("--option", action="append", default=[], metavar="NAME=VALUE", help="an env option")
    parser.add_argument("--chunk-steps", type=int, default=1000)
    parser.add_argument("--no-progress", action="store_true")
    args = parser.parse_args(argv)
    options: dict[str, Any] = {}
    for kv in args.option:
        name, sep, value = kv.partition("=")
        if not sep:
            parser.error(f"--option takes NAME=VALUE, got {kv!r}")
        options[name] = value
    limit_text = options.pop("max_episode_steps", "10000")
    limit = None if limit_text.lower() == "none" else int(limit_text)
    progress = False if args.no_progress else None
    try:
        if args.from_logs:
            ds = from_action_logs(args.out, args.from_logs, chunk_steps=args.chunk_steps, progress=progress, **options)
        else:
            ds = collect(args.out, args.policy, args.episodes, args.seed, max_episode_steps=limit,
                         chunk_steps=args.chunk_steps, progress=progress, **options)
    except (ValueError, ImportError) as e:
        print(f"error: {e}", file=sys.stderr)
        return 2
    print(f"wrote {ds.total_episodes} episodes ({ds.total_steps} steps) to {ds.storage.data_path.parent}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
