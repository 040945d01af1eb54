"""The single environment: Gymnasium's checker, seeding, types, options, errors, rendering, state."""

from __future__ import annotations

import pickle
import warnings

import gymnasium as gym
import numpy as np
import pytest
from gymnasium.utils.env_checker import check_env
from gymnasium.wrappers import RenderCollection

import chopperscape
from chopperscape import ChopperScapeEnv, _core

OBS_TYPES = ["rgb", "rgb_float", "grayscale", "features"]


def small(obs_type: str) -> dict:
    return {"obs_type": obs_type} if obs_type == "features" else {"obs_type": obs_type, "obs_size": (84, 84)}


@pytest.mark.parametrize("render_mode", [None, "rgb_array"])
@pytest.mark.parametrize("obs_type", OBS_TYPES)
def test_check_env_passes_and_warns_nothing_for_every_obs_type(obs_type, render_mode):
    env = gym.make("ChopperScape-v0", render_mode=render_mode, **small(obs_type))
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        check_env(env.unwrapped)
    # On the wrapped env, Gymnasium itself always warns that it is wrapped (as for CartPole); nothing else.
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        check_env(env)
    assert [str(w.message) for w in caught if "different from the unwrapped" not in str(w.message)] == []


def test_check_env_passes_at_the_full_default_size():
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        check_env(gym.make("ChopperScape-v0").unwrapped)


def test_registration_has_time_limit_and_vector_entry_point():
    spec = gym.spec("ChopperScape-v0")
    assert spec.max_episode_steps == 10_000
    assert spec.vector_entry_point == "chopperscape.vector:VectorEnv"
    env = gym.make("ChopperScape-v0", obs_type="features")
    assert isinstance(env.unwrapped, ChopperScapeEnv)
    assert env.spec.max_episode_steps == 10_000


def test_step_returns_python_float_and_bools_and_int_infos():
    env = gym.make("ChopperScape-v0", obs_type="features")
    obs, info = env.reset(seed=1)
    assert obs.dtype == np.float32 and obs.shape == (46,)
    assert info == {"fuel": 1000, "lives": 1}
    obs, reward, terminated, truncated, info = env.step(np.int64(4))
    assert type(reward) is float and reward == 1.0
    assert type(terminated) is bool and type(truncated) is bool
    assert info == {"fuel": 999, "lives": 1}
    assert type(info["fuel"]) is int and type(info["lives"]) is int


def test_termination_info_names_the_cause():
    env = ChopperScapeEnv(obs_type="features", max_fuel=5, bird_prob=0.0)
    env.reset(seed=0)
    for _ in range(4):
        assert env.step(4)[2] is False
    _obs, reward, terminated, truncated, info = env.step(4)
    assert (terminated, truncated, info) == (True, False, {"fuel": 0, "lives": 1, "cause": "fuel"})
    env = ChopperScapeEnv(obs_type="features", bird_prob=1.0)
    env.reset(seed=0)
    for _ in range(200):
        _, reward, terminated, _, info = env.step(3)
        if terminated:
            break
    assert terminated and info["cause"] == "bird" and reward == -10.0


def test_same_seed_same_trajectory_and_python_matches_the_core():
    def run(env, seed):
        out = [env.reset(seed=seed)[0]]
        for t in range(300):
            obs, r, term, _trunc, _ = env.step(t % 5)
            out.append((obs, r, term))
            if term:
                out.append(env.reset()[0])
        return out

    a, b = ChopperScapeEnv(**chopperscape_short()), ChopperScapeEnv(**chopperscape_short())
    ra, rb = run(a, 123), run(b, 123)
    assert all(
        np.array_equal(x[0] if isinstance(x, tuple) else x, y[0] if isinstance(y, tuple) else y) for x, y in zip(ra, rb)
    )
    core = _core.Env({**chopperscape_short(), "max_episode_steps": None})
    obs, _ = core.reset(123)
    assert np.array_equal(obs, ra[0])


def chopperscape_short() -> dict:
    return {"obs_type": "features", "max_fuel": 40, "bird_prob": 0.2}


def test_unseeded_reset_after_a_seeded_one_continues_the_stream():
    env = ChopperScapeEnv(obs_type="features")
    core = _core.Env({"obs_type": "features", "max_episode_steps": None})
    env.reset(seed=9)
    core.reset(9)
    for _ in range(3):
        obs, _ = env.reset()
        expected, _ = core.reset(None)
        assert np.array_equal(obs, expected)
    # ... and differs from reseeding.
    fresh, _ = ChopperScapeEnv(obs_type="features").reset(seed=9)
    assert not all(np.array_equal(env.reset()[0], fresh) for _ in range(5))


