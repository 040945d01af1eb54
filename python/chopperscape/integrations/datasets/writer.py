"""Episodes written into a new Minari dataset by Minari's own storage classes (HDF5, images raw), streamed every
`chunk_steps` steps so memory stays bounded, with the room of each write checked first (HDF5 cannot fail cleanly on
a full disk), a progress line on standard error, and SIGINT, SIGTERM and SIGHUP stopping at the next step with the
unfinished dataset removed.
"""

from __future__ import annotations

import errno
import os
import pathlib
import shutil
import sys
import time
from collections.abc import Iterable
from typing import Any, Callable

try:
    import resource
except ImportError:  # pragma: no cover - not on Windows
    resource = None  # type: ignore[assignment]

import gymnasium as gym
import numpy as np

from ... import _signals
from ..._checks import positive_int
from .place import dataset_dir, minari_modules, move_into_place, temp_folder


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


def write(
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
    minari, EpisodeBuffer, MinariStorage = minari_modules()
    chunk_steps = positive_int("chunk_steps", chunk_steps)
    final = dataset_dir(dataset_id)
    # From here on a signal only notes itself; the collection stops at the next step and removes its folder.
    guard = _signals.defer()
    tmp = None
    bar = _Progress(total, sys.stderr.isatty() if progress is None else bool(progress))
    try:
        tmp = temp_folder(final)
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
        move_into_place(tmp, final, dataset_id)
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
