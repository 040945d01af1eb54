"""The native vector env: the same results as Gymnasium's SyncVectorEnv of single envs, its conventions,
copy modes, refusals, the worker pool across fork(), Gymnasium's vector wrappers on it, and `keep_dim`."""

from __future__ import annotations

import multiprocessing
import pickle

import gymnasium as gym
import numpy as np
import pytest
from conftest import SHORT
from gymnasium.vector import AutoresetMode, SyncVectorEnv

import chopperscape
from chopperscape import VectorEnv

LIMIT = 30  # max_episode_steps of the short episodes: truncations happen too


def sync_of(num_envs: int, mode: AutoresetMode, **options) -> SyncVectorEnv:
    """Gymnasium's own vectorisation of single envs: the reference."""
    return SyncVectorEnv(
        [lambda: gym.make("ChopperScape-v0", max_episode_steps=LIMIT, **options) for _ in range(num_envs)],
        autoreset_mode=mode,
    )


def assert_same(a, b, where):
    if isinstance(a, dict):
        assert sorted(a) == sorted(b), f"{where}: info keys {sorted(a)} != {sorted(b)}"
        for k in a:
            assert_same(a[k], b[k], f"{where}[{k!r}]")
    elif isinstance(a, np.ndarray) and a.dtype == object:
        assert len(a) == len(b), where
        for i, (x, y) in enumerate(zip(a, b)):
            assert_same(x, y, f"{where}[{i}]")
    elif isinstance(a, np.ndarray):
        assert a.shape == np.shape(b) and np.array_equal(a, b), f"{where}: {a} != {b}"
    else:
        assert a == b, f"{where}: {a!r} != {b!r}"


def run_against_sync(num_envs, threads, seed, mode, steps=120, **options):
    ours = VectorEnv(num_envs, num_threads=threads, autoreset_mode=mode, max_episode_steps=LIMIT, **options)
    ref = sync_of(num_envs, mode, **options)
    (o1, i1), (o2, i2) = ours.reset(seed=seed), ref.reset(seed=seed)
    assert_same(o1, o2, "reset obs")
    assert_same(i1, i2, "reset info")
    rng = np.random.default_rng(seed)
    ended = 0
    for t in range(steps):
        actions = rng.integers(0, 5, num_envs)
        a, b = ours.step(actions), ref.step(actions)
        for name, x, y in zip(["obs", "rewards", "terminated", "truncated", "infos"], a, b):
            assert_same(x, y, f"step {t} {name}")
        assert a[1].dtype == b[1].dtype and a[2].dtype == np.bool_
        ended += int(np.sum(a[2] | a[3]))
    assert ended >= 2 * num_envs, f"only {ended} episodes ended: the test needs autoresets"


@pytest.mark.parametrize("threads", [1, 2, 3])
@pytest.mark.parametrize("seed", [0, 42, 2**40])
def test_next_step_batch_equals_sync_vector_env_of_single_envs(seed, threads):
    run_against_sync(5, threads, seed, AutoresetMode.NEXT_STEP, **SHORT)


@pytest.mark.parametrize("threads", [1, 2])
def test_same_step_batch_equals_sync_vector_env_of_single_envs(threads):
    run_against_sync(4, threads, 11, AutoresetMode.SAME_STEP, **SHORT)


def test_pixel_batches_equal_sync_vector_env_too():
    run_against_sync(
        3,
        2,
        5,
        AutoresetMode.NEXT_STEP,
        steps=80,
        **{**SHORT, "obs_type": "grayscale", "obs_size": (24, 32), "frame_stack": 2},
    )


def test_env_i_follows_the_single_env_seeded_s_plus_i():
    envs = VectorEnv(3, num_threads=2, **SHORT)
    obs, _ = envs.reset(seed=100)
    for i in range(3):
        single = gym.make("ChopperScape-v0", **SHORT)
        assert np.array_equal(obs[i], single.reset(seed=100 + i)[0])