def test_first_unseeded_reset_draws_its_seed_from_np_random():
    starts = set()
    for _ in range(6):
        env = ChopperScapeEnv(obs_type="features")
        obs, _ = env.reset()
        starts.add(tuple(obs[:2]))
    assert len(starts) > 1, "unseeded environments all started alike: the seed is not drawn from entropy"
    # np_random seeded by Gymnasium decides it: seeding np_random alone fixes the trajectory.
    a, b = ChopperScapeEnv(obs_type="features"), ChopperScapeEnv(obs_type="features")
    a._np_random, _ = gym.utils.seeding.np_random(77)
    b._np_random, _ = gym.utils.seeding.np_random(77)
    assert np.array_equal(a.reset()[0], b.reset()[0])


def test_seeds_beyond_u64_are_reduced_modulo_2_64():
    a, b = ChopperScapeEnv(obs_type="features"), ChopperScapeEnv(obs_type="features")
    assert np.array_equal(a.reset(seed=5)[0], b.reset(seed=5 + 2**64)[0])


def test_every_spec_option_is_a_make_keyword_with_its_effect():
    env = gym.make(
        "ChopperScape-v0",
        obs_type="grayscale",
        obs_size=(32, 48),
        frame_stack=3,
        hud=False,
        lives=3,
        alien_prob=0.5,
        bird_fuel_collision="destroy",
        frame_skip=2,
        sticky_prob=0.25,
        bird_prob=0.0,
        fuel_prob=0.0,
        max_fuel=50,
        render_mode="rgb_array",
    )
    obs, info = env.reset(seed=0)
    assert obs.shape == (32, 48, 3) and obs.dtype == np.uint8
    assert info == {"fuel": 50, "lives": 3}
    _, _reward, _, _, info = env.step(4)
    assert info["fuel"] == 48, "frame_skip=2 burns two units a step"
    assert env.render().shape == (600, 800, 3)
    assert set(chopperscape.OPTION_NAMES) == {
        "obs_type",
        "obs_size",
        "frame_stack",
        "hud",
        "hud_style",
        "look",
        "lives",
        "alien_prob",
        "bird_fuel_collision",
        "frame_skip",
        "sticky_prob",
        "bird_prob",
        "fuel_prob",
        "max_fuel",
        "render_mode",
    }


@pytest.mark.parametrize(
    "option, value",
    [
        ("obs_type", "rgba"),
        ("obs_size", (4, 4)),
        ("obs_size", "big"),
        ("frame_stack", 0),
        ("hud", "maybe"),
        ("hud_style", "bars"),
        ("hud_style", True),
        ("look", "sprites"),
        ("lives", 0),
        ("lives", 2.5),
        ("alien_prob", 1.5),
        ("bird_fuel_collision", "explode"),
        ("frame_skip", 0),
        ("sticky_prob", -0.1),
        ("bird_prob", float("nan")),
        ("fuel_prob", 2),
        ("max_fuel", 0),
        ("render_mode", "ascii"),
        ("gravity", 9.8),
    ],
)
def test_unknown_or_out_of_range_options_raise_value_error_naming_the_option(option, value):
    with warnings.catch_warnings():
        # gymnasium.make itself warns about an undeclared render_mode before the environment refuses it.
        warnings.filterwarnings("ignore", message=".*possible render_modes")
        with pytest.raises(ValueError, match=option):
            gym.make("ChopperScape-v0", **{option: value})


def test_max_episode_steps_belongs_to_make_not_to_the_env():
    with pytest.raises(ValueError, match="max_episode_steps"):
        ChopperScapeEnv(max_episode_steps=5)
    env = gym.make("ChopperScape-v0", obs_type="features", max_episode_steps=3, bird_prob=0.0)
    env.reset(seed=0)
    assert [env.step(4)[3] for _ in range(3)] == [False, False, True]


@pytest.mark.parametrize("action", [5, -1, 2**70, 1.5, "0", None, np.array([0, 1])])
def test_invalid_actions_raise_value_error_and_change_nothing(action):
    env = ChopperScapeEnv(obs_type="features")
    env.reset(seed=3)
    env.step(0)
    before = env.clone_state()
    with pytest.raises(ValueError, match=r"0\.\.=4"):
        env.step(action)
    assert env.clone_state() == before


def test_step_before_reset_and_after_the_end_are_runtime_errors():
    env = ChopperScapeEnv(obs_type="features", max_fuel=1)
    with pytest.raises(RuntimeError, match="reset"):
        env.step(0)
    env.reset(seed=0)
    assert env.step(0)[2] is True
    with pytest.raises(RuntimeError, match="reset"):
        env.step(0)
    with pytest.raises(gym.error.ResetNeeded):
        gym.make("ChopperScape-v0", obs_type="features").step(0)


