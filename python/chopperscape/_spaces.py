"""Gymnasium spaces built from what the Rust core declares."""

from __future__ import annotations

import numpy as np
from gymnasium import spaces


def observation_box(core) -> spaces.Box:
    """The observation space of one environment: `Box` with the core's shape, dtype and bounds."""
    shape = tuple(core.obs_shape)
    dtype = np.dtype(core.obs_dtype)
    low, high = core.obs_low, core.obs_high
    if dtype == np.uint8:
        return spaces.Box(low=0, high=255, shape=shape, dtype=np.uint8)
    if np.all(low == low[0]) and np.all(high == high[0]):
        return spaces.Box(low=float(low[0]), high=float(high[0]), shape=shape, dtype=np.float32)
    return spaces.Box(low=low.reshape(shape), high=high.reshape(shape), dtype=np.float32)


def core_seed(seed: int) -> int:
    """A Gymnasium seed as the core's `u64` seed: the same number for every seed below 2**64."""
    return int(seed) & 0xFFFF_FFFF_FFFF_FFFF
