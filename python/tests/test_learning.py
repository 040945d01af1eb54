"""The learning tool chain: the PPO recipe, evaluation, the SB3 adapter (== SB3's own make_vec_env), SB3 PPO
through it, and Gymnasium's vector wrappers on the native batch. Smoke sizes only: learning itself is a benchmark
(README, docs/learning.md)."""

from __future__ import annotations

import contextlib
import csv
import importlib.util
import json
import math
import re
import subprocess
import sys

import gymnasium as gym
import numpy as np
import pytest
from conftest import SHORT

from chopperscape import VectorEnv

needs_torch = pytest.mark.skipif(
    importlib.util.find_spec("torch") is None, reason="torch is not installed (scripts/test-python.sh installs it)"
)
needs_sb3 = pytest.mark.skipif(
    importlib.util.find_spec("stable_baselines3") is None or importlib.util.find_spec("torch") is None,
    reason="stable-baselines3 is not installed (scripts/test-python.sh installs it)",
)


@needs_torch
def test_recipe_trains_saves_and_evaluates(tmp_path, capsys):
    from chopperscape.learn import evaluate, train
    from chopperscape.learn.recipe import Recipe

    recipe = Recipe(num_envs=8, num_steps=64, env_options={"max_fuel": 200}, hidden=32, total_steps=3000)
    path = train.train(recipe, tmp_path)
    rows = (tmp_path / "progress.csv").read_text().splitlines()
    assert rows[0] == ",".join(train.CSV_COLUMNS)
    last = dict(zip(train.CSV_COLUMNS, rows[-1].split(",")))
    assert int(last["env_steps"]) >= 3000 and int(last["episodes"]) > 0
    assert all(math.isfinite(float(v)) for v in last.values() if v != "")
    # The checkpoint reloads into the same policy: evaluation is reproducible and uses the training options.
    assert evaluate.main([str(path), "--episodes", "3", "--seed", "77"]) == 0
    first = json.loads(capsys.readouterr().out)
    assert evaluate.main([str(path), "--episodes", "3", "--seed", "77", "--per-episode"]) == 0
    second = json.loads(capsys.readouterr().out)
    assert {k: first[k] for k in first if k != "per_episode"} == {k: second[k] for k in first}
    assert first["episodes"] == 3 and sum(first["causes"].values()) == pytest.approx(1.0, abs=0.01)
    assert [e["seed"] for e in second["per_episode"]] == [77, 78, 79]
    # max_fuel=200 came from the model: evaluate plays under the options the model was trained with, and giving
    # them again explicitly changes nothing.
    _, options = evaluate.load_recipe(path, False, 0, {})
    assert options["max_fuel"] == 200
    assert (
        evaluate.main([str(path), "--episodes", "3", "--seed", "77", "--per-episode", "--option", "max_fuel=200"]) == 0
    )
    assert json.loads(capsys.readouterr().out) == second


def _progress(path):
    import csv

    with open(path, newline="") as f:
        return list(csv.DictReader(f))


@needs_torch
def test_recipe_runs_are_reproducible_and_follow_env_steps_not_the_clock(tmp_path):
    from chopperscape.learn import train
    from chopperscape.learn.recipe import Recipe

    def run(name, **kw):
        recipe = Recipe(num_envs=8, num_steps=64, env_options={"max_fuel": 150}, hidden=16, total_steps=6000, **kw)
        train.train(recipe, tmp_path / name)
        return _progress(tmp_path / name / "progress.csv")

    first, second = run("a"), run("b")
    assert len(first) >= 5
    # Identical apart from the time column: same seed and budget, same curve, whatever the host's load.
    drop = [{k: v for k, v in r.items() if k != "wall_s"} for r in first]
    assert drop == [{k: v for k, v in r.items() if k != "wall_s"} for r in second]
    # The learning rate anneals linearly over the step budget from the start: lr = 3e-4 * (1 - steps / budget).
    lrs = [float(r["learning_rate"]) for r in first]
    assert lrs == sorted(lrs, reverse=True) and lrs[0] == 3e-4 and lrs[-1] < 1e-4
    steps_before = [0] + [int(r["env_steps"]) for r in first[:-1]]
    for r, before in zip(first, steps_before):
        assert float(r["learning_rate"]) == pytest.approx(3e-4 * max(1 - before / 6000, 0.05), rel=1e-4)
    # Another seed is another run.
    assert [r["mean_return"] for r in run("c", seed=1)] != [r["mean_return"] for r in first]


