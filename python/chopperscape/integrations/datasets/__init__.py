"""Datasets in Farama's Minari format: episodes of a built-in policy, or human play replayed from action logs.

>>> import os, tempfile
>>> os.environ["MINARI_DATASETS_PATH"] = tempfile.mkdtemp()  # where datasets go (default ~/.minari/datasets)
>>> from chopperscape.integrations import datasets
>>> ds = datasets.collect("chopperscape/heuristic-features-v0", policy="heuristic", episodes=3, obs_type="features")
>>> ds.total_episodes, ds.storage.metadata["seeds"]
(3, [0, 1, 2])
>>> import minari
>>> minari.load_dataset("chopperscape/heuristic-features-v0").total_steps == ds.total_steps  # the same dataset
True

Datasets are written under `MINARI_DATASETS_PATH` (default `~/.minari/datasets`), where `minari.load_dataset`
finds them, in Minari's HDF5 layout through Minari's own storage classes, with images stored raw (lossless,
`jpeg_encoding=False`), so a dataset equals a replay of its seeds exactly. Needs `pip install "minari[hdf5]"`.

- Episode `i` of `collect(..., seed=S)` is played from `reset(seed=S + i)` with the policy restarted with that seed:
  exactly the episodes of `chopperscape demo --policy P --episodes N --seed S`.
- Each episode's seed is stored (Minari's episode metadata `seed`); the dataset metadata holds the env spec (with
  every option), `chopperscape_version`, the observation layouts' versions (`features_version`, `pixels_version`:
  what the stored observations show), `policy`, `seeds`, `env_options` and `max_episode_steps`.
- Observations are `features` unless `obs_type` says otherwise (the one default of this module, of
  `python -m chopperscape.integrations.datasets` and of `chopperscape dataset`). `max_episode_steps=None` means no
  time limit
  (the dataset's env spec then has none either).
- Steps stream to disk every `chunk_steps` steps, so memory stays bounded however long the collection; the
  dataset is written in a temporary folder next to its place, `.NAME.PID.XXXXXXXX.part`, and moved there at the
  end, so an existing dataset is never overwritten. SIGINT, SIGTERM and SIGHUP stop the collection at the next
  step and remove that folder (exit status 130, 143, 129 from the command line); a folder left by a process that
  was killed outright is removed by the next collection into the same namespace. A write that fails (disk full, a
  file-size limit) is a `OSError` naming the file, with the partial dataset removed. Everything about the id and
  the place (the id's form, its length, `MINARI_DATASETS_PATH`, a dataset or anything else already at the id,
  another process writing the same id) is checked before anything is played.
- `from_action_logs` replays `chopperscape play --save-actions` logs (human play) into a dataset and checks that
  each replay reaches the steps and return its log recorded. Logs are read by the command line's own reader
  (`chopperscape replay` accepts exactly the same files, at most 64 MiB each).
"""

from __future__ import annotations

import functools
import os
import pathlib
from collections.abc import Iterable, Iterator
from typing import Any, Callable

from ... import _cli, _core, policies
from ..._checks import positive_int, time_limit
from ...env import make_env
from ...options import OBSERVATION_OPTIONS
from .place import minari_modules
from .writer import write

__all__ = ["DEFAULT_OBS_TYPE", "collect", "from_action_logs", "read_action_log"]

ENV_ID = "ChopperScape-v0"
#: The observation of a dataset unless `obs_type` says otherwise (600 × 800 rgb would be 1.4 MB a step).
DEFAULT_OBS_TYPE = "features"


def _metadata(dataset_id: str, algorithm: str, options: dict, max_episode_steps: int | None, **extra: Any) -> dict:
    minari, _, _ = minari_modules()
    meta = {
        "dataset_id": dataset_id,
        "minari_version": minari.__version__,
        "algorithm_name": algorithm,
        "requirements": [f"chopperscape=={_core.__version__}"],
        "chopperscape_version": _core.__version__,
        "features_version": _core.FEATURES_VERSION,
        "pixels_version": _core.PIXELS_VERSION,
        "env_options": {k: (list(v) if isinstance(v, tuple) else v) for k, v in options.items()},
        "max_episode_steps": max_episode_steps,
    }
    meta.update({k: v for k, v in extra.items() if v is not None})
    return meta


