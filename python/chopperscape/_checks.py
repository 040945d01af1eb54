"""The argument rules every surface shares (environments, policies, datasets, the recipe, evaluation): one
function per kind of value, each raising `ValueError` that names the argument, the value and what is allowed."""

from __future__ import annotations

import math
from typing import Any

import numpy as np

_U64 = 0xFFFF_FFFF_FFFF_FFFF
#: The largest `max_episode_steps` the core counts to (a `u32`).
MAX_EPISODE_STEPS = 2**32 - 1


def _is_int(value: Any) -> bool:
    return isinstance(value, (int, np.integer)) and not isinstance(value, (bool, np.bool_))


def positive_int(name: str, value: Any, maximum: int | None = None) -> int:
    """`value` as an `int` >= 1 (numpy's integers too, never a bool, a float or a string), at most `maximum`."""
    if not _is_int(value) or value < 1 or (maximum is not None and value > maximum):
        allowed = "an integer >= 1" if maximum is None else f"an integer in 1..={maximum}"
        raise ValueError(f"invalid value {value!r} for option `{name}`: allowed {allowed}")
    return int(value)


def int_in(name: str, value: Any, low: int, high: int) -> int:
    """`value` as an `int` in `low..=high` (numpy's integers too, never a bool, a float or a string)."""
    if not _is_int(value) or not low <= value <= high:
        raise ValueError(f"invalid value {value!r} for option `{name}`: allowed an integer in {low}..={high}")
    return int(value)


def number_in(
    name: str, value: Any, low: float, high: float, *, low_open: bool = False, high_open: bool = False
) -> float:
    """`value` as a finite `float` in `[low, high]` (`(low, …` with `low_open`, `…, high)` with `high_open`); NaN and
    infinities never."""
    ok = isinstance(value, (int, float, np.integer, np.floating)) and not isinstance(value, (bool, np.bool_))
    ok = ok and math.isfinite(value) and (value > low if low_open else value >= low)
    ok = ok and (value < high if high_open else value <= high)
    if not ok:
        interval = f"{'(' if low_open else '['}{low:g}, {high:g}{')' if high_open else ']'}"
        raise ValueError(f"invalid value {value!r} for option `{name}`: allowed a finite number in {interval}")
    return float(value)


def check_bool(option: str, value: Any) -> bool:
    """A bool option (`copy`, `hud`, ...): `True` or `False` (numpy's too), never a string or a number."""
    if not isinstance(value, (bool, np.bool_)):
        raise ValueError(f"invalid value {value!r} for option `{option}`: allowed True or False")
    return bool(value)


def core_seed(seed: Any, what: str = "seed") -> int:
    """A Gymnasium seed as the core's `u64` seed: a non-negative integer (numpy's too), reduced modulo 2**64.

    The one seed rule of `ChopperScapeEnv.reset` and `VectorEnv.reset` (a single seed or each one of a list).
    """
    if not _is_int(seed) or seed < 0:
        raise ValueError(
            f"invalid {what} {seed!r}: allowed a non-negative integer (seeds of 2**64 and above are reduced "
            "modulo 2**64), or None"
        )
    return int(seed) & _U64


def policy_seed(seed: Any) -> int:
    """A built-in policy's (and a dataset's first) seed: an integer in `[0, 2**64)`, as the command line's
    `--seed`."""
    if not _is_int(seed) or not 0 <= seed <= _U64:
        raise ValueError(f"invalid seed {seed!r}: allowed an integer in [0, 2**64)")
    return int(seed)


def time_limit(value: Any) -> int | None:
    """`max_episode_steps`: `None` (never truncate) or an integer in `1..=4294967295`."""
    if value is None:
        return None
    if not _is_int(value) or not 1 <= value <= MAX_EPISODE_STEPS:
        raise ValueError(
            f"invalid value {value!r} for option `max_episode_steps`: allowed an integer in 1..={MAX_EPISODE_STEPS}, "
            "or None to never truncate"
        )
    return int(value)


def check_reset_options(options: Any) -> None:
    """The one rule for `reset(options=...)` of both environments: ChopperScape's reset takes no options."""
    if options:
        names = sorted(options) if isinstance(options, dict) else options
        raise ValueError(
            f"reset options {names!r} are not supported: ChopperScape's reset takes no options "
            "(a partial reset with options['reset_mask'] is not supported either)"
        )


def regular_file(path: Any, what: str, max_bytes: int | None = None) -> int:
    """The size of `path`, a regular file (symbolic links followed) of at most `max_bytes`; `ValueError` starting
    with `what` (which names the file) and saying why not: it does not exist, cannot be read, is a folder, a device
    (/dev/zero), a pipe or a socket, or is too large. Nothing is read."""
    import os
    import stat

    try:
        st = os.stat(path)
    except FileNotFoundError:
        raise ValueError(f"{what} does not exist") from None
    except OSError as e:
        raise ValueError(f"{what} cannot be read: {e.strerror or e}") from None
    if stat.S_ISDIR(st.st_mode):
        raise ValueError(f"{what} is a folder, not a file")
    if not stat.S_ISREG(st.st_mode):
        kind = "a device" if stat.S_ISCHR(st.st_mode) or stat.S_ISBLK(st.st_mode) else "a pipe or a socket"
        raise ValueError(f"{what} is {kind}, not a regular file")
    if max_bytes is not None and st.st_size > max_bytes:
        raise ValueError(f"{what} is {st.st_size:,} bytes, more than the {max_bytes:,} allowed")
    return int(st.st_size)
