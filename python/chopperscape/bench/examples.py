"""Policies by import path, for `python -m chopperscape.bench evaluate pkg.mod:func` (and its tests)."""

from __future__ import annotations

import numpy as np


def always_up(obs: np.ndarray) -> np.ndarray:
    """Action 3 (Up) for every observation of the batch."""
    return np.full(len(obs), 3, dtype=np.int64)
