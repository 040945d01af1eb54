"""Shared settings: short episodes, so a few hundred steps hold many autoresets; the optional packages a test needs;
reading a progress CSV back."""

import csv
import functools
import importlib.util
import json
import os
import pathlib
import shutil
import subprocess

import pytest

os.environ.setdefault("SDL_VIDEODRIVER", "dummy")
os.environ.setdefault("SDL_AUDIODRIVER", "dummy")

import chopperscape  # noqa: F401  (registers ChopperScape-v0)

#: Little fuel and many birds: episodes end every few dozen steps.
SHORT = {"obs_type": "features", "max_fuel": 40, "bird_prob": 0.2, "fuel_prob": 0.05}


#: Tests of the learning tool chain need torch, and those of the SB3 adapter SB3 too (scripts/test-python.sh installs
#: both; under CI=true a skip fails the run).
needs_torch = pytest.mark.skipif(
    importlib.util.find_spec("torch") is None, reason="torch is not installed (scripts/test-python.sh installs it)"
)
needs_sb3 = pytest.mark.skipif(
    importlib.util.find_spec("stable_baselines3") is None or importlib.util.find_spec("torch") is None,
    reason="stable-baselines3 is not installed (scripts/test-python.sh installs it)",
)


@pytest.fixture
def short():
    return dict(SHORT)


@functools.cache
def cli() -> pathlib.Path | None:
    """The `chopperscape` command line, built by cargo (debug), or None without cargo."""
    if shutil.which("cargo") is None:
        return None
    root = pathlib.Path(__file__).resolve().parents[2]
    subprocess.run(["cargo", "build", "-q", "-p", "chopperscape-cli"], cwd=root, check=True)
    meta = json.loads(
        subprocess.run(
            ["cargo", "metadata", "--format-version", "1", "--no-deps"], cwd=root, check=True, capture_output=True
        ).stdout
    )
    return pathlib.Path(meta["target_directory"]) / "debug" / "chopperscape"


def pixel_recipe(**settings):
    """A pixel recipe small enough for a test to train in seconds (16×16 frames, 2 stacked, 4 envs × 16 steps, 4
    updates); `settings` replace any of these."""
    from chopperscape.learn.recipe import Recipe

    small = {
        "obs_type": "grayscale",
        "env_options": {"obs_size": [16, 16], "frame_stack": 2, "max_fuel": 120},
        "network": "small",
        "num_envs": 4,
        "num_steps": 16,
        "num_minibatches": 2,
        "total_steps": 4 * 16 * 4,
    }
    return Recipe(**{**small, **settings})


def progress_rows(path):
    """The rows of a progress CSV, as dicts of text."""
    with open(path, newline="") as f:
        return list(csv.DictReader(f))


def pytest_sessionfinish(session: pytest.Session, exitstatus: int) -> None:
    """Under CI=true nothing may be skipped: a test that skips (a package that could not be installed, a tool that
    is missing) fails the run, naming each. A local run only reports them (`-rs`)."""
    if os.environ.get("CI") != "true":
        return
    reporter = session.config.pluginmanager.get_plugin("terminalreporter")
    skipped = reporter.stats.get("skipped", []) if reporter is not None else []
    if skipped:
        names = ", ".join(report.nodeid for report in skipped)
        print(f"\nFAILED: {len(skipped)} tests skipped under CI=true (nothing may be skipped there): {names}")
        session.exitstatus = pytest.ExitCode.TESTS_FAILED