@needs_torch
def test_progress_diagnostics_are_sane(tmp_path):
    from chopperscape.learn import train
    from chopperscape.learn.recipe import Recipe

    recipe = Recipe(num_envs=8, num_steps=64, env_options={"max_fuel": 100}, hidden=16, total_steps=4000)
    train.train(recipe, tmp_path)
    rows = _progress(tmp_path / "progress.csv")
    for r in rows:
        # Entropy of a 5-action policy lies in [0, ln 5]; the fresh policy is nearly uniform.
        assert 0 <= float(r["entropy"]) <= math.log(5) + 1e-6
        assert 0 <= float(r["clip_frac"]) <= 1 and float(r["approx_kl"]) >= -1e-6
        assert float(r["explained_var"]) <= 1 and float(r["value_loss"]) >= 0
        if int(r["ended"]):
            assert r["mean_return"] != ""
            shares = [float(r[k]) for k in ("bird", "fuel", "limit")]
            assert sum(shares) == pytest.approx(1, abs=0.002)
    assert float(rows[0]["entropy"]) > 0.95 * math.log(5)
    # With 100 fuel and a policy that cannot yet refuel, fuel ends most episodes; no episode reaches 10,000 steps.
    ended = sum(int(r["ended"]) for r in rows)
    fuel = sum(float(r["fuel"]) * int(r["ended"]) for r in rows if int(r["ended"]))
    assert ended == int(rows[-1]["episodes"]) and fuel / ended > 0.3
    assert all(float(r["limit"] or 0) == 0 for r in rows)


@needs_torch
def test_pixel_recipe_smoke_trains_reloads_and_evaluates(tmp_path, capsys):
    import chopperscape
    from chopperscape.learn import evaluate, model, train

    # The pixel preset at a smoke size: small frames, few envs; the same code path as the full recipe.
    out = tmp_path / "px"
    assert (
        train.main(
            [
                "--preset",
                "pixels",
                "--steps",
                "1200",
                "--num-envs",
                "8",
                "--num-steps",
                "32",
                "--out",
                str(out),
                "--option",
                "obs_size=42x42",
                "--option",
                "max_fuel=300",
            ]
        )
        == 0
    )
    capsys.readouterr()
    recipe = json.loads((out / "recipe.json").read_text())
    assert recipe["obs_type"] == "grayscale" and recipe["network"] == "small" and recipe["gamma"] == 0.998
    assert recipe["env_options"] == {"obs_size": [42, 42], "frame_stack": 4, "frame_skip": 4, "max_fuel": 300}
    rows = _progress(out / "progress.csv")
    assert rows and all(math.isfinite(float(r[k])) for r in rows for k in ("entropy", "value_loss", "policy_loss"))
    import torch

    payload = torch.load(out / "model.pt", weights_only=True)
    assert payload["obs_shape"] == [42, 42, 4] and payload["pixels_version"] == chopperscape.PIXELS_VERSION
    # A model of a later pixel layout is refused, naming both versions; one of an older layout is shown that
    # layout (version 2: the art; version 1: the art and the text HUD), its own options over those.
    later = chopperscape.PIXELS_VERSION + 1
    with pytest.raises(ValueError, match=f"pixel layout v{later}, and this chopperscape draws v{later - 1}"):
        model.agent_from_checkpoint({**payload, "pixels_version": later})
    assert model.from_payload({**payload, "pixels_version": 2}).recipe["env_options"]["look"] == "art"
    old = model.from_payload({**payload, "pixels_version": 1}).recipe["env_options"]
    assert (old["look"], old["hud_style"], old["max_fuel"]) == ("art", "text", 300)
    assert "look" not in model.from_payload(payload).recipe["env_options"]
    agent = model.agent_from_checkpoint(payload)
    assert isinstance(agent, model.CnnAgent)
    # The frame skip, stack and size came back from the model: evaluation plays the frames it was trained on.
    assert evaluate.main([str(out / "model.pt"), "--episodes", "2", "--seed", "9", "--per-episode"]) == 0
    res = json.loads(capsys.readouterr().out)
    assert res["episodes"] == 2 and all(e["return"] % 4 == 0 or e["cause"] == "bird" for e in res["per_episode"])
    # Reloading gives the same greedy actions on the same frames.
    env_obs = np.random.default_rng(0).integers(0, 256, (3, 42, 42, 4), dtype=np.uint8)
    again = model.agent_from_checkpoint(torch.load(out / "model.pt", weights_only=True))
    with torch.no_grad():
        assert torch.equal(agent.actor(torch.from_numpy(env_obs)), again.actor(torch.from_numpy(env_obs)))


