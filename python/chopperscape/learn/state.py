"""Everything a training run carries from one update to the next, in one object that saves and restores itself:
:class:`TrainState`, and its file ``OUT/resume.pt`` (format ``chopperscape-ppo-resume/2``).

A field of the state is saved by what it is, never by a list kept elsewhere: an object with ``state_dict`` /
``load_state_dict`` (the networks, the optimiser, the normalisers, the episodes, the env batch, the random
streams) gives and takes its own; a tensor, an array, a number or a generator is stored as data. A new piece of
state is a new field, and checkpoints carry it with no other change. The file holds tensors and plain data only
(read with ``torch.load(weights_only=True)``) and names the recipe it belongs to (its SHA-256): a resume state
copied from another run is refused.
"""

from __future__ import annotations

import json
import os
import time
from dataclasses import dataclass, fields
from pathlib import Path
from typing import Any

import numpy as np
import torch

from .. import _atomic, _signals
from ..vector import VectorEnv
from .recipe import Recipe
from .rundir import RECIPE_KEY, check_recipe_hash, recipe_hash

#: The format of `OUT/resume.pt`: 2 is the state by field (1, by a fixed list of keys, is refused).
RESUME_FORMAT = "chopperscape-ppo-resume/2"
#: Fields added after resume states existed, with what an older state stands for (the part's state when off), so
#: that older run folders still resume; a run whose recipe turns the part on has a recipe hash no older state has.
LATER_FIELDS: dict[str, Any] = {"frames_loss": None, "novelty": None}


class EnvBatch:
    """A vector env's whole state (every env's snapshot, its autoreset flag and step count) as tensors and plain
    data; restoring it puts the envs back where they were, the core checking every snapshot."""

    def __init__(self, envs: VectorEnv):
        self.envs = envs

    def state_dict(self) -> dict[str, Any]:
        started, each = self.envs.batch_state()
        return {
            "started": bool(started),
            "snapshots": [torch.frombuffer(bytearray(b), dtype=torch.uint8) for b, _, _ in each],
            "flags": [bool(f) for _, f, _ in each],
            "steps": [int(k) for _, _, k in each],
        }

    def load_state_dict(self, s: dict[str, Any]) -> None:
        each = [(bytes(t.numpy().tobytes()), f, k) for t, f, k in zip(s["snapshots"], s["flags"], s["steps"])]
        if len(each) != self.envs.num_envs:
            raise ValueError(f"the resume state holds {len(each)} envs, the run has {self.envs.num_envs}")
        self.envs.set_batch_state(bool(s["started"]), each)


class TorchRng:
    """torch's global random stream (action sampling, the random shift) as a state field."""

    def state_dict(self) -> torch.Tensor:
        return torch.get_rng_state()

    def load_state_dict(self, s: torch.Tensor) -> None:
        torch.set_rng_state(s)


class Clock:
    """The run's wall time: the seconds of the processes before this one (a resumed run's curve keeps counting)
    plus this one's."""

    def __init__(self) -> None:
        self.before, self.start = 0.0, time.monotonic()

    def restart(self) -> None:
        self.start = time.monotonic()

    def elapsed(self) -> float:
        """Seconds of this process's part of the run."""
        return time.monotonic() - self.start

    def seconds(self) -> float:
        return self.before + self.elapsed()

    def state_dict(self) -> float:
        return self.seconds()

    def load_state_dict(self, s: float) -> None:
        self.before = float(s)


