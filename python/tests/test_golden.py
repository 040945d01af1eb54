"""Python replays the Rust golden trajectories bit for bit: the same seed and actions give the same rewards,
flags, infos and features observations (CRC-32 of their little-endian float32 bytes) as the Rust core.

The files are written by `UPDATE_GOLDEN=1 cargo test -p chopperscape-core --test golden_trajectory`.
"""

import pathlib
import zlib

import gymnasium as gym
import numpy as np
import pytest

GOLDEN = pathlib.Path(__file__).resolve().parents[2] / "crates" / "core" / "tests" / "golden"

CASES = {
    "trajectory_v0_random_seed42.txt": (42, {}),
    "trajectory_options_heuristic_seed7.txt": (
        7,
        {
            "lives": 3,
            "alien_prob": 0.02,
            "bird_fuel_collision": "destroy",
            "frame_skip": 2,
            "sticky_prob": 0.25,
            "bird_prob": 0.05,
            "fuel_prob": 0.03,
            "max_fuel": 400,
            "max_episode_steps": 600,
        },
    ),
}


def crc(obs: np.ndarray) -> str:
    return f"{zlib.crc32(np.ascontiguousarray(obs, dtype='<f4').tobytes()):08x}"


def fields(line: str) -> dict[str, str]:
    return dict(part.split("=", 1) for part in line.split() if "=" in part)


@pytest.mark.parametrize("name", sorted(CASES))
def test_python_replays_the_rust_golden_trajectory(name):
    seed, options = CASES[name]
    lines = [line for line in (GOLDEN / name).read_text().splitlines() if not line.startswith("#")]
    env = gym.make("ChopperScape-v0", obs_type="features", **options)
    obs, info = env.reset(seed=seed)
    head = fields(lines[0])
    assert (info["fuel"], info["lives"], crc(obs)) == (int(head["fuel"]), int(head["lives"]), head["obs"])
    for i, line in enumerate(lines[1:], start=1):
        action, reward, terminated, truncated = line.split()[:4]
        want = fields(line)
        obs, r, term, trunc, info = env.step(int(action))
        assert r == float(reward), f"line {i}"
        assert (term, trunc) == (terminated == "1", truncated == "1"), f"line {i}"
        assert (info["fuel"], info["lives"]) == (int(want["fuel"]), int(want["lives"])), f"line {i}"
        assert info.get("cause", "-") == want["cause"], f"line {i}"
        assert crc(obs) == want["obs"], f"line {i}: observation differs"
    assert term or trunc, "the golden episode ends on its last line"
    env.close()