def test_networks_refuse_observations_they_cannot_take():
    pytest.importorskip("torch")
    from chopperscape.learn import model

    with pytest.raises(ValueError, match="mlp network takes vector observations"):
        model.build_agent("mlp", (84, 84, 4))
    with pytest.raises(ValueError, match="takes grayscale frames"):
        model.build_agent("small", (46,))
    with pytest.raises(ValueError, match="too small"):
        model.build_agent("nature", (16, 16, 4))
    with pytest.raises(ValueError, match="allowed 'auto', 'mlp', 'small', 'nature'"):
        model.build_agent("resnet", (84, 84, 4))


def test_iqm_and_bootstrap_match_their_definitions():
    from chopperscape.learn.seeds import bootstrap_ci, iqm, parse_seeds

    assert parse_seeds("0-3,7, 2") == [0, 1, 2, 3, 7] and parse_seeds("1,0,2-3") == [1, 0, 2, 3]
    for bad in ("", "a", "3-1", "-1", "0-5000"):
        with pytest.raises(ValueError, match=r"^--seeds"):
            parse_seeds(bad)
    # At most 1000 seeds a range, wherever it starts (boundaries from the mutation pass).
    assert len(parse_seeds("0-999")) == 1000 and parse_seeds("600-700")[-1] == 700
    with pytest.raises(ValueError, match=r"^--seeds '0-1000': '0-1000' must be 0 <= FIRST <= LAST with at most 1000"):
        parse_seeds("0-1000")
    x = np.array([100.0, 1, 2, 3, 4, 5, 6, 7, 8, -50])
    # scipy.stats.trim_mean(x, 0.25): drop int(0.25 * 10) = 2 from each end.
    assert iqm(x) == pytest.approx(np.mean([2, 3, 4, 5, 6, 7]))
    assert iqm(np.arange(8.0)) == pytest.approx(np.mean([2, 3, 4, 5]))
    lo, hi = bootstrap_ci(x, resamples=4000)
    assert lo < iqm(x) < hi and lo >= -50 and hi <= 100
    assert bootstrap_ci(x, resamples=4000) == (lo, hi)  # seeded: a summary is reproducible
    assert bootstrap_ci(np.full(6, 7.0), resamples=100) == (7.0, 7.0)
    with pytest.raises(ValueError, match=r"^--seeds '0-999,1000': at most 1000 seeds$"):
        parse_seeds("0-999,1000")
    # The percentile bootstrap by its definition: resample the runs with replacement (numpy's generator, seeded),
    # take the statistic of each resample, and the 2.5th and 97.5th percentiles of those.
    rng = np.random.default_rng(3)
    idx = rng.integers(0, len(x), size=(1000, len(x)))
    ref = np.percentile([iqm(x[i]) for i in idx], [2.5, 97.5])
    assert bootstrap_ci(x, resamples=1000, seed=3) == tuple(ref)
    assert bootstrap_ci(x, resamples=1000, level=0.5, seed=3) == tuple(
        np.percentile([iqm(x[i]) for i in idx], [25.0, 75.0])
    )
    # With a statistic that is not stepped (the mean), every percentile and the default seed 0 show.
    idx0 = np.random.default_rng(0).integers(0, len(x), size=(1000, len(x)))
    means = x[idx0].mean(axis=-1)
    assert np.allclose(bootstrap_ci(x, stat=np.mean, resamples=1000), np.percentile(means, [2.5, 97.5]), atol=1e-9)
    assert np.allclose(
        bootstrap_ci(x, stat=np.mean, resamples=1000, level=0.8), np.percentile(means, [10, 90]), atol=1e-9
    )
    # The protocol the docs state: 100 held-out seeds from 1,000,000; rliable's 50,000 resamples, 95 %, seed 0.
    from chopperscape.learn import seeds

    assert (seeds.EVAL_EPISODES, seeds.EVAL_SEED, seeds.RESAMPLES) == (100, 1_000_000, 50_000)
    assert bootstrap_ci(x) == bootstrap_ci(x, resamples=50_000, level=0.95, seed=0)
    # `python -m chopperscape.learn.seeds` is a command (its --help needs no training).
    out = subprocess.run([sys.executable, "-m", "chopperscape.learn.seeds", "--help"], capture_output=True, text=True)
    assert out.returncode == 0 and "--seeds SEEDS" in out.stdout, out.stderr
    # Curves: points along the first axis are bootstrapped together, one interval per point.
    lo2, hi2 = bootstrap_ci(np.stack([x, x + 10]), resamples=4000)
    assert np.allclose(lo2, [lo, lo + 10]) and np.allclose(hi2, [hi, hi + 10])