@dataclass
class TrainState:
    """A run between two updates: what a checkpoint saves and `--resume` restores, each field by itself."""

    agent: Any  # networks.ActorCritic
    optimizer: torch.optim.Optimizer
    obs_norm: Any  # normalize.ObsNormalizer
    rewards: Any  # normalize.RewardScaler
    episodes: Any  # rollout.Episodes
    envs: EnvBatch
    guidance: Any  # the recipe's guidance part (parts.Unguided for plain PPO)
    frames_loss: Any  # the recipe's self-supervised part (selfsup.NoFramesLoss when off)
    novelty: Any  # the recipe's exploration bonus (novelty.NoNovelty when off)
    rng: np.random.Generator  # the minibatch permutations
    torch_rng: TorchRng
    clock: Clock
    next_obs: torch.Tensor  # the observation the next step acts on, as the network takes it
    next_done: np.ndarray  # the previous step ended an episode: the next step is a reset step
    env_steps: int = 0
    update: int = 0

    def state_dict(self) -> dict[str, Any]:
        return {f.name: _save(getattr(self, f.name)) for f in fields(self)}

    def load_state_dict(self, saved: dict[str, Any]) -> None:
        """Restores every field from `saved`; `ValueError` naming the first that is missing or does not fit."""
        for f in fields(self):
            if f.name not in saved and f.name not in LATER_FIELDS:
                raise ValueError(f"it holds no `{f.name}`")
            try:
                setattr(self, f.name, _load(getattr(self, f.name), saved.get(f.name, LATER_FIELDS.get(f.name))))
            except (KeyError, TypeError, ValueError, RuntimeError, AttributeError) as e:
                raise ValueError(f"`{f.name}` does not fit ({e})") from None

    def save(self, path: Path, recipe: Recipe) -> None:
        """Writes the state to `path` whole or not at all (a signal waits until it is written)."""
        payload = {"format": RESUME_FORMAT, RECIPE_KEY: recipe_hash(recipe), "state": self.state_dict()}
        with _signals.deferred(f"the resume state is saved in {path}"), _atomic.replacing(path) as tmp:
            torch.save(payload, tmp)

    def resume(self, path: Path, recipe: Recipe) -> None:
        """Restores the state `path` holds (see :func:`read_resume`); `ValueError` naming the run folder when it does
        not fit this run."""
        try:
            self.load_state_dict(read_resume(path, recipe))
        except ValueError as e:
            raise ValueError(f"--resume {path.parent}: resume.pt does not fit this run's recipe: {e}") from None


def read_resume(path: Path, recipe: Recipe) -> dict[str, Any]:
    """The state a resume file holds (tensors and plain data, read with `weights_only=True`); `ValueError` naming
    the file when it is missing, not one this trainer wrote, or another run's (its recipe differs)."""
    from .modelfile import read_checkpoint

    what = f"resume state {str(path)!r}"
    if not os.path.lexists(path):
        raise ValueError(
            f"--resume {path.parent}: no resume.pt there (a run saves one at each checkpoint, every 50 updates)"
        )
    payload = read_checkpoint(path, what)
    if not isinstance(payload, dict) or payload.get("format") != RESUME_FORMAT or "state" not in payload:
        raise ValueError(f"{what} is not a resume state of this trainer (format {RESUME_FORMAT})")
    if payload.get(RECIPE_KEY) is None:
        raise ValueError(f"{what} records no recipe: it is not a resume state of this trainer (format {RESUME_FORMAT})")
    check_recipe_hash(payload, recipe, path.parent)
    return payload["state"]


def _save(value: Any) -> Any:
    """A field as tensors and plain data."""
    if hasattr(value, "state_dict"):
        return value.state_dict()
    if isinstance(value, torch.Tensor):
        return value.detach().cpu()
    if isinstance(value, np.ndarray):
        return torch.from_numpy(value.copy())
    if isinstance(value, np.random.Generator):
        return json.dumps(value.bit_generator.state)
    if isinstance(value, (bool, int, float, str)) or value is None:
        return value
    raise TypeError(f"a training state field of type {type(value).__name__} cannot be saved")


def _load(current: Any, saved: Any) -> Any:
    """The field `current` restored from `saved` (in place for objects that load their own state)."""
    if hasattr(current, "load_state_dict"):
        current.load_state_dict(saved)
        return current
    if isinstance(current, torch.Tensor):
        if not isinstance(saved, torch.Tensor) or saved.shape != current.shape or saved.dtype != current.dtype:
            raise ValueError(f"a tensor of {tuple(current.shape)} {current.dtype} is wanted")
        return saved.to(current.device)
    if isinstance(current, np.ndarray):
        if not isinstance(saved, torch.Tensor) or tuple(saved.shape) != current.shape:
            raise ValueError(f"an array of shape {current.shape} is wanted")
        return saved.numpy().astype(current.dtype)
    if isinstance(current, np.random.Generator):
        current.bit_generator.state = json.loads(saved)
        return current
    if isinstance(current, bool) or current is None or isinstance(saved, bool):
        return saved
    return type(current)(saved)
