"""The learning tool chain: the PPO recipe, evaluation, the SB3 adapter (== SB3's own make_vec_env), SB3 PPO
through it, and Gymnasium's vector wrappers on the native batch. Smoke sizes only: learning itself is a benchmark
(README, docs/learning.md)."""

from __future__ import annotations

import importlib.util
import json
import math

import gymnasium as gym
import numpy as np
import pytest

from chopperscape import VectorEnv

from conftest import SHORT

needs_torch = pytest.mark.skipif(
    importlib.util.find_spec("torch") is None, reason="torch is not installed (scripts/test-python.sh installs it)"
)
needs_sb3 = pytest.mark.skipif(
    importlib.util.find_spec("stable_baselines3") is None or importlib.util.find_spec("torch") is None,
    reason="stable-baselines3 is not installed (scripts/test-python.sh installs it)",
)


@needs_torch
def test_recipe_trains_saves_and_evaluates(tmp_path, capsys):
    from chopperscape import evaluate, train

    recipe = train.Recipe(num_envs=8, num_steps=64, env_options={"max_fuel": 200}, hidden=32)
    path = train.train(recipe, tmp_path, minutes=None, total_steps=3000)
    rows = (tmp_path / "progress.csv").read_text().splitlines()
    assert rows[0] == ",".join(train.CSV_COLUMNS)
    last = dict(zip(train.CSV_COLUMNS, rows[-1].split(",")))
    assert int(last["env_steps"]) >= 3000 and int(last["episodes"]) > 0
    assert all(math.isfinite(float(v)) for v in last.values())
    # The checkpoint reloads into the same policy: evaluation is reproducible and uses the training options.
    assert evaluate.main([str(path), "--episodes", "3", "--seed", "77"]) == 0
    first = json.loads(capsys.readouterr().out)
    assert evaluate.main([str(path), "--episodes", "3", "--seed", "77", "--per-episode"]) == 0
    second = json.loads(capsys.readouterr().out)
    assert {k: first[k] for k in first if k != "per_episode"} == {k: second[k] for k in first}
    assert first["episodes"] == 3 and sum(first["causes"].values()) == pytest.approx(1.0, abs=0.01)
    assert [e["seed"] for e in second["per_episode"]] == [77, 78, 79]
    # max_fuel=200 came from the model: no episode outlives its fuel without a tank.
    assert all(e["steps"] <= 200 or e["return"] > 0 for e in second["per_episode"])


def test_evaluate_plays_pilots_on_the_same_seeds_as_the_command_line(capsys):
    from chopperscape import evaluate, pilots

    assert evaluate.main(["random", "--episodes", "3", "--seed", "4", "--per-episode",
                          "--option", "max_fuel=300"]) == 0
    out = json.loads(capsys.readouterr().out)
    expected = [(e["seed"], e["return"], e["steps"]) for e in
                ({"seed": 4 + i, "return": r, "steps": s} for i, (r, s) in
                 enumerate((ep["return"], ep["steps"]) for ep in pilots.episodes("random", 3, 4, max_fuel=300)))]
    assert [(e["seed"], e["return"], e["steps"]) for e in out["per_episode"]] == expected


@needs_torch
def test_evaluate_names_a_bad_model_file(tmp_path, capsys):
    from chopperscape import evaluate

    bad = tmp_path / "model.pt"
    bad.write_bytes(b"not a model")
    assert evaluate.main([str(bad), "--episodes", "1"]) == 2
    assert "model.pt" in capsys.readouterr().err
    assert evaluate.main([str(tmp_path / "missing.pt")]) == 2
    assert "does not exist" in capsys.readouterr().err


