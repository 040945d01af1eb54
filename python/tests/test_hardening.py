"""Hostile input: sizes that do not fit, crafted states, wrong types, two threads. Each is a clear error that
changes nothing, never an abort, a panic or a silent misreading."""

from __future__ import annotations

import pickle
import resource
import struct
import subprocess
import sys
import textwrap
import threading
import time
import zlib

import gymnasium as gym
import numpy as np
import pytest
from conftest import SHORT

import chopperscape
from chopperscape import ChopperScapeEnv, VectorEnv, _core

# Payload offsets of snapshot format version 3 (crates/core/src/snapshot.rs).
OBS_TYPE, OBS_H, OBS_W, FRAME_STACK, RETURN, STEPS, HEADER = 0, 1, 5, 9, 110, 122, 10


def tamper(state: bytes, **fields: bytes) -> bytes:
    """Snapshot bytes with payload fields overwritten (offset name -> bytes) and a correct checksum."""
    payload = bytearray(state[HEADER:-4])
    for name, value in fields.items():
        at = globals()[name.upper()]
        payload[at : at + len(value)] = value
    return state[:6] + struct.pack("<I", len(payload)) + bytes(payload) + struct.pack("<I", zlib.crc32(payload))


def huge_snapshot() -> bytes:
    small = ChopperScapeEnv(obs_type="features").clone_state()
    return tamper(
        small,
        obs_type=b"\x01",
        obs_h=struct.pack("<I", 4096),
        obs_w=struct.pack("<I", 4096),
        frame_stack=struct.pack("<I", 64),
    )


def rss_mib() -> float:
    with open("/proc/self/statm") as f:
        return int(f.read().split()[1]) * resource.getpagesize() / 2**20


# --- memory and sizes -------------------------------------------------------------------------------------


def test_observations_over_the_memory_budget_are_a_value_error_with_the_size():
    for make in (
        lambda: ChopperScapeEnv(obs_size=(4096, 4096), frame_stack=64),
        lambda: VectorEnv(2, obs_size=(4096, 4096), frame_stack=64),
    ):
        with pytest.raises(ValueError, match=r"frame_stack 64.*GiB.*budget of 4\.0 GiB"):
            make()


@pytest.mark.parametrize("n", [2**40, 2**62, 2**64, 2**70])
def test_absurd_batch_sizes_are_a_value_error(n):
    with pytest.raises(ValueError, match="num_envs"):
        VectorEnv(n, obs_type="features")


def test_a_default_rgb_batch_of_64_takes_its_frames_not_a_gigabyte():
    before = rss_mib()
    envs = VectorEnv(64, num_threads=1)
    envs.reset(seed=0)
    grown = rss_mib() - before
    frames = 64 * 600 * 800 * 3 / 2**20  # 88 MiB of observations
    # A canvas and an observation per env (and the renderer's sprites); it was ~1.2 GB with bounds per element.
    assert grown < 3 * frames + 64, f"{grown:.0f} MiB"
    for space in (envs.single_observation_space, envs.observation_space):
        assert all(s == 0 for s in space.low.strides) and not space.low.flags.writeable
    assert envs.observation_space.shape == (64, 600, 800, 3)
    assert envs.observation_space.contains(envs.step(np.zeros(64, dtype=np.int64))[0])


def test_spaces_without_per_element_bounds_are_plain_boxes_in_every_other_way():
    for obs_type in ["rgb", "rgb_float", "grayscale", "features"]:
        options = {"obs_type": obs_type, "obs_size": (16, 24), "frame_stack": 3}
        space = ChopperScapeEnv(**options).observation_space
        expected_low, expected_high = (
            (np.tile(_feature_bounds()[0], 3), np.tile(_feature_bounds()[1], 3))
            if obs_type == "features"
            else (0, 1 if obs_type == "rgb_float" else 255)
        )
        plain = gym.spaces.Box(low=expected_low, high=expected_high, shape=space.shape, dtype=space.dtype)
        assert space == plain and plain == space
        assert space.contains(space.sample()) and space.is_bounded()
        copy = pickle.loads(pickle.dumps(space))
        assert copy == space and copy.low.strides == space.low.strides
        batched = VectorEnv(3, **options).observation_space
        assert batched == gym.vector.utils.batch_space(plain, 3)


