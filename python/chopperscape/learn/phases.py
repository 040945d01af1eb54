"""Where a training loop's wall time goes: a stopwatch with one lap per phase of the loop.

:func:`chopperscape.learn.train.train` takes one (``phases=Phases()``) and calls :meth:`Phases.lap` at the end of each
phase; ``python/bench_train.py`` prints the totals beside each phase's floor. Without one the loop uses
:data:`OFF`, whose laps do nothing, so a training run pays a function call per lap and nothing else.
"""

from __future__ import annotations

import time

#: The phases of one update, in loop order. ``env``: `VectorEnv.step`; ``obs_norm``: observation normalisation and
#: the copy into a tensor; ``forward``: the rollout's forward passes (action sampling included); ``bookkeeping``:
#: the rest of a rollout step in Python (buffers, episode statistics, reward scaling); ``gae``: advantages and
#: returns; ``update``: the epochs of minibatch forward + backward + Adam; ``logging``: the progress row and the
#: checkpoint.
PHASES = ("env", "obs_norm", "forward", "bookkeeping", "gae", "update", "logging")


class Phases:
    """Seconds of wall time per phase, summed over the run (`seconds`), with the env steps they covered (`steps`)."""

    def __init__(self) -> None:
        self.seconds = dict.fromkeys(PHASES, 0.0)
        self.steps = 0
        self._last = time.perf_counter()

    def start(self) -> None:
        """Starts the clock (the time since the last lap, or since creation, is not counted)."""
        self._last = time.perf_counter()

    def lap(self, phase: str) -> None:
        """Adds the time since the last lap (or `start`) to `phase`."""
        now = time.perf_counter()
        self.seconds[phase] += now - self._last
        self._last = now


class _Off(Phases):
    """A stopwatch that measures nothing (the default of a training run)."""

    def start(self) -> None:
        pass

    def lap(self, phase: str) -> None:
        pass


#: The stopwatch a run uses when none is given.
OFF: Phases = _Off()
