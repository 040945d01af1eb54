"""Running statistics and the two normalisations of the recipe: observations standardised by running mean and
variance (:class:`ObsNormalizer`, clipped to ±10, frozen at evaluation) and rewards scaled by the running standard
deviation of the discounted return (:class:`RewardScaler`, Gymnasium's NormalizeReward). Each keeps its state as
plain data (`state_dict` / `load_state_dict`), the form a checkpoint holds. No torch."""

from __future__ import annotations

import math
from typing import Any

import numpy as np
from gymnasium.wrappers.utils import RunningMeanStd as _GymRunningMeanStd


class RunningMeanStd(_GymRunningMeanStd):
    """Gymnasium's running mean and variance (Chan et al.'s parallel update, the one its and SB3's normalisers keep),
    with its state as plain data for checkpoints."""

    def __init__(self, shape: tuple[int, ...] = ()):
        super().__init__(shape=shape)

    def state(self) -> dict[str, Any]:
        return {"mean": self.mean.tolist(), "var": self.var.tolist(), "count": float(self.count)}

    @classmethod
    def from_state(cls, s: dict[str, Any]) -> RunningMeanStd:
        r = cls()
        r.mean, r.var, r.count = np.asarray(s["mean"]), np.asarray(s["var"]), float(s["count"])
        return r


class ObsNormalizer:
    """Standardises observations with running statistics, clipped to ±10 (frozen at evaluation)."""

    def __init__(self, shape: tuple[int, ...], enabled: bool = True):
        self.rms = RunningMeanStd(shape)
        self.enabled = enabled

    def __call__(self, obs: np.ndarray, update: bool = False) -> np.ndarray:
        obs = obs.astype(np.float32, copy=False)
        if not self.enabled:
            return obs
        if update:
            self.rms.update(obs)
        out = (obs - self.rms.mean) / np.sqrt(self.rms.var + 1e-8)
        return np.clip(out, -10.0, 10.0).astype(np.float32)

    def state_dict(self) -> dict[str, Any]:
        """The running statistics as plain data (kept even when disabled: a checkpoint's shape does not vary)."""
        return self.rms.state()

    def load_state_dict(self, s: dict[str, Any]) -> None:
        self.rms = RunningMeanStd.from_state(s)


class RewardScaler:
    """Rewards divided by the running standard deviation of the discounted return (Gymnasium's NormalizeReward, the
    scaling that let the value head learn: docs/learning.md), for a batch of `num_envs` envs stepped in NEXT_STEP
    autoreset mode. A reset step (`valid` False) neither updates the statistics nor carries a return, and its
    reward is 0; the return restarts after an episode's end. Disabled, the rewards pass as they are (as float32)."""

    def __init__(self, num_envs: int, gamma: float, enabled: bool = True):
        self.rms = RunningMeanStd(())
        self.disc_return = np.zeros(num_envs)
        self.gamma, self.enabled = gamma, enabled

    def __call__(self, reward: np.ndarray, valid: np.ndarray, done: np.ndarray) -> np.ndarray:
        r = reward.astype(np.float64)
        if self.enabled:
            self.disc_return = np.where(valid, self.disc_return * self.gamma + r, 0.0)
            if valid.any():
                self.rms.update(self.disc_return[valid])
            r = r / math.sqrt(self.rms.var + 1e-8)
            self.disc_return[done] = 0.0
        return np.where(valid, r, 0.0).astype(np.float32)

    def state_dict(self) -> dict[str, Any]:
        return {"rms": self.rms.state(), "disc_return": self.disc_return.tolist()}

    def load_state_dict(self, s: dict[str, Any]) -> None:
        disc_return = np.asarray(s["disc_return"], dtype=np.float64)
        if disc_return.shape != self.disc_return.shape:
            raise ValueError(
                f"the discounted returns of {disc_return.shape} envs, where the run has {self.disc_return.shape}"
            )
        self.rms, self.disc_return = RunningMeanStd.from_state(s["rms"]), disc_return
