"""SIGINT, SIGTERM and SIGHUP during work that must not be cut at an arbitrary point (a dataset being written, a
model being saved): the one place where the package handles them.

While a `defer()` guard is active, these signals only note themselves; the work looks at `guard.pending` (or
calls `guard.check()`) at its safe points and stops there, cleaning up what it left unfinished. A Ctrl-C is
therefore never raised inside a finalizer or a weakref callback (where Python prints "Exception ignored" and
carries on), nor halfway through a file. `Interrupted` (a `BaseException`, as `KeyboardInterrupt`) carries the
exit status a program stopped by that signal reports: 130, 143, 129.

Handlers can only be set in the main thread; elsewhere a guard notes nothing and the signals keep their usual
behaviour. Guards nest: an inner one shares the outer one's state.
"""

from __future__ import annotations

import contextlib
import signal
import threading
from collections.abc import Iterator
from typing import Any

#: The signals a guard defers.
SIGNALS = tuple(getattr(signal, name) for name in ("SIGINT", "SIGTERM", "SIGHUP") if hasattr(signal, name))


class Interrupted(BaseException):
    """The work stopped at a safe point because of signal `signum`; `exit_code` is `128 + signum`."""

    def __init__(self, signum: int, message: str = ""):
        self.signum = signum
        self.exit_code = 128 + signum
        name = {int(signal.SIGINT): "interrupted"}.get(signum) or (
            "terminated" if signum == getattr(signal, "SIGTERM", None) else "hung up"
        )
        super().__init__(f"{name}{'; ' + message if message else ''}")


class Guard:
    """Deferred signals (see the module docs)."""

    def __init__(self) -> None:
        self.pending: int | None = None
        self._previous: dict[int, Any] = {}
        self._depth = 0

    def _note(self, signum: int, frame: object) -> None:
        if self.pending is None:
            self.pending = signum

    def check(self, message: str = "") -> None:
        """Raises `Interrupted` if a signal came since the guard started."""
        if self.pending is not None:
            raise Interrupted(self.pending, message)

    def restore(self) -> None:
        """Gives the signals back their handlers (the outermost guard only); `pending` stays readable."""
        global _active
        self._depth -= 1
        if self._depth > 0:
            return
        for signum, handler in self._previous.items():
            signal.signal(signum, handler)
        self._previous.clear()
        if _active is self:
            _active = None


_active: Guard | None = None


def defer() -> Guard:
    """Starts deferring SIGINT, SIGTERM and SIGHUP (or joins the guard already active); call `restore()` when
    the work is done, in a `finally`."""
    global _active
    if _active is not None:
        _active._depth += 1
        return _active
    guard = Guard()
    guard._depth = 1
    if threading.current_thread() is threading.main_thread():
        for signum in SIGNALS:
            guard._previous[signum] = signal.signal(signum, guard._note)
        _active = guard
    return guard


@contextlib.contextmanager
def deferred(message: str = "") -> Iterator[Guard]:
    """`defer()` for a block: once the block has completed, a signal that came during it raises `Interrupted`
    (an outermost guard only; an inner one leaves that to the outer work)."""
    guard = defer()
    outermost = guard._depth == 1
    try:
        yield guard
    finally:
        guard.restore()
    if outermost:
        guard.check(message)
