"""Where a training loop's wall time goes: a stopwatch that wraps the functions the loop calls, one phase each.

:func:`chopperscape.learn.train.train` takes one (``phases=Phases()``) and, before its loop, passes the functions
it calls through :meth:`Phases.timed`; the loop's text holds no timing. ``python/bench_train.py`` prints the totals
beside each phase's floor. Without one the run uses :data:`OFF`, whose :meth:`~Phases.timed` gives each function
back unchanged: a training run pays nothing.
"""

from __future__ import annotations

import time
from collections.abc import Callable
from typing import TypeVar

#: The phases of one update, in loop order. ``env``: `VectorEnv.step`; ``obs_norm``: observation normalisation and
#: the copy into a tensor; ``forward``: the rollout's forward passes (action sampling included); ``bookkeeping``:
#: the rest of the loop in Python (buffers, episode statistics, reward scaling, the schedule: the loop's time less
#: every other phase); ``gae``: advantages and returns; ``update_forward``: the update's forward passes and losses
#: (augmentation and guidance included); ``backward``: their gradients; ``optimizer``: gradient clipping and
#: Adam's step; ``logging``: the progress row and the checkpoint.
PHASES = ("env", "obs_norm", "forward", "bookkeeping", "gae", "update_forward", "backward", "optimizer", "logging")

_F = TypeVar("_F", bound=Callable)


class Phases:
    """Seconds of wall time per phase, summed over the run (`seconds`), with the env steps they covered (`steps`).
    Each phase's first call is counted apart (`first`): there a compiled network (`--torch-compile`) compiles, which
    says nothing of the phase's cost per step."""

    def __init__(self) -> None:
        self.seconds = dict.fromkeys(PHASES, 0.0)
        self.first = dict.fromkeys(PHASES, 0.0)
        self.steps = 0
        self._start = time.perf_counter()

    def timed(self, phase: str, fn: _F) -> _F:
        """`fn`, its wall time added to `phase` at each call but the first (added to `first[phase]`)."""
        seconds, first = self.seconds, self.first
        called = False

        def wrapped(*args, **kwargs):
            nonlocal called
            t = time.perf_counter()
            try:
                return fn(*args, **kwargs)
            finally:
                (seconds if called else first)[phase] += time.perf_counter() - t
                called = True

        return wrapped  # type: ignore[return-value]

    def start(self) -> None:
        """Starts the loop's clock (what came before, the setup, is not counted)."""
        self._start = time.perf_counter()

    def finish(self, steps: int) -> None:
        """Stops the loop's clock at `steps` env steps: the loop's time not in a timed phase is `bookkeeping`."""
        self.steps = steps
        timed = sum(v for k, v in self.seconds.items() if k != "bookkeeping") + sum(self.first.values())
        self.seconds["bookkeeping"] = max(time.perf_counter() - self._start - timed, 0.0)


class _Off(Phases):
    """A stopwatch that measures nothing (the default of a training run)."""

    def timed(self, phase: str, fn: _F) -> _F:
        return fn

    def start(self) -> None:
        pass

    def finish(self, steps: int) -> None:
        pass


#: The stopwatch a run uses when none is given.
OFF: Phases = _Off()