def _feature_bounds():
    low, high = _core.Env({"obs_type": "features"}).obs_bounds
    return low, high


def test_memory_refused_by_the_system_is_a_value_error_not_an_abort():
    code = textwrap.dedent(
        """
        import resource
        resource.setrlimit(resource.RLIMIT_AS, (3 << 30, 3 << 30))
        import chopperscape
        for make in (lambda: chopperscape.ChopperScapeEnv(obs_type="rgb_float", obs_size=(4096, 4096), frame_stack=8),
                     lambda: chopperscape.VectorEnv(12, obs_type="rgb_float", obs_size=(4096, 4096))):
            try:
                make()
            except (ValueError, MemoryError) as e:
                print("refused:", e)
        """
    )
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, timeout=120)
    assert out.returncode == 0, out.stderr[-2000:]
    assert out.stdout.count("refused:") == 2 and "could not allocate" in out.stdout, out.stdout


# --- crafted snapshots ------------------------------------------------------------------------------------


def test_a_small_crafted_snapshot_asking_for_a_huge_observation_is_a_value_error():
    crafted = huge_snapshot()
    assert len(crafted) < 200
    with pytest.raises(ValueError, match="budget"):
        _core.Env.from_snapshot(crafted)

    class Crafted:
        def __reduce__(self):
            return (_core.Env.from_snapshot, (crafted,))

    with pytest.raises(ValueError, match="budget"):
        pickle.loads(pickle.dumps(Crafted()))
    env = ChopperScapeEnv(obs_type="features")
    with pytest.raises(ValueError):
        env.restore_state(crafted)


def test_crafted_counters_and_values_no_episode_reaches_are_refused():
    env = ChopperScapeEnv(obs_type="features", frame_stack=2)
    env.reset(seed=1)
    for t in range(10):
        env.step(t % 5)
    state = env.clone_state()
    for fields in [{"steps": struct.pack("<I", 2**32 - 1)}, {"return": struct.pack("<q", 2**63 - 1)}]:
        with pytest.raises(ValueError, match="corrupted"):
            env.restore_state(tamper(state, **fields))
    nan = state[:-8] + struct.pack("<f", float("nan")) + state[-4:]
    nan = tamper(nan)
    with pytest.raises(ValueError, match="frame stack"):
        env.restore_state(nan)
    assert env.clone_state() == state


# --- vector env states ------------------------------------------------------------------------------------


def ended_state(**options) -> tuple[bytes, int]:
    env = ChopperScapeEnv(**options)
    env.reset(seed=3)
    while not env.step(4)[2]:
        pass
    return env.clone_state(), env._core.elapsed_steps


def test_set_state_refuses_states_the_batch_cannot_step_and_changes_nothing():
    options = {**SHORT, "bird_prob": 0.0}
    envs = VectorEnv(2, **options)
    envs.reset(seed=0)
    _started, slots = envs._core.state()
    before = [envs.env_state(i) for i in range(2)]
    ended, steps = ended_state(**options)
    never = ChopperScapeEnv(**options).clone_state()
    for slot, message in [
        ((ended, False, steps), "no reset is pending"),
        ((never, False, 0), "before any reset"),
        ((ended, True, steps + 1), f"elapsed steps {steps + 1}"),
    ]:
        with pytest.raises(ValueError, match=message):
            envs._core.set_state(True, [slot, slots[1]])
        assert [envs.env_state(i) for i in range(2)] == before
    # Every later step still works, and moves every environment.
    _obs, rewards, *_ = envs.step(np.array([4, 4]))
    assert list(rewards) == [1.0, 1.0]
    envs._core.set_state(True, [(ended, True, steps), slots[1]])
    _, rewards, *_ = envs.step(np.array([4, 4]))
    assert list(rewards) == [0.0, 1.0], "the ended environment resets, the other steps"