def test_make_vec_builds_the_native_env_with_the_registered_time_limit():
    envs = gym.make_vec(
        "ChopperScape-v0", num_envs=4, vectorization_mode="vector_entry_point", obs_type="features", num_threads=2
    )
    assert isinstance(envs.unwrapped, VectorEnv)
    assert envs.unwrapped.max_episode_steps == 10_000 and envs.unwrapped.num_threads == 2
    assert envs.metadata["autoreset_mode"] == AutoresetMode.NEXT_STEP
    assert envs.single_observation_space == gym.make("ChopperScape-v0", obs_type="features").observation_space
    assert envs.observation_space.shape == (4, 46)
    assert envs.single_action_space == gym.spaces.Discrete(5)
    assert envs.action_space == gym.spaces.MultiDiscrete([5] * 4)
    obs, _info = envs.reset(seed=0)
    assert envs.observation_space.contains(obs)
    obs, rewards, _terminated, _truncated, _info = envs.step(envs.action_space.sample())
    assert rewards.dtype == np.float64 or rewards.dtype == np.float32
    assert envs.observation_space.contains(obs)
    envs.close()
    envs.close()


def test_same_step_metadata_and_final_observations():
    envs = VectorEnv(2, autoreset_mode=AutoresetMode.SAME_STEP, **SHORT)
    assert envs.metadata["autoreset_mode"] == AutoresetMode.SAME_STEP
    assert VectorEnv.metadata["autoreset_mode"] == AutoresetMode.NEXT_STEP


def test_copy_false_reuses_the_same_arrays_and_copy_true_does_not():
    shared = VectorEnv(4, copy=False, **SHORT)
    o1, _ = shared.reset(seed=0)
    o2, r2, *_ = shared.step(np.zeros(4, dtype=np.int64))
    o3, r3, *_ = shared.step(np.zeros(4, dtype=np.int64))
    assert o1 is o2 is o3 and r2 is r3
    fresh = VectorEnv(4, copy=True, **SHORT)
    p1, _ = fresh.reset(seed=0)
    p2, *_ = fresh.step(np.zeros(4, dtype=np.int64))
    kept = p2.copy()
    p3, *_ = fresh.step(np.zeros(4, dtype=np.int64))
    assert p1 is not p2 and p2 is not p3 and np.array_equal(p2, kept)


@pytest.mark.parametrize(
    "actions, message",
    [
        (np.zeros(3, dtype=np.int64), "shape"),
        (np.zeros((4, 1), dtype=np.int64), "shape"),
        (np.zeros(4, dtype=np.float32), "dtype"),
        (np.array([0, 1, 5, 2]), "invalid action 5 at index 2"),
        (np.array([0, -1, 2, 2]), "invalid action -1 at index 1"),
        (np.array([0, 1, 2, 255], dtype=np.uint8), "invalid action 255 at index 3"),
        ([0, 1], "shape"),
    ],
)
def test_invalid_action_arrays_raise_value_error_and_change_no_env(actions, message):
    envs = VectorEnv(4, num_threads=2, **SHORT)
    envs.reset(seed=1)
    envs.step([0, 1, 2, 3])
    before = [envs.env_state(i) for i in range(4)]
    with pytest.raises(ValueError, match=message):
        envs.step(actions)
    assert [envs.env_state(i) for i in range(4)] == before


def test_list_actions_and_narrow_integer_dtypes_are_accepted():
    a, b = VectorEnv(3, **SHORT), VectorEnv(3, **SHORT)
    a.reset(seed=2)
    b.reset(seed=2)
    assert np.array_equal(a.step([0, 3, 4])[0], b.step(np.array([0, 3, 4], dtype=np.uint8))[0])


def test_step_before_reset_is_a_runtime_error():
    with pytest.raises(RuntimeError, match="reset"):
        VectorEnv(2, **SHORT).step([0, 0])


@pytest.mark.parametrize(
    "kwargs, option",
    [
        ({"num_envs": 0}, "num_envs"),
        ({"num_envs": 2, "num_threads": 0}, "num_threads"),
        ({"num_envs": 2, "max_episode_steps": 0}, "max_episode_steps"),
        ({"num_envs": 2, "autoreset_mode": "disabled"}, "autoreset_mode"),
        ({"num_envs": 2, "render_mode": "human"}, "render_mode"),
        ({"num_envs": 2, "lives": 0}, "lives"),
        ({"num_envs": 2, "warp": 9}, "warp"),
    ],
)
def test_bad_constructor_arguments_raise_value_error_naming_them(kwargs, option):
    with pytest.raises(ValueError, match=option):
        VectorEnv(**kwargs)


