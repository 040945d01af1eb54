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

import errno
import functools
import os
import pathlib
import re
import shutil
import sys
import tempfile
import time
from collections.abc import Iterable, Iterator
from typing import Any, Callable

try:
    import resource
except ImportError:  # pragma: no cover - not on Windows
    resource = None  # type: ignore[assignment]

import gymnasium as gym
import numpy as np

from .. import _cli, _core, _signals, policies
from .._checks import positive_int, time_limit
from ..env import make_env

__all__ = ["DEFAULT_OBS_TYPE", "collect", "from_action_logs", "read_action_log"]

ENV_ID = "ChopperScape-v0"
#: The observation of a dataset unless `obs_type` says otherwise (600 × 800 rgb would be 1.4 MB a step).
DEFAULT_OBS_TYPE = "features"
#: The longest dataset name (the last part of its id), in bytes: a folder name, plus our temporary suffix.
MAX_NAME_BYTES = 200
#: The temporary folder a dataset is written in: `.{name}.{pid}.{8 random}.part` beside its place.
_TEMP_RE = re.compile(r"\.(?P<name>.+)\.(?P<pid>[0-9]+)\.[a-z0-9_]{8}\.part")


def _minari():
    try:
        import h5py  # noqa: F401
        import minari
        import PIL  # noqa: F401  (Minari's HDF5 storage imports it)
        from minari.data_collector import EpisodeBuffer
        from minari.dataset.minari_storage import MinariStorage
    except ImportError as e:
        raise ImportError(
            "chopperscape.integrations.datasets needs Minari with HDF5 support: "
            f'pip install "minari[hdf5]" pillow ({e})'
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


def _running(pid: int) -> bool:
    """Whether process `pid` runs (True when that cannot be told, so that nothing of a live run is touched)."""
    try:
        os.kill(pid, 0)
    except ProcessLookupError:
        return False
    except (PermissionError, OverflowError, OSError):
        return True
    return True


def _sweep(folder: pathlib.Path, name: str) -> None:
    """Removes temporary dataset folders in `folder` left by processes that no longer run (saying so on standard
    error); `ValueError` if a running process is writing the dataset `name` there now."""
    try:
        entries = list(os.scandir(folder))
    except OSError:
        return
    for entry in entries:
        m = _TEMP_RE.fullmatch(entry.name)
        if m is None or not entry.is_dir(follow_symlinks=False):
            continue
        pid = int(m.group("pid"))
        if pid == os.getpid():
            continue
        if _running(pid):
            if m.group("name") == name:
                raise ValueError(
                    f"another process (pid {pid}) is writing a dataset {name!r} in {folder} now: wait for it, or "
                    "choose another name or version"
                )
            continue
        shutil.rmtree(entry.path, ignore_errors=True)
        if not os.path.lexists(entry.path):
            print(f"removed {entry.path}, the unfinished dataset of a stopped run (pid {pid})", file=sys.stderr)


def _datasets_root() -> pathlib.Path:
    """Where datasets go (`MINARI_DATASETS_PATH`, else `~/.minari/datasets`), made if missing; `ValueError` naming
    the variable when it is empty, a file, or cannot be made or written."""
    given = os.environ.get("MINARI_DATASETS_PATH")
    if given is not None and not given.strip():
        raise ValueError("MINARI_DATASETS_PATH is set but empty: unset it (for ~/.minari/datasets) or name a folder")
    root = pathlib.Path(given) if given is not None else pathlib.Path.home() / ".minari" / "datasets"
    what = f"MINARI_DATASETS_PATH={given!r}" if given is not None else f"the datasets folder {str(root)!r}"
    if root.exists() and not root.is_dir():
        raise ValueError(f"{what} is not a folder: name a folder for Minari's datasets")
    try:
        root.mkdir(parents=True, exist_ok=True)
    except OSError as e:
        raise ValueError(f"{what} cannot be made: {e.strerror or e}") from None
    if not os.access(root, os.W_OK | os.X_OK):
        raise ValueError(f"{what} is not writable: name a folder you can write")
    return root


def _dataset_dir(dataset_id: Any) -> pathlib.Path:
    """The folder of a new dataset `dataset_id`, checked before anything is played: the id's form and length,
    the datasets folder, and that nothing (not even a dangling symbolic link) is at the id."""
    _minari()
    from minari.dataset.minari_dataset import parse_dataset_id

    form = '"namespace/name-vN" or "name-vN" (for example "chopperscape/heuristic-v0")'
    if not isinstance(dataset_id, str) or not re.search(r"-v[0-9]+$", dataset_id):
        raise ValueError(f"Malformed dataset ID {dataset_id!r}: allowed {form}")
    namespace, name, _ = parse_dataset_id(dataset_id)  # ValueError for a malformed id, naming the expected form
    full = f"{name}-v{_}"
    if len(os.fsencode(full)) > MAX_NAME_BYTES or any(
        len(os.fsencode(part)) > MAX_NAME_BYTES for part in (namespace or "").split("/")
    ):
        raise ValueError(f"dataset ID {dataset_id[:60]!r}… is too long: each part may take {MAX_NAME_BYTES} bytes")
    root = _datasets_root()
    path = root / dataset_id
    if os.path.lexists(path):
        what = "a Minari dataset" if path.is_dir() else "something that is not a dataset"
        if path.is_symlink():
            what = f"a symbolic link (to {os.readlink(path)})"
        raise ValueError(
            f"{what} already exists at {path} (dataset id {dataset_id!r}): choose another name or version, or "
            f"delete it (minari.delete_dataset({dataset_id!r}) for a dataset)"
        )
    if namespace is not None:
        from minari.namespace import NAMESPACE_METADATA_FILENAME, create_namespace

        if not (root / namespace / NAMESPACE_METADATA_FILENAME).is_file():
            try:
                create_namespace(namespace)
            except OSError as e:
                raise ValueError(f"cannot make the namespace folder {root / namespace}: {e.strerror or e}") from None
    return path


def _temp_folder(final: pathlib.Path) -> pathlib.Path:
    """Makes this process's temporary folder beside `final`, after sweeping those of stopped runs; `ValueError`
    when it cannot be made (a folder that is not writable, a name too long) or another run writes `final`."""
    try:
        final.parent.mkdir(parents=True, exist_ok=True)
        _sweep(final.parent, final.name)
        return pathlib.Path(tempfile.mkdtemp(prefix=f".{final.name}.{os.getpid()}.", suffix=".part", dir=final.parent))
    except OSError as e:
        raise ValueError(f"cannot write the dataset folder {final}: {e.strerror or e}") from None


#: The room a write into a dataset needs beyond its arrays: HDF5 allocates whole chunks and keeps metadata
#: (measured: at most 10 % and 1.5 MB more than the arrays, for rgb 600 × 800 in chunks of 10 steps).
_ROOM_FACTOR, _ROOM_EXTRA = 1.25, 4 << 20


def _check_room(file: pathlib.Path, nbytes: int) -> None:
    """`OSError` (ENOSPC or EFBIG) naming `file` unless a write of about `nbytes` of arrays fits both the free
    space of its file system and the process's file-size limit. HDF5 cannot fail cleanly: a write that hits a
    full disk or the limit ends in a crash (SIGSEGV) when h5py closes the file, so the room is checked before."""
    need = int(nbytes * _ROOM_FACTOR) + _ROOM_EXTRA
    size = file.stat().st_size if file.exists() else 0
    limit = resource.getrlimit(resource.RLIMIT_FSIZE)[0] if resource is not None else -1
    if limit != getattr(resource, "RLIM_INFINITY", -1) and limit >= 0 and size + need > limit:
        raise OSError(
            errno.EFBIG,
            f"the file-size limit (ulimit -f) of {_mib(limit)} leaves no room for the next "
            f"{_mib(need)} (the file has {_mib(size)})",
            str(file),
        )
    st = os.statvfs(file.parent if file.parent.exists() else file.parent.parent)
    free = (st.f_bfree if os.geteuid() == 0 else st.f_bavail) * st.f_frsize
    if need > free:
        raise OSError(
            errno.ENOSPC, f"the disk is full: {_mib(free)} free, the next write needs about {_mib(need)}", str(file)
        )


def _mib(n: int) -> str:
    return f"{n / 2**20:.1f} MiB"


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
    chunk_steps = positive_int("chunk_steps", chunk_steps)
    final = _dataset_dir(dataset_id)
    # From here on a signal only notes itself; the collection stops at the next step and removes its folder.
    guard = _signals.defer()
    tmp = None
    bar = _Progress(total, sys.stderr.isatty() if progress is None else bool(progress))
    try:
        tmp = _temp_folder(final)
        data_file = tmp / "data" / "main_data.hdf5"
        _check_room(data_file, 0)
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
            o: list[Any] = [obs]
            a: list[int] = []
            r: list[float] = []
            te: list[bool] = []
            tr: list[bool] = []
            first, steps, ret = True, 0, 0.0

            def flush(ep: int = ep, seed: int = seed) -> None:  # bound now: called within this episode only
                nonlocal first, o, a, r, te, tr
                if not a:
                    return
                buffer = EpisodeBuffer(
                    id=ep,
                    seed=seed if first else None,
                    observations=np.stack(o),
                    actions=np.asarray(a, dtype=np.int64),
                    rewards=np.asarray(r, dtype=np.float64),
                    terminations=np.asarray(te, dtype=np.bool_),
                    truncations=np.asarray(tr, dtype=np.bool_),
                )
                _check_room(
                    data_file,
                    sum(
                        getattr(buffer, k).nbytes
                        for k in ("observations", "actions", "rewards", "terminations", "truncations")
                    ),
                )
                storage.update_episodes([buffer])
                first, o, a, r, te, tr = False, [], [], [], [], []

            while True:
                action = next_action()
                if action is None:
                    if not a:
                        raise ValueError(f"episode {ep} (seed {seed}) has no steps: a dataset episode needs one")
                    tr[-1] = tr[-1] or not te[-1]
                    break
                guard.check(f"removed the unfinished dataset {dataset_id!r}")
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
            _check_room(data_file, 0)
            storage.update_episode_metadata([{"total_steps": steps, "rewards_sum": ret}], [ep])
            bar.update(ep + 1, all_steps)
        bar.update(len(seeds), all_steps, force=True)
        _check_room(data_file, 0)
        storage.update_metadata({**metadata, "seeds": seeds})
        guard.check(f"removed the unfinished dataset {dataset_id!r}")
        umask = os.umask(0)
        os.umask(umask)
        os.chmod(tmp, 0o777 & ~umask)  # mkdtemp made it private
        _move_into_place(tmp, final, dataset_id)
    except OSError as e:
        # A failed write (disk full, a file-size limit): one line naming the file; the partial dataset goes.
        where = e.filename or (tmp / "data" / "main_data.hdf5" if tmp is not None else final)
        raise OSError(
            e.errno,
            f"cannot write the dataset {dataset_id!r} ({where}): {e.strerror or e}; the unfinished dataset was removed",
        ) from None
    finally:
        if tmp is not None and tmp.exists():
            shutil.rmtree(tmp, ignore_errors=True)
        bar.close()
        guard.restore()
    guard.check()  # a signal during the last moments: the dataset is complete, the exit status still says so
    return minari.load_dataset(dataset_id)


def _move_into_place(tmp: pathlib.Path, final: pathlib.Path, dataset_id: str) -> None:
    """Renames the finished folder to the dataset's place, never over anything that appeared there meanwhile."""
    if os.path.lexists(final):
        raise ValueError(
            f"a dataset {dataset_id!r} appeared at {final} while this one was written: nothing was "
            "replaced; choose another name or version"
        )
    try:
        os.rename(tmp, final)
    except OSError as e:
        if e.errno in (errno.EEXIST, errno.ENOTEMPTY, errno.ENOTDIR, errno.EISDIR):
            raise ValueError(
                f"a dataset {dataset_id!r} appeared at {final} while this one was written: nothing "
                "was replaced; choose another name or version"
            ) from None
        raise


def _metadata(dataset_id: str, algorithm: str, options: dict, max_episode_steps: int | None, **extra: Any) -> dict:
    minari, _, _ = _minari()
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
        return _write(dataset_id, env, plays(), episodes, meta, chunk_steps, progress)
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
    bad = sorted(set(obs_options) - set(_cli.OBSERVATION_OPTIONS))
    if bad:
        raise ValueError(
            f"options {bad} change the rules, which come from the logs: allowed {', '.join(_cli.OBSERVATION_OPTIONS)}"
        )
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
        ds = _write(dataset_id, env, plays(), len(paths), meta, chunk_steps, progress)
    finally:
        env.close()
    for i, (p, log) in enumerate(zip(paths, read)):
        meta_i = next(iter(ds.storage.get_episode_metadata([i])))
        if meta_i["total_steps"] != log["steps"] or meta_i["rewards_sum"] != log["return"]:
            minari = _minari()[0]
            minari.delete_dataset(dataset_id)
            raise ValueError(
                f"{p}: the replay took {meta_i['total_steps']} steps for a return of {meta_i['rewards_sum']:g}, but "
                f"the log recorded {log['steps']} steps and a return of {log['return']}: it was not played under "
                "these rules; nothing was written"
            )
    return ds


def main(argv: list[str] | None = None) -> int:
    """`python -m chopperscape.integrations.datasets`: what `chopperscape dataset` runs (see `--help`)."""
    import argparse

    parser = argparse.ArgumentParser(
        prog="python -m chopperscape.integrations.datasets",
        description="Write a Minari dataset of ChopperScape-v0 episodes (under MINARI_DATASETS_PATH). "
        f"Observations are {DEFAULT_OBS_TYPE} unless --option obs_type=... says otherwise.",
    )
    parser.add_argument("--out", required=True, help='the dataset id, e.g. "chopperscape/heuristic-v0"')
    parser.add_argument("--policy", choices=policies.NAMES, help="the built-in policy (default heuristic)")
    parser.add_argument("--episodes", type=int, help="episodes to play (default 1)")
    parser.add_argument("--seed", type=int, help="seed of the first episode (default 0)")
    parser.add_argument("--from-logs", nargs="+", metavar="LOG", help="replay these action logs instead of a policy")
    parser.add_argument(
        "--option",
        action="append",
        default=[],
        metavar="NAME=VALUE",
        help="an env option, as the command line's flags take it (obs_size=84x84, hud=false, max_episode_steps=none)",
    )
    parser.add_argument("--chunk-steps", type=int, default=1000)
    parser.add_argument("--no-progress", action="store_true")
    args = parser.parse_args(argv)
    options = _cli.env_options(parser, args.option)
    if args.from_logs:
        given = [f"--{n}" for n in ("policy", "episodes", "seed") if getattr(args, n) is not None]
        if given:
            parser.error(
                f"{', '.join(given)} cannot be given with --from-logs: the logs hold their own seeds and actions"
            )
    limit = options.pop("max_episode_steps", 10_000)
    progress = False if args.no_progress else None
    try:
        if args.from_logs:
            if "max_episode_steps" in [o.partition("=")[0].strip() for o in args.option]:
                raise ValueError(
                    "--option max_episode_steps cannot be given with --from-logs: the logs hold their own rules"
                )
            ds = from_action_logs(args.out, args.from_logs, chunk_steps=args.chunk_steps, progress=progress, **options)
        else:
            ds = collect(
                args.out,
                args.policy or "heuristic",
                1 if args.episodes is None else args.episodes,
                0 if args.seed is None else args.seed,
                max_episode_steps=limit,
                chunk_steps=args.chunk_steps,
                progress=progress,
                **options,
            )
    except (ValueError, ImportError) as e:
        print(f"error: {e}", file=sys.stderr)
        return 2
    except OSError as e:
        print(f"error: {e.strerror if e.strerror and not e.filename else e}", file=sys.stderr)
        return 1
    except _signals.Interrupted as e:
        print(e, file=sys.stderr)
        return e.exit_code
    return _cli.print_line(
        f"wrote {ds.total_episodes} episodes ({ds.total_steps} steps) to {ds.storage.data_path.parent}"
    )


if __name__ == "__main__":
    sys.exit(main())