@needs_torch
def test_seeds_runner_smoke_trains_evaluates_resumes_and_summarises(tmp_path, capsys):
    from chopperscape.learn import train

    out = tmp_path / "bench"
    args = [
        "--seeds",
        "0-1",
        "--steps",
        "2000",
        "--out",
        str(out),
        "--eval-episodes",
        "3",
        "--jobs",
        "2",
        "--num-envs",
        "8",
        "--num-steps",
        "64",
        "--hidden",
        "16",
        "--option",
        "max_fuel=150",
    ]
    assert train.main(args) == 0
    summary = json.loads((out / "summary.json").read_text())
    assert summary["seeds"] == [0, 1] and set(summary["per_seed"]) == {"0", "1"}
    means = [summary["per_seed"][s]["mean_return"] for s in ("0", "1")]
    lo, hi = summary["iqm_ci95"]
    assert lo <= summary["iqm"] <= hi and min(means) <= lo and hi <= max(means)
    assert summary["eval"] == {"episodes": 3, "seed": 1_000_000}
    assert set(summary["baselines"]) == {"random", "heuristic"}
    # The options reached training and every evaluation: max_fuel 150 bounds the policies' episodes without tanks.
    assert json.loads((out / "seed-1" / "recipe.json").read_text())["env_options"] == {"max_fuel": 150}
    assert "IQM" in (out / "summary.md").read_text() and "| 1 |" in (out / "summary.md").read_text()
    # Run again: every seed is already evaluated with these settings, so nothing is retrained.
    stamp = (out / "seed-0" / "model.pt").stat().st_mtime_ns
    assert train.main(args) == 0 and (out / "seed-0" / "model.pt").stat().st_mtime_ns == stamp
    assert json.loads((out / "summary.json").read_text()) == summary


def test_seeds_summarise_reads_another_trainers_evaluations_and_refuses_mismatches(tmp_path, capsys):
    """`--summarise DIR`: the SB3 and RLlib rows get the recipe's statistics from their own files."""
    from chopperscape.learn import seeds

    folder = tmp_path / "rllib"
    folder.mkdir()
    means = {0: 3425.6, 1: 900.0, 2: 5100.0, 3: 4000.0}
    for k, m in means.items():
        result = {"seed": 1_000_000, "episodes": 3, "mean_return": m, "std_return": 10.0, "min_return": int(m) - 5}
        result |= {"max_return": int(m) + 5, "mean_steps": m, "causes": {"bird": 1.0}}
        (folder / f"seed-{k}.eval.json").write_text(json.dumps(result))
        (folder / f"seed-{k}.csv").write_text("env_steps,wall_s,episodes,mean_return\n100,1,1,5\n200,2,2,9\n")
    (folder / "seed-x.eval.json").write_text("{}")  # not a seed's: ignored
    args = ["--summarise", str(folder), "--steps", "200", "--eval-episodes", "3", "--title", "RLlib PPO"]
    assert seeds.main(args) == 0
    summary = json.loads((folder / "summary.json").read_text())
    assert summary["seeds"] == [0, 1, 2, 3] and summary["steps"] == 200
    assert summary["iqm"] == round(float(seeds.iqm(np.array(list(means.values())))), 1) == 3712.8
    assert summary["min"] == 900.0 and set(summary["baselines"]) == {"random", "heuristic"}
    assert (folder / "baseline-heuristic.json").is_file() and "| 3 | 4,000 ± 10 |" in (
        folder / "summary.md"
    ).read_text()
    capsys.readouterr()
    # Evaluations of other held-out seeds, a missing curve, an empty folder, training flags: refused, named.
    assert seeds.main(["--summarise", str(folder), "--steps", "200"]) == 2
    assert "played 3 episodes from seed 1000000; this summary is of 100 from 1000000" in capsys.readouterr().err
    (folder / "seed-2.csv").unlink()
    assert seeds.main(args) == 2 and "seed-2.csv missing" in capsys.readouterr().err
    assert seeds.main(["--summarise", str(tmp_path / "none"), "--eval-episodes", "3"]) == 2
    assert "has no seed-K.eval.json" in capsys.readouterr().err
    with pytest.raises(SystemExit):
        seeds.main([*args, "--seeds", "0-1"])
    assert "--summarise DIR takes no --seeds" in capsys.readouterr().err


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
    from chopperscape.learn.evaluate import play_episodes

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
def test_sb3_adapter_equals_make_vec_env_trajectory_for_trajectory():
    from stable_baselines3.common.env_util import make_vec_env

    from chopperscape.integrations.sb3 import ChopperScapeVecEnv

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
    from chopperscape.integrations.sb3 import ChopperScapeVecEnv

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

    from chopperscape.integrations.sb3 import ChopperScapeVecEnv

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
    returns, lengths = evaluate_policy(again, env, n_eval_episodes=4, return_episode_rewards=True, warn=False)
    # Whole episodes reach SB3: +1 a step, and a bird hit pays -10 in place of the +1 (lives=1); never past the fuel
    # cap without a tank, so every episode ends by a bird (length - 11) or with its fuel (the return is its length).
    assert len(returns) == 4 and all(r in (n, n - 11) for r, n in zip(returns, lengths)), (returns, lengths)