def test_without_max_episode_steps_a_step_count_of_2_32_is_not_a_truncation():
    options = {"obs_type": "features", "bird_prob": 0.0}
    envs = VectorEnv(1, max_episode_steps=None, **options)
    envs.reset(seed=0)
    envs.step(np.array([4]))
    _, slots = envs._core.state()
    steps = 2**32 - 2
    top = tamper(slots[0][0], steps=struct.pack("<I", steps), **{"return": struct.pack("<q", steps)})
    envs._core.set_state(True, [(top, False, steps)])
    for _ in range(3):
        _, _, terminated, truncated, _ = envs.step(np.array([4]))
        assert not terminated[0] and not truncated[0]
    assert envs._core.state()[1][0][2] == 2**32 - 1


def test_env_state_of_an_env_that_does_not_exist_names_the_range():
    envs = VectorEnv(2, **SHORT)
    for i in (-1, 2, 2**70, 1.0):
        with pytest.raises(IndexError, match=r"allowed 0\.\.=1"):
            envs.env_state(i)


# --- Python API consistency -------------------------------------------------------------------------------


def test_copy_false_arrays_are_read_only_and_copy_true_arrays_are_yours():
    for autoreset in ["NextStep", "SameStep"]:
        envs = VectorEnv(2, copy=False, autoreset_mode=autoreset, obs_type="grayscale", obs_size=(16, 16))
        obs, _ = envs.reset(seed=0)
        out = envs.step(np.array([0, 1]))
        for array in (obs, *out[:4]):
            assert not array.flags.writeable
            with pytest.raises(ValueError, match="read-only"):
                array[...] = 0
        assert np.shares_memory(envs.step(np.array([0, 1]))[0], obs), "copy=False: the same arrays every call"
    fresh = VectorEnv(2, copy=True, **SHORT)
    obs, _ = fresh.reset(seed=0)
    assert obs.flags.writeable
    single = ChopperScapeEnv(**SHORT)
    obs, _ = single.reset(seed=0)
    obs[...] = 0  # a fresh array every call: the caller's to keep or change
    assert not np.array_equal(single.step(4)[0], obs)


@pytest.mark.parametrize("value", ["False", "True", 0, 1, None])
def test_bool_options_take_bools_only(value):
    with pytest.raises(ValueError, match=r"copy.*True or False"):
        VectorEnv(2, copy=value, **SHORT)
    with pytest.raises(ValueError, match=r"hud.*True or False"):
        ChopperScapeEnv(hud=value)
    with pytest.raises(ValueError, match=r"hud.*True or False"):
        VectorEnv(2, hud=value)


def test_numpy_bools_are_bools():
    assert VectorEnv(2, copy=np.False_, **SHORT).copy is False
    assert ChopperScapeEnv(hud=np.False_, obs_size=(32, 32)).reset(seed=0)[0].shape == (32, 32, 3)


def test_reset_options_follow_one_rule_in_both_envs():
    for env in (ChopperScapeEnv(**SHORT), VectorEnv(2, **SHORT)):
        with pytest.raises(ValueError, match=r"reset options \['x'\] are not supported"):
            env.reset(options={"x": 1})
        env.reset(options={})
        env.reset(options=None)


def test_seeds_follow_one_rule_in_both_envs():
    envs = VectorEnv(4, **SHORT)
    with pytest.raises(ValueError, match=r"invalid seed at index 3 -4: allowed a non-negative integer"):
        envs.reset(seed=[1, 2, 3, -4])
    for env in (ChopperScapeEnv(**SHORT), envs):
        for bad in (-1, 1.5, "7", True):
            with pytest.raises(ValueError, match="invalid seed"):
                env.reset(seed=bad)
    a, _ = VectorEnv(2, **SHORT).reset(seed=[np.int64(5), np.uint64(6)])
    b, _ = VectorEnv(2, **SHORT).reset(seed=5)
    assert np.array_equal(a, b)
    single = ChopperScapeEnv(**SHORT)
    assert np.array_equal(single.reset(seed=np.int64(5))[0], a[0])


