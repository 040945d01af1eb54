"""How a results file was made: the fields a results file may carry beyond :mod:`.results`' first schema, each
optional (files written before them load and report as they did), each checked when present (:func:`check`).

- `meta.commit`: the project's commit, `git rev-parse HEAD` of the checkout the package runs from (or, installed,
  of the checkout it is run in whose sources it is), with `meta.modified` true when tracked files differ from it;
  the package version (`package.version`) otherwise (:func:`project_commit`). In `meta`, as it differs between
  two evaluations of one policy (:func:`.results.comparable` leaves it out).
- `meta.command`: the exact command that wrote the file, as a list of arguments (`bench evaluate`'s own).
- `training`: a trained row's training record (:data:`TRAINING`), made by `python -m chopperscape.bench row`:

      {"format": "chopperscape-bench/training/1", "row", "trainer", "mode", "seed", "command", "commit",
       "settings", "steps", "env_steps", "train_seeds": [[first, count], ...]}

  `command` is the exact training command, `commit` the project's commit it ran at, `settings` the trainer's full
  settings (the recipe of `chopperscape.learn.train`; the SB3 and RLlib trainers' settings with their defaults
  written out), `steps` the step budget, `env_steps` the steps trained, and `train_seeds` every reset seed the
  trainer's environments were seeded with, as ranges (RLlib's runners' too: runner `w` of seed `s` resets game `i`
  with `(s + w) * 2**20 + i`), each checked against the evaluation seeds.
"""

from __future__ import annotations

import functools
import json
import os
import re
import subprocess
from pathlib import Path
from typing import Any

from .. import __version__
from . import protocol

#: The format of a training record (`training` of a results file, `RUN/training.json`).
TRAINING = "chopperscape-bench/training/1"
_KEYS = ("format", "row", "trainer", "mode", "seed", "command", "commit", "settings", "steps", "env_steps")
#: The largest training record read (a settings object is a few kilobytes).
MAX_BYTES = 1 << 20


def _git(root: Path, *args: str) -> str | None:
    """`git -C root ARGS`'s output, or None where git fails (no git, not a checkout)."""
    try:
        done = subprocess.run(["git", "-C", str(root), *args], capture_output=True, timeout=30)
    except (OSError, subprocess.SubprocessError):
        return None
    return done.stdout.decode(errors="replace") if done.returncode == 0 else None


def _head(root: Path) -> tuple[str, bool] | None:
    """`(HEAD, modified)` of the checkout at `root`: whether tracked files differ from HEAD."""
    sha = (_git(root, "rev-parse", "HEAD") or "").strip()
    status = _git(root, "status", "--porcelain", "--untracked-files=no")
    if not re.fullmatch(r"[0-9a-f]{40}", sha):
        return None
    return sha, status is None or bool(status.strip())


def _same_sources(package: Path, source: Path) -> bool:
    """Whether every module of the checkout's package sources `source` is in the installed `package`, byte for
    byte (the wheel built from that checkout, not an older one)."""
    modules = sorted(source.rglob("*.py"))
    if not modules:
        return False
    try:
        return all((package / m.relative_to(source)).read_bytes() == m.read_bytes() for m in modules)
    except OSError:
        return False


@functools.lru_cache(maxsize=1)
def project_commit() -> tuple[str, bool | None]:
    """`(commit, modified)`: the checkout's HEAD and whether tracked files differ from it. The checkout is the one
    this package's files are tracked in, or, for an installed package (a wheel in a venv), the checkout of the
    current folder when its `python/chopperscape` modules are the installed ones byte for byte (`pip install
    ./python`, then run from the checkout). Else `(package version, None)`."""
    package = Path(__file__).resolve().parents[1]
    if _git(package / "bench", "ls-files", "--error-unmatch", Path(__file__).name) is not None:
        head = _head(package)
        if head is not None:
            return head
    top = (_git(Path.cwd(), "rev-parse", "--show-toplevel") or "").strip()
    if top and _same_sources(package, Path(top) / "python" / "chopperscape"):
        head = _head(Path(top))
        if head is not None:
            return head
    return __version__, None