@needs_sb3
def test_sb3_cnn_policy_accepts_grayscale_with_a_channel_axis():
    from stable_baselines3 import PPO

    from chopperscape.integrations.sb3 import ChopperScapeVecEnv

    env = ChopperScapeVecEnv(2, seed=0, obs_type="grayscale", obs_size=(84, 84), max_fuel=100)
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
    rng = np.random.default_rng(0)
    for _ in range(300):
        obs, rew, _term, _trunc, info = wrapped.step(rng.integers(0, 5, 4))
        assert np.isfinite(obs).all() and np.isfinite(rew).all() and (np.abs(rew) <= 5).all()
        if "episode" in info:
            finished += int(info["_episode"].sum())
            assert (info["episode"]["l"][info["_episode"]] > 0).all()
    assert finished > 5


def test_plot_draws_progress_csvs_and_names_a_bad_one(tmp_path, capsys, monkeypatch):
    pytest.importorskip("matplotlib", reason="matplotlib is not installed")
    from chopperscape.learn import plot

    good = tmp_path / "run" / "progress.csv"
    good.parent.mkdir()
    good.write_text(
        "env_steps,wall_s,episodes,mean_return,std_return,mean_length\n1000,1.0,3,500,100,510\n2000,2.0,6,900,150,910\n"
    )
    out = tmp_path / "curve.png"
    assert plot.main([str(good), "--out", str(out), "--hline", "random=600"]) == 0
    assert out.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"
    bad = tmp_path / "bad.csv"
    bad.write_text("steps,return\n1,2\n")
    assert plot.main([str(bad), "--out", str(tmp_path / "x.png")]) == 2
    assert "missing columns" in capsys.readouterr().err and not (tmp_path / "x.png").exists()
    # --frame-skip: one per CSV; the left panel then counts game frames (env steps × frame skip).
    import matplotlib.axes

    drawn = []
    real_plot = matplotlib.axes.Axes.plot
    monkeypatch.setattr(
        matplotlib.axes.Axes, "plot", lambda ax, x, *r, **k: drawn.append(list(x)) or real_plot(ax, x, *r, **k)
    )
    assert plot.main([str(good), str(good), "--frame-skip", "1", "--frame-skip", "4", "--out", str(out)]) == 0
    assert drawn == [[0.001, 0.002], [1 / 60, 2 / 60], [0.004, 0.008], [1 / 60, 2 / 60]]
    for args, message in (
        (["--frame-skip", "4"], "1 --frame-skip for 2 CSV files"),
        (["--frame-skip", "0"] * 2, "allowed an integer ≥ 1"),
    ):
        with pytest.raises(SystemExit):
            plot.main([str(good), str(good), *args, "--out", str(tmp_path / "y.png")])
        assert message in capsys.readouterr().err and not (tmp_path / "y.png").exists()


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