def test_evaluation_episodes_replay_single_envs():
    from chopperscape.evaluate import play_episodes

    results = play_episodes(lambda obs, envs: np.full(len(obs), 4), 3, 5, dict(SHORT))
    for r in results:
        env = gym.make("ChopperScape-v0", **SHORT)
        env.reset(seed=r["seed"])
        total, steps, done = 0.0, 0, False
        while not done:
            _, reward, term, trunc, info = env.step(4)
            total, steps, done = total + reward, steps + 1, term or trunc
        assert (r["return"], r["steps"]) == (total, steps)




@needs_sb3
def test_sb3_adapter_equals_make_vec_env_trajectory_for_trajectory():
    from stable_baselines3.common.env_util import make_vec_env

    from chopperscape.sb3 import ChopperScapeVecEnv

    options = dict(SHORT, lives=2)
    ref = make_vec_env("ChopperScape-v0", n_envs=3, seed=11, env_kwargs=options)
    ours = ChopperScapeVecEnv(3, seed=11, **options)
    assert ours.observation_space == ref.observation_space and ours.action_space == ref.action_space
    assert np.array_equal(ref.reset(), ours.reset())
    rng = np.random.default_rng(1)
    ended = 0
    for t in range(600):
        actions = rng.integers(0, 5, 3)
        o1, r1, d1, i1 = ref.step(actions)
        o2, r2, d2, i2 = ours.step(actions)
        assert np.array_equal(o1, o2) and np.array_equal(r1, r2) and np.array_equal(d1, d2), t
        for a, b in zip(i1, i2):
            for key in ("TimeLimit.truncated", "fuel", "lives", "cause"):
                assert a.get(key) == b.get(key), (t, key)
            assert ("terminal_observation" in a) == ("terminal_observation" in b)
            if "terminal_observation" in a:
                ended += 1
                assert np.array_equal(a["terminal_observation"], b["terminal_observation"])
                assert (a["episode"]["r"], a["episode"]["l"]) == (b["episode"]["r"], b["episode"]["l"])
    assert ended > 20


@needs_sb3
def test_sb3_adapter_reports_truncation_as_sb3_does():
    from chopperscape.sb3 import ChopperScapeVecEnv

    env = ChopperScapeVecEnv(2, seed=0, obs_type="features", bird_prob=0.0, max_episode_steps=5)
    env.reset()
    for _ in range(4):
        _, _, dones, infos = env.step(np.array([4, 4]))
        assert not dones.any() and not infos[0]["TimeLimit.truncated"]
    obs, _, dones, infos = env.step(np.array([4, 4]))
    assert dones.all() and all(i["TimeLimit.truncated"] for i in infos)
    assert all(i["episode"]["l"] == 5 for i in infos)
    # The returned observation is the reset one, the last one is kept aside.
    assert not np.array_equal(obs[0], infos[0]["terminal_observation"])


@needs_sb3
def test_sb3_ppo_learns_a_few_steps_through_the_adapter_and_reloads(tmp_path):
    from stable_baselines3 import PPO
    from stable_baselines3.common.evaluation import evaluate_policy

    from chopperscape.sb3 import ChopperScapeVecEnv

    env = ChopperScapeVecEnv(4, seed=0, obs_type="features", max_fuel=200)
    model = PPO("MlpPolicy", env, n_steps=128, batch_size=128, n_epochs=1, seed=0, device="cpu")
    model.learn(1024)
    assert len(model.ep_info_buffer) > 0, "episode statistics reach SB3's logger without a Monitor"
    import torch

    assert all(torch.isfinite(p).all() for p in model.policy.parameters())
    model.save(tmp_path / "ppo")
    again = PPO.load(tmp_path / "ppo", device="cpu")
    obs = env.reset()
    assert np.array_equal(model.predict(obs, deterministic=True)[0], again.predict(obs, deterministic=True)[0])
    mean, _ = evaluate_policy(again, env, n_eval_episodes=4)
    assert mean > 0


