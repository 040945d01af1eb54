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
  auxiliary features loss (``--aux-coef``) and KL(teacher ‖ policy) (``--teacher``).
"""

from __future__ import annotations

import csv
import os
from collections.abc import Mapping, Sequence
from pathlib import Path
from typing import Any, TextIO

RETURNS = ("env_steps", "wall_s", "episodes", "mean_return", "std_return", "mean_length")
DIAGNOSTICS = ("learning_rate", "entropy", "approx_kl", "clip_frac", "explained_var", "value_loss", "policy_loss")
ENDINGS = ("ended", "bird", "fuel", "limit")
GUIDANCE = ("aux_loss", "teacher_kl")
#: The columns ``chopperscape.learn.train`` writes, in order.
COLUMNS = RETURNS + DIAGNOSTICS + ENDINGS + GUIDANCE


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
    episode have none); `ValueError` naming the file when a column is missing or no row has a return."""
    with open(path, newline="") as f:
        rows = list(csv.DictReader(f))
    if not rows:
        raise ValueError(f"{path}: no rows")
    missing = [c for c in columns if c not in rows[0]]
    if missing:
        raise ValueError(f"{path}: missing columns {missing} (expected {','.join(RETURNS)}, ...)")
    rows = [r for r in rows if r["mean_return"] not in ("", None)]
    if not rows:
        raise ValueError(f"{path}: no finished episode yet")
    try:
        return {c: [float(r[c]) if r[c] != "" else float("nan") for r in rows] for c in columns}
    except (TypeError, ValueError) as e:
        raise ValueError(f"{path}: not a progress CSV ({e})") from None
