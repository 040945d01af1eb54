"""Shared settings: short episodes, so a few hundred steps hold many autoresets."""

import os

import pytest

os.environ.setdefault("SDL_VIDEODRIVER", "dummy")
os.environ.setdefault("SDL_AUDIODRIVER", "dummy")

import chopperscape  # noqa: F401  (registers ChopperScape-v0)

#: Little fuel and many birds: episodes end every few dozen steps.
SHORT = {"obs_type": "features", "max_fuel": 40, "bird_prob": 0.2, "fuel_prob": 0.05}


@pytest.fixture
def short():
    return dict(SHORT)


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