@needs_sb3
def test_evaluate_reads_an_sb3_model_with_its_vecnormalize(tmp_path, capsys, monkeypatch):
    from stable_baselines3 import PPO
    from stable_baselines3.common.vec_env import VecNormalize

    from chopperscape.integrations.sb3 import ChopperScapeVecEnv, save_normalization
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
    from chopperscape.integrations import sb3

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


@needs_torch
@pytest.mark.parametrize("network, shape", [("small", (84, 84, 4)), ("small", (42, 42, 4)), ("nature", (84, 84))])
def test_cnn_act_runs_the_trunk_once_and_matches_both_heads(network, shape):
    """`CnnAgent.act` shares one trunk pass between the heads (half the convolutions of calling `actor` and
    `critic`); its log-probabilities, entropy, value and gradients are those of the two heads called apart."""
    import torch

    from chopperscape.learn import model

    torch.manual_seed(0)
    agent = model.build_agent(network, shape)
    x = torch.randint(0, 256, (6, *shape), dtype=torch.uint8)
    actions = torch.tensor([0, 1, 2, 3, 4, 0])
    trunk = agent.actor[0]
    calls = []
    hook = trunk.register_forward_hook(lambda *_: calls.append(1))
    _, logp, ent, value = agent.act(x, actions)
    hook.remove()
    assert len(calls) == 1
    dist = torch.distributions.Categorical(logits=agent.actor(x))
    torch.testing.assert_close(logp, dist.log_prob(actions), rtol=0, atol=1e-6)
    torch.testing.assert_close(ent, dist.entropy(), rtol=0, atol=1e-6)
    torch.testing.assert_close(value, agent.value(x), rtol=0, atol=1e-6)
    # The same gradients as the loss built from the separate heads.
    (logp.sum() + value.sum()).backward()
    shared = [p.grad.clone() for p in agent.parameters()]
    agent.zero_grad()
    (dist.log_prob(actions).sum() + agent.value(x).sum()).backward()
    for got, want in zip(shared, (p.grad for p in agent.parameters())):
        torch.testing.assert_close(got, want, rtol=1e-5, atol=1e-6)
    # Frames: uint8 and float frames in 0..255 give the same numbers, and a float input is not changed in place.
    xf = x.float()
    before = xf.clone()
    torch.testing.assert_close(agent.act(xf, actions)[1], logp.detach(), rtol=0, atol=1e-6)
    assert torch.equal(xf, before)


@needs_torch
def test_auxiliary_features_train_the_trunk_only_and_leave_no_trace_in_the_model(tmp_path, capsys):
    """`--aux-coef`: a twin features env in lockstep (its rewards checked every step), a loss on the CNN's trunk;
    the saved model is an ordinary pixel model (no extra head) that evaluate plays. Refused for the features MLP."""
    import torch

    from chopperscape.learn import model, train

    base = ["--preset", "pixels", "--steps", "600", "--num-envs", "4", "--num-steps", "32", "--seed", "5"]
    base += ["--option", "obs_size=42x42", "--option", "max_fuel=120"]
    assert train.main([*base, "--out", str(tmp_path / "aux"), "--aux-coef", "2"]) == 0
    assert train.main([*base, "--out", str(tmp_path / "plain")]) == 0
    capsys.readouterr()
    aux = torch.load(tmp_path / "aux" / "model.pt", weights_only=True)
    plain = torch.load(tmp_path / "plain" / "model.pt", weights_only=True)
    assert json.loads((tmp_path / "aux" / "recipe.json").read_text())["aux_coef"] == 2.0
    assert set(aux) == set(plain)  # no auxiliary head saved
    assert all(aux[part].keys() == plain[part].keys() for part in ("actor", "critic"))
    # The loss moved the trunk: the same run with a vanishing weight (the same twin and head, so the runs differ
    # only by the loss's weight; 1e-30 is lost in rounding) ends elsewhere.
    assert train.main([*base, "--out", str(tmp_path / "faint"), "--aux-coef", "1e-30"]) == 0
    faint = torch.load(tmp_path / "faint" / "model.pt", weights_only=True)
    assert not torch.equal(aux["actor"]["0.1.weight"], faint["actor"]["0.1.weight"])
    assert isinstance(model.agent_from_checkpoint(aux), model.CnnAgent)
    # The twin runs the same game: with equal seeds and actions, every reward and end matched (else it raises).
    rows = _progress(tmp_path / "aux" / "progress.csv")
    assert rows and int(rows[-1]["episodes"]) > 0
    with pytest.raises(SystemExit):
        train.main(["--steps", "100", "--out", str(tmp_path / "mlp"), "--aux-coef", "1"])
    assert "`aux_coef`: the auxiliary features loss is for CNN recipes" in capsys.readouterr().err
    with pytest.raises(SystemExit):
        train.main([*base, "--out", str(tmp_path / "neg"), "--aux-coef", "-1"])
    assert "invalid value -1.0 for option `aux_coef`" in capsys.readouterr().err
    assert not (tmp_path / "mlp").exists() and not (tmp_path / "neg").exists()