@needs_sb3
def test_sb3_cnn_policy_accepts_grayscale_with_a_channel_axis():
    from stable_baselines3 import PPO

    from chopperscape.sb3 import ChopperScapeVecEnv

    env = ChopperScapeVecEnv(2, seed=0, obs_type="grayscale", obs_size=(84, 84), hud=False, max_fuel=100)
    assert env.observation_space.shape == (84, 84, 1)
    model = PPO("CnnPolicy", env, n_steps=32, batch_size=32, n_epochs=1, device="cpu")
    model.learn(64)
    stacked = ChopperScapeVecEnv(2, obs_type="grayscale", obs_size=(84, 84), frame_stack=4)
    assert stacked.observation_space.shape == (84, 84, 4)


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
    for _ in range(300):
        obs, rew, term, trunc, info = wrapped.step(np.random.default_rng(0).integers(0, 5, 4))
        assert np.isfinite(obs).all() and np.isfinite(rew).all() and (np.abs(rew) <= 5).all()
        if "episode" in info:
            finished += int(info["_episode"].sum())
            assert (info["episode"]["l"][info["_episode"]] > 0).all()
    assert finished > 5


def test_plot_draws_progress_csvs_and_names_a_bad_one(tmp_path, capsys):
    pytest.importorskip("matplotlib", reason="matplotlib is not installed")
    from chopperscape import plot

    good = tmp_path / "run" / "progress.csv"
    good.parent.mkdir()
    good.write_text("env_steps,wall_s,episodes,mean_return,std_return,mean_length\n1000,1.0,3,500,100,510\n"
                    "2000,2.0,6,900,150,910\n")
    out = tmp_path / "curve.png"
    assert plot.main([str(good), "--out", str(out), "--hline", "random=600"]) == 0
    assert out.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"
    bad = tmp_path / "bad.csv"
    bad.write_text("steps,return\n1,2\n")
    assert plot.main([str(bad), "--out", str(tmp_path / "x.png")]) == 2
    assert "missing columns" in capsys.readouterr().err and not (tmp_path / "x.png").exists()


@pytest.mark.parametrize("mode", ["NEXT_STEP", "SAME_STEP"])
def test_keep_dim_gives_grayscale_a_channel_axis_everywhere(mode):
    options = dict(obs_type="grayscale", obs_size=(84, 84), hud=False, max_fuel=30)
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
        obs, _, term, trunc, info = envs.step(np.array([4, 4]))
        assert obs.shape == (2, 84, 84, 1)
        if "final_obs" in info:
            assert all(f.shape == (84, 84, 1) for f in info["final_obs"][info["_final_obs"]])
    # Stacked or colour frames already have a channel axis: keep_dim changes nothing there.
    stacked = gym.make("ChopperScape-v0", keep_dim=True, obs_type="grayscale", obs_size=(84, 84), frame_stack=4)
    assert stacked.observation_space.shape == (84, 84, 4)
    with pytest.raises(ValueError, match="keep_dim"):
        gym.make("ChopperScape-v0", keep_dim="yes")


@needs_sb3
def test_evaluate_reads_an_sb3_model_with_its_vecnormalize(tmp_path, capsys):
    from stable_baselines3 import PPO
    from stable_baselines3.common.vec_env import VecNormalize

    from chopperscape import evaluate
    from chopperscape.sb3 import ChopperScapeVecEnv

    env = VecNormalize(ChopperScapeVecEnv(2, seed=0, obs_type="features", max_fuel=100), gamma=0.999)
    model = PPO("MlpPolicy", env, n_steps=64, batch_size=64, n_epochs=1, device="cpu").learn(128)
    model.save(tmp_path / "model.zip")
    env.save(str(tmp_path / "vecnormalize.pkl"))
    args = [str(tmp_path / "model.zip"), "--episodes", "2", "--option", 'obs_type="features"', "--option",
            "max_fuel=100"]
    assert evaluate.main(args) == 0
    out = json.loads(capsys.readouterr().out)
    assert out["episodes"] == 2 and set(out["causes"]) <= {"bird", "fuel", "truncated"} and out["greedy"]
