"""The SB3 trainers (`chopperscape.integrations.sb3_train`) at smoke budgets: their settings (SB3's defaults written
out), the record each run writes (full settings, training seeds as the envs were reset), the command line, and the
fast preset's settings in SB3's terms."""

from __future__ import annotations

import inspect
import json
import subprocess
import sys

import pytest
from conftest import needs_sb3


@needs_sb3
def test_the_written_out_defaults_are_sb3s_own():
    """What the trainers call SB3's defaults are SB3's (a new SB3 default would change a row unseen otherwise)."""
    from stable_baselines3 import DQN, PPO

    from chopperscape.integrations import sb3_train

    for cls, defaults, ours in (
        (PPO, sb3_train.PPO_DEFAULTS, ()),
        (DQN, sb3_train.DQN_DEFAULTS, ("gamma", "buffer_size", "learning_starts")),
    ):
        sb3 = {k: v.default for k, v in inspect.signature(cls).parameters.items()}
        for key, value in defaults.items():
            if key in sb3 and sb3[key] is not inspect.Parameter.empty and key not in ours:
                assert sb3[key] == value, (cls.__name__, key)


@needs_sb3
def test_the_progress_columns_are_the_learn_packages():
    from chopperscape.integrations.sb3_train import COLUMNS
    from chopperscape.learn import progress

    assert COLUMNS == progress.RETURNS


@needs_sb3
@pytest.mark.parametrize("algo", ["ppo", "dqn"])
def test_a_smoke_run_records_its_full_settings_and_training_seeds(algo, tmp_path):
    from chopperscape.integrations import sb3_train
    from chopperscape.learn import progress

    given = {"num_envs": 3, "n_steps": 64, "batch_size": 64} if algo == "ppo" else {"learning_starts": 100}
    record = sb3_train.train(algo, tmp_path / "run", given, seed=7, steps=320, mode="sticky-v0")
    on_disk = json.loads((tmp_path / "run" / "trainer.json").read_text())
    assert on_disk == record
    assert record["trainer"] == f"sb3-{algo}" and record["seed"] == 7 and record["mode"] == "sticky-v0"
    assert record["settings"] == sb3_train.settings_of(algo, given)
    assert record["train_seeds"] == [[7, 3 if algo == "ppo" else 1]]
    assert record["env_steps"] >= 320
    assert (tmp_path / "run" / "model.zip").is_file()
    assert (tmp_path / "run" / "vecnormalize.json").is_file() == (algo == "dqn")
    curve = tmp_path / "run" / "progress.csv"
    if algo == "ppo":  # (DQN's one game finishes no episode in 320 steps: a header only)
        progress.read(curve)  # the learn package reads it
    assert curve.read_text().splitlines()[0] == ",".join(progress.RETURNS)


@needs_sb3
def test_bad_settings_and_contradicting_modes_are_refused_before_anything_is_written(tmp_path):
    from chopperscape.integrations import sb3_train

    with pytest.raises(ValueError, match="ppo setting 'n_step' is unknown: allowed"):
        sb3_train.train("ppo", tmp_path / "a", {"n_step": 5}, steps=10)
    with pytest.raises(ValueError, match="frame_skip 4 != 1"):
        sb3_train.train("dqn", tmp_path / "b", steps=10, mode="v0")
    assert not (tmp_path / "a").exists() and not (tmp_path / "b").exists()
    done = subprocess.run(
        [sys.executable, "-m", "chopperscape.integrations.sb3_train", "ppo", "--out", str(tmp_path / "c")]
        + ["--steps", "10", "--settings", "[1]"],
        capture_output=True,
        text=True,
        timeout=300,
    )
    assert done.returncode == 2
    assert done.stderr == "error: --settings must be a JSON object such as '{\"n_epochs\": 4}'\n"


@needs_sb3
def test_the_fast_presets_settings_in_sb3s_terms():
    from chopperscape.integrations.sb3 import ppo_settings
    from chopperscape.integrations.sb3_train import recipe_settings
    from chopperscape.learn.recipe import LR_FLOOR, PRESETS, Recipe

    fast = Recipe(**{k: v for k, v in PRESETS["fast"].items() if k != "total_steps"})
    s = recipe_settings(fast)
    ppo = ppo_settings(fast)
    assert s["net_arch"] == ppo.pop("policy_kwargs")["net_arch"]
    assert {k: s[k] for k in ppo} == ppo
    assert (s["num_envs"], s["env_options"], s["normalize"]) == (128, {"obs_type": "features", "frame_skip": 4}, True)
    assert (s["learning_rate"], s["lr_floor"]) == (1e-3, LR_FLOOR)
