"""Held-out evaluation (`python -m chopperscape.learn.evaluate`, `chopperscape.learn.episodes`): built-in policies on
the command line's seeds, a bad model file named, episodes equal to single envs', an SB3 model with its
normalisation."""

from __future__ import annotations

import json

import gymnasium as gym
import numpy as np
from conftest import SHORT, needs_sb3, needs_torch


def test_evaluate_plays_builtin_policies_on_the_same_seeds_as_the_command_line(capsys):
    from chopperscape import policies
    from chopperscape.learn import evaluate

    assert evaluate.main(["random", "--episodes", "3", "--seed", "4", "--per-episode", "--option", "max_fuel=300"]) == 0
    out = json.loads(capsys.readouterr().out)
    expected = [
        (e["seed"], e["return"], e["steps"])
        for e in (
            {"seed": 4 + i, "return": r, "steps": s}
            for i, (r, s) in enumerate(
                (ep["return"], ep["steps"]) for ep in policies.episodes("random", 3, 4, max_fuel=300)
            )
        )
    ]
    assert [(e["seed"], e["return"], e["steps"]) for e in out["per_episode"]] == expected


@needs_torch
def test_evaluate_names_a_bad_model_file(tmp_path, capsys):
    from chopperscape.learn import evaluate

    bad = tmp_path / "model.pt"
    bad.write_bytes(b"not a model")
    assert evaluate.main([str(bad), "--episodes", "1"]) == 2
    assert "model.pt" in capsys.readouterr().err
    assert evaluate.main([str(tmp_path / "missing.pt")]) == 2
    assert "does not exist" in capsys.readouterr().err


def test_evaluation_episodes_replay_single_envs():
    from chopperscape.learn.episodes import play_episodes

    results = play_episodes(lambda obs, envs: np.full(len(obs), 4), 3, 5, dict(SHORT))
    for r in results:
        env = gym.make("ChopperScape-v0", **SHORT)
        env.reset(seed=r["seed"])
        total, steps, done = 0.0, 0, False
        while not done:
            _, reward, term, trunc, _info = env.step(4)
            total, steps, done = total + reward, steps + 1, term or trunc
        assert (r["return"], r["steps"]) == (total, steps)


@needs_sb3
def test_evaluate_reads_an_sb3_model_with_its_vecnormalize(tmp_path, capsys, monkeypatch):
    from stable_baselines3 import PPO
    from stable_baselines3.common.vec_env import VecNormalize

    from chopperscape.integrations.sb3 import ChopperScapeVecEnv
    from chopperscape.integrations.sb3_files import save_normalization
    from chopperscape.learn import evaluate

    env = VecNormalize(ChopperScapeVecEnv(2, seed=0, obs_type="features", max_fuel=100), gamma=0.999)
    model = PPO("MlpPolicy", env, n_steps=64, batch_size=64, n_epochs=1, device="cpu").learn(128)
    model.save(tmp_path / "model.zip")
    save_normalization(env, tmp_path / "vecnormalize.json")  # the statistics as data (a .pkl needs --trust-pickle)
    args = [
        str(tmp_path / "model.zip"),
        "--episodes",
        "2",
        "--option",
        'obs_type="features"',
        "--option",
        "max_fuel=100",
    ]
    assert evaluate.main(args) == 0
    out = json.loads(capsys.readouterr().out)
    assert out["episodes"] == 2 and set(out["causes"]) <= {"bird", "fuel", "truncated"} and out["greedy"]
    # The statistics are applied: the normaliser evaluate loads is VecNormalize's own transform, and every
    # observation the model acts on went through it.
    from chopperscape.integrations import sb3_files as sb3

    norm = sb3.load_normalization(tmp_path, False)
    obs = env.get_original_obs()
    assert norm is not None and np.allclose(norm(obs), env.normalize_obs(obs), atol=1e-6)
    seen: list[tuple[int, ...]] = []
    original = sb3.load_normalization

    def spying(folder, trust_pickle=False):
        inner = original(folder, trust_pickle)
        assert inner is not None

        def apply(o):
            seen.append(o.shape)
            return inner(o)

        return apply

    monkeypatch.setattr(sb3, "load_normalization", spying)
    assert evaluate.main(args) == 0
    assert json.loads(capsys.readouterr().out) == out
    # One call per decision, on the batch of raw features (the policy never acts on an unnormalised observation).
    assert all(shape[1:] == (46,) for shape in seen) and len(seen) >= out["mean_steps"]