def test_reset_with_a_seed_list_and_its_refusals():
    envs = VectorEnv(3, **SHORT)
    obs, _ = envs.reset(seed=[7, 8, 9])
    again, _ = VectorEnv(3, **SHORT).reset(seed=7)
    assert np.array_equal(obs, again)
    with pytest.raises(ValueError, match="num_envs=3"):
        envs.reset(seed=[1, 2])
    with pytest.raises(ValueError, match="reset_mask"):
        envs.reset(options={"reset_mask": np.ones(3, dtype=bool)})


def test_unseeded_resets_draw_from_np_random_then_continue():
    a, b = VectorEnv(2, **SHORT), VectorEnv(2, **SHORT)
    assert not all(np.array_equal(a.reset()[0], b.reset()[0]) for _ in range(3))
    c = VectorEnv(2, **SHORT)
    c.reset(seed=4)
    single = gym.make("ChopperScape-v0", **SHORT)
    single.reset(seed=4)
    assert np.array_equal(c.reset()[0][0], single.reset()[0])


def test_render_returns_one_full_frame_per_env():
    envs = VectorEnv(2, render_mode="rgb_array", **SHORT)
    envs.reset(seed=0)
    frames = envs.render()
    assert len(frames) == 2 and all(f.shape == (600, 800, 3) and f.dtype == np.uint8 for f in frames)


def test_async_vector_env_of_the_single_env_matches_the_native_one():
    asyncs = gym.make_vec("ChopperScape-v0", num_envs=2, vectorization_mode="async", **SHORT)
    native = gym.make_vec("ChopperScape-v0", num_envs=2, vectorization_mode="vector_entry_point", **SHORT)
    try:
        (o1, _), (o2, _) = asyncs.reset(seed=3), native.reset(seed=3)
        assert np.array_equal(o1, o2)
        for t in range(60):
            a, b = asyncs.step([t % 5, (t + 2) % 5]), native.step([t % 5, (t + 2) % 5])
            for x, y in zip(a[:4], b[:4]):
                assert np.array_equal(x, y), f"step {t}"
    finally:
        asyncs.close()


def _step_in_child(envs, queue):
    obs, *_ = envs.step(np.zeros(envs.num_envs, dtype=np.int64))
    queue.put(obs.tolist())


def test_a_forked_child_steps_a_vector_env_whose_pool_the_parent_built():
    envs = VectorEnv(8, num_threads=2, **SHORT)
    envs.reset(seed=0)
    envs.step(np.zeros(8, dtype=np.int64))  # the parent's pool now exists
    ctx = multiprocessing.get_context("fork")
    queue = ctx.Queue()
    child = ctx.Process(target=_step_in_child, args=(envs, queue))
    child.start()
    child.join(timeout=60)
    assert child.exitcode == 0, "the child hung or crashed (an inherited thread pool?)"
    obs, *_ = envs.step(np.zeros(8, dtype=np.int64))
    assert np.array_equal(np.array(queue.get(timeout=5), dtype=np.float32), obs)


def test_single_envs_pickle_into_the_same_state_for_worker_processes():
    env = gym.make("ChopperScape-v0", **SHORT)
    env.reset(seed=5)
    env.step(1)
    copy = pickle.loads(pickle.dumps(env))
    assert np.array_equal(env.step(2)[0], copy.step(2)[0])


@pytest.mark.parametrize("mode", [AutoresetMode.NEXT_STEP, AutoresetMode.SAME_STEP])
def test_a_pickled_vector_env_continues_identically(mode):
    envs = VectorEnv(3, num_threads=2, autoreset_mode=mode, max_episode_steps=LIMIT, **SHORT)
    envs.reset(seed=8)
    rng = np.random.default_rng(0)
    for _ in range(45):
        envs.step(rng.integers(0, 5, 3))
    copy = pickle.loads(pickle.dumps(envs))
    for t in range(80):
        actions = rng.integers(0, 5, 3)
        a, b = envs.step(actions), copy.step(actions)
        for name, x, y in zip(["obs", "rewards", "terminated", "truncated", "infos"], a, b):
            assert_same(x, y, f"step {t} {name}")
    assert_same(envs.reset()[0], copy.reset()[0], "unseeded reset")