def test_rgb_array_render_is_the_full_frame_and_matches_the_rgb_observation():
    env = gym.make("ChopperScape-v0", render_mode="rgb_array")
    obs, _ = env.reset(seed=4)
    frame = env.render()
    assert frame.shape == (600, 800, 3) and frame.dtype == np.uint8
    assert np.array_equal(frame, obs)
    obs, *_ = env.step(0)
    assert np.array_equal(env.render(), obs)


def test_render_without_a_mode_warns_and_returns_none():
    env = ChopperScapeEnv(obs_type="features")
    env.reset(seed=0)
    with pytest.warns(UserWarning, match="render_mode"):
        assert env.render() is None


def test_rendering_collects_fresh_frames_like_record_video():
    env = RenderCollection(gym.make("ChopperScape-v0", obs_type="features", render_mode="rgb_array"))
    env.reset(seed=2)
    for _ in range(20):
        env.step(0)
    frames = env.render()
    assert len(frames) == 21
    assert all(f.shape == (600, 800, 3) and f.dtype == np.uint8 for f in frames)
    assert len({id(f) for f in frames}) == 21, "frames must not share memory"
    assert not np.array_equal(frames[0], frames[-1]), "the chopper moved right: the frames differ"


def test_human_mode_shows_a_window_or_names_the_missing_dependency():
    from chopperscape.env import HUMAN_AVAILABLE

    if not HUMAN_AVAILABLE:
        assert "human" not in ChopperScapeEnv.metadata["render_modes"]
        with pytest.raises(ValueError, match="pygame"):
            ChopperScapeEnv(render_mode="human")
        return
    assert "human" in ChopperScapeEnv.metadata["render_modes"]
    env = gym.make("ChopperScape-v0", obs_type="features", render_mode="human")
    env.reset(seed=0)
    env.step(0)
    assert env.render() is None
    env.close()
    env.close()


def test_action_meanings_and_keys_for_play():
    env = gym.make("ChopperScape-v0", obs_type="features")
    assert env.unwrapped.get_action_meanings() == ["Right", "Left", "Down", "Up", "Do Nothing"]
    keys = env.unwrapped.get_keys_to_action()
    assert sorted(keys.values()) == [0, 1, 2, 3]
    assert all(isinstance(k, tuple) and k and all(isinstance(c, str) and len(c) == 1 for c in k) for k in keys)


def test_clone_and_restore_state_replays_exactly():
    env = ChopperScapeEnv(obs_type="grayscale", obs_size=(32, 32), frame_stack=2, bird_prob=0.1)
    env.reset(seed=8)
    for t in range(50):
        env.step(t % 5)
    state = env.clone_state()
    assert isinstance(state, bytes)
    first = [env.step(t % 3) for t in range(40) if True]
    env.restore_state(state)
    again = [env.step(t % 3) for t in range(40)]
    for a, b in zip(first, again):
        assert np.array_equal(a[0], b[0]) and a[1:] == b[1:]


def test_restore_refuses_foreign_or_corrupt_bytes_and_changes_nothing():
    env = ChopperScapeEnv(obs_type="features")
    env.reset(seed=1)
    before = env.clone_state()
    with pytest.raises(ValueError, match="snapshot"):
        env.restore_state(b"not a snapshot")
    with pytest.raises(ValueError):
        env.restore_state(before[:-3])
    other = ChopperScapeEnv(obs_type="features", lives=3)
    other.reset(seed=1)
    with pytest.raises(ValueError, match="options"):
        env.restore_state(other.clone_state())
    assert env.clone_state() == before


@pytest.mark.parametrize("wrapped", [False, True])
def test_pickled_env_continues_identically(wrapped):
    env = (
        gym.make("ChopperScape-v0", obs_type="features", bird_prob=0.1)
        if wrapped
        else ChopperScapeEnv(obs_type="features", bird_prob=0.1)
    )
    env.reset(seed=6)
    for t in range(30):
        env.step(t % 5)
    copy = pickle.loads(pickle.dumps(env))
    for t in range(60):
        a, b = env.step(t % 4), copy.step(t % 4)
        assert np.array_equal(a[0], b[0]) and a[1:] == b[1:]
        if a[2]:
            break
    assert np.array_equal(env.reset()[0], copy.reset()[0])


def test_close_twice_is_fine():
    env = gym.make("ChopperScape-v0", obs_type="features", render_mode="rgb_array")
    env.reset(seed=0)
    env.close()
    env.close()


def test_a_rust_panic_becomes_a_python_exception():
    with pytest.raises(BaseException, match="boom") as caught:
        _core._panic("boom")
    assert type(caught.value).__name__ == "PanicException"
