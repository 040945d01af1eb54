"""The fast preset (`--preset fast`) and the phase benchmark, at smoke size: learning in minutes is a benchmark
(docs/notes/fast-preset-probes.md), not a test; these check that the preset trains, saves, reloads and
evaluates with finite losses, and that `python/bench_train.py` still runs and accounts for every phase."""

from __future__ import annotations

import csv
import json
import math
import subprocess
import sys
from dataclasses import replace
from pathlib import Path

import pytest
from conftest import cli

torch = pytest.importorskip("torch", reason="torch is not installed (scripts/test-python.sh installs it)")

ROOT = Path(__file__).resolve().parents[2]


def test_the_fast_preset_trains_reloads_and_evaluates(tmp_path, capsys):
    from chopperscape.learn import evaluate, train
    from chopperscape.learn.recipe import PRESETS, Recipe

    recipe = replace(Recipe(**PRESETS["fast"]), num_envs=16, num_steps=32, total_steps=2048)
    path = train.train(recipe, tmp_path)
    with open(tmp_path / "progress.csv") as f:
        rows = list(csv.DictReader(f))
    assert rows and int(rows[-1]["env_steps"]) >= 2048
    assert all(math.isfinite(float(v)) for r in rows for k, v in r.items() if v and k != "wall_s")
    saved = json.loads((tmp_path / "recipe.json").read_text())
    assert saved["env_options"]["frame_skip"] == PRESETS["fast"]["env_options"]["frame_skip"]
    # The model plays at the preset's frame skip without being told it.
    assert evaluate.main([str(path), "--episodes", "2", "--seed", "1000000"]) == 0
    result = json.loads(capsys.readouterr().out)
    assert result["episodes"] == 2 and math.isfinite(result["mean_return"])


def test_the_preset_is_the_command_lines(tmp_path):
    """`--preset fast` on the command line is PRESETS["fast"], its step budget included; a flag given beside it
    wins."""
    from chopperscape.learn import train

    out = tmp_path / "run"
    code = train.main(["--preset", "fast", "--num-envs", "8", "--num-steps", "16", "--steps", "256", "--out", str(out)])
    assert code == 0
    saved = json.loads((out / "recipe.json").read_text())
    from chopperscape.learn.recipe import PRESETS

    for key, value in PRESETS["fast"].items():
        if key not in ("num_envs", "num_steps", "total_steps"):
            assert saved[key] == value, key
    assert (saved["num_envs"], saved["num_steps"], saved["total_steps"]) == (8, 16, 256)


@pytest.mark.parametrize("mode", ["sticky-v0", "full-v0"])
def test_train_mode_trains_on_the_modes_rules_and_its_model_plays_them(mode, tmp_path, capsys):
    """`train --mode M` records exactly the options the mode sets (every other rules option at its default, as the
    core's `mode=` means), so `evaluate` and the bench play the model on the rules it learned."""
    from chopperscape import MODES, _core
    from chopperscape.bench import mode_options
    from chopperscape.learn import evaluate, train

    out = tmp_path / "run"
    code = train.main(["--preset", "fast", "--mode", mode, "--num-envs", "8", "--num-steps", "16", "--steps", "256",
                       "--out", str(out)])  # fmt: skip
    assert code == 0
    saved = json.loads((out / "recipe.json").read_text())["env_options"]
    listed = next(m for m in MODES if m["name"] == mode)["options"]
    assert saved == {k: _core.option_value(k, v) for k, v in listed.items()}
    rules = {k: v for k, v in mode_options(mode).items() if k != "mode"}
    assert all(saved.get(k, v) == v for k, v in rules.items())
    capsys.readouterr()
    assert evaluate.main([str(out / "model.pt"), "--episodes", "2", "--seed", "1000000"]) == 0
    assert json.loads(capsys.readouterr().out)["episodes"] == 2


def test_the_phase_benchmark_runs_and_accounts_for_every_phase():
    """torch's phases, SB3's anchor and the Rust learner's phases at the same places (`--rust`), in one table."""
    pytest.importorskip("stable_baselines3", reason="stable-baselines3 is not installed (the SB3 anchor)")
    from chopperscape.learn.phases import PHASES

    exe = cli()
    if exe is None:
        pytest.skip("cargo is not installed: the Rust learner's column is not built")
    cmd = [sys.executable, str(ROOT / "python" / "bench_train.py"), "--smoke", "--case", "fast", "--sb3"]
    out = subprocess.run(
        [*cmd, "--rust", str(exe), "--rust-threads", "1"],
        capture_output=True,
        text=True,
        timeout=300,
        cwd=ROOT,
    )
    assert out.returncode == 0, out.stderr
    lines = out.stdout.splitlines()
    for phase in PHASES:
        (row,) = [line for line in lines if line.startswith(phase + " ")]
        torch_us, rust_us = float(row.split()[1]), float(row.split()[-1])
        assert torch_us >= 0 and rust_us >= 0, row
        if phase in ("env", "forward", "update_forward", "backward"):
            assert rust_us > 0, row  # timed where the loop does that work
    assert any(line.startswith("## fast:") for line in lines)
    assert any(line.startswith("Rust learner, 1 thread(s): ") for line in lines), out.stdout
    assert any(line.startswith("SB3 PPO, the same network") for line in lines), out.stdout


def test_the_phase_benchmark_takes_recipe_settings_and_refuses_what_is_not_one():
    """`--set FIELD=VALUE` (the exploration bonus's cost, measured): checked as a recipe's settings are."""
    cmd = [sys.executable, str(ROOT / "python" / "bench_train.py"), "--smoke", "--case", "pixels"]
    bonus = ["--set", "rnd_coef=0.5", "--set", "rnd_own_value=true", "--set", "rnd_pool=2"]
    out = subprocess.run([*cmd, *bonus], capture_output=True, text=True, timeout=300, cwd=ROOT)
    assert out.returncode == 0, out.stderr
    assert any(line.startswith("## pixels:") for line in out.stdout.splitlines())
    for bad, says in (
        ("rnd_pool=3", "`rnd_pool`: allowed 1, 2, 4"),
        ("rnd_pooling=2", "FIELD one of"),
        ("rnd_pool", "expected FIELD=VALUE"),
    ):
        out = subprocess.run([*cmd, *bonus[:4], "--set", bad], capture_output=True, text=True, timeout=300, cwd=ROOT)
        assert out.returncode != 0 and says in out.stderr and "## pixels" not in out.stdout, (bad, out.stderr)
