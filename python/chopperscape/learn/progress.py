"""The learning-curve CSV: one schema for every learner here and every reader.

Writers: ``python -m chopperscape.learn.train`` (all columns), the SB3 and RLlib examples (the :data:`RETURNS` columns;
they have no per-update diagnostics of their own). Readers: ``python -m chopperscape.learn.plot`` and
``python -m chopperscape.learn.seeds``. One row per update (train) or per rollout/iteration (the examples):

- :data:`RETURNS`: env steps so far, wall seconds, episodes finished so far, and the mean, standard deviation and
  mean length of the last 100 finished episodes (blank until one has finished);
- :data:`DIAGNOSTICS`: the update's learning rate, policy entropy, approximate KL (``(ratio - 1) - log ratio``),
  clip fraction, explained variance of the value targets, value and policy losses (means over its minibatches);
- :data:`ENDINGS`: how many episodes ended during the update, and the shares among them that a bird, the fuel and
  the step limit ended (blank when none ended);
- :data:`GUIDANCE`: the pixel recipes' training-only losses, means over the update's minibatches, blank when off: the
  auxiliary features loss (``--aux-coef``) and KL(teacher ‖ policy) (``--teacher``);
- :data:`SELF_SUPERVISED`: the loss from the frames alone (``--recon-coef``), its mean over the update's minibatches
  before the weight, blank when off;
- :data:`NOVELTY`: the exploration bonus's (``--rnd-coef``): its predictor's loss, mean over the update's
  minibatches, and the mean raw bonus (the prediction error) of the rollout's steps, blank when off.

A run's CSV written before a column group was added resumes: its rows are kept with the new columns blank.
"""

from __future__ import annotations

import csv
import io
import math
import os
from collections.abc import Mapping, Sequence
from pathlib import Path
from typing import Any, TextIO

from .._checks import regular_file

RETURNS = ("env_steps", "wall_s", "episodes", "mean_return", "std_return", "mean_length")
DIAGNOSTICS = ("learning_rate", "entropy", "approx_kl", "clip_frac", "explained_var", "value_loss", "policy_loss")
ENDINGS = ("ended", "bird", "fuel", "limit")
GUIDANCE = ("aux_loss", "teacher_kl")
SELF_SUPERVISED = ("recon_loss",)
NOVELTY = ("rnd_loss", "novelty")
#: The columns ``chopperscape.learn.train`` writes, in order.
COLUMNS = RETURNS + DIAGNOSTICS + ENDINGS + GUIDANCE + SELF_SUPERVISED + NOVELTY
#: The columns of the CSVs written before :data:`SELF_SUPERVISED` (they resume, the new columns blank).
OLDER_COLUMNS = RETURNS + DIAGNOSTICS + ENDINGS + GUIDANCE
#: Every header an earlier version wrote, oldest first: before :data:`SELF_SUPERVISED`, before :data:`NOVELTY`.
OLDER_HEADERS = (OLDER_COLUMNS, OLDER_COLUMNS + SELF_SUPERVISED)
#: The largest progress CSV read (a 15-million-step run of the recipe writes about 200 KB).
MAX_BYTES = 64 << 20