def commit() -> dict[str, Any]:
    """A results file's `meta.commit` (and `meta.modified` in a checkout)."""
    sha, modified = project_commit()
    return {"commit": sha} if modified is None else {"commit": sha, "modified": modified}


def _int(v: Any) -> bool:
    return isinstance(v, int) and not isinstance(v, bool)


def _strings(v: Any) -> bool:
    return isinstance(v, list) and len(v) > 0 and all(isinstance(x, str) for x in v)


def check_training(t: Any, mode: str | None = None) -> dict[str, Any]:
    """`t` if it is a complete training record (of mode `mode`, when given); `ValueError` naming the first field
    that is not."""

    def need(cond: bool, what: str) -> None:
        if not cond:
            raise ValueError(f"`training.{what}")

    need(isinstance(t, dict), "` must be an object")
    need(t.get("format") == TRAINING, f"format` must be {TRAINING!r}")
    missing = [k for k in (*_KEYS, "train_seeds") if k not in t]
    need(not missing, f"{missing[0] if missing else ''}` is missing")
    for key in ("row", "trainer", "mode", "commit"):
        need(isinstance(t[key], str) and t[key] != "", f"{key}` must be a non-empty string")
    if mode is not None:
        need(t["mode"] == mode, f"mode` is {t['mode']!r}, the results file's mode is {mode!r}")
    need(_int(t["seed"]) and t["seed"] >= 0, "seed` must be an int >= 0")
    need(_strings(t["command"]), "command` must be a non-empty list of strings")
    need(isinstance(t["settings"], dict), "settings` must be an object")
    for key in ("steps", "env_steps"):
        need(t[key] is None or (_int(t[key]) and t[key] >= 0), f"{key}` must be an int >= 0 or null")
    seeds = t["train_seeds"]
    need(
        isinstance(seeds, list)
        and len(seeds) > 0
        and all(isinstance(r, list) and len(r) == 2 and all(_int(x) for x in r) for r in seeds),
        "train_seeds` must be a non-empty list of [first, count]",
    )
    for first, count in seeds:
        try:
            protocol.check_training_seeds(first, count)
        except ValueError as e:
            raise ValueError(f"`training.train_seeds`: {e}") from None
    return t


def check(doc: dict[str, Any]) -> None:
    """Checks the optional fields of a results document (the module's docs); `ValueError` naming the first that
    is not as described. A document without them passes."""
    meta = doc.get("meta")
    meta = meta if isinstance(meta, dict) else {}
    if "commit" in meta:
        c, version = meta["commit"], doc["package"].get("version")
        if not (isinstance(c, str) and (re.fullmatch(r"[0-9a-f]{40}", c) is not None or c == version)):
            raise ValueError("`meta.commit` must be 40 hex digits or the package's version")
    if "modified" in meta and not isinstance(meta["modified"], bool):
        raise ValueError("`meta.modified` must be true or false")
    if "command" in meta and not _strings(meta["command"]):
        raise ValueError("`meta.command` must be a non-empty list of strings")
    if "training" in doc:
        check_training(doc["training"], doc["mode"]["name"])


def read_training(path: str | os.PathLike) -> dict[str, Any]:
    """A training record file (`RUN/training.json`), checked; `ValueError` naming the file and what is wrong."""
    name = str(path)
    try:
        if os.path.getsize(path) > MAX_BYTES:
            raise ValueError(f"training record {name!r}: larger than {MAX_BYTES} bytes")
        return check_training(json.loads(Path(path).read_text(encoding="utf-8")))
    except (OSError, UnicodeDecodeError) as e:
        raise ValueError(f"training record {name!r}: cannot read it ({e})") from None
    except ValueError as e:
        raise ValueError(f"training record {name!r}: {e}") from None
