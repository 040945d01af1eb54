"""Smoke test of the installed wheels, run by scripts/test-dist.sh in a fresh venv with no Rust toolchain on PATH
and outside the repository (so only the installed package can be imported)."""

from __future__ import annotations

import json
import os
import shutil
import subprocess
import sys
import warnings

import gymnasium as gym
import numpy as np
from gymnasium.utils.env_checker import check_env

import chopperscape
from chopperscape import policies


def test_no_rust_toolchain_and_the_installed_package():
    assert shutil.which("cargo") is None and shutil.which("rustc") is None, os.environ["PATH"]
    assert chopperscape.__file__.startswith(sys.prefix), chopperscape.__file__


def test_make_and_step_every_obs_type():
    for obs_type in ("rgb", "rgb_float", "grayscale", "features"):
        env = gym.make("ChopperScape-v0", obs_type=obs_type, obs_size=(84, 84))
        obs, _ = env.reset(seed=0)
        assert env.observation_space.contains(obs)
        for _ in range(50):
            obs, reward, terminated, truncated, _ = env.step(env.action_space.sample())
            assert env.observation_space.contains(obs) and reward in (1.0, -10.0)
            if terminated or truncated:
                env.reset()
        env.close()


def test_check_env():
    for obs_type in ("features", "grayscale"):
        env = gym.make("ChopperScape-v0", obs_type=obs_type, obs_size=(84, 84), render_mode="rgb_array")
        with warnings.catch_warnings():
            warnings.simplefilter("error")
            check_env(env.unwrapped)


def test_module_id_works_without_an_import():
    code = "import gymnasium as gym; e = gym.make('chopperscape:ChopperScape-v0', obs_type='features'); e.reset(seed=1)"
    subprocess.run([sys.executable, "-c", code], check=True)


def test_vector_env_equals_single_envs():
    envs = gym.make_vec("ChopperScape-v0", num_envs=4, vectorization_mode="vector_entry_point", obs_type="features")
    obs, _ = envs.reset(seed=10)
    singles = [gym.make("ChopperScape-v0", obs_type="features") for _ in range(4)]
    for i, env in enumerate(singles):
        assert np.array_equal(env.reset(seed=10 + i)[0], obs[i])
    actions = np.array([0, 1, 3, 4])
    obs, rewards, *_ = envs.step(actions)
    for i, env in enumerate(singles):
        o, r, *_ = env.step(int(actions[i]))
        assert np.array_equal(o, obs[i]) and r == rewards[i]
    assert isinstance(envs.unwrapped, chopperscape.VectorEnv)


def test_policies():
    episodes = list(policies.episodes("heuristic", 2, seed=0))
    assert len(episodes) == 2 and all(e["return"] > 0 for e in episodes)
    envs = chopperscape.VectorEnv(8, obs_type="features")
    batch = policies.VectorPolicy("heuristic", num_envs=8, seed=0)
    envs.reset(seed=0)
    actions = batch.act(envs)
    assert actions.shape == (8,) and set(actions.tolist()) <= set(range(5))
    envs.step(actions)


def test_the_cli_wheel_matches_the_package():
    exe = shutil.which("chopperscape")
    assert exe and exe.startswith(sys.prefix), exe
    out = subprocess.run(
        [exe, "demo", "--policy", "heuristic", "--episodes", "2", "--seed", "0", "--json"],
        check=True,
        capture_output=True,
        text=True,
    ).stdout
    lines = [json.loads(line) for line in out.splitlines()]
    expected = list(policies.episodes("heuristic", 2, seed=0))
    assert [e["return"] for e in lines] == [e["return"] for e in expected]
    version = subprocess.run([exe, "--version"], check=True, capture_output=True, text=True).stdout
    assert chopperscape.__version__ in version