def test_restoring_a_state_of_other_options_changes_nothing():
    envs = VectorEnv(2, **SHORT)
    envs.reset(seed=1)
    before = [envs.env_state(i) for i in range(2)]
    other = VectorEnv(2, **{**SHORT, "lives": 3})
    other.reset(seed=1)
    with pytest.raises(ValueError, match="options"):
        envs._core.set_state(*other._core.state())
    with pytest.raises(ValueError, match="4 environments: this batch has 2"):
        envs._core.set_state(True, other._core.state()[1] * 2)
    assert [envs.env_state(i) for i in range(2)] == before


def test_package_exports():
    assert chopperscape.VectorEnv is VectorEnv
    assert chopperscape.ACTION_MEANINGS == ["Right", "Left", "Down", "Up", "Do Nothing"]


def test_gymnasium_vector_wrappers_on_the_native_batch():
    from gymnasium.wrappers.vector import (
        ClipReward,
        NormalizeObservation,
        NormalizeReward,
        RecordEpisodeStatistics,
        TransformObservation,
    )

    envs = VectorEnv(4, **SHORT)
    wrapped = ClipReward(NormalizeReward(NormalizeObservation(RecordEpisodeStatistics(envs))), -5, 5)
    wrapped = TransformObservation(wrapped, lambda o: o * 2)
    obs, _ = wrapped.reset(seed=3)
    assert obs.shape == (4, envs.single_observation_space.shape[0])
    finished = 0
    rng = np.random.default_rng(0)
    for _ in range(300):
        obs, rew, _term, _trunc, info = wrapped.step(rng.integers(0, 5, 4))
        assert np.isfinite(obs).all() and np.isfinite(rew).all() and (np.abs(rew) <= 5).all()
        if "episode" in info:
            finished += int(info["_episode"].sum())
            assert (info["episode"]["l"][info["_episode"]] > 0).all()
    assert finished > 5


@pytest.mark.parametrize("mode", ["NEXT_STEP", "SAME_STEP"])
def test_keep_dim_gives_grayscale_a_channel_axis_everywhere(mode):
    options = dict(obs_type="grayscale", obs_size=(84, 84), max_fuel=30)
    env = gym.make("ChopperScape-v0", keep_dim=True, **options)
    plain = gym.make("ChopperScape-v0", **options)
    assert env.observation_space.shape == (84, 84, 1)
    obs, _ = env.reset(seed=2)
    ref, _ = plain.reset(seed=2)
    assert obs.shape == (84, 84, 1) and np.array_equal(obs[..., 0], ref) and env.observation_space.contains(obs)
    obs, *_ = env.step(3)
    assert np.array_equal(obs[..., 0], plain.step(3)[0])
    envs = VectorEnv(2, keep_dim=True, autoreset_mode=gym.vector.AutoresetMode[mode], copy=False, **options)
    assert envs.single_observation_space.shape == (84, 84, 1) and envs.observation_space.shape == (2, 84, 84, 1)
    obs, _ = envs.reset(seed=2)
    assert obs.shape == (2, 84, 84, 1) and np.array_equal(obs[0, ..., 0], ref) and not obs.flags.writeable
    for _ in range(40):
        obs, _, _term, _trunc, info = envs.step(np.array([4, 4]))
        assert obs.shape == (2, 84, 84, 1)
        if "final_obs" in info:
            assert all(f.shape == (84, 84, 1) for f in info["final_obs"][info["_final_obs"]])
    # Stacked or colour frames already have a channel axis: keep_dim changes nothing there.
    stacked = gym.make("ChopperScape-v0", keep_dim=True, obs_type="grayscale", obs_size=(84, 84), frame_stack=4)
    assert stacked.observation_space.shape == (84, 84, 4)
    with pytest.raises(ValueError, match="keep_dim"):
        gym.make("ChopperScape-v0", keep_dim="yes")
