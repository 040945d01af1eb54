"""Gymnasium spaces built from what the Rust core declares. (The argument rules both environments share are in
`_checks.py`; `check_bool`, `core_seed` and `check_reset_options` are re-exported here.)"""

from __future__ import annotations

from typing import Any

import numpy as np
from gymnasium import spaces

from ._checks import check_bool, check_reset_options, core_seed

__all__ = [
    "BroadcastBox",
    "batched_box",
    "channel_axis",
    "check_bool",
    "check_reset_options",
    "core_seed",
    "observation_box",
]


class BroadcastBox(spaces.Box):
    """A `gymnasium.spaces.Box` whose bounds repeat: one value for pixel observations, one features vector per
    stacked frame, and the same bounds for every environment of a batch.

    `low`, `high`, `bounded_below` and `bounded_above` are read-only broadcast views of one row of bounds, so
    the space costs no memory per element: a plain `Box` holds four arrays the size of an observation (of the
    whole batch, once batched), 368 MB for 64 rgb environments. It is a `Box` in every other way (equality,
    `contains`, `sample`, pickling, `isinstance`); `gymnasium.vector.utils.batch_space` of it is a plain `Box`.
    """

    def __init__(self, low: Any, high: Any, shape: tuple[int, ...], dtype: Any, seed: Any = None):
        row_low, row_high = np.asarray(low, dtype=dtype), np.asarray(high, dtype=dtype)
        super().__init__(low=row_low.copy(), high=row_high.copy(), dtype=dtype, seed=seed)
        self._row = (row_low, row_high)
        self._shape = tuple(int(d) for d in shape)
        for name in ("low", "high", "bounded_below", "bounded_above"):
            setattr(self, name, np.broadcast_to(getattr(self, name), self._shape))

    def __reduce__(self):
        return (_rebuild_box, (*self._row, self._shape, self.dtype, self._np_random))


def _rebuild_box(low: Any, high: Any, shape: tuple[int, ...], dtype: Any, np_random: Any) -> BroadcastBox:
    box = BroadcastBox(low, high, shape, dtype)
    if np_random is not None:
        box._np_random = np_random
    return box


def _bounds_row(core) -> tuple[np.ndarray, np.ndarray, tuple[int, ...], np.dtype]:
    """The core's bounds as the row `BroadcastBox` repeats: a scalar, or the flat features bounds."""
    shape = tuple(core.obs_shape)
    low, high = core.obs_bounds
    if len(low) == 1:
        return low.reshape(()), high.reshape(()), shape, np.dtype(core.obs_dtype)
    # One features vector's bounds, once per stacked frame: a few thousand values at most.
    reps = int(np.prod(shape)) // len(low)
    return np.tile(low, reps).reshape(shape), np.tile(high, reps).reshape(shape), shape, np.dtype(core.obs_dtype)


def observation_box(core, keep_dim: bool = False) -> BroadcastBox:
    """The observation space of one environment: a `Box` with the core's shape, dtype and bounds. With
    `keep_dim`, a 2-D (grayscale, unstacked) observation gets a trailing channel axis: `(H, W, 1)`."""
    low, high, shape, dtype = _bounds_row(core)
    if dtype == np.uint8:
        low, high = np.asarray(0.0), np.asarray(255.0)
    if keep_dim and len(shape) == 2:
        shape = (*shape, 1)
    return BroadcastBox(low, high, shape, dtype)


def channel_axis(keep_dim: Any, core) -> bool:
    """Whether observations get a trailing channel axis: `keep_dim` (a bool) and a 2-D observation."""
    return check_bool("keep_dim", keep_dim) and len(tuple(core.obs_shape)) == 2


def batched_box(single: BroadcastBox, n: int) -> BroadcastBox:
    """`single` stacked `n` times on a new first axis, still without bounds per element."""
    low, high = single._row
    return BroadcastBox(low, high, (n, *single.shape), single.dtype)