class Writer:
    """A progress CSV opened for writing (truncated), its header written; each :meth:`row` is flushed, so a
    crashed or stopped run keeps every row it reached. Values are written as given (format them first)."""

    def __init__(self, path: str | os.PathLike, columns: Sequence[str] = COLUMNS):
        unknown = [c for c in columns if c not in COLUMNS]
        if unknown or list(columns[: len(RETURNS)]) != list(RETURNS):
            raise ValueError(
                f"progress columns must start with {list(RETURNS)} and come from {list(COLUMNS)}; got {list(columns)}"
            )
        self.columns = tuple(columns)
        Path(path).parent.mkdir(parents=True, exist_ok=True)
        self._file: TextIO = open(path, "w", newline="")
        self._csv = csv.writer(self._file)
        self._csv.writerow(self.columns)
        self._file.flush()

    @classmethod
    def resume(cls, path: str | os.PathLike, env_steps: int) -> Writer:
        """Continues the progress CSV of a run resumed at `env_steps`: its rows up to there are kept (rows written
        after that checkpoint are dropped, since the resumed run writes them again), rewritten atomically, and the
        file opened for appending. `ValueError` naming the file when it is not this module's CSV."""
        from .. import _atomic

        regular_file(path, str(path), MAX_BYTES)
        try:
            with open(path, newline="", encoding="utf-8") as f:
                rows = list(csv.reader(f))
        except (UnicodeDecodeError, csv.Error, OSError) as e:
            raise ValueError(f"{path}: not a progress CSV this trainer wrote ({e})") from None
        if not rows or tuple(rows[0]) not in (COLUMNS, *OLDER_HEADERS):
            raise ValueError(f"{path}: not a progress CSV this trainer wrote (its header differs)")
        at, width, pad = COLUMNS.index("env_steps"), len(rows[0]), [""] * (len(COLUMNS) - len(rows[0]))
        keep = [r + pad for r in rows[1:] if len(r) == width and r[at].isdigit() and int(r[at]) <= env_steps]
        text = io.StringIO()
        csv.writer(text).writerows([list(COLUMNS), *keep])
        _atomic.write_text(path, text.getvalue())
        writer = cls.__new__(cls)
        writer.columns = COLUMNS
        writer._file = open(path, "a", newline="")
        writer._csv = csv.writer(writer._file)
        return writer

    def row(self, values: Mapping[str, Any]) -> None:
        """One row; a column missing from `values` is written blank, an unknown key is a `KeyError`."""
        unknown = set(values) - set(self.columns)
        if unknown:
            raise KeyError(f"not progress columns: {sorted(unknown)}")
        self._csv.writerow(["" if values.get(c) is None else values[c] for c in self.columns])
        self._file.flush()

    def close(self) -> None:
        self._file.close()

    def __enter__(self) -> Writer:
        return self

    def __exit__(self, *exc: object) -> None:
        self.close()


def read(path: str | os.PathLike, columns: Sequence[str] = RETURNS) -> dict[str, list[float]]:
    """`columns` of one progress CSV as float lists, over the rows that have a return (rows before the first finished
    episode have none); a blank cell is NaN. `ValueError` naming the file when it is not a regular UTF-8 file of at
    most `MAX_BYTES`, is not a CSV, a column is missing, a cell is not a number (``nan`` and ``inf`` written out
    are not), or no row has a return."""
    regular_file(path, str(path), MAX_BYTES)
    try:
        with open(path, newline="", encoding="utf-8") as f:
            rows = list(csv.DictReader(f))
    except UnicodeDecodeError:
        raise ValueError(f"{path}: not a progress CSV (not UTF-8 text)") from None
    except csv.Error as e:
        raise ValueError(f"{path}: not a progress CSV ({e})") from None
    except OSError as e:
        raise ValueError(f"{path}: cannot be read: {e.strerror or e}") from None
    if not rows:
        raise ValueError(f"{path}: no rows")
    missing = [c for c in columns if c not in rows[0]]
    if missing:
        raise ValueError(f"{path}: missing columns {missing} (expected {','.join(RETURNS)}, ...)")
    rows = [r for r in rows if r.get("mean_return") not in ("", None)]
    if not rows:
        raise ValueError(f"{path}: no finished episode yet")

    def number(row: int, column: str, text: str | None) -> float:
        if text == "":
            return float("nan")
        try:
            x = float(text)  # type: ignore[arg-type]
        except (TypeError, ValueError):
            x = math.nan
        if not math.isfinite(x):
            raise ValueError(f"{path}: not a progress CSV (row {row}, column {column}: {text!r} is not a number)")
        return x

    return {c: [number(i + 1, c, r.get(c)) for i, r in enumerate(rows)] for c in columns}