@needs_torch
def test_cnn_reads_inverted_frames_and_old_models_keep_plain_ones(tmp_path):
    """Recipe CNNs read ``1 - frame / 255`` (the white sky as 0); a 0.1.0 checkpoint, whose recipe has no
    `invert_frames`, is rebuilt reading ``frame / 255`` and gives the logits it was saved with."""
    import torch

    from chopperscape.learn import model
    from chopperscape.learn.recipe import Recipe

    x = torch.tensor([[[0, 51], [255, 204]]], dtype=torch.uint8)
    torch.testing.assert_close(model.Frames(invert=True)(x), 1 - x.unsqueeze(1).float() / 255, rtol=0, atol=1e-6)
    torch.testing.assert_close(model.Frames()(x), x.unsqueeze(1).float() / 255, rtol=0, atol=1e-6)
    assert Recipe().invert_frames is True
    shape = (42, 42, 2)
    frames = torch.randint(0, 256, (5, *shape), dtype=torch.uint8)
    for invert in (True, False):
        torch.manual_seed(3)
        agent = model.build_agent("small", shape, invert_frames=invert)
        recipe = Recipe(obs_type="grayscale", network="small", invert_frames=invert)
        path = tmp_path / f"invert-{invert}.pt"
        model.save(path, agent, model.ObsNormalizer(shape, False), recipe, shape, 0)
        if not invert:  # as 0.1.0 wrote it: no such key
            payload = torch.load(path, weights_only=True)
            del payload["recipe"]["invert_frames"]
            torch.save(payload, path)
        loaded = model.load(path).agent
        assert cast_frames(loaded).invert is invert
        torch.testing.assert_close(loaded.actor(frames), agent.actor(frames), rtol=0, atol=0)
    # The two readings are different inputs: the same weights give other logits.
    torch.manual_seed(3)
    plain = model.build_agent("small", shape)
    torch.manual_seed(3)
    inverted = model.build_agent("small", shape, invert_frames=True)
    assert not torch.allclose(plain.actor(frames), inverted.actor(frames))


def cast_frames(agent):
    """The `Frames` layer at the front of a CNN agent's trunk."""
    return agent.actor[0][0]


def _teacher_file(path, rules, favourite=3):
    """A features model as `train` writes it, whose policy plays `favourite` nearly always (a strong bias on its
    output layer), on the rules options `rules`."""
    import torch

    from chopperscape.learn import model
    from chopperscape.learn.recipe import Recipe

    torch.manual_seed(0)
    agent = model.build_agent("mlp", (46,), hidden=16)
    with torch.no_grad():
        agent.actor[-1].bias[favourite] = 8.0
    recipe = Recipe(obs_type="features", env_options=dict(rules), hidden=16)
    model.save(path, agent, model.ObsNormalizer((46,), True), recipe, (46,), 0)
    return path


def _column(path, name):
    """One column of a progress CSV, as written."""
    with open(path, newline="") as f:
        return [row[name] for row in csv.DictReader(f)]


