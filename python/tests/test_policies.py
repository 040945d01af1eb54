"""The built-in policies in Python play exactly the command line's episodes (`chopperscape demo --json`), for one
env and for the native vector env, through gymnasium wrappers, under any options."""

from __future__ import annotations

import json
import pathlib
import subprocess

import gymnasium as gym
import numpy as np
import pytest
from conftest import cli

import chopperscape
from chopperscape import policies

ROOT = pathlib.Path(__file__).resolve().parents[2]
#: (gym option name, CLI flag) for the options the tests vary.
FLAGS = {
    "frame_skip": "--frame-skip",
    "sticky_prob": "--sticky",
    "lives": "--lives",
    "alien_prob": "--aliens",
    "bird_fuel_collision": "--bird-fuel-collision",
    "max_fuel": "--max-fuel",
}
#: Short episodes, so that a debug build of the CLI plays them quickly.
STEPS = 1500


def demo(policy: str, episodes: int, seed: int, options: dict) -> list[dict]:
    exe = cli()
    if exe is None:
        pytest.skip("cargo is not installed: the comparison with `chopperscape demo --json` is skipped")
    cmd = [str(exe), "demo", "--policy", policy, "--episodes", str(episodes), "--seed", str(seed), "--json"]
    cmd += ["--max-episode-steps", str(STEPS)]
    for k, v in options.items():
        cmd += [FLAGS[k], str(v)]
    out = subprocess.run(cmd, check=True, capture_output=True, text=True).stdout
    return [json.loads(line) for line in out.splitlines()]


CASES = [
    ("random", {}),
    ("heuristic", {}),
    ("up", {}),
    ("heuristic", {"frame_skip": 4, "sticky_prob": 0.25}),
    ("random", {"frame_skip": 3, "sticky_prob": 0.5}),
    ("heuristic", {"alien_prob": 0.02, "lives": 3, "bird_fuel_collision": "destroy", "max_fuel": 300}),
]


@pytest.mark.parametrize(
    "policy,options", CASES, ids=[f"{p}-{'-'.join(map(str, o.values())) or 'v0'}" for p, o in CASES]
)
def test_single_env_policy_plays_the_cli_demo_episodes(policy, options):
    expected = demo(policy, 3, 11, options)
    got = list(policies.episodes(policy, 3, 11, max_episode_steps=STEPS, **options))
    assert [{k: v for k, v in e.items() if k != "actions"} for e in got] == expected


@pytest.mark.parametrize("policy,options", CASES[:4], ids=[p for p, _ in CASES[:4]])
def test_vector_policy_plays_the_cli_demo_episodes(policy, options):
    n, seed = 3, 11
    expected = demo(policy, n, seed, options)
    envs = chopperscape.VectorEnv(n, obs_type="features", max_episode_steps=STEPS, **options)
    batch = policies.VectorPolicy(policy, n, seed=seed)
    envs.reset(seed=seed)
    returns, steps, done = np.zeros(n, dtype=np.int64), np.zeros(n, dtype=np.int64), np.zeros(n, dtype=bool)
    causes = [None] * n
    while not done.all():
        actions = batch.act(envs)
        assert actions.dtype == np.int64 and actions.shape == (n,)
        _, rewards, terminated, truncated, info = envs.step(actions)
        live = ~done
        returns[live] += rewards[live].astype(np.int64)
        steps[live] += 1
        for i in np.flatnonzero(live & (terminated | truncated)):
            causes[i] = info["cause"][i] if terminated[i] else "truncated"
        done |= terminated | truncated
    got = [
        {"episode": i, "seed": seed + i, "steps": int(steps[i]), "return": int(returns[i]), "cause": causes[i]}
        for i in range(n)
    ]
    assert got == expected


def test_vector_policy_continues_across_autoresets_as_a_single_env_policy():
    opts = {"obs_type": "features", "max_fuel": 60, "bird_prob": 0.1}
    envs = chopperscape.VectorEnv(2, **opts)
    batch = policies.VectorPolicy("random", 2, seed=4)
    envs.reset(seed=4)
    vector_actions = []
    for _ in range(200):
        actions = batch.act(envs)
        vector_actions.append(int(actions[1]))
        envs.step(actions)
    # Environment 1 alone: seed 5, its policy seeded 5 and not restarted between episodes; the autoreset step's
    # action is ignored (Do Nothing) and draws nothing.
    env = gym.make("ChopperScape-v0", **opts)
    policy = policies.random(5)
    env.reset(seed=5)
    single_actions, ended = [], False
    for _ in range(200):
        if ended:
            single_actions.append(4)
            env.reset()
            ended = False
            continue
        a = policy.act(env)
        single_actions.append(a)
        _, _, terminated, truncated, _ = env.step(a)
        ended = terminated or truncated
    assert vector_actions == single_actions


def test_random_policy_is_seeded_and_reset_restarts_it():
    env = gym.make("ChopperScape-v0", obs_type="features")
    env.reset(seed=0)
    a, b = policies.random(9), policies.random(9)
    xs = [a.act(env) for _ in range(60)]
    assert xs == [b.act(env) for _ in range(60)]
    assert set(xs) == {0, 1, 2, 3, 4}
    a.reset()
    assert [a.act(env) for _ in range(60)] == xs
    a.reset(10)
    assert [a.act(env) for _ in range(60)] != xs
    assert repr(a) == "Policy('random', seed=10)"


def test_fixed_policies_and_names():
    env = gym.make("ChopperScape-v0", obs_type="features")
    env.reset(seed=0)
    assert [policies.fixed(i).act(env) for i in range(5)] == [0, 1, 2, 3, 4]
    assert policies.fixed("up").act(env) == 3
    assert set(policies.NAMES) == {"random", "heuristic", "right", "left", "down", "up", "noop"}


def test_heuristic_plans_for_the_frame_skip_of_the_env_it_flies():
    # At frame_skip 4 the heuristic plans in agent steps: far above random (planning per frame, it fell to
    # about random).
    mean = {
        name: np.mean([e["return"] for e in policies.episodes(name, 4, 0, max_episode_steps=STEPS, frame_skip=4)])
        for name in ("random", "heuristic")
    }
    assert mean["heuristic"] > 3 * mean["random"], mean


def test_bad_input_is_refused_clearly():
    with pytest.raises(ValueError, match=r"unknown policy 'genius'.*heuristic"):
        policies.make("genius")
    with pytest.raises(ValueError, match="invalid seed -1"):
        policies.random(-1)
    with pytest.raises(ValueError, match="invalid fixed action 7"):
        policies.fixed(7)
    envs = chopperscape.VectorEnv(2, obs_type="features")
    envs.reset(seed=0)
    with pytest.raises(TypeError, match="VectorPolicy"):
        policies.heuristic().act(envs)
    with pytest.raises(ValueError, match="has 2 environments but this policy plays 3"):
        policies.VectorPolicy("heuristic", 3).act(envs)
    with pytest.raises(TypeError, match="native VectorEnv"):
        policies.VectorPolicy("heuristic", 2).act(gym.make("ChopperScape-v0", obs_type="features"))
    with pytest.raises(ValueError, match="num_envs"):
        policies.VectorPolicy("heuristic", 0)


def test_the_package_exports_policies():
    assert "policies" in chopperscape.__all__ and chopperscape.policies is policies


def test_the_core_classes_are_named_policy():
    core = chopperscape._core
    assert core.Policy.__name__ == "Policy" and core.VectorPolicy.__name__ == "VectorPolicy"
    assert core.Policy.__module__ == "chopperscape._core"
    assert list(core.POLICY_NAMES) == policies.NAMES
