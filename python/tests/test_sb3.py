"""The SB3 adapter (`chopperscape.integrations.sb3`): trajectory for trajectory equal to SB3's own `make_vec_env`,
truncation as SB3 reports it, PPO learning through it and reloading, the CNN policy on grayscale frames. (Its
contract under hostile input: `test_sb3_contract.py`.)"""

from __future__ import annotations

import numpy as np
import pytest
from conftest import SHORT, needs_sb3


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


@needs_sb3
def test_sb3_cnn_policy_on_stacked_frames_is_read_back_without_pickle_by_evaluate_and_the_bench(tmp_path, capsys):
    """SB3 holds a channel-last frame stack channels first (`VecTransposeImage`); the no-pickle loader and the
    shape check follow it, so `python/examples/sb3_ppo.py --pixels` models evaluate, and a wrong size is named."""
    import json

    from stable_baselines3 import PPO

    from chopperscape.bench import __main__ as bench
    from chopperscape.integrations.sb3 import ChopperScapeVecEnv
    from chopperscape.learn import evaluate

    frames = {"obs_type": "grayscale", "obs_size": [42, 42], "frame_stack": 4, "frame_skip": 4}
    model = PPO("CnnPolicy", ChopperScapeVecEnv(2, seed=0, **frames), n_steps=16, batch_size=16, n_epochs=1)
    model.learn(32)
    assert model.observation_space.shape == (4, 42, 42)
    model.save(tmp_path / "model.zip")

    def flags(names: dict) -> list[str]:
        return [x for k, v in names.items() for x in ("--option", f"{k}={json.dumps(v)}")]

    options = flags(frames)
    assert evaluate.main([str(tmp_path / "model.zip"), "--episodes", "2", *options]) == 0
    assert json.loads(capsys.readouterr().out)["episodes"] == 2
    sticky = flags({k: v for k, v in frames.items() if k != "frame_skip"})  # the mode fixes the rules
    out = tmp_path / "results.json"
    assert bench.main(["evaluate", str(tmp_path / "model.zip"), "--mode", "sticky-v0", *sticky, "--out", str(out)]) == 0
    assert json.loads(out.read_text())["policy"]["kind"] == "sb3"
    wrong = [o.replace("[42, 42]", "[48, 48]") for o in options]
    assert evaluate.main([str(tmp_path / "model.zip"), "--episodes", "1", *wrong]) == 2
    assert "(4, 42, 42)" in capsys.readouterr().err


@needs_sb3
@pytest.mark.parametrize("args", [["--pixels", "42", "--mode", "sticky-v0"], ["--preset", "fast", "--mode", "full-v0"]])
def test_the_sb3_example_trains_on_a_mode_and_refuses_what_contradicts_it(args, tmp_path):
    """`python/examples/sb3_ppo.py` (the documented SB3 rows): a few steps on a mode's rules save a model; a frame
    skip the mode does not have is named, exit status 2, nothing written."""
    import subprocess
    import sys
    from pathlib import Path

    script = Path(__file__).resolve().parents[2] / "python" / "examples" / "sb3_ppo.py"
    run = [sys.executable, str(script), *args, "--seed", "3", "--steps", "64"]
    done = subprocess.run([*run, "--out", str(tmp_path / "ok")], capture_output=True, text=True, timeout=600)
    assert done.returncode == 0, done.stderr
    assert (tmp_path / "ok" / "model.zip").is_file() and (tmp_path / "ok" / "progress.csv").is_file()
    if "--pixels" in args:
        at = run.index("sticky-v0")
        wrong = [*run[:at], "v0", *run[at + 1 :], "--out", str(tmp_path / "no")]
        done = subprocess.run(wrong, capture_output=True, text=True, timeout=600)
        assert done.returncode == 2 and "frame_skip 4 != 1" in done.stderr
        assert not (tmp_path / "no").exists()
