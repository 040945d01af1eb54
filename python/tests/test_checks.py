"""The argument rules every surface shares (`chopperscape._checks`), at their boundaries: each accepts exactly what
its docstring says, returns it as a plain Python value, and refuses the rest with a message that names the
argument, the value and what is allowed. Written from a mutation pass (ARCHITECTURE.md, "Mutation testing"): the
surface-level tests let mutants of these rules live, each case here kills some."""

from __future__ import annotations

import math

import numpy as np
import pytest

from chopperscape import _checks as c

BAD_INTS = [True, False, np.bool_(True), 1.0, "1", None, [1], np.float32(1.0)]


@pytest.mark.parametrize("bad", BAD_INTS)
def test_integers_refuse_bools_floats_strings(bad):
    for check in (
        lambda v: c.positive_int("n", v),
        lambda v: c.int_in("n", v, 0, 5),
        lambda v: c.core_seed(v),
        lambda v: c.policy_seed(v),
        lambda v: c.time_limit(v) if v is not None else (_ for _ in ()).throw(ValueError("None is allowed")),
    ):
        with pytest.raises(ValueError):
            check(bad)


def test_positive_int_bounds_and_message():
    assert c.positive_int("n", 1) == 1 and type(c.positive_int("n", np.int64(7))) is int
    assert c.positive_int("n", 5, maximum=5) == 5
    with pytest.raises(ValueError, match=r"invalid value 0 for option `n`: allowed an integer >= 1$"):
        c.positive_int("n", 0)
    with pytest.raises(ValueError, match=r"invalid value 6 for option `m`: allowed an integer in 1\.\.=5$"):
        c.positive_int("m", 6, maximum=5)
    with pytest.raises(ValueError, match="allowed an integer >= 1"):
        c.positive_int("n", -3)


def test_int_in_bounds_and_message():
    assert c.int_in("k", 2, 2, 4) == 2 and c.int_in("k", 4, 2, 4) == 4 and type(c.int_in("k", np.int8(3), 2, 4)) is int
    for bad in (1, 5):
        with pytest.raises(ValueError, match=rf"invalid value {bad} for option `k`: allowed an integer in 2\.\.=4$"):
            c.int_in("k", bad, 2, 4)


def test_number_in_closed_open_and_non_finite():
    assert c.number_in("p", 0, 0.0, 1.0) == 0.0 and type(c.number_in("p", 1, 0.0, 1.0)) is float
    assert c.number_in("p", np.float32(0.5), 0.0, 1.0) == 0.5 and c.number_in("p", np.int64(1), 0.0, 1.0) == 1.0
    with pytest.raises(ValueError, match=r"invalid value 0 for option `g`: allowed a finite number in \(0, 1\]$"):
        c.number_in("g", 0, 0.0, 1.0, low_open=True)
    assert c.number_in("g", 1e-9, 0.0, 1.0, low_open=True) == 1e-9
    for bad in (-1e-12, 1.0000001, math.nan, math.inf, -math.inf, True, "0.5", None):
        with pytest.raises(ValueError, match=r"for option `p`: allowed a finite number in \[0, 1\]$"):
            c.number_in("p", bad, 0.0, 1.0)


def test_check_bool():
    assert c.check_bool("hud", True) is True and c.check_bool("hud", np.bool_(False)) is False
    for bad in (1, 0, "true", None, 1.0):
        with pytest.raises(ValueError, match=rf"invalid value {bad!r} for option `hud`: allowed True or False$"):
            c.check_bool("hud", bad)


def test_seeds():
    assert c.core_seed(0) == 0 and c.core_seed(2**64) == 0 and c.core_seed(2**64 + 5) == 5
    assert c.core_seed(np.uint64(2**64 - 1)) == 2**64 - 1 and type(c.core_seed(np.int32(3))) is int
    with pytest.raises(ValueError, match=r"^invalid reset seed -1: allowed a non-negative integer"):
        c.core_seed(-1, "reset seed")
    with pytest.raises(ValueError, match=r"^invalid seed -1: allowed a non-negative integer"):
        c.core_seed(-1)
    assert c.policy_seed(0) == 0 and c.policy_seed(2**64 - 1) == 2**64 - 1
    for bad in (-1, 2**64):
        with pytest.raises(ValueError, match=rf"^invalid seed {bad}: allowed an integer in \[0, 2\*\*64\)$"):
            c.policy_seed(bad)


def test_time_limit():
    assert c.time_limit(None) is None and c.time_limit(1) == 1
    assert c.time_limit(c.MAX_EPISODE_STEPS) == 2**32 - 1 and type(c.time_limit(np.int64(9))) is int
    for bad in (0, 2**32):
        with pytest.raises(ValueError, match=r"`max_episode_steps`: allowed an integer in 1\.\.=4294967295, or None"):
            c.time_limit(bad)


def test_reset_options():
    c.check_reset_options(None)
    c.check_reset_options({})
    with pytest.raises(
        ValueError, match=r"^reset options \['a', 'b'\] are not supported: ChopperScape's reset takes no"
    ):
        c.check_reset_options({"b": 1, "a": 2})
    with pytest.raises(ValueError, match=r"reset options \['reset_mask'\] are not supported"):
        c.check_reset_options(["reset_mask"])