def test_restoring_through_the_registered_env_rewinds_the_time_limit():
    env = gym.make("ChopperScape-v0", obs_type="features", bird_prob=0.0, max_episode_steps=50)
    env.reset(seed=2)
    for _ in range(30):
        env.step(4)
    state = chopperscape.clone_state(env)
    first = [env.step(4)[3] for _ in range(20)]
    assert first[-1] and not any(first[:-1])
    chopperscape.restore_state(env, state)
    again = [env.step(4)[3] for _ in range(20)]
    assert again == first, "the TimeLimit counts from the restored step"
    # The wrong way cannot rewind the wrapper: it fails loudly and changes nothing.
    with pytest.raises(RuntimeError, match=r"chopperscape\.restore_state\(env, state\)"):
        env.unwrapped.restore_state(state)
    # A restore before any reset is allowed through the wrappers too.
    fresh = gym.make("ChopperScape-v0", obs_type="features", bird_prob=0.0, max_episode_steps=50)
    chopperscape.restore_state(fresh, state)
    assert [fresh.step(4)[3] for _ in range(20)] == first


# --- messages ---------------------------------------------------------------------------------------------


@pytest.mark.parametrize("size", [[84, 84], np.array([84, 84]), (np.int64(84), 84), (np.int32(84), np.uint16(84))])
def test_obs_size_takes_any_pair_of_ints(size):
    assert ChopperScapeEnv(obs_size=size).reset(seed=0)[0].shape == (84, 84, 3)


@pytest.mark.parametrize("size", [(84,), (84, 84, 3), (84.0, 84), np.array([[84, 84]]), (True, 84), (4, 4), (-84, 84)])
def test_obs_size_refusals_name_the_option_and_the_form(size):
    with pytest.raises(ValueError, match=r"`obs_size`: allowed a tuple \(height, width\) of positive ints") as e:
        ChopperScapeEnv(obs_size=size)
    assert "invalid value [84" not in str(e.value)


def test_max_episode_steps_beyond_u32_names_the_allowed_range():
    for make in (
        lambda: VectorEnv(2, max_episode_steps=2**32, **SHORT),
        lambda: _core.Env({"max_episode_steps": 2**32}),
    ):
        with pytest.raises(ValueError, match=r"max_episode_steps.*1\.\.=4294967295") as e:
            make()
        assert "integral type conversion" not in str(e.value)


def test_a_restore_with_other_options_names_only_the_options_that_differ():
    env = ChopperScapeEnv(obs_type="features")
    other = ChopperScapeEnv(obs_type="features", lives=3)
    other.reset(seed=0)
    with pytest.raises(ValueError, match=r"lives 3 != 1 \(snapshot != environment\)") as e:
        env.restore_state(other.clone_state())
    assert "Config {" not in str(e.value)


def test_two_threads_on_one_env_get_a_message_that_says_so():
    core = _core.Env({"obs_size": (1024, 1024), "frame_stack": 4, "bird_prob": 0.0, "max_fuel": 1000000})
    core.reset(0)
    stop = threading.Event()

    def busy():
        while not stop.is_set():
            try:
                core.step(4)
            except RuntimeError:
                pass  # the main thread was inside a call: the same refusal, seen from here

    worker = threading.Thread(target=busy)
    worker.start()
    errors = []
    try:
        for _ in range(2000):
            try:
                core.step(4)
            except RuntimeError as e:
                errors.append(str(e))
                break
    finally:
        stop.set()
        worker.join()
    assert errors and "cannot be used from two threads at once" in errors[0], errors


# --- built-in policies and copy=False arrays (hardening, round two) --------------------------------------------------