def collect(
    dataset_id: str,
    policy: str = "heuristic",
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
    """Plays `episodes` episodes of the built-in `policy` (see `chopperscape.policies.NAMES`) into a new Minari
    dataset `dataset_id` (`"namespace/name-vN"`) and returns it (`minari.MinariDataset`). `options` are the env's
    keyword options (`obs_type="grayscale"`, `obs_size=(84, 84)`, `frame_skip=4`, ...; `obs_type` defaults to
    `"features"`). Episode `i` starts from `reset(seed=seed + i)` with the policy restarted with that seed, as
    `chopperscape demo` plays them. `max_episode_steps=None`: no time limit."""
    policies._check_name(policy)
    seed = policies._check_seed(seed)
    episodes = positive_int("episodes", episodes)
    max_episode_steps = time_limit(max_episode_steps)
    options = {"obs_type": DEFAULT_OBS_TYPE, **options}
    env = make_env(max_episode_steps, **options)
    player = policies.Policy(policy, seed)

    def plays() -> Iterator[tuple[int, Callable[[], int]]]:
        for i in range(episodes):
            s = (seed + i) % 2**64
            player.reset(s)
            yield s, lambda: player.act(env)

    meta = _metadata(
        dataset_id,
        f"chopperscape.policies:{policy}",
        options,
        max_episode_steps,
        policy=policy,
        author={author} if author else None,
        description=description
        or f"{episodes} episodes of the {policy} policy on {ENV_ID} (seeds {seed}..{seed + episodes - 1})",
    )
    try:
        return write(dataset_id, env, plays(), episodes, meta, chunk_steps, progress)
    finally:
        env.close()


def read_action_log(path: str | os.PathLike) -> dict[str, Any]:
    """Reads a `chopperscape play --save-actions` (or `record`) log with the command line's own reader (what
    `chopperscape replay` accepts, at most 64 MiB): `{"seed", "options", "max_episode_steps", "actions",
    "steps", "return", "cause", "policy"}`, with `options` the rules as the env's typed keyword options and
    `actions` as bytes (one 0..=4 per step). `ValueError` naming the file and what is wrong for anything else."""
    log = _core.read_action_log(os.fspath(path))
    log["options"] = {k: _cli.option_value(k, v) for k, v in log["options"].items()}
    return log


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
    log, from the log's seed with its rules options. `obs_options` choose the observation (`obs_type` (default
    `"features"`), `obs_size`, `frame_stack`, `hud`, `hud_style`); every log must have the same rules options. A log
    that
    stopped before its episode ended gives an episode whose last step is truncated. `ValueError` when a replay
    does not reach the steps or return its log recorded (a log from other rules)."""
    if isinstance(logs, (str, os.PathLike)):
        logs = [logs]
    paths = [pathlib.Path(p) for p in logs]
    if not paths:
        raise ValueError("no action logs given: from_action_logs needs at least one")
    bad = sorted(set(obs_options) - set(OBSERVATION_OPTIONS))
    if bad:
        allowed = ", ".join(OBSERVATION_OPTIONS)
        raise ValueError(f"options {bad} change the rules, which come from the logs: allowed {allowed}")
    read = [read_action_log(p) for p in paths]
    rules, limit = read[0]["options"], read[0]["max_episode_steps"]
    for p, log in zip(paths, read):
        if log["options"] != rules or log["max_episode_steps"] != limit:
            theirs = {**log["options"], "max_episode_steps": log["max_episode_steps"]}
            first = {**rules, "max_episode_steps": limit}
            diff = ", ".join(f"{k} {first[k]!r} vs {theirs[k]!r}" for k in first if first[k] != theirs[k])
            raise ValueError(
                f"{p} was played with other options than {paths[0]} ({diff}): one dataset holds one env spec"
            )
    options = {"obs_type": DEFAULT_OBS_TYPE, **rules, **obs_options}
    env = make_env(limit, **options)

    def plays() -> Iterator[tuple[int, Callable[[], int | None]]]:
        for log in read:
            yield log["seed"], functools.partial(next, iter(log["actions"]), None)

    meta = _metadata(
        dataset_id,
        "human" if all(log["policy"] in (None, "human") for log in read) else "action-logs",
        options,
        limit,
        policy="action logs",
        action_logs=[p.name for p in paths],
        author={author} if author else None,
        description=description or f"{len(paths)} episodes replayed from chopperscape action logs",
    )
    try:
        ds = write(dataset_id, env, plays(), len(paths), meta, chunk_steps, progress)
    finally:
        env.close()
    for i, (p, log) in enumerate(zip(paths, read)):
        meta_i = next(iter(ds.storage.get_episode_metadata([i])))
        if meta_i["total_steps"] != log["steps"] or meta_i["rewards_sum"] != log["return"]:
            minari = minari_modules()[0]
            minari.delete_dataset(dataset_id)
            raise ValueError(
                f"{p}: the replay took {meta_i['total_steps']} steps for a return of {meta_i['rewards_sum']:g}, but "
                f"the log recorded {log['steps']} steps and a return of {log['return']}: it was not played under "
                "these rules; nothing was written"
            )
    return ds