@needs_torch
def test_a_teacher_pulls_the_pixel_policy_toward_it_and_changes_nothing_at_weight_zero(tmp_path, capsys):
    """`--teacher`: KL(teacher ‖ policy) on the policy's own rollouts, read from a twin features env. At weight 0 the
    run is the plain run bit for bit (the twin only watches); with weight the KL falls and the greedy policy plays
    the teacher's action; the saved model is a plain pixel model."""
    import torch

    from chopperscape.learn import model, train

    rules = {"frame_skip": 2, "max_fuel": 150}
    teacher = _teacher_file(tmp_path / "teacher.pt", rules)
    base = ["--preset", "pixels", "--steps", "1500", "--num-envs", "4", "--num-steps", "32", "--seed", "2"]
    base += ["--option", "obs_size=42x42", "--option", "frame_skip=2", "--option", "max_fuel=150"]
    assert train.main([*base, "--out", str(tmp_path / "plain")]) == 0
    assert train.main([*base, "--out", str(tmp_path / "zero"), "--teacher", str(teacher), "--teacher-coef", "0"]) == 0
    assert train.main([*base, "--out", str(tmp_path / "taught"), "--teacher", str(teacher), "--teacher-coef", "5"]) == 0
    capsys.readouterr()
    plain, zero, taught = (
        torch.load(tmp_path / r / "model.pt", weights_only=True) for r in ("plain", "zero", "taught")
    )
    assert set(taught) == set(plain) and taught["actor"].keys() == plain["actor"].keys()
    assert all(torch.equal(zero["actor"][k], plain["actor"][k]) for k in plain["actor"])
    assert not torch.equal(taught["actor"]["1.weight"], plain["actor"]["1.weight"])
    kl = [float(v) for v in _column(tmp_path / "taught" / "progress.csv", "teacher_kl")]
    assert kl[-1] < kl[0] / 2, kl
    assert set(_column(tmp_path / "plain" / "progress.csv", "teacher_kl")) == {""}
    # The taught policy flies Up (the teacher's action) from frames it has never seen; the plain one does not.
    frames = torch.randint(0, 256, (64, 42, 42, 4), dtype=torch.uint8)
    for run, want in (("taught", True), ("plain", False)):
        agent = model.load(tmp_path / run / "model.pt").agent
        with torch.no_grad():
            up = (agent.actor(frames).argmax(-1) == 3).float().mean().item()
        assert (up > 0.9) is want, (run, up)


@needs_torch
def test_a_teacher_is_refused_unless_it_fits_before_anything_is_written(tmp_path, capsys):
    from chopperscape.learn import train

    good = _teacher_file(tmp_path / "t.pt", {"frame_skip": 4})
    other_rules = _teacher_file(tmp_path / "fs2.pt", {"frame_skip": 2})
    same_by_default = _teacher_file(tmp_path / "fs4.pt", {"frame_skip": 4.0, "alien_prob": 0.0, "max_fuel": 1000})
    (tmp_path / "junk.pt").write_bytes(b"not a model")
    base = ["--preset", "pixels", "--steps", "300", "--num-envs", "2", "--num-steps", "32"]
    cases = [
        ([*base, "--teacher", str(tmp_path / "none.pt")], "no such file"),
        ([*base, "--teacher", str(tmp_path / "junk.pt")], "is not a chopperscape.learn.train model"),
        ([*base, "--teacher", str(other_rules)], r"learned other rules \(\{'frame_skip': 2.0\}\) than this run's"),
        (["--steps", "300", "--teacher", str(good)], "a features teacher guides CNN recipes"),
        (
            [*base, "--teacher", str(good), "--teacher-fade", "0"],
            r"`teacher_fade`: allowed a finite number in \(0, 1\]",
        ),
        ([*base, "--teacher", str(good), "--teacher-coef", "-1"], "`teacher_coef`"),
    ]
    for args, message in cases:
        out = tmp_path / "run"
        with pytest.raises(SystemExit) if "teacher_" in message or "guides" in message else contextlib.nullcontext():
            assert train.main([*args, "--out", str(out)]) == 2
        assert re.search(message, capsys.readouterr().err), message
        assert not out.exists()
    # A pixel teacher is refused by name.
    pixel_run = tmp_path / "pix"
    assert train.main([*base, "--option", "obs_size=42x42", "--out", str(pixel_run)]) == 0
    capsys.readouterr()
    assert train.main([*base, "--teacher", str(pixel_run / "model.pt"), "--out", str(tmp_path / "run")]) == 2
    assert "a teacher must be a features model" in capsys.readouterr().err
    # Rules spelled with their defaults are the same rules.
    assert train.main([*base, "--option", "obs_size=42x42", "--teacher", str(same_by_default), "--out",
                       str(tmp_path / "ok")]) == 0  # fmt: skip
