"""What keeps a run folder one run's: a lock held while a process writes it, the recipe's hash that binds a
checkpoint to its run, and the removal of the temporary files a killed run left behind.

- :class:`RunLock`: an advisory lock (``flock``) on the run folder itself, held for the run's life by
  ``python -m chopperscape.learn.train`` (a new run, ``--force`` and ``--resume`` alike). A second writer is refused
  at once (`ValueError`, exit 2) with the folder's name and, where the system says it (``/proc/locks``), the process
  id holding it; nothing is written. The lock needs no file: it is the folder's, and it goes with the process (a
  killed run holds nothing). Where ``fcntl`` is missing (Windows) no lock is taken.
- :func:`recipe_hash`: the SHA-256 of the recipe's canonical JSON (sorted keys, no spaces), which a resume state
  records; :func:`check_recipe_hash` refuses a state recorded by another run (another seed, another learning rate).
- :func:`remove_stale_parts`: the ``.NAME.PID.part`` files (:mod:`chopperscape._atomic`) of the run's own files
  (``model.pt``, ``resume.pt``, ``recipe.json``, ``progress.csv``) that a process killed mid-write left, removed when
  a run starts or resumes, under the lock: no other process writes them then.
"""

from __future__ import annotations

import functools
import hashlib
import inspect
import json
import os
import re
from dataclasses import asdict, is_dataclass
from pathlib import Path
from typing import Any, Callable, TypeVar

try:
    import fcntl
except ImportError:  # pragma: no cover - Windows
    fcntl = None  # type: ignore[assignment]

#: The files of a run in its folder: the model, its curve, its recipe, and the state `--resume` continues from.
RUN_FILES = ("model.pt", "progress.csv", "recipe.json", "resume.pt")

#: The key of a resume state that records its run's recipe hash.
RECIPE_KEY = "recipe_sha256"

_PART = re.compile(r"\.(?P<name>.+)\.(?P<pid>[0-9]+)\.part")


def _holder(st: os.stat_result) -> int | None:
    """The process id holding an `flock` on the file or folder of `st`, as `/proc/locks` says (Linux), else None."""
    want = f"{os.major(st.st_dev):02x}:{os.minor(st.st_dev):02x}:{st.st_ino}"
    try:
        with open("/proc/locks", encoding="ascii", errors="replace") as f:
            for line in f:
                parts = line.split()
                # "1: FLOCK  ADVISORY  WRITE 1234 00:2d:5678 0 EOF" (a blocked waiter's line has "->" after "1:").
                if len(parts) >= 6 and parts[1] == "FLOCK" and parts[5] == want and parts[4].isdigit():
                    return int(parts[4])
    except OSError:
        pass
    return None


class RunLock:
    """An advisory lock on the run folder `out`, held from `__enter__` to `__exit__` (see the module's docs).

    `__enter__` makes `out` if it is missing (and `__exit__` removes it again if it is still empty, so a refused run
    leaves nothing), then locks it without waiting: `ValueError` naming the folder (and the holder's process id where
    known) if another process holds it, or if `out` is not a folder."""

    def __init__(self, out: str | os.PathLike):
        self.out = Path(out)
        self.fd: int | None = None
        self.made: list[Path] = []  # the folders __enter__ made, innermost first

    def __enter__(self) -> RunLock:
        out = self.out
        if os.path.lexists(out) and not out.is_dir():
            raise ValueError(f"--out {out} is not a folder: give a folder for progress.csv, model.pt and recipe.json")
        if fcntl is None:
            return self
        if not os.path.lexists(out):
            missing = [out, *(p for p in out.parents if not os.path.lexists(p))]
            try:
                out.mkdir(parents=True)
                self.made = [p for p in missing if not os.path.lexists(p) or p.is_dir()]
            except FileExistsError:
                pass
            except OSError as e:
                raise ValueError(f"--out {out}: cannot make the folder: {e.strerror or e}") from None
        try:
            fd = os.open(out, os.O_RDONLY | getattr(os, "O_DIRECTORY", 0))
        except OSError as e:
            self._unmake()
            raise ValueError(f"--out {out}: cannot open the folder to lock it: {e.strerror or e}") from None
        try:
            fcntl.flock(fd, fcntl.LOCK_EX | fcntl.LOCK_NB)
        except OSError:
            holder = _holder(os.fstat(fd))
            os.close(fd)
            by = f" by process {holder}" if holder is not None else " by another process"
            raise ValueError(
                f"run folder {out} is in use{by} (a training run holds its lock): wait for it to end, stop it, or "
                "give another folder"
            ) from None
        self.fd = fd
        return self

    def _unmake(self) -> None:
        for folder in self.made:  # innermost first, each only if nothing was written in it
            try:
                folder.rmdir()
            except OSError:
                break
        self.made = []

    def __exit__(self, *exc: object) -> None:
        self.release()

    def release(self) -> None:
        """Lets the lock go (and removes `out` if this lock made it and it is still empty)."""
        if self.fd is not None:
            self._unmake()
            os.close(self.fd)  # closing the descriptor releases the flock
            self.fd = None


