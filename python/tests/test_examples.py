"""The behaviour-cloning examples run end to end (from features: a few short episodes, one epoch; from frames: a
few hundred decisions); the registered id form
`"chopperscape:ChopperScape-v0"` works in a fresh interpreter without importing the package first; the vector env
uses one thread unless asked."""

from __future__ import annotations

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


def test_pixel_cloning_probe_runs_and_reports_accuracy_against_the_majority_action():
    pytest.importorskip("torch", reason="torch is not installed: the pixel cloning smoke test is skipped")
    summary = _example("bc_pixels.py", "--samples", "640", "--epochs", "1", "--eval-episodes", "2")
    assert summary["samples"] == 640 and summary["episodes"] == 2 and summary["mean_return"] > 0
    # 64 held-out decisions: shares in steps of 1/64, the majority action's at least a fifth of them.
    for key in ("held_out_accuracy", "majority_action_share"):
        assert round(summary[key] * 64) == pytest.approx(summary[key] * 64, abs=0.05)
    assert 0.2 <= summary["majority_action_share"] <= 1.0 and 0.0 <= summary["held_out_accuracy"] <= 1.0


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
