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