F = TypeVar("F", bound=Callable[..., Any])


def locked(func: F) -> F:
    """Runs `func` (a function with an `out` parameter: the run folder) holding :class:`RunLock` on `out`."""
    signature = inspect.signature(func)

    @functools.wraps(func)
    def wrapper(*args: Any, **kwargs: Any) -> Any:
        out = signature.bind(*args, **kwargs).arguments["out"]
        with RunLock(out):
            return func(*args, **kwargs)

    return wrapper  # type: ignore[return-value]


def recipe_hash(recipe: Any) -> str:
    """The SHA-256 (hex) of `recipe`'s canonical JSON: a dataclass (`Recipe`) or a dict, keys sorted, no spaces,
    tuples as lists (as `recipe.json` holds it, so the recipe read back from it hashes alike). A setting added later
    (`recipe.LATER_SETTINGS`) is left out at the value older runs had, so their resume states still match."""
    from .recipe import LATER_SETTINGS

    data = asdict(recipe) if is_dataclass(recipe) and not isinstance(recipe, type) else recipe
    data = {k: v for k, v in data.items() if not (k in LATER_SETTINGS and v == LATER_SETTINGS[k])}
    text = json.dumps(data, sort_keys=True, separators=(",", ":"), allow_nan=False)
    return hashlib.sha256(text.encode("utf-8")).hexdigest()


def check_recipe_hash(state: dict[str, Any] | None, recipe: Any, where: str | os.PathLike) -> None:
    """`ValueError` if the resume state `state` records another run's recipe than `recipe` (it was copied from
    another run folder). A state of an older trainer records none and is taken as it is; `None` (no state: a new
    run) passes."""
    recorded = None if state is None else state.get(RECIPE_KEY)
    if recorded is None:
        return
    if recorded != recipe_hash(recipe):
        raise ValueError(
            f"--resume {where}: its resume.pt belongs to another run (its recipe's hash {str(recorded)[:12]}… is not "
            f"that of {Path(where) / 'recipe.json'}, {recipe_hash(recipe)[:12]}…): a checkpoint resumes only the "
            "run that saved it"
        )


def stale_parts(out: str | os.PathLike) -> list[Path]:
    """The temporary files (`.NAME.PID.part`) of the run's own files in `out`, of any process."""
    out = Path(out)
    try:
        names = os.listdir(out)
    except OSError:
        return []
    found = []
    for name in sorted(names):
        m = _PART.fullmatch(name)
        if m is not None and m.group("name") in RUN_FILES and not os.path.isdir(out / name):
            found.append(out / name)
    return found


def remove_stale_parts(out: str | os.PathLike) -> list[Path]:
    """Removes :func:`stale_parts` (call it holding the run's lock: no live run writes them then); returns what it
    removed. A file that cannot be removed is left (it is only space)."""
    removed = []
    for path in stale_parts(out):
        try:
            os.unlink(path)
            removed.append(path)
        except OSError:
            pass
    return removed


def check_run_folder(out: Path, force: bool = False) -> None:
    """`ValueError` when `out` cannot hold a new run: it is not a folder, or it holds a run (`RUN_FILES`) and not
    `force`. Nothing is written."""
    out = Path(out)
    if os.path.lexists(out) and not out.is_dir():
        raise ValueError(f"--out {out} is not a folder: give a folder for progress.csv, model.pt and recipe.json")
    there = [name for name in RUN_FILES if os.path.lexists(out / name)]
    if there and not force:
        raise ValueError(
            f"--out {out} already holds a run ({', '.join(there)}): pass --force to start over in it (its files are "
            "replaced), or give another folder"
        )
