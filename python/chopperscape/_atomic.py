"""Writing a file whole or not at all: the package's one way to write a result file.

:func:`replacing` gives a temporary path beside the target, ``.NAME.PID.part`` (the process id tells a later run
a file of a killed process from one another run is still writing), for any writer (``torch.save``, ``onnx``,
Pillow, an ``ffmpeg`` process, a subprocess's standard output); once the block ends normally the file is flushed to
disk (``fsync``) and renamed onto the target, and the folder's entry is synced too. If the block raises, the
temporary file is removed and the target is left as it was. :func:`write_bytes` and :func:`write_text` are the
one-call forms.

A reader therefore sees the old file or the new one, never half of one, even after a crash or a full disk.
"""

from __future__ import annotations

import contextlib
import hashlib
import os
from collections.abc import Iterator
from pathlib import Path


def temporary_path(path: str | os.PathLike) -> Path:
    """The temporary name :func:`replacing` writes `path` under: ``.NAME.PID.part`` in the same folder."""
    p = Path(path)
    return p.with_name(f".{p.name}.{os.getpid()}.part")


def _fsync(path: Path, directory: bool = False) -> None:
    fd = os.open(path, os.O_RDONLY | (getattr(os, "O_DIRECTORY", 0) if directory else 0))
    try:
        os.fsync(fd)
    except OSError:
        if not directory:  # some file systems cannot sync a folder; the file itself must be synced
            raise
    finally:
        os.close(fd)


@contextlib.contextmanager
def replacing(path: str | os.PathLike) -> Iterator[Path]:
    """Yields the temporary path to write `path`'s new content into; on normal exit, syncs it and renames it onto
    `path`; on an exception (a full disk, a signal, a failed check), removes it and leaves `path` unchanged.
    `OSError` from the sync or the rename is raised after the temporary file is removed."""
    target = Path(path)
    tmp = temporary_path(target)
    try:
        yield tmp
        _fsync(tmp)
        os.replace(tmp, target)
    finally:
        if os.path.lexists(tmp):
            os.unlink(tmp)
    with contextlib.suppress(OSError):
        _fsync(target.parent if str(target.parent) else Path("."), directory=True)


def write_bytes(path: str | os.PathLike, data: bytes) -> None:
    """Writes `data` to `path` atomically (:func:`replacing`)."""
    with replacing(path) as tmp, open(tmp, "wb") as f:
        f.write(data)


def write_text(path: str | os.PathLike, text: str) -> None:
    """Writes `text` (UTF-8) to `path` atomically (:func:`replacing`)."""
    write_bytes(path, text.encode("utf-8"))


def sha256(path: str | os.PathLike) -> str:
    """The SHA-256 of a file's bytes, read in 1 MiB blocks (what a results file or an export records of its
    source)."""
    h = hashlib.sha256()
    with open(path, "rb") as f:
        for block in iter(lambda: f.read(1 << 20), b""):
            h.update(block)
    return h.hexdigest()
