"""The SB3 adapter keeps SB3's `VecEnv` contract as `DummyVecEnv` keeps it, call for call (checked against a real
`DummyVecEnv` over the same envs), and refuses at once, changing nothing, what `DummyVecEnv` would store and fail
on later."""

from __future__ import annotations

import numpy as np
import pytest
from conftest import SHORT

pytest.importorskip("stable_baselines3", reason="stable-baselines3 is not installed")
from stable_baselines3.common.env_util import make_vec_env
from stable_baselines3.common.monitor import Monitor

from chopperscape.integrations.sb3 import ChopperScapeVecEnv

N = 4


def pair():
    ref = make_vec_env("ChopperScape-v0", n_envs=N, env_kwargs=dict(SHORT))
    ours = ChopperScapeVecEnv(N, render_mode="rgb_array", **SHORT)  # make_vec_env asks for rgb_array frames
    return ref, ours


def same_step(ref, ours, actions):
    o1, r1, d1, i1 = ref.step(actions)
    o2, r2, d2, i2 = ours.step(actions)
    assert np.array_equal(o1, o2) and np.array_equal(r1, r2) and np.array_equal(d1, d2)
    for a, b in zip(i1, i2):
        assert a.get("cause") == b.get("cause") and a.get("TimeLimit.truncated") == b.get("TimeLimit.truncated")


def test_the_same_calls_give_the_same_results_as_dummy_vec_env():
    ref, ours = pair()
    assert ref.seed(5) == ours.seed(5) == [5, 6, 7, 8]
    assert np.array_equal(ref.reset(), ours.reset())
    rng = np.random.default_rng(0)
    for _ in range(120):
        same_step(ref, ours, rng.integers(0, 5, N))
    # A list of actions, numpy ints of other widths: accepted by both.
    same_step(ref, ours, [0, 1, 2, 3])
    same_step(ref, ours, np.array([4, 3, 2, 1], dtype=np.int32))
    # Indices: None, an int, a list, negative ones from the end.
    for indices in (None, 1, [0, 3], [-1], [np.int64(2)]):
        assert ref.get_attr("render_mode", indices) == ours.get_attr("render_mode", indices)
        assert ref.env_method("get_action_meanings", indices=indices) == ours.env_method(
            "get_action_meanings", indices=indices
        )
        assert ref.env_is_wrapped(Monitor, indices) == ours.env_is_wrapped(Monitor, indices)
    # Out of range: IndexError from both, for every indexed call; not indices: TypeError from both.
    for indices, error in (
        ([N], IndexError),
        ([-N - 1], IndexError),
        (N + 5, IndexError),
        (np.int64(2), TypeError),
        ([1.0], TypeError),
    ):
        for call in (
            lambda e, indices=indices: e.get_attr("render_mode", indices),
            lambda e, indices=indices: e.env_method("get_action_meanings", indices=indices),
            lambda e, indices=indices: e.env_is_wrapped(Monitor, indices),
        ):
            for env in (ref, ours):
                with pytest.raises(error):
                    call(env)
    # Empty options are fine for both, then the envs reset as before.
    ref.set_options({})
    ours.set_options([{}] * N)
    assert ref.seed(9) == ours.seed(9)
    assert np.array_equal(ref.reset(), ours.reset())
    same_step(ref, ours, np.array([1, 1, 1, 1]))


# (A value out of range is refused by both too, but DummyVecEnv steps the envs before it first.)
@pytest.mark.parametrize(
    "bad",
    [np.zeros((2, 2), np.int64), np.zeros((N, 1), np.int64), np.zeros(N, np.float32)],
    ids=["2x2", "Nx1", "float"],
)
def test_bad_actions_are_refused_as_dummy_vec_env_refuses_them_and_never_reused(bad):
    ref, ours = pair()
    ref.seed(1)
    ours.seed(1)
    ref.reset()
    ours.reset()
    for env in (ref, ours):
        with pytest.raises(ValueError):
            env.step(bad)
    # Ours does not step again with actions of a failed call.
    with pytest.raises(RuntimeError, match="without step_async"):
        ours.step_wait()
    # Nothing moved: both continue identically.
    same_step(ref, ours, np.array([3, 3, 3, 3]))


def test_a_bad_seed_or_options_are_refused_at_once_and_change_nothing():
    ours = ChopperScapeVecEnv(N, seed=3, **SHORT)
    first = ours.reset()
    for bad in (-1, 1.5, "7"):
        with pytest.raises(ValueError, match="seed"):
            ours.seed(bad)
    for options in ({"x": 1}, [{}, {"x": 1}, {}, {}], [{}]):
        with pytest.raises(ValueError):
            ours.set_options(options)
    # Every later reset works: the stored seeds (none) and options (empty) were kept.
    again = ChopperScapeVecEnv(N, seed=3, **SHORT).reset()
    assert np.array_equal(first, again)
    ours.reset()
    ours.seed(3)
    assert np.array_equal(ours.reset(), first)