def test_vector_policy_sizes_are_checked_against_the_batch_budget_before_allocating():
    from chopperscape import policies

    for bad in (0, -1, 2**64, 1.5, "8", True):
        with pytest.raises(ValueError, match="num_envs"):
            policies.VectorPolicy("heuristic", bad)
    # In a process with 1 GiB of address space: without the budget, these sizes took the machine's memory or
    # aborted the interpreter.
    code = textwrap.dedent(
        """
        import resource
        resource.setrlimit(resource.RLIMIT_AS, (1 << 30, 1 << 30))
        from chopperscape import policies
        for n in (2**62, 2**64 - 1, 10**8, 10**7):
            try:
                policies.VectorPolicy("heuristic", n)
            except (ValueError, MemoryError) as e:
                print("refused:", e)
        """
    )
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, timeout=120)
    assert out.returncode == 0, out.stderr[-2000:]
    lines = out.stdout.splitlines()
    assert len(lines) == 4 and all(line.startswith("refused:") for line in lines), out.stdout
    assert all("budget of 16.0 GiB" in line for line in lines[:3]) and "could not allocate" in lines[3], out.stdout


@pytest.mark.parametrize("n", [-1, 0, 2.5, "3", None, True])
def test_policy_episodes_checks_its_arguments_at_once(n):
    from chopperscape import policies

    with pytest.raises(ValueError, match="`n`"):
        policies.episodes("random", n)
    with pytest.raises(ValueError, match="seed"):
        policies.episodes("random", 1, seed=-1)
    with pytest.raises(ValueError, match="max_episode_steps"):
        policies.episodes("random", 1, max_episode_steps=0)


def _busy(step, stop):
    def run():
        while not stop.is_set():
            try:
                step()
            except RuntimeError:
                pass

    return threading.Thread(target=run)


def test_a_policy_on_an_env_another_thread_steps_gets_the_two_threads_message():
    from chopperscape import policies

    core = _core.Env({"obs_size": (1024, 1024), "frame_stack": 4, "bird_prob": 0.0, "max_fuel": 1000000})
    core.reset(0)
    envs = VectorEnv(4, obs_size=(512, 512), frame_stack=2, bird_prob=0.0, max_fuel=1000000, max_episode_steps=None)
    envs.reset(seed=0)
    for act, step in [
        (lambda: policies.Policy("heuristic").act(core), lambda: core.step(4)),
        (lambda: policies.VectorPolicy("heuristic", 4).act(envs), lambda: envs.step(np.full(4, 4))),
    ]:
        stop = threading.Event()
        worker = _busy(step, stop)
        worker.start()
        errors = []
        try:
            for _ in range(20000):
                time.sleep(0.0002)  # lets the other thread into a step (the policy holds the env while it plans)
                try:
                    act()
                except RuntimeError as e:
                    errors.append(str(e))
                    break
        finally:
            stop.set()
            worker.join()
        assert errors and "cannot be used from two threads at once" in errors[0], errors


def test_copy_false_arrays_cannot_be_made_writable_again():
    for autoreset in ["NextStep", "SameStep"]:
        envs = VectorEnv(
            2, copy=False, autoreset_mode=autoreset, keep_dim=True, obs_type="grayscale", obs_size=(16, 16), max_fuel=5
        )
        obs, info = envs.reset(seed=0)
        before = obs.copy()
        outputs = [obs, *envs.step(np.array([0, 1]))[:4], info["fuel"], info["lives"], info["_fuel"], info["_lives"]]
        for array in outputs:
            chain = array
            while isinstance(chain, np.ndarray):
                with pytest.raises(ValueError):
                    chain.flags.writeable = True
                chain = chain.base
        # The frames the batch draws incrementally are as a fresh env draws them.
        fresh = VectorEnv(2, copy=True, keep_dim=True, obs_type="grayscale", obs_size=(16, 16), max_fuel=5)
        assert np.array_equal(fresh.reset(seed=0)[0], before)
        assert np.shares_memory(envs.step(np.array([0, 1]))[0], obs), "copy=False: the same arrays every call"
