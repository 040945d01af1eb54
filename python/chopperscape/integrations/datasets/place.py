"""Where a new dataset goes and how it gets there: the dataset id checked (its form and length), the datasets folder
(`MINARI_DATASETS_PATH`), the temporary folder it is written in beside its place (`.{name}.{pid}.{8 random}.part`),
the unfinished folders of stopped runs swept, and the finished folder renamed into place, never over anything.
Everything here is checked before a step is played. Also the one import of Minari, with what to install.
"""

from __future__ import annotations

import errno
import os
import pathlib
import re
import shutil
import sys
import tempfile
from typing import Any

#: The longest dataset name (the last part of its id), in bytes: a folder name, plus our temporary suffix.
MAX_NAME_BYTES = 200
#: The temporary folder a dataset is written in: `.{name}.{pid}.{8 random}.part` beside its place.
_TEMP_RE = re.compile(r"\.(?P<name>.+)\.(?P<pid>[0-9]+)\.[a-z0-9_]{8}\.part")


def minari_modules():
    """`(minari, EpisodeBuffer, MinariStorage)`; `ImportError` saying what to install without Minari, h5py or
    Pillow (what `chopperscape dataset` checks before it runs the collection)."""
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


def datasets_root() -> pathlib.Path:
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


def dataset_dir(dataset_id: Any) -> pathlib.Path:
    """The folder of a new dataset `dataset_id`, checked before anything is played: the id's form and length,
    the datasets folder, and that nothing (not even a dangling symbolic link) is at the id."""
    minari_modules()
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
    root = datasets_root()
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


def temp_folder(final: pathlib.Path) -> pathlib.Path:
    """Makes this process's temporary folder beside `final`, after sweeping those of stopped runs; `ValueError`
    when it cannot be made (a folder that is not writable, a name too long) or another run writes `final`."""
    try:
        final.parent.mkdir(parents=True, exist_ok=True)
        _sweep(final.parent, final.name)
        return pathlib.Path(tempfile.mkdtemp(prefix=f".{final.name}.{os.getpid()}.", suffix=".part", dir=final.parent))
    except OSError as e:
        raise ValueError(f"cannot write the dataset folder {final}: {e.strerror or e}") from None


def move_into_place(tmp: pathlib.Path, final: pathlib.Path, dataset_id: str) -> None:
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
