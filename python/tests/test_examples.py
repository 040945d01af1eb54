"""The behaviour-cloning example and the perception check run end to end (from features: a few short episodes, one
epoch; the perception check: a few hundred decisions at two frame sizes); the registered id form
`"chopperscape:ChopperScape-v0"` works in a fresh interpreter without importing the package first; the vector env
uses one thread unless asked."""

from __future__ import annotations

import csv
import json
import pathlib
import subprocess
import sys

import pytest

ROOT = pathlib.Path(__file__).resolve().parents[2]


def _example(script: str, *args: str) -> dict:
    """Runs `python/examples/SCRIPT ARGS...` and returns its last line, a JSON summary."""
    done = subprocess.run(
        [sys.executable, str(ROOT / "python" / "examples" / script), *args],
        capture_output=True,
        text=True,
        timeout=600,
    )
    assert done.returncode == 0, done.stderr
    return json.loads(done.stdout.strip().splitlines()[-1])


def test_bc_example_trains_and_reports_held_out_scores(tmp_path):
    pytest.importorskip("torch", reason="torch is not installed: the behaviour-cloning smoke test is skipped")
    pytest.importorskip("minari", reason="minari is not installed: the behaviour-cloning smoke test is skipped")
    args = ("--episodes", "2", "--epochs", "1", "--eval-episodes", "3", "--max-episode-steps", "200")
    summary = _example("bc_train.py", *args)
    assert summary["dataset_steps"] == 400 and summary["dataset_episodes"] == 2
    for name in ("bc", "heuristic", "random"):
        assert summary[name]["episodes"] == 3 and 0 < summary[name]["mean"] <= 200


def test_perception_check_runs_at_two_sizes_and_appends_one_csv(tmp_path):
    pytest.importorskip("torch", reason="torch is not installed: the perception check's smoke test is skipped")
    out = tmp_path / "perception.csv"
    args = ("--size", "84,42", "--samples", "640", "--epochs", "1", "--features-epochs", "1", "--eval-episodes", "2")
    summary = _example("perception.py", *args, "--out", str(out))
    with out.open() as f:
        rows = list(csv.DictReader(f))
    # One header, then the same measurements for each size, in the order the sizes ran.
    assert [r["size"] for r in rows] == ["84x84"] * (len(rows) // 2) + ["42x42"] * (len(rows) // 2)
    assert {r["size"] + ":" + r["measurement"]: float(r["value"]) for r in rows} == summary
    for size in ("84x84", "42x42"):
        # 160 held-out decisions: accuracies in steps of 1/160, every share in [0, 1].
        for name in ("clone_frames_agreement", "clone_features_agreement", "bird0_present", "tank0_present"):
            assert 0.0 <= summary[f"{size}:{name}"] <= 1.0
            assert summary[f"{size}:{name}"] * 160 == pytest.approx(round(summary[f"{size}:{name}"] * 160), abs=0.01)
        for name in ("clone_frames_flown", "clone_features_flown", "heuristic_flown", "random_flown"):
            assert summary[f"{size}:{name}"] > 0


FRESH = """
import gymnasium as gym
env = gym.make("chopperscape:ChopperScape-v0", obs_type="features")
obs, info = env.reset(seed=1)
envs = gym.make_vec("chopperscape:ChopperScape-v0", num_envs=3, vectorization_mode="vector_entry_point",
                    obs_type="features")
import chopperscape
assert type(envs).__module__ == "chopperscape.vector", type(envs)
vobs, _ = envs.reset(seed=1)
assert (vobs[0] == obs).all()
sync = gym.make_vec("chopperscape:ChopperScape-v0", num_envs=2, vectorization_mode="sync", obs_type="features")
sync.reset(seed=0)
print("ok", env.spec.id, env.spec.max_episode_steps)
"""


def test_the_module_qualified_id_needs_no_prior_import():
    done = subprocess.run([sys.executable, "-c", FRESH], capture_output=True, text=True, cwd=ROOT / "python" / "tests")
    assert done.returncode == 0, done.stderr
    assert done.stdout.split() == ["ok", "ChopperScape-v0", "10000"]


def test_the_vector_env_uses_one_thread_unless_asked():
    import chopperscape

    # Measured (python/README.md, "Threads"): on 2-vCPU hosts a second thread loses whenever the CPU is shared.
    assert chopperscape.VectorEnv(1024, obs_type="features").num_threads == 1
    assert chopperscape.VectorEnv(1024, num_threads=2, obs_type="features").num_threads == 2


def test_the_trunk_probe_reads_values_out_of_a_pixel_policys_embedding(tmp_path):
    pytest.importorskip("torch", reason="torch is not installed: the trunk probe's smoke test is skipped")
    out = tmp_path / "probe.csv"
    args = ("--samples", "600", "--held-out", "300", "--envs", "8", "--init", "--out", str(out))
    init = _example("trunk_probe.py", str(ROOT / "models" / "ppo-pixels.pt"), *args)
    assert init["network"] == "init" and init["held_out"] == 300
    with open(out, newline="") as f:
        rows = list(csv.DictReader(f))
    assert [r["network"] for r in rows] == ["trained", "init"]
    for row in rows:  # a smoke size: the figures (docs/notes/pixels-speed-and-probes.md) need 20,000 decisions
        for value in ("fuel", "chopper_y", "bird0_dx", "tank0_dy"):
            assert -10.0 < float(row[value]) <= 1.0, row


def test_the_flight_probe_says_where_a_pixel_policy_flies():
    pytest.importorskip("torch", reason="torch is not installed: the flight probe's smoke test is skipped")
    row = _example("flight_probe.py", str(ROOT / "models" / "ppo-pixels.pt"), "--decisions", "400", "--envs", "8")
    assert row["decisions"] == 400
    for key in ("height_q10_q50_q90", "column_q10_q50_q90"):
        low, mid, high = row[key]
        assert 0.0 <= low <= mid <= high <= 1.0, row
    assert 0.0 <= row["upper_third"] <= 1.0 and 0.0 <= row["tank_reachable"] <= 1.0 and row["refuels_per_1000"] >= 0


def test_the_flight_probe_counts_a_refuel_but_not_a_reset():
    import importlib.util

    import numpy as np

    spec = importlib.util.spec_from_file_location("flight_probe", ROOT / "python" / "examples" / "flight_probe.py")
    assert spec is not None and spec.loader is not None
    probe = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(probe)
    # Two envs, four steps: env 0 refuels between steps 1 and 2; env 1's episode ends at step 1 and restarts full.
    features = np.zeros((8, 46), np.float32)
    features[:, probe.FUEL] = [0.5, 0.3, 0.49, 0.29, 1.0, 1.0, 0.99, 0.99]
    features[0::2, probe.CHOPPER_Y] = 0.0  # env 0 at the top, env 1 at the bottom
    features[1::2, probe.CHOPPER_Y] = 1.0
    ended = np.zeros(8, bool)
    ended[3] = True  # env 1's decision at step 1 ended its episode
    row = probe.flight(features, ended, 2)
    assert row["refuels_per_1000"] == 1000.0 * 1 / 8
    assert row["upper_third"] == 0.5 and row["decisions"] == 8
